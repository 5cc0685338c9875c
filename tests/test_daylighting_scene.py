"""Radiance scene export: rtrace (Radiance) of the exported sky against skydome's model in
200 directions, and its horizontal illuminance (rtrace -I) against the model's."""

from __future__ import annotations

import numpy as np
import pytest

import skydome as sd
from skydome.daylighting.scene import sun_direct_illuminance, write_radiance_sky


def _rtrace(tmp_path, rad, rays, args):
    from _radiance import run_radiance

    import subprocess

    from _radiance import _env, _tool

    oct_ = subprocess.run([_tool("oconv"), rad.name], capture_output=True, env=_env(),
                          cwd=tmp_path, timeout=120)
    assert oct_.returncode == 0, oct_.stderr
    (tmp_path / "sky.oct").write_bytes(oct_.stdout)
    out = run_radiance("rtrace", ["-h", *args, "sky.oct"], stdin=rays, cwd=tmp_path)
    return np.array(out.split(), dtype=float).reshape(-1, 3) @ np.array([0.265, 0.670, 0.065])


@pytest.mark.parametrize("name, params", [
    ("perez1993", dict(dni=650.0, dhi=120.0, day_of_year=100)),
    ("cie2003", dict(sky_type=12)),
])
def test_rtrace_of_exported_sky(tmp_path, name, params):
    from _radiance import hemisphere_directions

    sun = sd.Sun(elevation_deg=35.0, azimuth_deg=200.0)
    model = sd.model(name, sun=sun, **params)
    rad, dat, cal = write_radiance_sky(model, tmp_path / "sky.rad")
    d = hemisphere_directions(200, seed=3, min_elevation_deg=1.0)
    # stay off the solar disc itself (the sun is a separate source)
    d = d[np.degrees(np.arccos(np.clip(d @ sun.direction, -1, 1))) > 1.0]
    rays = "\n".join(f"0 0 0 {x:.12g} {y:.12g} {z:.12g}" for x, y, z in d) + "\n"
    got = 179.0 * _rtrace(tmp_path, rad, rays, ["-ab", "0", "-ov"])
    want = model.luminance(d)
    assert len(d) >= 195
    np.testing.assert_allclose(got, want, rtol=0.01)
    # horizontal illuminance: sky (Monte Carlo, -ab 1) + sun (its source)
    e = 179.0 * _rtrace(tmp_path, rad, "0 0 0 0 0 1\n",
                        ["-I", "-ab", "1", "-ad", "32768", "-aa", "0", "-lw", "1e-7", "-ov"])
    mu = (np.arange(400) + 0.5) / 400
    phi = (np.arange(800) + 0.5) * 2 * np.pi / 800
    st = np.sqrt(1 - mu ** 2)
    g = np.stack(np.broadcast_arrays(st[:, None] * np.sin(phi), st[:, None] * np.cos(phi),
                                     mu[:, None]), axis=-1)
    e_sky = float(np.sum(model.luminance(g) * mu[:, None]) / 400 * 2 * np.pi / 800)
    e_sun = sun_direct_illuminance(model) * np.sin(np.radians(35.0))
    assert e[0] == pytest.approx(e_sky + e_sun, rel=0.01)
    if name == "perez1993":
        assert e_sky == pytest.approx(model.diffuse_illuminance, rel=2e-3)
        assert e_sun > 0.3 * e[0]


def test_export_refuses_existing(tmp_path):
    model = sd.model("perez1993", sun=sd.Sun(elevation_deg=30, azimuth_deg=180), dni=500,
                     dhi=100)
    write_radiance_sky(model, tmp_path / "s.rad")
    with pytest.raises(ValueError, match="exists"):
        write_radiance_sky(model, tmp_path / "s.rad")
    with pytest.raises(ValueError, match=".rad"):
        write_radiance_sky(model, tmp_path / "s.txt")


def test_cli_export_radiance(tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app

    out = tmp_path / "sky.rad"
    args = ["export", "radiance", "--model", "perez1993", "--dni", "650", "--dhi", "120",
            "--lat", "36.1", "--lon", "-79.95", "--time", "2021-06-21T12:30:00-05:00",
            "--out", str(out)]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    assert "solar source sun" in out.read_text() and (tmp_path / "sky.dat").exists()
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 2 and "exists" in r.output
    r = CliRunner().invoke(app, args[:-1] + [str(tmp_path / "b.rad"), "--dni", "5000"])
    assert r.exit_code == 2 and "dni" in r.output
    assert not (tmp_path / "b.rad").exists()
