"""tools/fitted_spectral_rank.py: its argument checks, and its truncation along the
wavelength against arrays of a known rank (built here, not by the tool)."""

import numpy as np
import pytest
from _tools import load_script


def _tool():
    return load_script("tools/fitted_spectral_rank.py")


def _known_rank_two(rng, weak_scale=0.1, A=2, B=3, E=4, H=5, W=11, T=6):
    """(coefficients (A, B, E, H, W, T), their weaker term): per sun node the rows are a
    mean spectrum plus two orthonormal spectral vectors with orthogonal, zero-mean
    amplitudes, the second's ``weak_scale`` times the first's in size."""
    C = np.empty((A, B, E, H, W, T))
    weak = np.empty_like(C)
    for e in range(E):
        mean = rng.normal(size=W)
        v1, v2 = np.linalg.qr(rng.normal(size=(W, 2)))[0].T
        a1 = rng.normal(size=(A, B, H, T)) * 10.0
        a2 = rng.normal(size=(A, B, H, T)) * 10.0 * weak_scale
        a1 -= a1.mean()
        a2 -= a2.mean()
        a2 -= a1 * np.sum(a1 * a2) / np.sum(a1 * a1)
        weak[:, :, e] = np.moveaxis(a2[..., None] * v2, -1, 3)
        C[:, :, e] = np.moveaxis(mean + a1[..., None] * v1, -1, 3) + weak[:, :, e]
    return C, weak


@pytest.mark.parametrize("rank", [0, 53])
def test_rank_out_of_range_refused_before_work(tmp_path, capsys, rank):
    """The rank is one of 1 .. the shipped file's number of table wavelengths (52:
    _grid.TABLE_WAVELENGTHS_NM, which tests/test_fitted.py checks the file holds)."""
    from skydome.models.fitted import _grid

    n = _grid.TABLE_WAVELENGTHS_NM.size
    assert n == 52
    out = tmp_path / "r.npz"
    assert _tool().main([str(out), "--rank", str(rank)]) == 2
    assert f"--rank = {rank} is out of range [1, {n}]" in capsys.readouterr().err
    assert not out.exists()


def test_missing_file_refused(tmp_path, capsys):
    out = tmp_path / "r.npz"
    assert _tool().main([str(out), "--rank", "4", "--coefficients",
                         str(tmp_path / "none.npz")]) == 2
    assert "is not a file" in capsys.readouterr().err
    assert not out.exists()


def test_truncation_keeps_an_array_of_that_rank_and_drops_the_rest():
    """Per sun node, rows = mean + two orthogonal spectral vectors with orthogonal,
    zero-mean amplitudes (rank 2 along the wavelength after the mean): rank 2 gives them
    back to rounding, rank 1 removes exactly the weaker term, known from the
    construction."""
    C, dropped = _known_rank_two(np.random.default_rng(3), weak_scale=0.01)
    tool = _tool()
    R2, rel2 = tool.truncate(C, 2)
    np.testing.assert_allclose(R2, C, rtol=0, atol=1e-10 * np.abs(C).max())
    assert rel2 < 1e-12
    R1, rel1 = tool.truncate(C, 1)
    # rank 1 removes the weaker term exactly: with orthogonal spectral vectors and
    # orthogonal amplitudes the two terms are the decomposition's singular terms
    np.testing.assert_allclose(C - R1, dropped, rtol=0, atol=1e-9 * np.abs(C).max())
    assert rel1 == pytest.approx(np.sqrt(np.mean(dropped ** 2) / np.mean(C ** 2)),
                                 rel=1e-6)


def test_fit_stores_spectral_terms_the_model_reads_back():
    """tools/fit_fitted.py --spectral-rank (_coefficients.spectral_factors): the factors of
    coefficients of rank 2 along the wavelength, read by the model's loader
    (_coefficients._coefficients_mixed, float32 and float16 with a scale per row as
    --float16 writes them; one altitude and a mix of two) give the coefficients back; the
    measuring tool expands them the same way."""
    from skydome.models.fitted import _coefficients

    C = _known_rank_two(np.random.default_rng(8))[0].astype(np.float32)
    amp, spec, mean, rel = _coefficients.spectral_factors(C, 2)
    assert amp.shape == (2, 3, 4, 5, 2, 6) and spec.shape == (4, 2, 11)
    assert mean.shape == (4, 11) and rel < 1e-6
    full = {"coef_sky": C}
    factors = {"coef_sky_amp": amp, "coef_sky_spec": spec, "coef_sky_spec_mean": mean}
    scale = np.max(np.abs(amp), axis=-1)
    half = {"coef_sky_amp": (amp / scale[..., None]).astype(np.float16),
            "coef_sky_amp_scale": scale, "coef_sky_spec": spec, "coef_sky_spec_mean": mean}
    peak = float(np.abs(C).max())
    for i, j, ks, st in ((0, 0, [0, 1, 2], [(0, 1.0)]), (1, 2, [3], [(4, 1.0)]),
                         (1, 1, [1, 3], [(2, 0.3), (3, 0.7)])):
        want = sum(w * C[i, j, ks, h] for h, w in st)
        got = _coefficients._coefficients_mixed(factors, "coef_sky", i, j, ks, st)
        assert got.shape == want.shape == (len(ks), 11, 6)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-5 * peak)
        np.testing.assert_allclose(_coefficients._coefficients_mixed(full, "coef_sky", i, j,
                                                                     ks, st),
                                   want, rtol=0, atol=1e-6 * peak)
        # float16 amplitudes: 2^-11 of each row's largest, times the spectra
        got16 = _coefficients._coefficients_mixed(half, "coef_sky", i, j, ks, st)
        np.testing.assert_allclose(got16, want, rtol=0, atol=2e-3 * peak)
    np.testing.assert_allclose(_tool().expanded(dict(factors), "coef_sky"), C, rtol=0,
                               atol=1e-5 * peak)


def test_fit_refuses_a_spectral_rank_out_of_range(capsys):
    fit = load_script("tools/fit_fitted.py")
    assert fit.main(["unused", "--spectral-rank", "-1"]) == 2
    assert "--spectral-rank = -1 is out of range [0, 256]" in capsys.readouterr().err
