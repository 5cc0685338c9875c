"""The viewer's shaders against skydome's CPU models, in real headless Chromium.

Each model is rendered by its WebGL2 shader into a float render target (skydome's
equirect-hemisphere projection, 128 x 64, pixel centres), read back, and compared with
the CPU model's ``xyz()`` in the same directions with the same parameters: PSNR on linear
XYZ (peak = the reference's largest value) must be at least 40 dB. The floor follows
Bruneton's own GPU-vs-CPU tests (35-47 dB, precomputed_atmospheric_scattering
model_test). The reference is skydome's CPU evaluation, independent of the shader code
(numba/numpy in float64 against GLSL in float32).
"""

from __future__ import annotations

import numpy as np
import pytest

from _viewer import browser_page, psnr_db, viewer_url  # noqa: F401 - fixtures

W, H = 128, 64
PSNR_FLOOR_DB = 40.0

# (model, sun elevations [deg] the model allows, its parameters)
CASES = [
    ("preetham1999", (60.0, 20.0, 5.0, 0.0), {"turbidity": 2.5}),
    ("preetham1999", (20.0,), {"turbidity": 6.0}),
    ("hoffman_preetham2002", (60.0, 20.0, 5.0, 0.0), {"turbidity": 2.5, "g": 0.76}),
    ("hoffman_preetham2002", (20.0,), {"turbidity": 4.0, "g": 0.6, "phase": "henyey_greenstein"}),
    ("oneil2005", (60.0, 20.0, 5.0, 0.0, -4.0), {}),
    ("oneil2005", (20.0,), {"kr": 0.004, "km": 0.002, "g": -0.9, "samples": 4}),
    ("hillaire2020", (60.0, 20.0, 5.0, 0.0, -4.0), {}),
    ("hillaire2020", (20.0,), {"turbidity": 5.0, "observer_altitude_m": 10000.0}),
    ("precomputed", (60.0, 20.0, 5.0, 0.0, -4.0), {}),
]
VIEWS = [(m, el, p) for m, els, p in CASES for el in els]
SUN_AZIMUTH_DEG = 135.0

FIGURES: dict[str, float] = {}


def _cpu_model(model: str, elevation: float, params: dict):
    import skydome

    sun = {"sun_elevation": elevation, "sun_azimuth": SUN_AZIMUTH_DEG}
    if model == "precomputed":
        # the same tables as the server's (built once per turbidity, viewer sizes)
        from skydome.viewer.scene import build_model

        return build_model(model, sun, params)
    return skydome.model(model, sun=skydome.Sun(elevation_deg=elevation,
                                                azimuth_deg=SUN_AZIMUTH_DEG), **params)


def cpu_xyz(model: str, elevation: float, params: dict) -> np.ndarray:
    from skydome.imaging.projections import Equirect

    sky = _cpu_model(model, elevation, params)
    d, _ = Equirect(W, H, hemisphere=True).directions()
    return np.asarray(sky.xyz(d), dtype=np.float64)


def gpu_xyz(page, model: str, elevation: float, params: dict) -> np.ndarray:
    values = {"sun_elevation": elevation, "sun_azimuth": SUN_AZIMUTH_DEG, **params}
    flat = page.evaluate("([m, v, w, h]) => window.skydomeViewer.renderFloat(m, v, w, h, 1)",
                         [model, values, W, H])
    return np.asarray(flat, dtype=np.float64).reshape(H, W, 3)


def test_hillaire2020_ground_from_10km(browser_page):  # noqa: F811
    """The whole sphere (equirect) from 10 km: the lower half of the sky-view LUT holds the
    lit ground and the air in front of it; the shader must match the CPU there too."""
    import skydome
    from skydome.imaging.projections import Equirect

    page, messages = browser_page
    params = {"observer_altitude_m": 10000.0}
    sky = skydome.model("hillaire2020", sun=skydome.Sun(elevation_deg=30.0,
                                                        azimuth_deg=SUN_AZIMUTH_DEG), **params)
    d, _ = Equirect(W, W // 2).directions()
    ref = np.asarray(sky.xyz(d), dtype=np.float64)
    values = {"sun_elevation": 30.0, "sun_azimuth": SUN_AZIMUTH_DEG, **params}
    flat = page.evaluate("([m, v, w, h]) => window.skydomeViewer.renderFloat(m, v, w, h, 3)",
                         ["hillaire2020", values, W, W // 2])
    gpu = np.asarray(flat, dtype=np.float64).reshape(W // 2, W, 3)
    assert np.max(ref[W // 4:]) > 0.05 * np.max(ref)        # the lower half is not dark
    value = psnr_db(gpu, ref)
    print(f"PSNR hillaire2020 10 km, full sphere, sun 30 deg: {value:.1f} dB")
    assert value >= PSNR_FLOOR_DB


def test_precomputed_from_100km(browser_page):  # noqa: F811
    """The whole sphere from just below the top of the atmosphere (99 km): every direction
    that does not meet the ground, against the CPU model with the same tables."""
    from skydome.imaging.projections import Equirect

    page, messages = browser_page
    params = {"observer_altitude_m": 99000.0}
    for elevation in (20.0, -4.0):
        sky = _cpu_model("precomputed", elevation, params)
        d, _ = Equirect(W, W // 2).directions()
        r, R = sky.atmosphere.planet_radius_m + 99000.0, sky.atmosphere.planet_radius_m
        mu = d[..., 2]
        sky_dirs = ~((mu < 0.0) & (r * r * (mu * mu - 1.0) + R * R >= 0.0))
        assert 0.5 < sky_dirs.mean() < 0.6                     # the horizon dips 10 deg
        ref = np.asarray(sky.xyz(d), dtype=np.float64)[sky_dirs]
        values = {"sun_elevation": elevation, "sun_azimuth": SUN_AZIMUTH_DEG, **params}
        flat = page.evaluate("([m, v, w, h]) => window.skydomeViewer.renderFloat(m, v, w, h, 3)",
                             ["precomputed", values, W, W // 2])
        gpu = np.asarray(flat, dtype=np.float64).reshape(W // 2, W, 3)[sky_dirs]
        value = psnr_db(gpu, ref)
        print(f"PSNR precomputed 99 km, sun {elevation:g} deg: {value:.1f} dB")
        assert value >= PSNR_FLOOR_DB


def test_psnr_self_check():
    ref = np.linspace(0.0, 1.0, 100)
    assert psnr_db(ref + 0.01, ref) == pytest.approx(40.0)


@pytest.mark.parametrize("model,elevation,params", VIEWS,
                         ids=[f"{m}-{e:g}deg-{'-'.join(f'{k}{v}' for k, v in p.items()) or 'default'}"
                              for m, e, p in VIEWS])
def test_shader_matches_cpu(browser_page, model, elevation, params):  # noqa: F811
    page, messages = browser_page
    ref = cpu_xyz(model, elevation, params)
    gpu = gpu_xyz(page, model, elevation, params)
    assert np.all(np.isfinite(gpu)) and np.all(gpu >= 0.0)
    assert np.max(ref) > 0.0
    value = psnr_db(gpu, ref)
    FIGURES[f"{model} sun {elevation:g} deg {params}"] = value
    print(f"PSNR {model} sun {elevation:g} deg {params}: {value:.1f} dB")
    assert value >= PSNR_FLOOR_DB, (f"{model} sun {elevation:g} deg {params}: PSNR "
                                    f"{value:.1f} dB < {PSNR_FLOOR_DB} dB")
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]]


@pytest.mark.parametrize("elevation", [60.0, 20.0, 5.0])
def test_hillaire2020_aerial_perspective_volume(browser_page, elevation):  # noqa: F811
    """The per-frame aerial-perspective volume ([Hil20] 5.4, 32^3 froxels built by the GPU)
    looked up at a few distances over the whole sphere, against the CPU model's
    ``aerial_perspective(directions, distance_m, wavelengths_nm)``: in-scattered light and
    transmittance (as the XYZ of sunlight seen through it)."""
    import skydome
    from skydome.imaging.projections import Equirect
    from skydome.spectra import default_wavelengths, solar_irradiance, spectrum_to_xyz

    page, messages = browser_page
    sky = skydome.model("hillaire2020", sun=skydome.Sun(elevation_deg=elevation,
                                                        azimuth_deg=SUN_AZIMUTH_DEG))
    d, _ = Equirect(W, W // 2).directions()
    wl = default_wavelengths()
    values = {"sun_elevation": elevation, "sun_azimuth": SUN_AZIMUTH_DEG}
    for dist in (1000.0, 10000.0, 60000.0):
        T, L = sky.aerial_perspective(d, dist, wl)
        ref = {1: spectrum_to_xyz(L, wl),
               2: spectrum_to_xyz(T * solar_irradiance(wl) * sky.sun.irradiance_scale, wl)}
        for output, name in ((1, "in-scattering"), (2, "transmittance")):
            flat = page.evaluate("([m, v, w, h, o, s]) => window.skydomeViewer.renderFloat(m, v, w, h, 3, "
                                 "{output: o, distance: s})", ["hillaire2020", values, W, W // 2, output, dist])
            gpu = np.asarray(flat, dtype=np.float64).reshape(W // 2, W, 3)
            assert np.max(ref[output]) > 0.0
            value = psnr_db(gpu, ref[output])
            print(f"PSNR hillaire2020 aerial perspective {name}, {dist / 1000:g} km, sun {elevation:g} deg: "
                  f"{value:.1f} dB")
            assert value >= PSNR_FLOOR_DB
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]]


GROUND_VIEWS = [(0.0, el) for el in (60.0, 20.0, 5.0, 0.0, -4.0)] + [(99000.0, el) for el in (60.0, 20.0, -4.0)]


@pytest.mark.parametrize("altitude,elevation", GROUND_VIEWS,
                         ids=[f"{a / 1000:g}km-sun{e:g}deg" for a, e in GROUND_VIEWS])
def test_precomputed_ground(browser_page, altitude, elevation):  # noqa: F811
    """The ground below the horizon ([Bru17] GetSkyRadianceToPoint + GetSunAndSkyIrradiance:
    the Lambertian ground lit by the transmitted sun and the sky irradiance table, seen
    through the air in front of it) over every ground-hit direction of the whole sphere,
    against the CPU model's ground-hit rays (PrecomputedSky.radiance, the same tables)."""
    from skydome.imaging.projections import Equirect

    page, messages = browser_page
    params = {"observer_altitude_m": altitude}
    sky = _cpu_model("precomputed", elevation, params)
    d, _ = Equirect(W, W // 2).directions()
    r, R = sky.atmosphere.planet_radius_m + altitude, sky.atmosphere.planet_radius_m
    mu = d[..., 2]
    hits = (mu < 0.0) & (r * r * (mu * mu - 1.0) + R * R >= 0.0)
    assert 0.4 < hits.mean() <= 0.5
    ref = np.asarray(sky.xyz(d), dtype=np.float64)[hits]
    assert np.max(ref[:, 1]) > 0.0                              # the ground is lit
    values = {"sun_elevation": elevation, "sun_azimuth": SUN_AZIMUTH_DEG, **params}
    flat = page.evaluate("([m, v, w, h]) => window.skydomeViewer.renderFloat(m, v, w, h, 3)",
                         ["precomputed", values, W, W // 2])
    gpu = np.asarray(flat, dtype=np.float64).reshape(W // 2, W, 3)[hits]
    assert np.all(np.isfinite(gpu)) and np.all(gpu >= 0.0)
    value = psnr_db(gpu, ref)
    print(f"PSNR precomputed ground, observer {altitude / 1000:g} km, sun {elevation:g} deg: "
          f"{value:.1f} dB (ground Y max {np.max(ref[:, 1]):.4g} cd/m^2)")
    assert value >= PSNR_FLOOR_DB
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]]
