"""Analytic single-scattering Rayleigh polarisation (survey 5.7)."""

import numpy as np
import pytest

from skydome.effects.polarisation import (angle_of_polarisation, degree_of_polarisation,
                                          neutral_points_on_meridian,
                                          rayleigh_degree_of_polarisation,
                                          rayleigh_single_scattering_stokes)
from skydome.transport.geometry import direction_from_angles

EAST_HORIZON = direction_from_angles(0.0, 90.0)


@pytest.mark.parametrize("rho, expect", [(0.0, 1.0), (0.0279, (1 - 0.0279) / (1 + 0.0279))])
def test_maximum_at_90_degrees_is_one_minus_rho_over_one_plus_rho(rho, expect):
    """Chandrasekhar 1950 / Hansen & Travis 1974: P(90 deg) = (1 - rho)/(1 + rho)
    (0.9457 for rho = 0.0279)."""
    assert rayleigh_degree_of_polarisation(0.0, rho) == pytest.approx(expect, rel=1e-12)
    theta = np.radians(np.linspace(0, 180, 181))
    p = rayleigh_degree_of_polarisation(np.cos(theta), rho)
    assert np.argmax(p) == 90
    assert p[0] == pytest.approx(0.0, abs=1e-15) and p[180] == pytest.approx(0.0, abs=1e-15)


def test_classical_formula_without_depolarisation():
    theta = np.radians([30.0, 60.0, 120.0])
    np.testing.assert_allclose(rayleigh_degree_of_polarisation(np.cos(theta)),
                               np.sin(theta) ** 2 / (1 + np.cos(theta) ** 2))


def test_e_vector_perpendicular_to_scattering_plane():
    """Sun on the east horizon. Zenith: E along north-south = the zenith frame's
    reference (north): AoP 0, P 1. North horizon: scattering plane horizontal, E vertical:
    AoP 0. 45 deg up in the west (theta = 135 deg): scattering plane = the vertical E-W
    plane, E horizontal: AoP 90, P = sin^2/(1+cos^2) = 1/3."""
    d = np.stack([[0, 0, 1.0], direction_from_angles(0.0, 0.0), direction_from_angles(45.0, 270.0)])
    st = rayleigh_single_scattering_stokes(d, EAST_HORIZON, intensity=2.0)
    aop = angle_of_polarisation(st)
    dop = degree_of_polarisation(st)
    np.testing.assert_allclose(dop, [1.0, 1.0, 1 / 3], atol=1e-12)
    assert abs(aop[0]) < 1e-9 and abs(aop[1]) < 1e-9 and aop[2] == pytest.approx(90.0)
    np.testing.assert_allclose(st[..., 0], 2.0)
    np.testing.assert_allclose(st[..., 3], 0.0)


def test_neutral_point_finder():
    e = np.linspace(0, 180, 181)
    dop = np.abs(np.sin(np.radians(e - 25))) * 0.8 + 0.0   # zero at 25 deg: above a sun at 10 deg
    dop += np.where(np.abs(e - 160) < 1, -0.5, 0.0).clip(-dop, None)
    found = neutral_points_on_meridian(e, np.maximum(dop, 0), sun_elevation_deg=10.0)
    assert found["babinet"] == pytest.approx(25.0)


def test_cli_montecarlo_shows_the_progress_of_its_paths(tmp_path, monkeypatch):
    """`skydome polarisation --method montecarlo` runs under the command line's progress
    reporter: the kernel's blocks arrive as the stage "montecarlo paths", up to all paths."""
    from typer.testing import CliRunner

    import skydome.cli.apps as cli_apps
    from skydome.cli import app
    from skydome.cli._kit import _Progress
    from skydome.models.simulated import montecarlo as mc

    calls = []

    class Recorder(_Progress):
        def __call__(self, *args):
            calls.append(args)
            super().__call__(*args)

    monkeypatch.setattr(cli_apps, "_Progress", Recorder)
    monkeypatch.setattr(mc, "PROGRESS_PATHS_PER_BLOCK", 200)   # several blocks in a short run
    out = tmp_path / "pol.png"
    res = CliRunner().invoke(app, ["polarisation", "--method", "montecarlo", "--size", "6",
                                   "--samples", "20", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert out.is_file()
    paths = [c for c in calls if c[0] == "montecarlo paths"]
    assert len(paths) >= 2
    done = [c[1] for c in paths]
    assert done == sorted(done) and done[-1] == paths[-1][2] and paths[-1][2] % 20 == 0


def test_cli_montecarlo_bad_input_one_line_nothing_written(tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app

    res = CliRunner().invoke(app, ["polarisation", "--method", "montecarlo", "--samples", "1",
                                   "--out", str(tmp_path / "pol.png")])
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert res.exit_code == 2 and len(lines) == 1, res.output
    assert lines[0].startswith("error: --samples = 1") and "[2, 100000000]" in lines[0]
    assert list(tmp_path.iterdir()) == []
