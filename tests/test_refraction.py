"""Refraction near the horizon and the flattened sun (skydome.effects.refraction)."""

import numpy as np
import pytest

from skydome.effects import refraction as rf


def test_bennett_horizon_and_45_deg():
    """Bennett 1982 / Meeus 1998 ch. 16: R = 34.5' at apparent elevation 0 (the standard
    horizontal refraction, ~34'), about 1' at 45 deg (cot 45.1 deg = 0.9965)."""
    assert rf.refraction_bennett_arcmin(0.0) == pytest.approx(34.5, abs=0.1)
    assert rf.refraction_bennett_arcmin(45.0) == pytest.approx(0.9965, abs=0.01)
    assert rf.refraction_bennett_arcmin(90.0) == pytest.approx(0.0, abs=0.01)


def test_saemundsson_is_inverse_of_bennett():
    """Meeus 1998 ch. 16: Saemundsson's formula (from true elevation) is consistent with
    Bennett's (from apparent elevation) to about 0.1 arcmin."""
    h_app = np.array([0.0, 0.5, 1.0, 2.0, 5.0, 10.0, 30.0, 60.0])
    h_true = rf.true_elevation(h_app)
    back = rf.apparent_elevation(h_true)
    assert np.max(np.abs(back - h_app)) * 60.0 < 0.15


def test_pressure_temperature_scaling():
    """Meeus 1998 ch. 16: R scales with (P / 101 kPa)(283 / (273 + T))."""
    r0 = rf.refraction_bennett_arcmin(2.0)
    r1 = rf.refraction_bennett_arcmin(2.0, pressure_pa=80800.0, temperature_c=-10.0)
    assert r1 / r0 == pytest.approx(0.8 * 283.0 / 263.0, rel=1e-12)


def test_sun_flattened_at_horizon_round_at_30_deg():
    """The sun at the horizon looks flattened to ~0.8-0.85 of its width with standard
    refraction (Meeus 1998 ch. 16: lower limb lifted ~35', upper ~29.5'); at 30 deg it is
    round to within 0.2 %."""
    low = rf.sun_disc_shape(-0.55)         # centre near the apparent horizon
    assert 0.78 <= low["ratio"] <= 0.87
    assert abs(low["apparent_centre_deg"]) < 0.15
    high = rf.sun_disc_shape(30.0)
    assert high["ratio"] == pytest.approx(1.0, abs=2e-3)
    assert high["horizontal_deg"] == pytest.approx(2 * 0.26667, rel=1e-3)


def test_no_refraction_well_below_horizon_and_errors():
    assert rf.refraction_saemundsson_arcmin(-5.0) == 0.0
    assert rf.refraction_bennett_arcmin(-3.0) == 0.0
    with pytest.raises(ValueError, match="pressure_pa"):
        rf.refraction_bennett_arcmin(1.0, pressure_pa=-1.0)
    with pytest.raises(ValueError, match="true_elevation_deg"):
        rf.sun_disc_shape(-10.0)


def test_sun_command_reports_refraction():
    """`skydome sun` near sunset: apparent elevation above the geometric one by ~0.5 deg
    and a flattened disc (ratio < 0.9)."""
    from typer.testing import CliRunner

    from skydome.cli import app

    res = CliRunner().invoke(app, ["sun", "--lat", "48.21", "--lon", "16.37", "--time", "2026-06-21T20:55+02:00"])
    assert res.exit_code == 0, res.output
    val = {ln.split()[0]: float(ln.split()[2] if ln.startswith("disc") else ln.split()[1])
           for ln in res.output.splitlines() if ln.split() and ln.split()[0] in ("elevation", "apparent", "disc")}
    assert 0.4 < val["apparent"] - val["elevation"] < 0.65
    assert val["disc"] < 0.9
