"""Tests of the Preetham, Shirley & Smits (1999) model ([PSS99]).

Reference values come from the paper (its Appendix A.2 formulas and tables, evaluated by
hand below), from Iqbal (1983) (the source of Table 2), from the ASTM G173 standard, from
published Rayleigh coefficients (Riley et al. 2004 / Bruneton & Neyret 2008) and from
physical consistency (the paper's definition of turbidity, Beer-Lambert).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import skydome as sd
from skydome.data import load_table
from skydome.models import available, model
from skydome.models.analytic import preetham1999 as P
from skydome.spectra import spectrum_to_xyz, xyz_to_xy

WL = np.arange(380.0, 781.0, 10.0)


def _sun(el, az=180.0):
    return sd.Sun(elevation_deg=el, azimuth_deg=az)


# --------------------------------------------------------------------------------------
# Tables (integrity)
# --------------------------------------------------------------------------------------

def test_distribution_table_entries():
    # [PSS99] Appendix A.2: A_Y = 0.1787 T - 1.4630, E_y = -0.0109 T + 0.0529
    cols, a = load_table("preetham1999_distribution")
    assert a.shape == (5, 7)
    assert tuple(a[0, 1:3]) == (0.1787, -1.4630)
    assert tuple(a[4, 5:7]) == (-0.0109, 0.0529)
    assert tuple(a[3, 3:5]) == (-0.0641, -0.8989)


def test_zenith_chromaticity_table_entries():
    # [PSS99] Appendix A.2: constant terms 0.25886 (x) and 0.26688 (y)
    cols, a = load_table("preetham1999_zenith_chromaticity")
    assert a.shape == (3, 9)
    row0 = a[a[:, 0] == 0][0]
    assert row0[4] == 0.25886 and row0[8] == 0.26688
    row2 = a[a[:, 0] == 2][0]
    assert row2[1] == 0.00166 and row2[5] == 0.00275


def test_sun_absorption_table_matches_iqbal():
    # Iqbal (1983) p. 127 / 130 values (the source of [PSS99] Table 2):
    # k_o(600 nm) = 0.125 cm^-1, k_wa(720 nm) = 1.0 cm^-1, k_g(760 nm) = 3.0, k_g(770) = 0.21
    _, a = load_table("preetham1999_sun_absorption")
    assert a.shape == (41, 4)
    row = {int(r[0]): r[1:] for r in a}
    assert row[600][0] == 0.125
    assert row[720][1] == 1.0
    assert row[760][2] == 3.0 and row[770][2] == 0.21
    assert row[450][0] == 0.003 and row[570][0] == 0.120


def test_mie_eta_integrates_to_K():
    # [PSS99] A.3: beta_p(theta) integrates to beta_p, i.e. int eta sin = K (Table 2).
    th = np.radians(np.linspace(0.0, 180.0, 4001))
    wt, K = P._spectra_table()
    for lam in (450.0, 550.0, 650.0):
        eta = P.mie_eta(th, [lam])[:, 0]
        integral = np.trapezoid(eta * np.sin(th), th)
        assert integral == pytest.approx(np.interp(lam, wt, K), rel=0.10)


def test_table2_sun_column_vs_astm_g173():
    # [PSS99] Table 2 extraterrestrial sun radiance [W cm^-2 um^-1 sr^-1] = 10 W m^-2 nm^-1 sr^-1
    # against ASTM G173 AM0 / solid angle of the disc: the band 400-750 nm agrees to 3 %.
    _, a = load_table("preetham1999_spectra")
    w = a[2:38, 0]                                    # 400 .. 750 nm
    table = 10.0 * a[2:38, 2]
    ours = P.extraterrestrial_sun_radiance(w)
    assert ours.sum() == pytest.approx(table.sum(), rel=0.03)


# --------------------------------------------------------------------------------------
# Zenith values and the Perez distribution
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("T,ts_deg", [(2.0, 45.0), (5.0, 30.0), (10.0, 80.0)])
def test_zenith_luminance_formula(T, ts_deg):
    # [PSS99] A.2, evaluated by hand: Y_z = (4.0453 T - 4.9710) tan chi - 0.2155 T + 2.4192
    ts = math.radians(ts_deg)
    chi = (4.0 / 9.0 - T / 120.0) * (math.pi - 2.0 * ts)
    expected = 1000.0 * ((4.0453 * T - 4.9710) * math.tan(chi) - 0.2155 * T + 2.4192)
    assert float(P.zenith_luminance(T, ts)) == pytest.approx(expected, rel=1e-12)


def test_zenith_luminance_number():
    # T = 2, theta_s = 45 deg: chi = 0.427778 * pi/2 = 0.671953, tan chi = 0.795338;
    # Y_z = 3.1196 * 0.795338 + 1.9882 = 4.4693 kcd/m^2 (hand calculation)
    assert float(P.zenith_luminance(2.0, math.pi / 4)) == pytest.approx(4469.3, abs=1.0)


def test_zenith_chromaticity_number():
    # T = 2, theta_s = 0: x_z = 4 * 0 + 2 * 0.00394 + 0.25886 = 0.26674,
    # y_z = 2 * 0.00516 + 0.26688 = 0.27720 ([PSS99] A.2 by hand)
    x, y = P.zenith_chromaticity(2.0, 0.0)
    assert float(x) == pytest.approx(0.26674, abs=1e-9)
    assert float(y) == pytest.approx(0.27720, abs=1e-9)


def test_zenith_is_bluish_at_low_turbidity():
    # Clear sky zenith at T = 2, sun at 45 deg is blue: x < 0.3 (and bluer than D65)
    sky = model("preetham1999", sun=_sun(45.0), turbidity=2.0)
    x, y, Y = sky.xyY([0.0, 0.0, 1.0])
    assert x < 0.3 and y < 0.3
    assert Y == pytest.approx(float(P.zenith_luminance(2.0, math.pi / 4)), rel=1e-12)


def test_perez_normalisation_at_zenith():
    # F(0, theta_s) / F(0, theta_s) = 1: the zenith returns Y_z, x_z, y_z exactly
    for T, el in ((3.0, 20.0), (8.0, 70.0)):
        sky = model("preetham1999", sun=_sun(el), turbidity=T)
        x, y, Y = sky.xyY([0.0, 0.0, 1.0])
        xz, yz = P.zenith_chromaticity(T, math.radians(90.0 - el))
        assert (x, y) == pytest.approx((float(xz), float(yz)), rel=1e-12)


def test_circumsolar_brighter_than_antisolar():
    sky = model("preetham1999", sun=_sun(30.0, 180.0), turbidity=3.0)
    near = sky.luminance(sd.transport.geometry.direction_from_angles(35.0, 180.0))
    far = sky.luminance(sd.transport.geometry.direction_from_angles(35.0, 0.0))
    assert near > 2.0 * far


def test_symmetry_about_solar_meridian():
    sky = model("preetham1999", sun=_sun(25.0, 120.0), turbidity=4.0)
    from skydome.transport.geometry import direction_from_angles
    a = sky.xyz(direction_from_angles(40.0, 120.0 + 37.0))
    b = sky.xyz(direction_from_angles(40.0, 120.0 - 37.0))
    assert a == pytest.approx(b, rel=1e-10)


def test_spectrum_matches_luminance():
    sky = model("preetham1999", sun=_sun(40.0), turbidity=3.0)
    d = np.array([[0.0, 0.0, 1.0], [0.3, 0.5, 0.4]])
    L = sky.radiance(d, np.arange(360.0, 831.0, 1.0))
    Y = spectrum_to_xyz(L, np.arange(360.0, 831.0, 1.0))[..., 1]
    assert Y == pytest.approx(sky.luminance(d), rel=2e-3)


# --------------------------------------------------------------------------------------
# Valid range
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("T", [1.9, 10.5, -1.0])
def test_turbidity_out_of_range(T):
    with pytest.raises(ValueError, match=r"turbidity = .* out of range \[2, 10\]"):
        model("preetham1999", sun=_sun(30.0), turbidity=T)


def test_sun_below_horizon_refused():
    with pytest.raises(ValueError, match="elevation_deg = -3 deg is out of range"):
        model("preetham1999", sun=_sun(-3.0), turbidity=3.0)


def test_below_horizon_is_zero_and_registered():
    assert "preetham1999" in available()
    sky = model("preetham1999", sun=_sun(30.0), turbidity=3.0)
    L = sky.radiance([[0.0, 1.0, -0.2], [1.0, 0.0, -1.0]], WL)
    assert np.all(L == 0.0)


@settings(max_examples=40, deadline=None)
@given(T=st.floats(2.0, 10.0), el=st.floats(0.0, 90.0), az=st.floats(0.0, 360.0),
       vel=st.floats(0.0, 90.0), vaz=st.floats(0.0, 360.0))
def test_no_nan_or_negative(T, el, az, vel, vaz):
    from skydome.transport.geometry import direction_from_angles
    sky = model("preetham1999", sun=_sun(el, az), turbidity=T)
    d = direction_from_angles([vel, 0.0, el], [vaz, vaz, az])   # any, horizon, the sun
    xyz = sky.xyz(d)
    assert np.all(np.isfinite(xyz)) and np.all(xyz >= 0.0)
    L = sky.radiance(d, WL)
    assert np.all(np.isfinite(L)) and np.all(L >= 0.0)
    s = sky.sun_radiance(WL)
    assert np.all(np.isfinite(s)) and np.all(s >= 0.0)


# --------------------------------------------------------------------------------------
# Sun
# --------------------------------------------------------------------------------------

def test_air_mass_values():
    # [PSS99] A.1 / Iqbal (1983) eq. 5.7.2 (Kasten 1966) evaluated by hand:
    # m(0) = 1 / (1 + 0.15 * 93.885^-1.253) = 0.99949, m(60) = 1.9928, m(90) = 36.5
    assert float(P.relative_air_mass(0.0)) == pytest.approx(0.99949, abs=2e-5)
    assert float(P.relative_air_mass(60.0)) == pytest.approx(1.9928, abs=2e-3)
    assert float(P.relative_air_mass(90.0)) == pytest.approx(36.5, rel=0.01)


def test_rayleigh_transmittance_vs_bucholtz():
    # Rayleigh optical depth of the sea-level atmosphere at 550 nm is about 0.097-0.098
    # (Bucholtz 1995, Appl. Opt. 34; Hansen & Travis 1974). Iqbal's fit (0.1001) agrees to 5 %.
    _, comp = P.sun_transmittance([550.0], 0.0, 2.0, components=True)
    tau = -math.log(float(comp["rayleigh"][0]) ** (1.0 / float(P.relative_air_mass(0.0))))
    assert tau == pytest.approx(0.0975, rel=0.05)


def test_sun_redder_at_low_elevation():
    xs = [xyz_to_xy(spectrum_to_xyz(P.sun_radiance(WL, _sun(el), 3.0), WL))[0]
          for el in (5.0, 15.0, 45.0, 85.0)]
    assert xs[0] > xs[1] > xs[2] > xs[3]


def test_sun_dimmer_with_turbidity_and_zero_below_horizon():
    a = P.sun_radiance(WL, _sun(30.0), 2.0)
    b = P.sun_radiance(WL, _sun(30.0), 8.0)
    assert np.all(b < a)
    assert np.all(P.sun_radiance(WL, _sun(-1.0), 2.0) == 0.0)
    with pytest.raises(ValueError, match="wavelengths_nm"):
        P.sun_radiance([300.0, 400.0], _sun(30.0), 2.0)


def test_sun_transmittance_absorption_bands():
    # Table 2: water vapour band at 720 nm and O2 A band at 760 nm dim the sun there
    t = P.sun_transmittance([710.0, 720.0, 750.0, 760.0], 30.0, 2.0)
    assert t[1] < 0.95 * t[0]
    assert t[3] < 0.95 * t[2]


# --------------------------------------------------------------------------------------
# Scattering coefficients and aerial perspective
# --------------------------------------------------------------------------------------

def test_rayleigh_coefficient_published():
    # Sea-level Rayleigh scattering (5.8, 13.5, 33.1) 1e-6 m^-1 at (680, 550, 440) nm
    # (Riley et al. 2004; Bruneton & Neyret 2008, section 2)
    b = P.rayleigh_coefficient([680.0, 550.0, 440.0])
    assert b == pytest.approx([5.8e-6, 13.5e-6, 33.1e-6], rel=0.03)


@pytest.mark.parametrize("T", [2.0, 4.0, 7.0, 10.0])
def test_turbidity_definition_recovered(T):
    # [PSS99] section 2: T = (t_m + t_h) / t_m. The haze and molecular columns at 550 nm
    # (sea-level coefficient times scale height) must give back T to 20 %: this checks
    # the SI conversion of the concentration factor c (off by 100x without it).
    tm = P.rayleigh_coefficient(550.0) / P.ALPHA_MOLECULES
    th = P.mie_coefficient(550.0, T) / P.ALPHA_HAZE
    assert (tm + th) / tm == pytest.approx(T, rel=0.20)


def test_aerial_perspective_zero_distance():
    tau, L = P.aerial_perspective([[0.0, 1.0, 0.0], [0.5, 0.5, 0.2]], 0.0, WL,
                                  sun=_sun(30.0), turbidity=3.0)
    assert np.all(tau == 1.0) and np.all(L == 0.0)


def test_aerial_perspective_small_distance_limit():
    tau, L = P.aerial_perspective([0.0, 1.0, 0.0], [1e-3, 1.0, 1000.0], WL,
                                  sun=_sun(30.0), turbidity=3.0)
    assert np.all(1.0 - tau[0] < 1e-6) and np.all(L[0] < 1e-3 * L[2])
    assert np.all(tau[2] < tau[1]) and np.all(L[2] > L[1])


def test_aerial_perspective_beer_lambert_horizontal():
    # Horizontal ray on a flat earth: constant density, tau = exp(-(b_R + b_M) s) and,
    # without skylight, L_in = A (1 - tau) / (b_R + b_M) (closed form of the integral)
    sun = _sun(30.0, 90.0)
    s = 7000.0
    tau, L = P.aerial_perspective([0.0, 1.0, 0.0], s, WL, sun=sun, turbidity=4.0,
                                  include_skylight=False)
    b = P.rayleigh_coefficient(WL) + P.mie_coefficient(WL, 4.0)
    assert tau == pytest.approx(np.exp(-b * s), rel=1e-9)
    cos_psi = float(np.dot([0.0, 1.0, 0.0], sun.direction))
    A = (P.rayleigh_angular_coefficient(WL, cos_psi)
         + P.mie_angular_coefficient(WL, 4.0, math.acos(cos_psi))) \
        * P.sun_radiance(WL, sun, 4.0) * sun.solid_angle_sr
    assert L == pytest.approx(A * (1.0 - np.exp(-b * s)) / b, rel=1e-6)


def test_aerial_perspective_bluer_at_low_turbidity():
    d = [0.0, 1.0, 0.02]
    xs = []
    for T in (2.0, 8.0):
        _, L = P.aerial_perspective(d, 20000.0, WL, sun=_sun(40.0), turbidity=T)
        xs.append(xyz_to_xy(spectrum_to_xyz(L, WL))[0])
    assert xs[0] < xs[1]


def test_aerial_perspective_errors():
    with pytest.raises(ValueError, match="distance_m"):
        P.aerial_perspective([0, 1, 0], -1.0, WL, sun=_sun(30.0), turbidity=3.0)
    with pytest.raises(ValueError, match="turbidity"):
        P.aerial_perspective([0, 1, 0], 10.0, WL, sun=_sun(30.0), turbidity=12.0)
    with pytest.raises(ValueError, match="elevation_deg"):
        P.aerial_perspective([0, 1, 0], 10.0, WL, sun=_sun(-5.0), turbidity=3.0)
