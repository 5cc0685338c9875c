"""Absorbing gases: water vapour, the uniformly mixed gases (O2, CO2) and ozone's Huggins band.

Coefficients from Bird & Riordan (1986), the SPCTRAL2 model ([BR86] below; J. Climate Appl.
Meteor. 25, 87-97, Table 1; table ``bird_riordan1986_absorption``), 300-4000 nm at about
10 nm resolution. Their transmittances of water vapour and of the mixed gases are band
models, not Beer's law: at the resolution of the table a band's lines saturate, so the
band optical depth grows more slowly than the path ([BR86] eqs. 2-8 and 2-11). skydome's
kernels need an extinction coefficient (Beer's law along every path), so each band's
optical depth is matched at one reference air mass ``m_ref`` (1.5 by default, the air mass
of the ASTM G173 standard spectra; the sun's air mass for a closure against a
pyranometer): the vertical optical depth is tau_band(m_ref) / m_ref. Paths of air mass m
then see tau_band(m_ref) m / m_ref instead of tau_band(m): too much absorption for
m > m_ref and too little for m < m_ref in saturated bands (a factor (m / m_ref)^0.45 on
the band depth in the strong limit), exact in the weak limit. docs/models.md records it.
"""

from __future__ import annotations

import numpy as np

from skydome._validate import check_number
from skydome.atmosphere.profiles import ExponentialProfile
from skydome.constants import DOBSON_UNIT, H_RAYLEIGH

__all__ = ["absorption_table", "water_vapour_band_depth", "mixed_gas_band_depth",
           "water_vapour", "mixed_gases", "ozone_cross_section_br86",
           "PRECIPITABLE_WATER_CM", "WATER_SCALE_HEIGHT_M", "REFERENCE_AIRMASS"]

#: precipitable water of the US Standard Atmosphere 1976 [cm] (1.42 g cm^-2: Anderson et
#: al. 1986, AFGL Atmospheric Constituent Profiles, AFGL-TR-86-0110, the "US standard" model)
PRECIPITABLE_WATER_CM = 1.42

#: water vapour scale height [m]: about 2 km (the AFGL US standard profile's column 1.42 g
#: cm^-2 over its surface density 5.9 g m^-3 is an equivalent height of 2.4 km)
WATER_SCALE_HEIGHT_M = 2000.0

#: air mass at which the band models are matched by a Beer's-law coefficient (ASTM G173's 1.5)
REFERENCE_AIRMASS = 1.5


def absorption_table() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """([BR86] Table 1) wavelengths [nm], a_w [cm^-1], a_o [cm^-1], a_u (as printed)."""
    from skydome.data import load_table

    _, t = load_table("bird_riordan1986_absorption")
    return t[:, 0], t[:, 1], t[:, 2], t[:, 3]


def _interp(wavelength_nm, column: int) -> np.ndarray:
    t = absorption_table()
    # linear between the table's band means, 0 beyond 4000 nm and the 300 nm value held below
    return np.interp(np.asarray(wavelength_nm, dtype=np.float64), t[0], t[column],
                     left=t[column][0], right=0.0)


def water_vapour_band_depth(wavelength_nm, precipitable_water_cm: float, airmass: float) -> np.ndarray:
    """Band optical depth of water vapour along a path of relative air mass ``airmass``:
    0.2385 a_w W m / (1 + 20.07 a_w W m)^0.45 ([BR86] eq. 2-8, the exponent of T_w)."""
    x = _interp(wavelength_nm, 1) * precipitable_water_cm * airmass
    return 0.2385 * x / (1.0 + 20.07 * x) ** 0.45   # [BR86] eq. 2-8


def mixed_gas_band_depth(wavelength_nm, airmass: float) -> np.ndarray:
    """Band optical depth of the uniformly mixed gases along a path of (pressure-corrected)
    air mass ``airmass``: 1.41 a_u m / (1 + 118.93 a_u m)^0.45 ([BR86] eq. 2-11)."""
    y = _interp(wavelength_nm, 3) * airmass
    return 1.41 * y / (1.0 + 118.93 * y) ** 0.45   # [BR86] eq. 2-11


def ozone_cross_section_br86(wavelength_nm) -> np.ndarray:
    """Ozone absorption cross section [m^2] from [BR86]'s a_o [cm^-1 per atm-cm]:
    sigma = a_o / (1000 DU x 2.6867e20 m^-2 per DU) (one atm-cm is the Loschmidt number
    times 1 cm). The table's Huggins band, 300-350 nm."""
    return _interp(wavelength_nm, 2) / (1000.0 * DOBSON_UNIT)


def _check_airmass(reference_airmass: float) -> float:
    return check_number("gas_reference_airmass", reference_airmass, 1.0, 40.0)


def water_vapour(precipitable_water_cm: float = PRECIPITABLE_WATER_CM, top_altitude_m: float = 100e3,
                 *, scale_height_m: float = WATER_SCALE_HEIGHT_M,
                 reference_airmass: float = REFERENCE_AIRMASS):
    """An absorbing water-vapour constituent holding ``precipitable_water_cm`` [cm] in
    [0, 10] on an exponential profile of ``scale_height_m``; its band optical depths matched
    at ``reference_airmass`` (module docstring)."""
    from skydome.atmosphere._constituent import Constituent

    w = check_number("precipitable_water_cm", precipitable_water_cm, 0.0, 10.0, "cm")
    m = _check_airmass(reference_airmass)
    profile = ExponentialProfile(check_number("water_scale_height_m", scale_height_m, 100.0, 2e4, "m"))
    column = profile.column(top_altitude_m)

    def absorption(wl):
        return water_vapour_band_depth(wl, w, m) / m / column   # sea-level coefficient [m^-1]

    return Constituent("water_vapour", scattering=0.0, absorption=absorption, profile=profile,
                       phase="isotropic")


def mixed_gases(top_altitude_m: float = 100e3, *, scale_height_m: float = H_RAYLEIGH,
                reference_airmass: float = REFERENCE_AIRMASS):
    """The uniformly mixed gases (O2 with its A and B bands, CO2) of a sea-level column,
    with the air density (exponential profile of ``scale_height_m``, the Rayleigh one)."""
    from skydome.atmosphere._constituent import Constituent

    m = _check_airmass(reference_airmass)
    profile = ExponentialProfile(scale_height_m)
    column = profile.column(top_altitude_m)

    def absorption(wl):
        return mixed_gas_band_depth(wl, m) / m / column

    return Constituent("mixed_gases", scattering=0.0, absorption=absorption, profile=profile,
                       phase="isotropic")
