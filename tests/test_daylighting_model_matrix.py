"""``skydome skymatrix --model precomputed --aod-from ... --components spectral:N --out X.zarr``:
a physically based spectral sky per hour of a weather file, with each hour's aerosol optical
depth, written as Zarr one chunk of hours at a time."""

from __future__ import annotations

import numpy as np
import pytest

import skydome as sd
from skydome.daylighting.patches import patches
from skydome.daylighting.weather import read_weather, sample_weather_path

# small tables (seconds to build); the physics of the full-size tables is tested elsewhere
SMALL = dict(orders=2, transmittance_mu_size=16, transmittance_r_size=8, scattering_r_size=4,
             scattering_mu_size=8, scattering_mu_s_size=4, scattering_nu_size=2,
             irradiance_mu_s_size=8, irradiance_r_size=4, integration_samples=4,
             sphere_samples=4)
PARAMS = [a for k, v in SMALL.items() for a in ("--param", f"{k}={v}")]
AOD_COL = 58  # "AOD (unitless)" in a TMY3 record [WM08]


def _cli(args):
    from typer.testing import CliRunner

    from skydome.cli import app

    return CliRunner().invoke(app, [str(a) for a in args])


def _two_days_with_aod(tmp_path, aods=(0.08, 0.30)):
    """The sample TMY3's first two days with the AOD column set per day (the sample's own
    AOD is missing)."""
    lines = sample_weather_path().read_text().splitlines()
    out = lines[:2]
    for k, ln in enumerate(lines[2:50]):
        f = ln.split(",")
        f[AOD_COL] = f"{aods[k // 24]:.3f}"
        out.append(",".join(f))
    p = tmp_path / "two_days.csv"
    p.write_text("\n".join(out) + "\n")
    return p


def test_precomputed_spectral_zarr_from_weather_aod(tmp_path):
    import zarr

    wpath = _two_days_with_aod(tmp_path)
    out = tmp_path / "annual.zarr"
    r = _cli(["skymatrix", "--weather", wpath, "--patches", "tregenza", "--model",
              "precomputed", "--aod-from", "weather", "--components", "spectral:4",
              "--order", "0", "--chunk-hours", "12", "--out", out, *PARAMS])
    assert r.exit_code == 0, r.output
    z = zarr.open_array(str(out), mode="r")
    assert z.shape == (48, 146, 4) and z.chunks == (12, 146, 4)
    a = z[:]
    w = read_weather(wpath)
    lit = (w.dni + w.dhi) > 1e-4
    assert lit.sum() > 10
    assert np.all(a[~lit] == 0.0) and np.all(a[:, 0] == 0.0)  # nights black; no ground
    assert np.all(np.isfinite(a)) and np.all(a >= 0.0)
    # every lit hour is the model with that hour's sun and that day's AOD: patch centres
    # (order 0) against a model built directly for two hours, one per day
    ps = patches("tregenza")
    centres = ps.centres[1:]
    wl = np.linspace(380.0, 780.0, 4)
    for h, aod in ((int(np.argmax(lit)), 0.08), (24 + int(np.argmax(lit[24:])), 0.30)):
        d = w.sun_directions[h]
        sun = sd.Sun(elevation_deg=float(np.degrees(np.arcsin(d[2]))),
                     azimuth_deg=float(np.degrees(np.arctan2(d[0], d[1])) % 360.0))
        m = sd.model("precomputed", sun=sun, table_wavelengths_nm=wl,
                     atmosphere=sd.Atmosphere.earth(aerosol_optical_depth=aod), **SMALL)
        np.testing.assert_allclose(a[h, 1:], m.radiance(centres, wl), rtol=1e-9)


def test_precomputed_one_aod_luminance(tmp_path):
    import zarr

    wpath = _two_days_with_aod(tmp_path)
    out = tmp_path / "lum.zarr"
    r = _cli(["skymatrix", "--weather", wpath, "--patches", "tregenza", "--model",
              "precomputed", "--aod-from", "0.1", "--components", "luminance", "--order", "1",
              "--out", out, *PARAMS, "--param", "n_wavelengths=4"])
    assert r.exit_code == 0, r.output
    z = zarr.open_array(str(out), mode="r")
    assert z.shape == (48, 146, 1) and z.attrs["units"] == "cd/m^2"
    assert float(np.max(z[:])) > 100.0  # a daylit clear sky: thousands of cd/m^2


def test_model_matrix_bad_input(tmp_path):
    out = tmp_path / "x.zarr"
    # the sample file holds no AOD
    r = _cli(["skymatrix", "--weather", sample_weather_path(), "--model", "precomputed",
              "--aod-from", "weather", "--out", out, *PARAMS])
    assert r.exit_code == 2 and "aerosol optical depth" in r.output
    assert not out.exists() and not list(tmp_path.iterdir())
    for extra, word in ((["--aod-from", "-1"], "aod-from"),
                        (["--components", "spectral:0"], "components"),
                        (["--sun", "separate"], "sun"),
                        (["--param", "orders=99"], "orders")):
        r = _cli(["skymatrix", "--weather", _two_days_with_aod(tmp_path), "--model",
                  "precomputed", "--out", out, *PARAMS, *extra])
        assert r.exit_code == 2 and word in r.output, r.output
        assert not out.exists()
    r = _cli(["skymatrix", "--weather", sample_weather_path(), "--model", "precomputed",
              "--out", tmp_path / "x.mtx"])
    assert r.exit_code == 2 and "Zarr" in r.output
    out.mkdir()
    r = _cli(["skymatrix", "--weather", sample_weather_path(), "--model", "precomputed",
              "--out", out])
    assert r.exit_code == 2 and "exists" in r.output
