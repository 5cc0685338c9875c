"""Absorbing gases (water vapour, O2 / CO2, ozone's Huggins band) from Bird & Riordan 1986."""

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere, gases, ozone_cross_section


def test_transmittance_equals_spectrl2_at_reference_airmass():
    """At the reference air mass the Beer's-law water and mixed-gas optical depths give the
    band transmittances of pvlib's independent SPECTRL2 implementation
    (pvlib.spectrum.spectrl2, Bird & Riordan 1986 eqs. 2-8, 2-11; it uses 118.3 where the
    report prints 118.93, hence the tolerance)."""
    import importlib

    br = importlib.import_module("pvlib.spectrum.spectrl2")

    wl = br._SPECTRL2_COEFFS["wavelength"]
    sel = wl <= 2800.0
    out = br._spectrl2_transmittances(np.array([48.19]), np.array([1.5]), np.array([101300.0]),
                                      np.array([1.42]), np.array([0.3]),
                                      np.zeros((wl.size, 1)), np.zeros((wl.size, 1)), np.array([1]))
    t_ref = (out[3] * out[5])[:, 0]
    atm = Atmosphere.earth(gas_reference_airmass=1.5)
    tau = atm.vertical_optical_depth(wl)
    t = np.exp(-1.5 * (tau["water_vapour"] + tau["mixed_gases"]))
    assert np.allclose(t[sel], t_ref[sel], atol=0.01)
    # the bands are there: O2 A (762.5 nm), water at 940 and 1380 nm
    k = {w: int(np.argmin(np.abs(wl - w))) for w in (762.5, 937.0, 1395.0)}
    assert t[k[762.5]] < 0.75 and t[k[937.0]] < 0.5 and t[k[1395.0]] < 0.05


def test_ozone_huggins_band():
    """Below 350 nm the cross section is Bird & Riordan's a_o [cm^-1 per atm-cm] divided by
    the Loschmidt constant 2.6868e19 cm^-3 (CODATA 2018, 273.15 K, 101325 Pa) x 1 cm; it
    rises steeply and monotonically to shorter wavelengths from the Serdyuchenko table at
    365 nm."""
    wl = np.array([300.0, 310.0, 320.0, 330.0, 340.0, 350.0])
    a_o = np.array([10.0, 2.7, 0.8, 0.16, 0.04, 0.007])   # [BR86] Table 1
    sigma_cm2 = ozone_cross_section(wl) * 1e4
    assert np.allclose(sigma_cm2, a_o / 2.6868e19, rtol=1e-3)
    grid = np.arange(300.0, 366.0, 1.0)
    s = ozone_cross_section(grid)
    assert np.all(np.diff(s) < 0) and s[0] / s[-1] > 1e4
    # 365 nm onwards unchanged: Serdyuchenko's 360-370 nm bin
    assert ozone_cross_section(365.0) == pytest.approx(1.18e-27)


def test_gas_parameters_validated():
    with pytest.raises(ValueError, match=r"precipitable_water_cm = -1"):
        Atmosphere.earth(precipitable_water_cm=-1.0)
    with pytest.raises(ValueError, match=r"gas_reference_airmass = 0.5"):
        Atmosphere.earth(gas_reference_airmass=0.5)
    with pytest.raises(TypeError, match="mixed_gases"):
        Atmosphere.earth(mixed_gases="yes")
    with pytest.raises(ValueError, match="precipitable_water_cm"):
        gases.water_vapour(11.0)


def test_water_column():
    """The water constituent holds the column it is given: the vertical weak-line optical
    depth 0.2385 a_w W at a weak band (Bird & Riordan eq. 2-8 with 20.07 a_w W m << 1)."""
    atm = Atmosphere.earth(precipitable_water_cm=2.0, gas_reference_airmass=1.0)
    tau = atm.vertical_optical_depth([593.0])["water_vapour"][0]   # a_w = 0.075
    x = 0.075 * 2.0
    assert tau == pytest.approx(0.2385 * x / (1 + 20.07 * x) ** 0.45, rel=1e-9)
    assert "water_vapour" not in {c.name for c in Atmosphere.earth(precipitable_water_cm=0).constituents}


def test_default_sky_visible_almost_unchanged():
    """The gases move the default (US standard) sky's luminance by under 2 % and its xy by
    under 0.005 (single scattering; measured: -0.5 % mean, 0.003 xy, the 720 nm water and
    760 nm O2 bands)."""
    from skydome.spectra import spectrum_to_xyz, xyz_to_xy

    sun = sd.Sun(45.0, 180.0)
    el, az = np.meshgrid(np.radians([5.0, 30.0, 60.0, 90.0]), np.radians(np.arange(0, 360, 45.0)))
    d = np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], -1).reshape(-1, 3)
    wl = np.arange(380.0, 781.0, 5.0)
    xyz = []
    for atm in (Atmosphere.earth(), Atmosphere.earth(precipitable_water_cm=0.0, mixed_gases=False)):
        xyz.append(spectrum_to_xyz(sd.model("single_scattering", sun=sun, atmosphere=atm).radiance(d, wl), wl))
    r = xyz[0][:, 1] / xyz[1][:, 1] - 1.0
    assert np.all(r < 0) and np.all(r > -0.02)
    assert np.max(np.linalg.norm(xyz_to_xy(xyz[0]) - xyz_to_xy(xyz[1]), axis=-1)) < 0.005


def test_fold_absorbers_keeps_the_medium():
    """The mixed gases follow the air density, so they fold into Rayleigh's constituent: the
    extinction at every altitude and the scattering are unchanged (the exponential profile's
    density exp(-h/H) evaluated here, independently of the kernels)."""
    from skydome.atmosphere import fold_absorbers

    wl = np.array([450.0, 550.0, 687.0, 760.0, 940.0])
    p = Atmosphere.earth().optical_properties(wl)
    f, keep = fold_absorbers(p)
    assert p.profile_code.size == 5 and f.profile_code.size == 4
    assert list(keep) == [0, 1, 2, 3]              # rayleigh, aerosol, ozone, water vapour kept
    assert np.array_equal(f.scattering, p.scattering[keep])
    for h in (0.0, 1500.0, 8000.0, 30000.0):
        def ext(q):
            expo = q.profile_code == 0
            return (np.exp(-h / q.profile_p0[expo])[:, None] * q.extinction[expo]).sum(axis=0)
        assert np.allclose(ext(f), ext(p), rtol=1e-14, atol=0.0)
    assert np.array_equal(f.extinction[2], p.extinction[2])   # the ozone layer untouched
    # nothing to fold in a gas-free atmosphere
    g = Atmosphere.earth(precipitable_water_cm=0.0, mixed_gases=False).optical_properties(wl)
    assert fold_absorbers(g)[0].profile_code.size == g.profile_code.size
