"""The Atmosphere container: presets, explicit construction and validation."""

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere, Constituent, ozone_cross_section
from skydome.atmosphere.profiles import ExponentialProfile, TentProfile, UniformProfile
from skydome.atmosphere.rayleigh import rayleigh_scattering_coefficient


def test_earth_rayleigh_is_survey_eq8_with_h0_7994():
    atm = Atmosphere.earth(turbidity=2.5)
    ray = atm.constituent("rayleigh")
    wl = np.array([400.0, 550.0, 700.0])
    assert np.allclose(ray.scattering(wl), rayleigh_scattering_coefficient(wl), rtol=1e-14)
    assert ray.profile == ExponentialProfile(7994.0)
    assert atm.constituent("aerosol").profile == ExponentialProfile(1200.0)


def test_earth_aerosol_optical_depth_matches_angstrom():
    atm = Atmosphere.earth(aerosol_optical_depth=0.2, angstrom_alpha=1.3)
    tau = atm.vertical_optical_depth([550.0, 1000.0])["aerosol"]
    assert tau[0] == pytest.approx(0.2, rel=1e-12)
    assert tau[1] == pytest.approx(0.2 * (1000 / 550) ** -1.3, rel=1e-12)
    # turbidity: Angstrom beta at 1 um = 0.04608 T - 0.04586 (Preetham 1999 A.2)
    atm = Atmosphere.earth(turbidity=3.0)
    assert atm.vertical_optical_depth([1000.0])["aerosol"][0] == pytest.approx(0.04608 * 3 - 0.04586)


def test_rayleigh_vertical_optical_depth_order_of_magnitude():
    # sea-level Rayleigh optical depth at 550 nm is about 0.097 (Bucholtz 1995, Table 2,
    # US standard atmosphere); the survey's constants (no King factor, H0 = 7994 m) give
    # beta(550) * H0 = 0.0878 -- within 10 %.
    atm = Atmosphere.earth()
    tau = atm.vertical_optical_depth([550.0])["rayleigh"][0]
    assert tau == pytest.approx(0.0973, rel=0.11)


def test_ozone_column_300_du():
    atm = Atmosphere.earth(ozone_du=300.0)
    oz = atm.constituent("ozone")
    # column number density = peak density * 15 km equivalent thickness = 300 DU
    peak = oz.absorption(600.0) / ozone_cross_section(600.0)
    column = peak * oz.profile.column(atm.top_altitude_m)
    assert column == pytest.approx(300 * 2.6867e20, rel=1e-6)
    # Chappuis band: absorption peaks near 600 nm
    wl = np.arange(400.0, 800.0, 10.0)
    assert 570 <= wl[np.argmax(oz.absorption(wl))] <= 620
    # The Chappuis-band peak cross section is about 5.2e-21 cm^2 near 602 nm (Burrows et al.
    # 1999; Serdyuchenko et al. 2014), so 300 DU (8.06e18 cm^-2) give tau ~ 0.042 at the
    # peak; the 10 nm bin means are a little lower.
    assert 0.033 < atm.vertical_optical_depth([600.0])["ozone"][0] < 0.043


def test_ozone_table_integrity():
    from skydome.data import load_table

    cols, t = load_table("ozone_cross_section_233k")
    assert cols == ("wavelength_nm", "cross_section_m2")
    assert t.shape == (48, 2)
    assert t[0, 0] == 360 and t[-1, 0] == 830
    assert t[24, 1] == pytest.approx(5.019e-25)  # 600 nm bin, Serdyuchenko et al. 2014 via Bruneton 2017


def test_bruneton_preset_numbers():
    atm = Atmosphere.bruneton2017()
    assert atm.planet_radius_m == 6360e3 and atm.top_radius_m == 6420e3
    wl = np.array([440.0, 550.0, 680.0])
    ray = atm.constituent("rayleigh").scattering(wl)
    assert np.allclose(ray, 1.24062e-6 * (wl / 1000) ** -4)
    aer = atm.constituent("aerosol")
    assert aer.scattering(550.0) / (aer.scattering(550.0) + aer.absorption(550.0)) == pytest.approx(0.9)
    assert aer.g == 0.8 and aer.phase == "cornette_shanks"


def test_custom_reproduces_explicit_coefficients():
    wl_tab = [400.0, 500.0, 600.0, 700.0]
    atm = Atmosphere.custom(rayleigh_scattering=(wl_tab, [3e-5, 1.3e-5, 6e-6, 3.5e-6]),
                            mie_scattering=2e-5, mie_extinction=2.2e-5, mie_g=0.7,
                            mie_phase="henyey_greenstein", rayleigh_scale_height_m=8000)
    op = atm.optical_properties([450.0, 600.0])
    assert op.scattering[0] == pytest.approx([2.15e-5, 6e-6])
    assert op.extinction[1] == pytest.approx([2.2e-5, 2.2e-5])
    assert op.phase_param[1] == 0.7 and op.phase_code[1] == 1
    assert op.profile_p0[0] == 8000


def test_optical_properties_shapes():
    # rayleigh, aerosol, ozone, water_vapour, mixed_gases
    op = Atmosphere.earth().optical_properties(np.linspace(380, 780, 16))
    assert op.scattering.shape == (5, 16) and op.extinction.shape == (5, 16)
    op = Atmosphere.earth(precipitable_water_cm=0, mixed_gases=False).optical_properties(
        np.linspace(380, 780, 16))
    assert op.scattering.shape == (3, 16) and op.extinction.shape == (3, 16)
    assert np.all(op.extinction >= op.scattering)
    assert op.ground_albedo.shape == (16,)


@pytest.mark.parametrize("kwargs, match", [
    ({"turbidity": -1}, r"turbidity = -1 is out of range"),
    ({"turbidity": 40}, r"turbidity"),
    ({"aerosol_optical_depth": -0.1}, "aerosol_optical_depth"),
    ({"ground_albedo": 1.5}, "ground_albedo"),
    ({"ozone_du": -3}, "ozone_du"),
    ({"aerosol_g": 1.0}, "g"),
    ({"aerosol_single_scattering_albedo": 1.2}, "aerosol_single_scattering_albedo"),
    ({"aerosol_phase": "mie"}, "phase"),
    ({"planet_radius_m": 0}, "planet_radius_m"),
])
def test_earth_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Atmosphere.earth(**kwargs)


def test_turbidity_and_aod_exclusive():
    with pytest.raises(ValueError, match="either"):
        Atmosphere.earth(turbidity=2, aerosol_optical_depth=0.1)


def test_constituent_validation():
    with pytest.raises(ValueError, match="scattering"):
        Constituent("x", scattering=-1.0)
    with pytest.raises(TypeError, match="profile"):
        Constituent("x", profile="exp")
    with pytest.raises(ValueError, match="unique"):
        Atmosphere((Constituent("a"), Constituent("a")))


def test_profiles():
    assert ExponentialProfile(7994).density(7994) == pytest.approx(np.exp(-1))
    t = TentProfile(25e3, 15e3)
    assert t.density([10e3, 25e3, 40e3, 50e3]) == pytest.approx([0, 1, 0, 0])
    assert t.column(100e3) == pytest.approx(15e3, rel=1e-6)
    assert UniformProfile(5000).column(1e5) == 5000
    with pytest.raises(ValueError, match="scale_height_m"):
        ExponentialProfile(-5)


def test_public_api_exports_atmosphere():
    assert sd.Atmosphere is Atmosphere
