"""klassen1987: two homogeneous layers over a flat earth (Klassen 1987; survey section 7.1)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import skydome as sd
from skydome.models.simulated import klassen1987 as kl
from skydome.spectra import spectrum_to_xyz, xyz_to_xy

WL = np.array([400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0])


def _sky(elev=30.0, az=180.0, **kw):
    return sd.model("klassen1987", sun=sd.Sun(elevation_deg=elev, azimuth_deg=az), **kw)


def _beta_rayleigh(wl_nm, n=1.000278, ns=2.545e25):
    """Survey eq. 8 written out independently: 8 pi^3 (n^2 - 1)^2 / (3 N_s lambda^4)."""
    lam = wl_nm * 1e-9
    return 8.0 * math.pi ** 3 * (n * n - 1.0) ** 2 / (3.0 * ns * lam ** 4)


def test_registered_with_parameters():
    cls = sd.models.available()["klassen1987"]
    names = {p.name for p in cls.parameters}
    assert {"haze_layer_height_m", "air_layer_height_m", "turbidity", "refractive_index"} <= names


def test_horizontal_fog_is_beer_lambert_exactly():
    """Inside the haze layer a horizontal path of length d has the transmittance
    exp(-(beta_R + beta_haze) d) (Beer-Lambert in a constant-density medium), with beta_R
    from survey eq. 8 and beta_haze = k550 (lambda/550)^-alpha as given."""
    sky = _sky(haze_extinction_m=2e-4, angstrom_alpha=1.3)
    for d in (10.0, 1000.0, 25_000.0):
        t, _ = sky.aerial_perspective([0.0, 1.0, 0.0], d, WL)
        k = _beta_rayleigh(WL) + 2e-4 * (WL / 550.0) ** -1.3
        np.testing.assert_allclose(t, np.exp(-k * d), rtol=1e-12)


def test_slant_path_through_both_layers_is_beer_lambert():
    """A path at zenith cosine u to the top crosses h_haze of haze-filled air and
    h_air - h_haze of clear air: T = exp(-(k1 h1 + k2 (h2 - h1)) / u)."""
    h1, h2 = 1500.0, 8000.0
    sky = _sky(haze_extinction_m=1e-4, haze_layer_height_m=h1, air_layer_height_m=h2)
    u = 0.6
    d = np.array([0.0, math.sqrt(1 - u * u), u])
    br = _beta_rayleigh(WL)
    bh = 1e-4 * (WL / 550.0) ** -1.3
    expected = np.exp(-((br + bh) * h1 + br * (h2 - h1)) / u)
    np.testing.assert_allclose(sky.transmittance(d, WL), expected, rtol=1e-12)
    # an object inside the haze layer, 2 km along the same ray
    t, _ = sky.aerial_perspective(d, 2000.0, WL)
    np.testing.assert_allclose(t, np.exp(-(br + bh) * 2000.0), rtol=1e-12)


def test_sun_radiance_is_attenuated_by_the_vertical_depth():
    """Sun disc: E_sun/Omega x exp(-m tau) with the flat air mass 1/sin(h_apparent)."""
    from skydome.spectra import solar_irradiance

    sky = _sky(elev=40.0, airmass="flat", haze_extinction_m=5e-5)
    tau = _beta_rayleigh(WL) * 7994.0 + 5e-5 * (WL / 550.0) ** -1.3 * 1200.0
    h_app = 40.0 + kl.refraction_saemundsson_deg(40.0)
    expected = (solar_irradiance(WL) / sky.sun.solid_angle_sr * sky.sun.irradiance_scale
                * np.exp(-tau / math.sin(math.radians(h_app))))
    np.testing.assert_allclose(sky.sun_radiance(WL), expected, rtol=1e-12)


def test_closed_form_matches_quadrature_of_the_single_scattering_integral():
    """The layer-wise closed form equals a fine numerical quadrature of
    E sum_i beta_i P_i integral exp(-tau_view(t) - m tau_up(z(t))) dt along the view ray."""
    from skydome.spectra import solar_irradiance

    h1, h2, kh, g = 1000.0, 8000.0, 3e-4, 0.7
    sky = _sky(elev=20.0, az=90.0, haze_extinction_m=kh, haze_layer_height_m=h1,
               air_layer_height_m=h2, haze_g=g, haze_albedo=0.8, airmass="flat")
    u = 0.3
    v = np.array([math.sqrt(1 - u * u), 0.0, u])
    L = sky.radiance(v, WL)
    br = _beta_rayleigh(WL)
    bh = kh * (WL / 550.0) ** -1.3
    mu_s = math.sin(math.radians(sky.apparent_elevation_deg))
    sdir = sky.apparent_sun_direction
    c = float(v @ sdir)
    p_r = 3.0 / (16 * math.pi) * (1 + c * c)
    p_h = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * c) ** 1.5)
    t = np.linspace(0.0, h2 / u, 400_001)
    z = u * t
    inside = z < h1
    k = np.where(inside[:, None], br + bh, br)
    # cumulative optical depth along the ray (trapezoid; k piecewise constant, so exact
    # away from the boundary node)
    dt = t[1] - t[0]
    tau_v = np.concatenate([np.zeros((1, WL.size)), np.cumsum(0.5 * (k[1:] + k[:-1]) * dt, axis=0)])
    tau_up = br * (h2 - z)[:, None] + bh * np.clip(h1 - z, 0, None)[:, None]
    f = np.exp(-tau_v - tau_up / mu_s)
    sc = br * p_r + np.where(inside[:, None], 0.8 * bh * p_h, 0.0)
    integrand = sc * f
    ref = solar_irradiance(WL) * np.trapezoid(integrand, t, axis=0)
    np.testing.assert_allclose(L, ref, rtol=2e-4)


def test_fog_adds_up_to_the_sky_and_object_radiance():
    """L = L0 T + L_in; for a very long path L_in tends to the sky radiance."""
    sky = _sky(elev=35.0)
    d = np.array([0.3, 0.5, 0.81])
    t, lin = sky.aerial_perspective(d, 1e9, WL)
    np.testing.assert_allclose(lin, sky.radiance(d, WL), rtol=1e-12)
    L0 = np.full(WL.size, 0.05)
    t2, tot = sky.aerial_perspective([1.0, 0.0, 0.0], 3000.0, WL, object_radiance=L0)
    _, lin2 = sky.aerial_perspective([1.0, 0.0, 0.0], 3000.0, WL)
    np.testing.assert_allclose(tot, L0 * t2 + lin2)
    # fog grows with distance: more in-scattering, less transmittance
    ts, ls = sky.aerial_perspective([[1.0, 0.0, 0.0]],
                     np.array([100.0, 1000.0, 10_000.0])[:, None] * np.ones((1, 1)), WL)
    assert np.all(np.diff(ts[:, 0], axis=0) < 0) and np.all(np.diff(ls[:, 0], axis=0) > 0)


def test_noon_sky_is_blue_and_low_sun_is_redder():
    """Colour by Rayleigh's lambda^-4: the zenith sky under a high sun is blue (x, y below
    the equal-energy white point 1/3), the low sun and the sky near it are redder than at
    noon."""
    wl = np.linspace(380.0, 780.0, 41)
    noon = _sky(elev=70.0)
    low = _sky(elev=3.0)
    xy_zen = xyz_to_xy(spectrum_to_xyz(noon.radiance([0, 0, 1], wl), wl))
    assert xy_zen[0] < 0.3 and xy_zen[1] < 0.32
    xy_sun_noon = xyz_to_xy(spectrum_to_xyz(noon.sun_radiance(wl), wl))
    xy_sun_low = xyz_to_xy(spectrum_to_xyz(low.sun_radiance(wl), wl))
    assert xy_sun_low[0] > xy_sun_noon[0] + 0.05
    near_sun = [0.0, -0.99, 0.1411]     # south, 8 deg up, towards the sun at azimuth 180
    xy_near_low = xyz_to_xy(spectrum_to_xyz(low.radiance(near_sun, wl), wl))
    xy_near_noon = xyz_to_xy(spectrum_to_xyz(noon.radiance(near_sun, wl), wl))
    assert xy_near_low[0] > xy_near_noon[0] + 0.03


def test_refraction_formulae_meeus():
    """Meeus 1998 ch. 16: Saemundsson's R(true h) agrees with Bennett's R(apparent h0)
    within 0.1'; the horizontal refraction is 34.5' (apparent 0 deg)."""
    h_true = np.array([-0.5, 0.0, 1.0, 2.0, 5.0, 10.0, 30.0, 60.0, 85.0])
    r_s = kl.refraction_saemundsson_deg(h_true)
    r_b = kl.refraction_bennett_deg(h_true + r_s)
    assert np.max(np.abs(r_s - r_b)) * 60.0 < 0.1
    assert kl.refraction_bennett_deg(0.0) * 60.0 == pytest.approx(34.5, abs=0.1)
    # the model lifts the sun by the refraction
    sky = _sky(elev=0.0)
    assert sky.apparent_elevation_deg == pytest.approx(0.0 + r_s[1], abs=1e-12)
    assert 0.45 < sky.apparent_elevation_deg < 0.52


def test_kasten_young_air_mass():
    """Kasten & Young 1989: their tabulated air mass is 38.0868 at the horizon and 1 at
    the zenith; the paper states the formula's relative error below
    0.5 % everywhere (largest at the horizon)."""
    assert kl.kasten_young_airmass(90.0) == pytest.approx(1.0, abs=5e-4)
    assert kl.kasten_young_airmass(0.0) == pytest.approx(38.0868, rel=5e-3)
    # plane-parallel limit far from the horizon: 1/sin(h) within 0.3 % above 30 deg
    h = np.array([30.0, 45.0, 60.0])
    np.testing.assert_allclose(kl.kasten_young_airmass(h), 1 / np.sin(np.radians(h)), rtol=3e-3)


def test_validation():
    with pytest.raises(ValueError, match=r"sun.elevation_deg = -5 deg is out of range \[0, 90\]"):
        _sky(elev=-5.0)
    with pytest.raises(ValueError, match="haze_layer_height_m"):
        _sky(haze_layer_height_m=9000.0, air_layer_height_m=8000.0)
    with pytest.raises(ValueError, match=r"haze_layer_height_m = 0.5 m is out of range"):
        _sky(haze_layer_height_m=0.5)
    with pytest.raises(ValueError, match="turbidity"):
        _sky(turbidity=50.0)
    with pytest.raises(ValueError, match="distance_m"):
        _sky().aerial_perspective([1, 0, 0], -1.0, WL)
    with pytest.raises(TypeError):
        _sky(foo=1)


@settings(max_examples=30, deadline=None)
@given(elev=st.floats(0.0, 90.0), az=st.floats(0.0, 360.0), turb=st.floats(1.0, 32.0),
       h1=st.one_of(st.just(0.0), st.floats(1.0, 5000.0)), x=st.floats(-1, 1), y=st.floats(-1, 1), z=st.floats(-1, 1),
       airmass=st.sampled_from(["flat", "kasten_young"]))
def test_no_nan_or_negative(elev, az, turb, h1, x, y, z, airmass):
    if x * x + y * y + z * z < 1e-6:
        z = 1.0
    sky = _sky(elev, az, turbidity=turb, haze_layer_height_m=h1, airmass=airmass)
    L = sky.radiance([[x, y, z], [0, 0, 1], [1, 0, 0], [0, 0, -1]], WL)
    assert np.all(np.isfinite(L)) and np.all(L >= 0)
    s = sky.sun_radiance(WL)
    assert np.all(np.isfinite(s)) and np.all(s >= 0)
    t, lin = sky.aerial_perspective([x, y, z] if z != 0 or x or y else [1, 0, 0], np.array([0.0, 10.0, 1e5]), WL)
    assert np.all(np.isfinite(t)) and np.all((t >= 0) & (t <= 1))
    assert np.all(np.isfinite(lin)) and np.all(lin >= 0)
