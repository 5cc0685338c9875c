"""tools/fitted_horizon_diagnosis.py: its argument checks and its view-grid share
("angular alone") against the analytic error of bilinear interpolation."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

TOOL = Path(__file__).resolve().parents[1] / "tools" / "fitted_horizon_diagnosis.py"


def _tool():
    spec = importlib.util.spec_from_file_location("fitted_horizon_diagnosis_tool", TOOL)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


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


def test_angular_share_matches_bilinear_error_of_a_quadratic():
    """A reference quadratic in the sky grid's row index u, L = (u + 1)^2 on the nodes and
    (u + 1.5)^2 at the cells' centres: the lookup's bilinear value at a centre is the mean
    of its corners, (u + 1.5)^2 + 1/4, so its relative error is 1 / (4 (u + 1.5)^2), largest
    in the first row above the horizon (u = 0): 1/9."""
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
    assert r["angular"][1] == pytest.approx(1.0 / 9.0, rel=1e-5)
    assert r["angular low"][1] == pytest.approx(1.0 / 9.0, rel=1e-5)
    # the second row alone: 1 / (4 x 2.5^2) = 0.04 is the RMS of rows 0-1's errors with
    # row 0's (1/9): both rows keep every azimuth (the sun at 45 deg is far from them)
    assert r["angular low"][0] == pytest.approx(np.sqrt(((1 / 9) ** 2 + 0.04 ** 2) / 2),
                                                rel=1e-5)
