"""Weather that cannot be: a direct beam beyond the clear-sky limit is refused the way
Radiance's gendaylit refuses it, checked against gendaylit's own decisions."""

from __future__ import annotations

import subprocess
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import skydome as sd
from skydome.models.analytic.perez1993 import Perez1993, clear_sky_limit_exceeded

from _radiance import _env, _tool

ELEVATIONS = (1.0, 3.0, 5.0, 10.0, 20.0, 30.0, 45.0, 60.0, 80.0, 88.0)
DNIS = (0.0, 300.0, 700.0, 900.0, 1000.0, 1100.0, 1200.0, 1250.0, 1300.0, 1358.0, 1367.0,
        1368.0, 1400.0)
DHIS = (1.0, 5.0, 20.0, 50.0, 100.0, 200.0, 400.0, 700.0)


def _gendaylit_refuses(elev: float, dni: float, dhi: float) -> bool:
    """gendaylit -ang ELEV 0 -W DNI DHI: True where it prints its error sky because the beam
    exceeds its solar constant (irradiance or illuminance)."""
    r = subprocess.run([_tool("gendaylit"), "-ang", f"{elev:g}", "0", "-W", f"{dni:g}",
                        f"{dhi:g}"], capture_output=True, env=_env(), timeout=60, text=True)
    assert r.returncode == 0, r.stderr
    return "exceeds solar constant" in r.stderr


@pytest.fixture(scope="module")
def gendaylit_grid():
    _tool("gendaylit")  # skip without Radiance
    cases = [(e, i, d) for e in ELEVATIONS for i in DNIS for d in DHIS]
    with ThreadPoolExecutor(4) as pool:
        refused = list(pool.map(lambda c: _gendaylit_refuses(*c), cases))
    return cases, np.array(refused)


def test_limit_reproduces_gendaylit_decisions(gendaylit_grid):
    """Reference: gendaylit (the build pyradiance ships) over 1040 (elevation, DNI, DHI)
    cases; gendaylit -ang leaves its day number at 0, whose eccentricity is day 365's."""
    cases, refused = gendaylit_grid
    e, i, d = (np.array(v) for v in zip(*cases))
    ours = clear_sky_limit_exceeded(i, d, 90.0 - e, day_of_year=365)
    disagree = [c for c, a, b in zip(cases, refused, ours) if a != b]
    assert not disagree, disagree[:10]
    # the grid exercises both rules and both answers
    assert 50 < refused.sum() < len(cases) - 50
    assert refused[[c == (20.0, 1358.0, 20.0) for c in cases]].all()
    assert not refused[[c == (20.0, 1358.0, 100.0) for c in cases]].any()
    assert refused[[c[1] == 1368.0 for c in cases]].all()  # rule 1 alone


def test_perez1993_refuses_what_gendaylit_refuses(gendaylit_grid):
    cases, refused = gendaylit_grid
    for (elev, dni, dhi), bad in zip(cases[::3], refused[::3]):
        sun = sd.Sun(elevation_deg=elev, azimuth_deg=180.0)
        if bad:
            with pytest.raises(ValueError, match=r"clear-sky limit.*dni|dni.*clear-sky limit"):
                Perez1993(sun=sun, dni=dni, dhi=dhi, day_of_year=365)
            m = Perez1993(sun=sun, dni=dni, dhi=dhi, day_of_year=365, invalid="black")
            assert not m.valid and m.sun_luminance() == 0.0
            assert np.all(m.luminance(np.array([[0.0, 0.0, 1.0], [0.0, -0.5, 0.866]])) == 0.0)
        else:
            try:
                m = Perez1993(sun=sun, dni=dni, dhi=dhi, day_of_year=365)
            except ValueError as exc:  # only the fitted model's own domain (b > 0) remains
                assert "clear-sky" not in str(exc), (elev, dni, dhi, str(exc))


def test_1358_at_20_deg_with_little_diffuse_is_refused():
    """The case reported: 1358 W/m^2 at 20 deg elevation (gendaylit: 'direct illuminance
    exceeds solar constant' with Dh = 20 W/m^2, see the grid test)."""
    with pytest.raises(ValueError, match=r"dni = 1358 W/m\^2 with dhi = 20 W/m\^2 at sun "
                                         r"elevation 20 deg is beyond the clear-sky limit"):
        sd.model("perez1993", sun=sd.Sun(elevation_deg=20.0, azimuth_deg=180.0), dni=1358.0,
                 dhi=20.0)


def test_illuminance_input_limit():
    """gendaylit -L refuses a direct normal illuminance above 127 500 lx."""
    sun = sd.Sun(elevation_deg=40.0, azimuth_deg=180.0)
    Perez1993(sun=sun, dni_illuminance=127000.0, dhi_illuminance=15000.0)
    with pytest.raises(ValueError, match="dni_illuminance = 128000 lx"):
        Perez1993(sun=sun, dni_illuminance=128000.0, dhi_illuminance=15000.0)
    r = subprocess.run([_tool("gendaylit"), "-ang", "40", "0", "-L", "128000", "15000"],
                       capture_output=True, env=_env(), timeout=60, text=True)
    assert "exceeds solar constant" in r.stderr


def test_asrc_cie_refuses_the_same_beam():
    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=180.0)
    with pytest.raises(ValueError, match="asrc_cie: dni = 1358 W/m\\^2 .* clear-sky limit"):
        sd.model("asrc_cie", sun=sun, dni=1358.0, dhi=20.0)
    sd.model("asrc_cie", sun=sun, dni=1358.0, dhi=100.0)


def test_weather_hours_beyond_the_limit_flagged_in_the_sky_matrix(tmp_path):
    """A year's sky matrix keeps such hours (as gendaymtx does) and one note counts them."""
    import warnings

    from skydome.daylighting.skymatrix import ClearSkyNote, perez_sky_matrix_from_weather
    from skydome.daylighting.weather import read_weather, sample_weather_path

    w = read_weather(sample_weather_path())
    w = w.select(np.arange(len(w)) < 24 * 3)
    noon = int(np.argmin(w.sun_zenith_deg[24:48])) + 24
    dni = w.dni.copy()
    dhi = w.dhi.copy()
    dni[noon], dhi[noon] = 1366.0, 5.0  # beyond rule 2 at a winter noon (~33 deg)
    import dataclasses

    w = dataclasses.replace(w, dni=dni, dhi=dhi)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        m = perez_sky_matrix_from_weather(w, order=0)
    notes = [str(r.message) for r in rec if issubclass(r.category, ClearSkyNote)]
    assert len(notes) == 1 and f"1 hour(s) beyond the clear-sky limit (gendaylit's rule; " \
        f"first: record {noon + 1}" in notes[0]
    assert np.asarray(m.sky)[noon].max() > 0.0
