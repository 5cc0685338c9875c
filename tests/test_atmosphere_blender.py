"""Atmosphere.blender(): Blender's own atmospheres against the constants of Blender's
sources, typed here from them:

* intern/sky/source/sky_multiple_scattering.cpp (Blender 5.0, MIT): MOLECULAR_SCATTERING_
  COEFFICIENT_BASE, AEROSOL_*_CROSS_SECTION, AEROSOL_BASE_DENSITY, AEROSOL_HEIGHT_SCALE,
  OZONE_ABSORPTION_CROSS_SECTION, OZONE_MEAN_DOBSON, the molecular and ozone density
  functions, EARTH_RADIUS, ATMOSPHERE_THICKNESS, G, GROUND_ALBEDO;
* intern/sky/source/sky_nishita.cpp (Blender 2.90-4.x, Apache-2.0): rayleigh_coeff,
  ozone_coeff, mie_coeff, the scale heights and radii.

The vertical optical depths of the profiles skydome uses in place of Blender's are checked
against Blender's density functions integrated here by quadrature."""

import numpy as np
import pytest

from skydome.atmosphere import Atmosphere

WL = np.array([630.0, 560.0, 490.0, 430.0])
# sky_multiple_scattering.cpp, km^-1 and cm^2-like cross sections as printed there
MOL = np.array([6.605e-3, 1.067e-2, 1.842e-2, 3.156e-2])
AER_S = np.array([1.5908e-22, 1.7711e-22, 2.0942e-22, 2.4033e-22])
AER_A = np.array([2.8722e-24, 4.6168e-24, 7.9706e-24, 1.3578e-23])
N0 = 1.3681e20
OZ = np.array([3.472e-25, 3.914e-25, 1.349e-25, 11.03e-27])


def _blender_columns_km():
    """Blender 5's densities (h in km) integrated from 0 to 100 km."""
    h = np.concatenate([np.linspace(1e-6, 1.0, 200001), np.linspace(1.0, 100.0, 400001)[1:]])
    mol = np.exp(-0.07771971 * h ** 1.16364243)
    aer = np.exp(-h / 0.73) + 2e6 / N0
    log_h = np.log(h)
    oz = 3.78547397e20 * np.exp(-(log_h - 3.22261) ** 2 * 5.55555555 - log_h)
    return {k: float(np.trapezoid(v, h)) for k, v in (("mol", mol), ("aer", aer), ("oz", oz))}


def test_multiple_scattering_constants():
    a = Atmosphere.blender()
    assert a.planet_radius_m == 6371e3 and a.top_altitude_m == 100e3
    np.testing.assert_allclose(a.ground_albedo(WL), 0.3)
    ray, aer, oz = (a.constituent(n) for n in ("rayleigh", "aerosol", "ozone"))
    # sea level: Blender's km^-1 in m^-1
    np.testing.assert_allclose(ray.scattering(WL), MOL * 1e-3, rtol=1e-12)
    np.testing.assert_allclose(aer.scattering(WL), AER_S * N0 * 1e-3, rtol=1e-12)
    np.testing.assert_allclose(aer.absorption(WL), AER_A * N0 * 1e-3, rtol=1e-12)
    assert aer.phase == "henyey_greenstein" and aer.g == 0.8 and ray.phase == "rayleigh"
    assert aer.profile.scale_height_m == 730.0
    # vertical optical depths against Blender's own density functions (0.1 %)
    cols = _blender_columns_km()
    tau = a.vertical_optical_depth(WL)
    np.testing.assert_allclose(tau["rayleigh"], MOL * cols["mol"], rtol=1e-3)
    np.testing.assert_allclose(tau["aerosol"], (AER_S + AER_A) * N0 * cols["aer"], rtol=1e-3)
    np.testing.assert_allclose(tau["ozone"], OZ * 334.5 * cols["oz"], rtol=1e-3)


def test_multiple_scattering_density_factors():
    base = Atmosphere.blender().vertical_optical_depth(WL)
    t = Atmosphere.blender(air_density=2.0, aerosol_density=0.5,
                           ozone_density=0.0).vertical_optical_depth(WL)
    np.testing.assert_allclose(t["rayleigh"], 2.0 * base["rayleigh"], rtol=1e-12)
    np.testing.assert_allclose(t["aerosol"], 0.5 * base["aerosol"], rtol=1e-12)
    np.testing.assert_allclose(t["ozone"], 0.0)


def test_nishita_constants():
    a = Atmosphere.blender("nishita")
    assert a.planet_radius_m == 6360e3 and a.top_altitude_m == 60e3
    ray, aer, oz = (a.constituent(n) for n in ("rayleigh", "aerosol", "ozone"))
    # rayleigh_coeff[0], [1], [10], [20] and ozone_coeff[0], [11], [20] (380, 400, 580, 780 nm)
    np.testing.assert_allclose(ray.scattering([380.0, 400.0, 580.0, 780.0]),
                               [5.424820087636473e-5, 4.418549866505454e-5,
                                9.99557429990163e-6, 3.05591531679811e-6], rtol=1e-6)
    np.testing.assert_allclose(oz.absorption([380.0, 600.0, 780.0]),
                               [3.25126849861e-9, 2.73551299461512e-6, 1.6828623364192e-7],
                               rtol=1e-12)
    np.testing.assert_allclose(aer.scattering(550.0), 2e-5)
    np.testing.assert_allclose(aer.absorption(550.0), 0.11 * 2e-5)     # extinction 1.11 x
    assert ray.profile.scale_height_m == 8e3 and aer.profile.scale_height_m == 1.2e3
    assert aer.phase == "cornette_shanks" and aer.g == 0.76


@pytest.mark.parametrize("kw, match", [({"sky_type": "hosek"}, "sky_type"),
                                       ({"air_density": -1.0}, "air_density"),
                                       ({"ozone_density": 11.0}, "ozone_density")])
def test_blender_atmosphere_rejects_bad_values(kw, match):
    with pytest.raises(ValueError, match=match):
        Atmosphere.blender(**kw)
