"""Hourly plane illuminance from a weather file (the vectorised many-hours path) against the
public per-sky API, skydome.illuminance, applied to the single-sky Perez1993 model of each
hour (itself checked against Radiance's gendaylit in test_perez1993.py)."""

from __future__ import annotations

import numpy as np
import pytest

from skydome.daylighting.series import parse_plane, plane_series
from skydome.daylighting.weather import read_weather, sample_weather_path


@pytest.fixture(scope="module")
def day():
    w = read_weather(sample_weather_path())
    return w.select(w.day_of_year == 100)


def test_planes_against_single_sky_model(day):
    import skydome as sd
    from skydome import illuminance
    from skydome.models.analytic.perez1993 import Perez1993

    planes = [parse_plane(s) for s in ("horizontal", "vertical:180", "vertical:90",
                                       "tilted:30:180", "vertical:0")]
    res = plane_series(day, planes)
    hours = [i for i in range(len(day)) if day.sun_zenith_deg[i] < 80 and day.dhi[i] > 20][::2]
    assert len(hours) >= 3
    for i in hours:
        sun = sd.Sun(elevation_deg=90.0 - day.sun_zenith_deg[i],
                     azimuth_deg=day.sun_azimuth_deg[i])
        m = Perez1993(sun=sun, dni=float(day.dni[i]), dhi=float(day.dhi[i]),
                      day_of_year=int(day.day_of_year[i]),
                      dew_point_c=float(day.dew_point_c[i]), air_mass="kasten1966")
        for p in planes:
            want = illuminance.sky_illuminance(m, p.tilt_deg, p.azimuth_deg)
            got = res[p.name]["sky_lx"][i]
            assert got == pytest.approx(want, rel=5e-3), (i, p.name)
            want_g = illuminance.ground_illuminance(m, p.tilt_deg, p.azimuth_deg,
                                                    ground_albedo=0.2)
            assert res[p.name]["ground_lx"][i] == pytest.approx(want_g, rel=5e-3, abs=1e-9)
        # the sun: direct normal illuminance times the cosine of incidence
        s = sun.direction
        n = parse_plane("vertical:180").normal
        assert res["vertical_180"]["sun_lx"][i] == pytest.approx(
            m.direct_illuminance * max(float(s @ n), 0.0), rel=1e-6, abs=1e-6)


def test_horizontal_and_ground_parts(day):
    res = plane_series(day, ["horizontal", "vertical:180", "tilted:180:0"],
                       ground_reflectance=0.3)
    h, v, down = res["horizontal"], res["vertical_180"], res["tilted_180_0"]
    assert np.all(h["ground_lx"] == 0.0)
    # a plane facing down sees only the ground: rho x global horizontal illuminance
    np.testing.assert_allclose(down["ground_lx"], 0.3 * (h["sky_lx"] + h["sun_lx"]), rtol=1e-12)
    assert np.all(down["sky_lx"] == 0.0) and np.all(down["sun_lx"] == 0.0)
    np.testing.assert_allclose(v["ground_lx"], 0.5 * down["ground_lx"], rtol=1e-12)
    # horizontal diffuse irradiance equals the file's DHI
    np.testing.assert_allclose(h["sky_wm2"], day.dhi, rtol=1e-9, atol=1e-9)
    for part in res.values():
        if isinstance(part, dict):
            for v_ in part.values():
                assert np.all(np.isfinite(v_)) and np.all(v_ >= 0.0)


@pytest.mark.parametrize("spec", ["vertical", "vertical:400", "tilted:30", "slanted:1:2"])
def test_bad_plane(spec):
    with pytest.raises(ValueError, match="plane = "):
        parse_plane(spec)


def test_cli_illuminance(tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app

    lines = sample_weather_path().read_text().splitlines(keepends=True)
    w = tmp_path / "d.csv"
    w.write_text("".join(lines[:2 + 48]))
    out = tmp_path / "hourly.csv"
    args = ["illuminance", "--weather", str(w), "--plane", "horizontal", "--plane",
            "vertical:180", "--out", str(out)]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    rows = out.read_text().splitlines()
    assert len(rows) == 49 and "vertical_180_sun_lx" in rows[0]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 2 and "exists" in r.output
    r = CliRunner().invoke(app, args[:-1] + [str(tmp_path / "x.csv"), "--plane", "up"])
    assert r.exit_code == 2 and "plane = 'up'" in r.output
    assert not (tmp_path / "x.csv").exists()
