"""Blender's own atmospheres, for comparisons with its Sky Texture node.

``MULTIPLE_SCATTERING`` (Blender 5.0's default sky; intern/sky/source/
sky_multiple_scattering.cpp, MIT, after F. Garcia Linan's 2022 thesis; h in km, the
coefficients in km^-1):

* planet radius 6371 km, atmosphere 100 km thick, ground albedo 0.3;
* molecules: scattering 6.605e-3, 1.067e-2, 1.842e-2, 3.156e-2 km^-1 at 630, 560, 490,
  430 nm (MOLECULAR_SCATTERING_COEFFICIENT_BASE) x exp(-0.07771971 h^1.16364243);
  Rayleigh phase;
* aerosols: number density 1.3681e20 (exp(-h / 0.73) + 2e6 / 1.3681e20)
  (AEROSOL_BASE_DENSITY, AEROSOL_HEIGHT_SCALE, AEROSOL_BACKGROUND_DENSITY) times the
  scattering cross sections 1.5908e-22, 1.7711e-22, 2.0942e-22, 2.4033e-22 and the
  absorption cross sections 2.8722e-24, 4.6168e-24, 7.9706e-24, 1.3578e-23; Henyey-
  Greenstein phase, g = 0.8;
* ozone: cross sections 3.472e-25, 3.914e-25, 1.349e-25, 11.03e-27 x 334.5 (OZONE_MEAN_
  DOBSON) x 3.78547397e20 exp(-(ln h - 3.22261)^2 x 5.55555555 - ln h), a log-normal
  layer in h (mu = 3.22261, sigma = 0.3);
* the node's air, aerosol and ozone densities multiply the three (1 by default).

skydome's kernels know exponential, tent, uniform and Gaussian profiles, so two profiles
are replaced with the same vertical column: the molecules' stretched exponential by an
exponential of scale height Gamma(1 + 1/b) / a^(1/b) = 8.521 km (a = 0.07771971,
b = 1.16364243), the ozone's log-normal by a Gaussian layer with its mean (26.25 km) and
standard deviation (8.06 km). Between and beyond the four wavelengths the coefficients
are interpolated linearly in log(coefficient) against log(wavelength) (power laws; the
end segments extended). Blender's background aerosol term (2e6 / 1.3681e20 = 1.5e-14 of
the sea-level density) is left out.

``NISHITA`` (Blender 2.90-4.x; intern/sky/source/sky_nishita.cpp, Apache-2.0):
radii 6360 / 6420 km; Rayleigh 5.424820087636473e-5 (lambda / 380 nm)^-4 m^-1 (its
rayleigh_coeff table at 380, 400, ..., 780 nm follows that law), 8 km; aerosol scattering 2e-5 m^-1
(mie_coeff), extinction 1.11 x that, 1.2 km (mie_scale), g = 0.76 (its phase_mie is
Cornette-Shanks'); ozone on the 10-25-40 km tent with the ozone_coeff peak coefficients at
380, 400, ..., 780 nm;
ground albedo: none in Blender's single-scattering texture (skydome's 0.1 default kept).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MULTIPLE_SCATTERING", "NISHITA_OZONE_COEFF", "blender_atmosphere"]

#: the constants of Blender 5's sky_multiple_scattering.cpp, as printed there
MULTIPLE_SCATTERING = {
    "wavelengths_nm": (630.0, 560.0, 490.0, 430.0),
    "earth_radius_km": 6371.0,
    "atmosphere_thickness_km": 100.0,
    "ground_albedo": 0.3,
    "aerosol_g": 0.8,
    "molecular_scattering_base_km": (6.605e-3, 1.067e-2, 1.842e-2, 3.156e-2),
    "molecular_profile_a": 0.07771971,
    "molecular_profile_b": 1.16364243,
    "ozone_cross_section": (3.472e-25, 3.914e-25, 1.349e-25, 11.03e-27),
    "ozone_mean_dobson": 334.5,
    "ozone_density_scale": 3.78547397e20,
    "ozone_log_mu": 3.22261,
    "ozone_log_inv_two_sigma2": 5.55555555,
    "aerosol_absorption_cross_section": (2.8722e-24, 4.6168e-24, 7.9706e-24, 1.3578e-23),
    "aerosol_scattering_cross_section": (1.5908e-22, 1.7711e-22, 2.0942e-22, 2.4033e-22),
    "aerosol_base_density": 1.3681e20,
    "aerosol_height_scale_km": 0.73,
}

#: the peak ozone absorption coefficients [m^-1] of Blender 4.x's sky_nishita.cpp
#: (ozone_coeff) at 380, 400, ..., 780 nm
NISHITA_OZONE_COEFF = (
    3.25126849861e-09, 5.85395365047e-09, 1.977191155085e-08, 7.309568762914e-08,
    2.0084561514287e-07, 4.0383958096161e-07, 6.3551335912363e-07, 9.670704118097e-07,
    1.5479740042441e-06, 2.09038647223331e-06, 2.46128056164565e-06, 2.73551299461512e-06,
    2.15125863128643e-06, 1.59051840791988e-06, 1.12356197979857e-06, 7.3527551487574e-07,
    4.6450130357806e-07, 3.3096079921048e-07, 2.2512612292678e-07, 1.487912926649e-07,
    1.6828623364192e-07)


def _loglog(wl_tab, values, factor: float = 1.0):
    """A callable of wavelength [nm]: ``factor`` x power-law pieces through (wl_tab,
    values)."""
    order = np.argsort(wl_tab)
    lx = np.log(np.asarray(wl_tab, dtype=np.float64)[order])
    ly = np.log(np.asarray(values, dtype=np.float64)[order])

    def f(wl):
        x = np.log(np.asarray(wl, dtype=np.float64))
        y = np.interp(x, lx, ly)
        lo = (ly[1] - ly[0]) / (lx[1] - lx[0])
        hi = (ly[-1] - ly[-2]) / (lx[-1] - lx[-2])
        y = np.where(x < lx[0], ly[0] + lo * (x - lx[0]), y)
        y = np.where(x > lx[-1], ly[-1] + hi * (x - lx[-1]), y)
        return factor * np.exp(y)

    return f


def molecular_scale_height_km() -> float:
    """The exponential scale height with the column of exp(-a h^b): Gamma(1 + 1/b) /
    a^(1/b) [km]."""
    c = MULTIPLE_SCATTERING
    a, b = c["molecular_profile_a"], c["molecular_profile_b"]
    return math.gamma(1.0 + 1.0 / b) / a ** (1.0 / b)


def ozone_layer_moments_km() -> tuple[float, float, float]:
    """Mean, standard deviation [km] and column [km x density] of Blender's ozone number
    density c exp(-(ln h - mu)^2 / (2 s^2)) / h (log-normal: column c s sqrt(2 pi), mean
    exp(mu + s^2 / 2), variance (exp(s^2) - 1) exp(2 mu + s^2))."""
    c = MULTIPLE_SCATTERING
    s2 = 1.0 / (2.0 * c["ozone_log_inv_two_sigma2"])
    mu = c["ozone_log_mu"]
    mean = math.exp(mu + s2 / 2.0)
    sd = math.sqrt((math.exp(s2) - 1.0) * math.exp(2.0 * mu + s2))
    column = c["ozone_density_scale"] * math.sqrt(2.0 * math.pi * s2)
    return mean, sd, column


def blender_atmosphere(atmosphere_cls, sky_type: str = "multiple_scattering",
                       air_density: float = 1.0, aerosol_density: float = 1.0,
                       ozone_density: float = 1.0):
    """Blender's atmosphere (module docstring) as a skydome Atmosphere, of the class
    ``atmosphere_cls`` (:meth:`skydome.atmosphere.Atmosphere.blender` passes its own: this
    module does not import the package that calls it)."""
    from skydome._validate import check_choice, check_number
    from skydome.atmosphere._constituent import Constituent
    from skydome.atmosphere.profiles import (ExponentialProfile, GaussianLayerProfile,
                                             TentProfile)

    Atmosphere = atmosphere_cls
    kind = check_choice("sky_type", str(sky_type).lower(), ("multiple_scattering", "nishita"))
    air = check_number("air_density", air_density, 0.0, 10.0)
    aer = check_number("aerosol_density", aerosol_density, 0.0, 10.0)
    oz = check_number("ozone_density", ozone_density, 0.0, 10.0)
    if kind == "nishita":
        wl_tab = np.linspace(380.0, 780.0, 21)
        return Atmosphere(
            (Constituent("rayleigh", scattering=lambda wl: air * 5.424820087636473e-5
                         * (np.asarray(wl, dtype=np.float64) / 380.0) ** -4.0,
                         profile=ExponentialProfile(8000.0), phase="rayleigh"),
             Constituent("aerosol", scattering=aer * 2e-5, absorption=aer * 0.11 * 2e-5,
                         profile=ExponentialProfile(1200.0), phase="cornette_shanks", g=0.76),
             Constituent("ozone", scattering=0.0,
                         absorption=lambda wl: oz * np.interp(wl, wl_tab, NISHITA_OZONE_COEFF),
                         profile=TentProfile(25e3, 15e3), phase="isotropic")),
            planet_radius_m=6360e3, top_altitude_m=60e3, ground_albedo=0.1,
            name="blender_nishita")
    c = MULTIPLE_SCATTERING
    wl = c["wavelengths_nm"]
    top_m = c["atmosphere_thickness_km"] * 1e3
    n0 = c["aerosol_base_density"]
    # km^-1 -> m^-1
    mol = _loglog(wl, [1e-3 * v for v in c["molecular_scattering_base_km"]], air)
    aer_s = _loglog(wl, [1e-3 * n0 * v for v in c["aerosol_scattering_cross_section"]], aer)
    aer_a = _loglog(wl, [1e-3 * n0 * v for v in c["aerosol_absorption_cross_section"]], aer)
    mean_km, sd_km, column = ozone_layer_moments_km()
    layer = GaussianLayerProfile(mean_km * 1e3, sd_km * 1e3)
    # peak coefficient [m^-1] so that peak x column of the layer [m] = Blender's vertical
    # optical depth, cross section x dobson x column (km^-1 x km)
    tau = [s * c["ozone_mean_dobson"] * column for s in c["ozone_cross_section"]]
    peak = _loglog(wl, [t / layer.column(top_m) for t in tau], oz)
    ozone = Constituent("ozone", scattering=0.0, absorption=peak, profile=layer,
                        phase="isotropic")
    return Atmosphere(
        (Constituent("rayleigh", scattering=mol,
                     profile=ExponentialProfile(molecular_scale_height_km() * 1e3),
                     phase="rayleigh"),
         Constituent("aerosol", scattering=aer_s, absorption=aer_a,
                     profile=ExponentialProfile(c["aerosol_height_scale_km"] * 1e3),
                     phase="henyey_greenstein", g=c["aerosol_g"]),
         ozone),
        planet_radius_m=c["earth_radius_km"] * 1e3, top_altitude_m=top_m,
        ground_albedo=c["ground_albedo"], name="blender_multiple_scattering")
