"""Tests of the ``nishita1993`` model (the earth seen from space) and of the Camera projection.

References used: the physics of Rayleigh scattering (a blue limb, a reddened terminator,
as in the photographs and images of [NSTN93] fig. 8-9), the Fresnel equations, the
exact solid angle of a rectangular pyramid, the project's independent single-scattering
integrator (``single_scattering`` model) and the sea-water table's published entries.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere
from skydome.models import get_model_class
from skydome.camera import Camera
from skydome.spectra import spectrum_to_xyz, wavelength_grid, xyz_to_linear_srgb

WL = wavelength_grid(380.0, 780.0, n=12)
R = 6_371_000.0
GEO = 36e6


def _model(**kw):
    sun = kw.pop("sun", sd.Sun(elevation_deg=30.0, azimuth_deg=180.0))
    return get_model_class("nishita1993")(sun=sun, **kw)


def _south_ray(r0, tangent_alt):
    """Unit direction from the camera at (0, 0, r0 - R) towards the southern limb, tangent
    to the sphere of radius R + tangent_alt."""
    a = math.asin((R + tangent_alt) / r0)
    return np.array([0.0, -math.sin(a), -math.cos(a)])


def _rgb(L):
    return xyz_to_linear_srgb(spectrum_to_xyz(L, WL))


@pytest.fixture(scope="module")
def earth():
    return _model(atmosphere=Atmosphere.earth(turbidity=2.5, planet_radius_m=R))


def test_seawater_table_integrity():
    # Gregg & Casey OASIM table: 16 bands 375-775 nm; a_w(400) = 0.0063, b_w(500) = 0.0029 m^-1
    from skydome.data import load_table

    cols, t = load_table("seawater_optical_properties")
    assert cols == ("wavelength_nm", "a_w", "b_w")
    assert t.shape == (16, 3)
    assert t[t[:, 0] == 400][0, 1] == pytest.approx(0.0063)
    assert t[t[:, 0] == 500][0, 2] == pytest.approx(0.0029)


def test_fresnel_normal_incidence():
    # Fresnel: R(0) = ((n - 1) / (n + 1))^2 = 0.02110 for n = 1.34; R -> 1 at grazing
    from skydome.models.simulated._kernels_nishita1993 import fresnel

    assert fresnel(1.0, 1.34) == pytest.approx(((0.34) / 2.34) ** 2, rel=1e-12)
    assert fresnel(1e-9, 1.34) > 0.999
    # Brewster angle (tan theta_B = n): only the s-polarised part is reflected
    cb = math.cos(math.atan(1.34))
    ci = cb
    ct = math.sqrt(1 - (1 - ci * ci) / 1.34 ** 2)
    rs = ((ci - 1.34 * ct) / (ci + 1.34 * ct)) ** 2
    assert fresnel(cb, 1.34) == pytest.approx(0.5 * rs, rel=1e-9)


def test_limb_is_blue_on_day_side(earth):
    # Sun 30 deg high at the sub-camera point, towards the south: the southern limb is lit.
    d = np.stack([_south_ray(R + GEO, h) for h in (5e3, 15e3, 30e3)])
    rgb = _rgb(earth.radiance(d, WL))
    assert np.all(rgb[:, 2] > rgb[:, 0])       # blue over red
    assert np.all(rgb[:, 2] > 0.0)


def test_terminator_has_red_fringe():
    # Sun 3 deg above the horizon at the 10 km tangent point of the southern limb: the low
    # air along the limb (tangent 2-5 km) is lit by sunlight that has crossed a long path
    # and is seen through a long path: red (R > G > B); higher up the limb stays blue.
    a = math.asin((R + 10e3) / (R + GEO))
    elev = math.degrees(a) - 90.0 + 3.0
    m = _model(sun=sd.Sun(elevation_deg=elev, azimuth_deg=180.0),
               atmosphere=Atmosphere.earth(turbidity=2.5, planet_radius_m=R))
    d = np.stack([_south_ray(R + GEO, h) for h in (2e3, 5e3, 25e3)])
    rgb = _rgb(m.radiance(d, WL))
    assert np.all(rgb[:2, 0] > rgb[:2, 1]) and np.all(rgb[:2, 1] > rgb[:2, 2])
    assert np.all(rgb[:2, 0] > 0.0)
    assert rgb[2, 2] > rgb[2, 0]


def test_black_planet_without_atmosphere():
    atm = Atmosphere.custom(rayleigh_scattering=0.0, mie_scattering=0.0, planet_radius_m=R,
                            ground_albedo=0.0)
    m = _model(atmosphere=atm, surface="albedo", albedo=0.0)
    d = np.array([[0.0, 0.0, -1.0], _south_ray(R + GEO, 1e3), [0.1, 0.05, -1.0]])
    L = m.radiance(d / np.linalg.norm(d, axis=1, keepdims=True), WL)
    assert np.all(L == 0.0)
    # the same planet with albedo 1 is lit (the sun is up at the sub-camera point):
    # L = E_sun cos(theta_s) / pi exactly (no air, no sky light)
    m1 = _model(atmosphere=atm, surface="albedo", albedo=1.0)
    L1 = m1.radiance(np.array([0.0, 0.0, -1.0]), WL)
    from skydome.spectra import solar_irradiance

    assert L1 == pytest.approx(solar_irradiance(WL) * 0.5 / math.pi, rel=1e-9)


def test_space_is_black(earth):
    d = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -0.3, -0.954]])  # up, sideways, off the disc
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    a = math.asin((R + earth.atmosphere.top_altitude_m) / (R + GEO))
    assert math.acos(-d[2, 2]) > a                      # the third ray misses the atmosphere
    assert np.all(earth.radiance(d, WL) == 0.0)


def test_table_matches_direct_quadrature():
    # the spheres x cylinders table against integrating every light path directly: < 0.5 %
    # where the pixel is brighter than 5 % of the brightest (< 3 % at the dim terminator)
    kw = dict(atmosphere=Atmosphere.earth(turbidity=2.5, planet_radius_m=R), surface="albedo",
              albedo=0.3)
    fast = _model(**kw)
    exact = _model(light_exact=True, **kw)
    rng = np.random.default_rng(3)
    a = math.asin((R + 100e3) / (R + GEO))
    th = a * np.sqrt(rng.uniform(0.0, 1.0, 300))
    ph = rng.uniform(0.0, 2 * math.pi, 300)
    d = np.stack([np.sin(th) * np.sin(ph), np.sin(th) * np.cos(ph), -np.cos(th)], axis=-1)
    d = np.concatenate([d, np.stack([_south_ray(R + GEO, h) for h in (2e3, 10e3, 20e3)])])
    wl = np.array([450.0, 550.0, 650.0])
    Lf = fast.radiance(d, wl)
    Le = exact.radiance(d, wl)
    Yf = Lf.sum(axis=1)
    Ye = Le.sum(axis=1)
    lit = Ye > 1e-3 * Ye.max()
    rel = np.abs(Yf[lit] / Ye[lit] - 1.0)
    bright = Ye[lit] > 0.05 * Ye.max()
    assert rel[bright].max() < 5e-3, rel[bright].max()     # the lit disc and limb
    assert rel.max() < 0.03, rel.max()                     # the dim terminator (> 0.1 % of max)


def test_agrees_with_single_scattering_reference():
    # camera on the ground looking at the sky: the same physics as the independent
    # single_scattering integrator (different quadrature and column table): within 1.5 %
    atm = Atmosphere.earth(turbidity=2.5, planet_radius_m=R)
    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=135.0)
    ref = get_model_class("single_scattering")(sun=sun, atmosphere=atm, view_samples=64)
    m = _model(sun=sun, atmosphere=atm, camera_altitude_m=0.0, spheres=128, substeps=4)
    el = np.radians([5.0, 15.0, 45.0, 80.0, 30.0])
    az = np.radians([135.0, 200.0, 300.0, 10.0, 135.0])
    d = np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], axis=-1)
    wl = np.array([450.0, 550.0, 650.0])
    np.testing.assert_allclose(m.radiance(d, wl), ref.radiance(d, wl), rtol=0.015)


def test_no_nan_anywhere():
    rng = np.random.default_rng(7)
    d = rng.normal(size=(400, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    for alt, elev, surface in ((400e3, -20.0, "ocean"), (5e3, 2.0, "albedo"), (GEO, 89.0, "ocean")):
        m = _model(sun=sd.Sun(elevation_deg=elev, azimuth_deg=40.0), camera_altitude_m=alt,
                   surface=surface, spheres=32)
        L = m.radiance(d, WL)
        assert np.all(np.isfinite(L)) and np.all(L >= 0.0)
        s = m.sun_radiance(WL)
        assert np.all(np.isfinite(s)) and np.all(s >= 0.0)


def test_texture_and_parameters(tmp_path):
    tex = np.zeros((8, 16, 3))
    tex[:, :8] = 1.0                       # western hemisphere white, eastern black
    atm = Atmosphere.custom(rayleigh_scattering=0.0, planet_radius_m=R)
    m = _model(atmosphere=atm, surface="texture", texture=tex, camera_longitude_deg=-45.0)
    L = m.radiance(np.array([0.0, 0.0, -1.0]), WL)       # looking down at (0 N, 45 W)
    assert np.all(L > 0.0)
    m = _model(atmosphere=atm, surface="texture", texture=tex, camera_longitude_deg=45.0)
    assert np.all(m.radiance(np.array([0.0, 0.0, -1.0]), WL) == 0.0)
    assert _model(camera_altitude="400km").camera_altitude_m == 400e3
    assert _model(camera_altitude="36000 km").camera_altitude_m == 36e6
    with pytest.raises(ValueError, match="camera_altitude"):
        _model(camera_altitude="far away")
    with pytest.raises(ValueError, match="camera_altitude_m"):
        _model(camera_altitude_m=-1.0)
    with pytest.raises(ValueError, match="texture"):
        _model(surface="texture")


def test_camera_projection():
    cam = Camera(40, 30, 60.0, position=(0, 0, 1e7), look_at=(0, 0, -R))
    d, mask = cam.directions()
    assert mask.all() and d.shape == (30, 40, 3)
    row, col = cam.pixel_from_direction(d)
    r0, c0 = np.meshgrid(np.arange(30) + 0.5, np.arange(40) + 0.5, indexing="ij")
    np.testing.assert_allclose(row, r0, atol=1e-9)
    np.testing.assert_allclose(col, c0, atol=1e-9)
    # exact solid angle of a rectangular pyramid: 4 asin(sin(a/2) sin(b/2))
    a = math.radians(60.0)
    b = 2 * math.atan(math.tan(a / 2) * 30 / 40)
    assert cam.solid_angles().sum() == pytest.approx(4 * math.asin(math.sin(a / 2) * math.sin(b / 2)),
                                                     rel=1e-4)
    # looking down with north up: east is on the right, north at the top
    assert d[15, 39, 0] > 0 and d[0, 20, 1] > 0
    assert np.all(np.isnan(cam.pixel_from_direction([0.0, 0.0, 1.0])))   # behind the camera
    with pytest.raises(ValueError, match="fov_deg"):
        Camera(8, 8, 180.0)


def test_render_full_disc_and_cli(tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app

    out = tmp_path / "earth.png"
    res = CliRunner().invoke(app, ["render", "--model", "nishita1993", "--camera-altitude",
                                   "36000km", "--sun-elevation", "30", "--projection", "camera",
                                   "--size", "24", "--wavelengths", "6", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert out.exists()
    m = _model()
    img = sd.render(m, m.default_projection(24), wavelength_grid(380, 780, n=6))
    Y = img.luminance()
    assert Y[0, 0] == 0.0 and Y[-1, -1] == 0.0          # corners: space
    assert Y[12, 12] > 0.0                              # the disc centre is lit
    res = CliRunner().invoke(app, ["render", "--projection", "camera", "--size", "8",
                                   "--out", str(tmp_path / "x.png")])
    assert res.exit_code == 2 and "camera" in res.output
