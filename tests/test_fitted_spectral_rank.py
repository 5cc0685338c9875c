"""tools/fitted_spectral_rank.py: its argument checks, and its truncation along the
wavelength against arrays of a known rank (built here, not by the tool)."""

import numpy as np
import pytest
from _tools import load_script


def _tool():
    return load_script("tools/fitted_spectral_rank.py")


@pytest.mark.parametrize("rank", [0, 50])
def test_rank_out_of_range_refused_before_work(tmp_path, capsys, rank):
    out = tmp_path / "r.npz"
    assert _tool().main([str(out), "--rank", str(rank)]) == 2
    assert f"--rank = {rank} is out of range [1, 49]" in capsys.readouterr().err
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
    rng = np.random.default_rng(3)
    A, B, E, H, W, T = 2, 3, 4, 5, 11, 6
    C = np.empty((A, B, E, H, W, T))
    weak = []
    for e in range(E):
        mean = rng.normal(size=W)
        v1, v2 = np.linalg.qr(rng.normal(size=(W, 2)))[0].T     # orthonormal
        a1 = rng.normal(size=(A, B, H, T)) * 10.0
        a2 = rng.normal(size=(A, B, H, T)) * 0.1
        a1 -= a1.mean()                                           # zero-mean amplitudes
        a2 -= a2.mean()
        a2 -= a1 * np.sum(a1 * a2) / np.sum(a1 * a1)             # orthogonal to a1
        rows = mean + a1[..., None] * v1 + a2[..., None] * v2     # (A, B, H, T, W)
        C[:, :, e] = np.moveaxis(rows, -1, 3)
        weak.append(np.moveaxis(a2[..., None] * v2, -1, 3))
    tool = _tool()
    R2, rel2 = tool.truncate(C, 2)
    np.testing.assert_allclose(R2, C, rtol=0, atol=1e-10 * np.abs(C).max())
    assert rel2 < 1e-12
    R1, rel1 = tool.truncate(C, 1)
    # rank 1 removes the weaker term exactly: with orthogonal spectral vectors and
    # orthogonal amplitudes the two terms are the decomposition's singular terms
    dropped = np.stack(weak, axis=2)                               # (A, B, E, H, W, T)
    np.testing.assert_allclose(C - R1, dropped, rtol=0, atol=1e-9 * np.abs(C).max())
    assert rel1 == pytest.approx(np.sqrt(np.mean(dropped ** 2) / np.mean(C ** 2)),
                                 rel=1e-6)
