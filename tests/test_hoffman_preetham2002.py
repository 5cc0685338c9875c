"""Tests of the Hoffman & Preetham (2002) scattering model ([HP02]).

References: the formulas of [HP02] (limits checked analytically), the normalisation of the
Rayleigh and Henyey-Greenstein (1941) phase functions, published sea-level Rayleigh
coefficients (Riley et al. 2004; Bruneton & Neyret 2008), and physical consistency.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import skydome as sd
from skydome.models import available, model
from skydome.models.analytic import hoffman_preetham2002 as H
from skydome.models.analytic import preetham1999 as P
from skydome.spectra import spectrum_to_xyz, xyz_to_xy
from skydome.transport.geometry import direction_from_angles

WL = np.arange(380.0, 781.0, 10.0)


def _sun(el, az=180.0):
    return sd.Sun(elevation_deg=el, azimuth_deg=az)


def _sphere_integral(f, n=20001):
    mu = np.linspace(-1.0, 1.0, n)
    return 2.0 * np.pi * np.trapezoid(f(mu), mu)


def test_rayleigh_phase_normalised():
    assert _sphere_integral(H.rayleigh_phase) == pytest.approx(1.0, rel=1e-6)


@pytest.mark.parametrize("g", [0.0, 0.5, 0.76])
def test_mie_phase_normalisation(g):
    # [HG41]: the (1 - g^2) form integrates to 1; the [HP02] (1 - g)^2 form to (1-g)/(1+g)
    hg = _sphere_integral(lambda m: H.mie_phase(m, g, "henyey_greenstein"), n=200001)
    hp = _sphere_integral(lambda m: H.mie_phase(m, g, "hoffman_preetham"), n=200001)
    assert hg == pytest.approx(1.0, rel=1e-3)
    assert hp == pytest.approx((1.0 - g) / (1.0 + g), rel=1e-3)


def test_rayleigh_coefficient_published():
    # (5.8, 13.5, 33.1) 1e-6 m^-1 at (680, 550, 440) nm (Riley et al. 2004)
    assert P.rayleigh_coefficient([680.0, 550.0, 440.0]) == pytest.approx(
        [5.8e-6, 13.5e-6, 33.1e-6], rel=0.03)


def test_extinction_formula():
    # [HP02] F_ex = exp(-(beta_R + beta_M) s)
    s = 3000.0
    f, _ = H.aerial_perspective([0.0, 1.0, 0.0], s, WL, sun=_sun(30.0), turbidity=3.0)
    b = P.rayleigh_coefficient(WL) + P.mie_coefficient(WL, 3.0)
    assert f == pytest.approx(np.exp(-b * s), rel=1e-12)


def test_limits_in_distance():
    sun = _sun(35.0, 90.0)
    d = [0.0, 1.0, 0.0]
    f0, l0 = H.aerial_perspective(d, 0.0, WL, sun=sun, turbidity=3.0)
    assert np.all(f0 == 1.0) and np.all(l0 == 0.0)
    f1, l1 = H.aerial_perspective(d, 1e-3, WL, sun=sun, turbidity=3.0)
    assert np.all(1.0 - f1 < 1e-6)
    # saturation: L_in -> beta(theta) / beta E_sun for s -> infinity
    finf, linf = H.aerial_perspective(d, 1e7, WL, sun=sun, turbidity=3.0)
    cos_t = float(np.dot(d, sun.direction))
    br, bm = P.rayleigh_coefficient(WL), P.mie_coefficient(WL, 3.0)
    ang = br * H.rayleigh_phase(cos_t) + bm * H.mie_phase(cos_t, 0.76)
    e_sun = P.sun_radiance(WL, sun, 3.0) * sun.solid_angle_sr
    assert linf == pytest.approx(ang / (br + bm) * e_sun, rel=1e-9)
    assert np.all(finf < 1e-12)


def test_in_scattered_bluer_at_low_turbidity():
    xs = []
    for T in (2.0, 9.0):
        _, L = H.aerial_perspective([0.0, 1.0, 0.05], 15000.0, WL, sun=_sun(45.0), turbidity=T)
        xs.append(xyz_to_xy(spectrum_to_xyz(L, WL))[0])
    assert xs[0] < xs[1]


def test_forward_scattering_peak():
    sun = _sun(20.0, 90.0)
    _, toward = H.aerial_perspective(direction_from_angles(20.0, 95.0), 5000.0, WL,
                                     sun=sun, turbidity=4.0)
    _, away = H.aerial_perspective(direction_from_angles(20.0, 275.0), 5000.0, WL,
                                   sun=sun, turbidity=4.0)
    assert np.all(toward > away)


def test_sky_model_registered_and_bluish():
    assert "hoffman_preetham2002" in available()
    sky = model("hoffman_preetham2002", sun=_sun(45.0), turbidity=2.0)
    X = spectrum_to_xyz(sky.radiance([0.0, 0.0, 1.0], WL), WL)
    x, y = xyz_to_xy(X)
    assert x < 0.3 and y < 0.3
    # brighter towards the horizon (longer path) at 90 deg from the sun
    zen = sky.luminance([0.0, 0.0, 1.0])
    hor = sky.luminance(direction_from_angles(3.0, 90.0))
    assert hor > zen


def test_shell_path_length():
    # zenith: H; horizon: sqrt(2 R H + H^2) (geometry of a chord tangent at the ground)
    H_m = 8000.0
    assert float(H.shell_path_length(1.0, H_m)) == pytest.approx(H_m, rel=1e-9)
    R = H.EARTH_RADIUS_M
    assert float(H.shell_path_length(0.0, H_m)) == pytest.approx(math.sqrt(2 * R * H_m + H_m ** 2),
                                                                  rel=1e-12)


def test_errors():
    with pytest.raises(ValueError, match="turbidity"):
        model("hoffman_preetham2002", sun=_sun(30.0), turbidity=1.0)
    with pytest.raises(ValueError, match="elevation_deg"):
        model("hoffman_preetham2002", sun=_sun(-2.0))
    with pytest.raises(ValueError, match="g = 1"):
        H.aerial_perspective([0, 1, 0], 10.0, WL, sun=_sun(30.0), g=1.0)
    with pytest.raises(ValueError, match="sky_distance_m"):
        model("hoffman_preetham2002", sun=_sun(30.0), sky_distance_m=10.0)
    with pytest.raises(ValueError, match="phase"):
        model("hoffman_preetham2002", sun=_sun(30.0), phase="rayleigh")


def test_below_horizon_zero():
    sky = model("hoffman_preetham2002", sun=_sun(30.0), turbidity=3.0)
    assert np.all(sky.radiance([[0.0, 1.0, -0.1], [0.0, 0.0, -1.0]], WL) == 0.0)


@settings(max_examples=30, deadline=None)
@given(T=st.floats(2.0, 10.0), el=st.floats(0.0, 90.0), az=st.floats(0.0, 360.0),
       vel=st.floats(-90.0, 90.0), vaz=st.floats(0.0, 360.0), g=st.floats(0.0, 0.99),
       s=st.floats(0.0, 1e6))
def test_no_nan_or_negative(T, el, az, vel, vaz, g, s):
    sun = _sun(el, az)
    sky = model("hoffman_preetham2002", sun=sun, turbidity=T, g=g)
    d = direction_from_angles([vel, 0.0, el], [vaz, vaz, az])
    L = sky.radiance(d, WL)
    assert np.all(np.isfinite(L)) and np.all(L >= 0.0)
    f, li = sky.aerial_perspective(d, s, WL)
    assert np.all(np.isfinite(f)) and np.all((f >= 0.0) & (f <= 1.0))
    assert np.all(np.isfinite(li)) and np.all(li >= 0.0)


@pytest.mark.parametrize("el, T, g, phase, H_m", [
    (30.0, 2.5, 0.76, "hoffman_preetham", 1.0 / P.ALPHA_MOLECULES),
    (2.0, 10.0, 0.9, "henyey_greenstein", 8000.0),
    (89.0, 2.0, 0.0, "hoffman_preetham", 100.0),
    (15.0, 6.0, 0.5, "henyey_greenstein", 100000.0)])
def test_sky_kernel_is_the_equations(el, T, g, phase, H_m):
    """The sky's parallel kernel against [HP02]'s equations written out here in NumPy (the
    shell path, F_ex, beta_R(theta), beta_M(theta), L_in; Preetham's coefficients, tested
    above against published values) and against the module's NumPy functions, on random
    directions of the whole sphere (zero below the horizon), unnormalised as given."""
    rng = np.random.default_rng(7)
    d = rng.normal(size=(3000, 3)) * rng.uniform(0.1, 10.0, size=(3000, 1))
    sun = _sun(el, 40.0)
    m = model("hoffman_preetham2002", sun=sun, turbidity=T, g=g, phase=phase,
              sky_distance_m=H_m)
    got = m.radiance(d, WL)
    v = d / np.linalg.norm(d, axis=1, keepdims=True)
    u = np.maximum(v[:, 2], 0.0)[:, None]
    R = 6371.0e3
    s = -R * u + np.sqrt(R * R * u * u + 2.0 * R * H_m + H_m * H_m)
    beta_r = P.rayleigh_coefficient(WL)
    beta_m = P.mie_coefficient(WL, T) * (P.ALPHA_MOLECULES / P.ALPHA_HAZE)
    c = np.clip(v @ sun.direction, -1.0, 1.0)[:, None]
    num = (1.0 - g) ** 2 if phase == "hoffman_preetham" else 1.0 - g * g
    ang = (beta_r * 3.0 / (16.0 * math.pi) * (1.0 + c * c)
           + beta_m * num / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * c) ** 1.5))
    e_sun = P.sun_radiance(WL, sun, T) * sun.solid_angle_sr
    want = ang / (beta_r + beta_m) * e_sun * (1.0 - np.exp(-(beta_r + beta_m) * s))
    want = np.where(v[:, 2:] >= 0.0, want, 0.0)
    assert np.all(got[v[:, 2] < 0.0] == 0.0)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(got, m._radiance_numpy(d, WL), rtol=1e-12, atol=0.0)
    assert got.shape == (3000, WL.size)
    assert m.radiance(d[5], WL).shape == (WL.size,)
    assert m.radiance(d.reshape(30, 100, 3), WL[::7]).shape == (30, 100, WL[::7].size)


def test_sky_kernel_refuses_bad_directions():
    m = model("hoffman_preetham2002", sun=_sun(30.0))
    with pytest.raises(ValueError, match="NaN or infinite"):
        m.radiance([[0.0, np.nan, 1.0]], WL)
    with pytest.raises(ValueError, match="zero-length"):
        m.radiance([[0.0, 0.0, 0.0]], WL)
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 3\)"):
        m.radiance([[0.0, 1.0]], WL)
    with pytest.raises(ValueError, match="wavelength"):
        m.radiance([[0.0, 0.0, 1.0]], [300.0])
