"""The earth from space of ``nishita1993``: the sun's glint on a rough sea, the land map, the
limb and the night side.

References used: the Fresnel equations (Born & Wolf, Principles of Optics, sec. 1.5.3,
written out here independently of the kernel), the Cox & Munk (1954) slope statistics and
their mean square slope sigma^2 = 0.003 + 5.12e-3 W, the energy of the reflected sunlight
computed by an independent quadrature over the wave slopes, the earth's land fraction
(29.2 % of the surface: 148.9e6 of 510.1e6 km^2, e.g. the CIA World Factbook), and the
geometry of the specular point on a sphere.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere
from skydome.models import get_model_class
from skydome.spectra import wavelength_grid

N = 1.34
R = 6_371_000.0
GEO = 36e6
WL = wavelength_grid(380.0, 780.0, n=8)


def _fresnel_ref(cos_i, n=N):
    """Unpolarised Fresnel reflectance (Born & Wolf 1.5.3), vectorised, air -> water."""
    ci = np.clip(np.asarray(cos_i, dtype=float), 0.0, 1.0)
    si = np.sqrt(1.0 - ci * ci)
    st = si / n
    ct = np.sqrt(1.0 - st * st)
    rs = (ci - n * ct) / (ci + n * ct)
    rp = (ci * n - ct) / (ci * n + ct)
    return 0.5 * (rs * rs + rp * rp)


def _glint(sun, views, sigma2):
    from skydome.models.simulated._kernels_nishita1993 import cox_munk_glint_many

    out = np.empty(views.shape[0])
    cox_munk_glint_many(np.ascontiguousarray(sun, dtype=float), np.ascontiguousarray(views),
                        np.array([0.0, 0.0, 1.0]), float(sigma2), N, out)
    return out


def _sun_dir(theta_s):
    t = math.radians(theta_s)
    return np.array([math.sin(t), 0.0, math.cos(t)])


def _reflected_fraction_view_space(theta_s, sigma2, alpha_max, n_a=300, n_p=360):
    """int L mu_v dOmega_v / (E_n mu_s) over the upper hemisphere, by Gauss-Legendre nodes in
    polar coordinates (alpha, phi) about the specular direction."""
    s = _sun_dir(theta_s)
    spec = np.array([-s[0], -s[1], s[2]])
    e1 = np.array([spec[2], 0.0, -spec[0]])
    e2 = np.cross(spec, e1)
    x, w = np.polynomial.legendre.leggauss(n_a)
    a = 0.5 * alpha_max * (x + 1.0)
    wa = 0.5 * alpha_max * w * np.sin(a)
    phi = (np.arange(n_p) + 0.5) * 2.0 * math.pi / n_p
    A, P = np.meshgrid(a, phi, indexing="ij")
    v = (np.cos(A)[..., None] * spec + np.sin(A)[..., None]
         * (np.cos(P)[..., None] * e1 + np.sin(P)[..., None] * e2)).reshape(-1, 3)
    g = _glint(s, v, sigma2)
    mu_v = np.maximum(v[:, 2], 0.0)
    wt = (wa[:, None] * np.full(n_p, 2.0 * math.pi / n_p)).reshape(-1)
    return float(np.sum(g * mu_v * wt)) / s[2]


def _reflected_fraction_slope_space(theta_s, sigma2, n=1001):
    """The same fraction over the facet slopes (zx, zy) of the Cox-Munk Gaussian: the flux
    each facet intercepts, E_n (n_f . s) / cos(beta) per unit horizontal area, times its
    Fresnel reflectance, for the facets that face the sun and send the light upwards."""
    s = _sun_dir(theta_s)
    lim = 9.0 * math.sqrt(sigma2 / 2.0)
    z = np.linspace(-lim, lim, n)
    dz = z[1] - z[0]
    ZX, ZY = np.meshgrid(z, z, indexing="ij")
    p = np.exp(-(ZX ** 2 + ZY ** 2) / sigma2) / (math.pi * sigma2)
    norm = np.sqrt(1.0 + ZX ** 2 + ZY ** 2)
    nx, ny, nz = -ZX / norm, -ZY / norm, 1.0 / norm
    cos_i = nx * s[0] + ny * s[1] + nz * s[2]
    vz = 2.0 * cos_i * nz - s[2]
    ok = (cos_i > 0.0) & (vz > 0.0)
    f = np.where(ok, _fresnel_ref(cos_i) * cos_i / nz * p, 0.0)
    return float(f.sum() * dz * dz) / s[2]


def test_cox_munk_mean_square_slope():
    from skydome.models.simulated.nishita1993 import cox_munk_mean_square_slope

    # [CM54]: sigma_c^2 + sigma_u^2 = 0.003 + 5.12e-3 W, hand-evaluated
    assert cox_munk_mean_square_slope(0.0) == pytest.approx(0.003, rel=1e-12)
    assert cox_munk_mean_square_slope(10.0) == pytest.approx(0.0542, rel=1e-12)


@pytest.mark.parametrize("theta_s", [0.0, 30.0, 60.0, 75.0])
def test_glint_of_a_flat_sea_reflects_the_fresnel_fraction(theta_s):
    """Nearly flat sea (sigma^2 = 1e-4): the reflected irradiance over the incident one is
    the Fresnel reflectance at the sun's incidence angle."""
    frac = _reflected_fraction_view_space(theta_s, 1e-4, alpha_max=0.15)
    assert frac == pytest.approx(float(_fresnel_ref(math.cos(math.radians(theta_s)))), rel=2e-3)
    if theta_s == 0.0:
        assert frac == pytest.approx((0.34 / 2.34) ** 2, rel=2e-3)


@pytest.mark.parametrize("theta_s", [20.0, 50.0])
@pytest.mark.parametrize("wind", [2.0, 10.0])
def test_glint_energy_matches_slope_space_quadrature(theta_s, wind):
    """Rough sea: the kernel's glint radiance integrated over the viewer's hemisphere equals
    the reflected flux summed facet by facet over the Cox-Munk slope distribution."""
    sigma2 = 0.003 + 5.12e-3 * wind
    view = _reflected_fraction_view_space(theta_s, sigma2, alpha_max=math.pi, n_a=500, n_p=400)
    slope = _reflected_fraction_slope_space(theta_s, sigma2)
    assert view == pytest.approx(slope, rel=1e-3)
    # and stays near the flat-sea Fresnel reflectance (0.4-11 % above it at these slopes)
    assert view == pytest.approx(float(_fresnel_ref(math.cos(math.radians(theta_s)))), rel=0.15)


def test_earth_map_land_fraction_and_places():
    from skydome.models.simulated.nishita1993 import _load_earth_map

    m = _load_earth_map()
    assert m.shape == (256, 512, 4)
    lat = 90.0 - (np.arange(256) + 0.5) * 180.0 / 256
    w = np.cos(np.radians(lat))[:, None] * np.ones((1, 512))
    assert float((m[..., 3] * w).sum() / w.sum()) == pytest.approx(0.292, abs=0.01)

    def at(la, lo):
        return m[int((90.0 - la) / 180.0 * 256), int((lo + 180.0) / 360.0 * 512)]

    assert at(23.0, 10.0)[3] == 1.0                      # Sahara (Algeria / Niger)
    assert at(23.0, 10.0)[0] > at(23.0, 10.0)[1] > at(23.0, 10.0)[2]   # desert: red > green > blue
    assert at(0.0, -150.0)[3] == 0.0                     # central Pacific
    assert at(35.0, -40.0)[3] == 0.0                     # North Atlantic
    assert at(-85.0, 0.0)[3] == 1.0 and at(-85.0, 0.0)[:3].min() > 0.6   # Antarctic ice
    assert at(-5.0, -60.0)[3] == 1.0 and at(-5.0, -60.0)[1] > at(-5.0, -60.0)[2]   # Amazon


def _down(lat, lon, **kw):
    sky = get_model_class("nishita1993")(sun=sd.Sun(elevation_deg=60.0, azimuth_deg=180.0),
                                         camera_altitude_m=GEO, camera_latitude_deg=lat,
                                         camera_longitude_deg=lon, spheres=32, **kw)
    return sky.radiance(np.array([0.0, 0.0, -1.0]), WL)


def test_earth_surface_land_and_sea():
    i650 = int(np.argmin(abs(WL - 650.0)))
    land = _down(23.0, 10.0, surface="earth")
    sea = _down(0.0, -150.0, surface="earth")
    assert land[i650] > 3.0 * sea[i650]
    # where the map has no land, 'earth' is the 'ocean' surface
    np.testing.assert_allclose(sea, _down(0.0, -150.0, surface="ocean"), rtol=1e-12)
    with pytest.raises(ValueError, match="texture"):
        get_model_class("nishita1993")(sun=sd.Sun(elevation_deg=60.0, azimuth_deg=180.0),
                                       surface="earth", texture=np.zeros((2, 2)))
    with pytest.raises(ValueError, match="wind_speed_m_s"):
        get_model_class("nishita1993")(sun=sd.Sun(elevation_deg=60.0, azimuth_deg=180.0),
                                       wind_speed_m_s=-1.0)


def _specular_point(r0, sun):
    """Unit normal of the point of a sphere of radius R that mirrors the sun towards the
    camera at (0, 0, r0): bisection on the angle gamma from the sub-camera point towards the
    sun's azimuth."""
    sh = np.array([sun[0], sun[1], 0.0]) / math.hypot(sun[0], sun[1])
    cam = np.array([0.0, 0.0, r0])

    def f(g):
        n = math.sin(g) * sh + math.cos(g) * np.array([0.0, 0.0, 1.0])
        v = cam - R * n
        v /= np.linalg.norm(v)
        return math.acos(v @ n) - math.acos(sun @ n)

    lo, hi = 0.0, math.acos(sun[2])
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if f(lo) * f(mid) <= 0.0:
            hi = mid
        else:
            lo = mid
    g = 0.5 * (lo + hi)
    return math.sin(g) * sh + math.cos(g) * np.array([0.0, 0.0, 1.0])


def test_glint_sits_at_the_specular_point():
    sun = sd.Sun(elevation_deg=50.0, azimuth_deg=240.0)
    atm = Atmosphere.custom(rayleigh_scattering=0.0, planet_radius_m=R)
    sky = get_model_class("nishita1993")(sun=sun, atmosphere=atm, camera_altitude_m=GEO,
                                         surface="ocean", wind_speed_m_s=1.0, spheres=16)
    n_exp = _specular_point(R + GEO, sun.direction)
    # directions from the camera towards points of the disc around the expected point
    cam = np.array([0.0, 0.0, R + GEO])
    g = np.radians(np.linspace(-12.0, 12.0, 49))
    e1 = np.cross(n_exp, [0.0, 0.0, 1.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n_exp, e1)
    pts = []
    for a in g:
        for b in g:
            n = n_exp * math.cos(math.hypot(a, b)) + math.sin(math.hypot(a, b)) * (
                (a * e1 + b * e2) / max(math.hypot(a, b), 1e-12))
            pts.append(R * n)
    pts = np.array(pts)
    d = pts - cam
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    L = sky.radiance(d, [550.0])[:, 0]
    n_max = pts[int(np.argmax(L))] / R
    assert math.degrees(math.acos(min(1.0, float(n_max @ n_exp)))) < 1.0
    assert L.max() > 20.0 * np.median(L)


def _limb_dirs(sky, az_deg, tangent_alt_m):
    a = np.arcsin((sky._R + np.asarray(tangent_alt_m)) / sky._r0)
    A = math.radians(az_deg)
    return np.stack([np.sin(a) * math.sin(A), np.sin(a) * math.cos(A), -np.cos(a)], -1)


def test_limb_is_bright_blue_and_converged():
    sun = sd.Sun(elevation_deg=50.0, azimuth_deg=240.0)
    sky = get_model_class("nishita1993")(sun=sun, camera_altitude_m=GEO, surface="earth")
    fine = get_model_class("nishita1993")(sun=sun, camera_altitude_m=GEO, surface="albedo",
                                          spheres=256, substeps=8)
    h = np.array([2e3, 5e3, 10e3, 20e3, 30e3, 40e3])
    wl = [450.0, 650.0]
    d = _limb_dirs(sky, 240.0, h)
    L = sky.radiance(d, wl)
    # rays grazing the planet cross the whole shell: converged to the fine reference
    np.testing.assert_allclose(L, fine.radiance(d, wl), rtol=0.01)
    # the rim (tangent 5-10 km) outshines the disc just inside it, in blue more than red
    inner = sky.radiance(_limb_dirs(sky, 240.0, [-100e3]), wl)[0]
    assert L[2, 0] > 1.05 * inner[0]
    assert L[2, 0] > 1.5 * L[2, 1]
    # far above the atmosphere's top: black space
    top = sky._Rt - sky._R
    assert np.all(sky.radiance(_limb_dirs(sky, 240.0, [top + 1e3]), wl) == 0.0)


def test_night_side_is_black_and_finite():
    sun = sd.Sun(elevation_deg=50.0, azimuth_deg=240.0)
    sky = get_model_class("nishita1993")(sun=sun, camera_altitude_m=GEO, surface="earth",
                                         spheres=32)
    d, mask = sky.default_projection(48).directions()
    L = sky.radiance(d[mask], WL)
    assert np.all(np.isfinite(L)) and np.all(L >= 0.0)
    day = sky.radiance(_limb_dirs(sky, 240.0, [10e3]), WL)[0]
    # the disc's anti-sun limb (az 60 deg, 114-121 deg from the subsolar point, the sun
    # 24-31 deg below the horizon there, so even the air at 100 km is in the shadow): 0
    night = sky.radiance(_limb_dirs(sky, 60.0, [-50e3, 0.0, 20e3]), WL)
    assert np.all(night == 0.0)
    # 104 deg from the subsolar point only the air near 100 km still sees the sun: dark
    dusk = sky.radiance(_limb_dirs(sky, 60.0, [-300e3]), WL)[0]
    assert np.all(dusk < 1e-6 * day.max())


def test_terminator_fades_to_night():
    """Across the terminator (points of the disc 70-100 deg from the subsolar point) the
    disc darkens monotonically, to under 1e-4 of the day side 10 deg past the terminator
    (only the high air still sees the sun there)."""
    from skydome.spectra import spectrum_to_xyz

    sky = get_model_class("nishita1993")(sun=sd.Sun(elevation_deg=50.0, azimuth_deg=240.0),
                                         camera_altitude_m=GEO, surface="ocean", spheres=32)
    a = math.radians(60.0)
    dirs = []
    for g in np.radians(np.arange(30.0, 61.0, 3.0)):       # 70 .. 100 deg from the subsolar point
        p = R * np.array([math.sin(g) * math.sin(a), math.sin(g) * math.cos(a), math.cos(g)])
        d = p - np.array([0.0, 0.0, R + GEO])
        dirs.append(d / np.linalg.norm(d))
    Y = spectrum_to_xyz(sky.radiance(np.array(dirs), WL), WL)[:, 1]
    assert np.all(np.diff(Y) < 0.0)
    assert Y[-1] < 1e-4 * Y[0]
