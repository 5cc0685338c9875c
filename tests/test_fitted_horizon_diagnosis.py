"""tools/fitted_horizon_diagnosis.py: its argument checks and its view-grid share
("angular alone") against the analytic error of bilinear interpolation."""

import numpy as np
import pytest
from _tools import load_script


def _tool():
    return load_script("tools/fitted_horizon_diagnosis.py")


@pytest.mark.parametrize("args, needle", [
    (["--aod", "1.5", "--albedo", "0.2", "--suns", "10", "--altitudes", "0"],
     "--aod = 1.5 is out of range [0, 1]"),
    (["--aod", "0.5", "--albedo", "0.2", "--suns", "10,95", "--altitudes", "0"],
     "--suns = 95 is out of range [-12, 90]"),
    (["--aod", "0.5", "--albedo", "0.2", "--suns", "10", "--altitudes", "-5"],
     "--altitudes = -5 is out of range [0, 15000]"),
    (["--aod", "0.5", "--albedo", "0.2", "--suns", "ten", "--altitudes", "0"],
     "--suns = 'ten' is not a comma-separated list of numbers"),
])
def test_reference_refuses_out_of_range(tmp_path, capsys, args, needle):
    assert _tool().main(["reference", str(tmp_path / "r.npz")] + args) == 2
    assert needle in capsys.readouterr().err
    assert not (tmp_path / "r.npz").exists()


def test_measure_refuses_bad_rows(tmp_path, capsys):
    assert _tool().main(["measure", str(tmp_path / "none.npz"), "--rows", "0"]) == 2
    assert "--rows = 0 is out of range [1, 63]" in capsys.readouterr().err


def test_angular_share_matches_the_spline_error_of_a_quadratic():
    """A reference quadratic in the sky grid's row index u, L = (u + 1)^2 on the nodes and
    (u + 1.5)^2 at the cells' centres. The lookup's Catmull-Rom spline reproduces a
    quadratic inside the grid: no error from the second row on. In the first row the row
    below the horizon is the straight line through rows 0 and 1 (-2 instead of 0): the
    centre's value (7 L0 + 10 L1 - L2) / 16 = 38/16 against 2.25, relative error 1/18.
    (The former bilinear lookup: 1/9 there, and 1 / (4 (u + 1.5)^2) in every row.)"""
    from skydome.models.fitted import _grid

    tool = _tool()
    wl = _grid.WAVELENGTHS_NM
    n_rows = _grid.N_SKY + _grid.N_GROUND
    u_n = np.arange(n_rows, dtype=float)
    u_c = np.arange(n_rows - 2, dtype=float) + 0.5
    shape_n = (1, 1, n_rows, _grid.N_PHI, wl.size)
    shape_c = (1, 1, n_rows - 2, _grid.N_PHI - 1, wl.size)
    ref = {"aod": 0.2, "albedo": 0.3, "suns": np.array([45.0]), "altitudes": np.array([0.0]),
           "wavelengths_nm": wl,
           "nodes": np.broadcast_to(((u_n + 1.0) ** 2)[None, None, :, None, None],
                                    shape_n).astype(np.float32),
           "centres": np.broadcast_to(((u_c + 1.0) ** 2)[None, None, :, None, None],
                                      shape_c).astype(np.float32)}
    (r,) = tool.compare(ref, rows=2)
    assert r["angular"][1] == pytest.approx(1.0 / 18.0, rel=1e-5)
    assert r["angular low"][1] == pytest.approx(1.0 / 18.0, rel=1e-5)
    # rows 0-1: row 0's 1/18 and row 1's 0 (both rows keep every azimuth: the sun at 45
    # deg is far from them)
    assert r["angular low"][0] == pytest.approx(np.sqrt((1 / 18) ** 2 / 2), rel=1e-5)
    # from the second row to the last but one the spline is exact, so the whole sky's RMS
    # is row 0's share (within 2 %: the centres within 5 deg of the sun are left out of
    # the count); the bilinear lookup's errors in every row would make it 0.015
    assert r["angular"][0] == pytest.approx(np.sqrt((1 / 18) ** 2 / (_grid.N_SKY - 1)),
                                            rel=0.02)


def test_elevation_share_is_the_cubic_interpolation_error_of_ln_s():
    """"elevation alone": a reference whose shape on the grid does not change with the sun
    and whose brightness is exp(k e^4) (e the sun elevation in deg): y is the same at every
    node, so the whole error is that of ln s cubic over the model's sun nodes at 0.25 deg,
    0, 0.5, 1 and 2 deg (a risen sun reads no node below the horizon; the AOD 0.2 takes the
    stencil in e). The Lagrange weights there are (21/64, 7/8, -7/32, 1/64), so e^4 = (0,
    1/16, 1, 16) is read as 11/128 against 1/256: the luminance off by exp(21/256 k) - 1 at
    every direction. A brightness exp(k e^3) is read exactly. A sun at a node, or without
    its four nodes, has no such figure."""
    from skydome.models.fitted import _grid

    tool = _tool()
    wl = _grid.WAVELENGTHS_NM
    suns = np.array([-1.0, 0.0, 0.25, 0.5, 1.0, 2.0, 3.5])
    rng = np.random.default_rng(2)
    g_n = rng.uniform(0.5, 1.5, (_grid.N_SKY + _grid.N_GROUND, _grid.N_PHI, wl.size))
    g_c = rng.uniform(0.5, 1.5, (_grid.N_SKY + _grid.N_GROUND - 2, _grid.N_PHI - 1, wl.size))
    k = 0.1
    for power, expected in ((4, np.expm1(21.0 / 256.0 * k)), (3, 0.0)):
        c = np.exp(k * suns ** power)[:, None, None, None, None]
        ref = {"aod": 0.2, "albedo": 0.3, "suns": suns, "altitudes": np.array([0.0]),
               "wavelengths_nm": wl,
               "nodes": (c * g_n[None, None]).astype(np.float32),
               "centres": (c * g_c[None, None]).astype(np.float32)}
        res = tool.compare(ref, rows=2)
        assert [("elevation" in r) for r in res] == [False, False, True, False, False, False,
                                                       False]
        rms, worst = res[2]["elevation"]
        assert worst == pytest.approx(abs(expected), abs=2e-6)
        assert rms == pytest.approx(abs(expected), abs=2e-6)
    assert tool.elevation_alone(dict(ref, suns=np.array([0.0, 0.25, 1.0])), 1, 0) is None
