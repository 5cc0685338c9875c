"""Rayleigh scattering by air molecules (survey eqs. 2-8).

References
----------
.. [KRZ06] Kment, Rauter & Zotti, "Modelling of Daylight for Computer Graphics", TU Wien
   (2006) -- the survey: eqs. 2-8 and Table 1.
.. [NSTN93] Nishita, Sirai, Tadamura & Nakamae, "Display of the Earth Taking into Account
   Atmospheric Scattering", SIGGRAPH 93.
.. [PR72] Peck & Reeves, "Dispersion of air", JOSA 62(8), 958-962 (1972).
.. [Cid96] Ciddor, "Refractive index of air: new equations for the visible and near
   infrared", Applied Optics 35(9), 1566-1573 (1996).
.. [Pen57] Penndorf, "Tables of the refractive index for standard air and the Rayleigh
   scattering coefficient ...", JOSA 47(2), 176-182 (1957) (King correction factor).
.. [Bat84] Bates, "Rayleigh scattering by air", Planet. Space Sci. 32(6), 785-790 (1984).
"""

from __future__ import annotations

import numpy as np

from skydome._validate import as_wavelengths, check_choice, check_number
from skydome.constants import N_AIR_SURVEY, N_S_SURVEY

__all__ = [
    "refractive_index_air",
    "rayleigh_k",
    "king_factor",
    "rayleigh_scattering_coefficient",
    "rayleigh_phase",
    "rayleigh_phase_normalised",
    "REFRACTIVE_INDEX_METHODS",
]

REFRACTIVE_INDEX_METHODS = ("survey", "peck_reeves1972", "ciddor1996")


def refractive_index_air(wavelength_nm, method: str = "survey") -> np.ndarray:
    """Refractive index of standard dry air, n(lambda).

    Parameters
    ----------
    wavelength_nm : array_like
        Vacuum wavelength [nm], in [200, 4000].
    method : {"survey", "peck_reeves1972", "ciddor1996"}
        ``"survey"``: the constant n = 1.000278 of survey eq. 6 (visible light, [Jac02]).
        ``"peck_reeves1972"``: [PR72] eq. 2 for standard air (15 degC, 101325 Pa, 300 ppm
        CO2), 1e8 (n - 1) = 8060.51 + 2480990 / (132.274 - s^2) + 17455.7 / (39.32957 - s^2),
        s = 1/lambda [um^-1]. ``"ciddor1996"``: [Cid96] eq. 1 for standard air (15 degC,
        101325 Pa, 450 ppm CO2, dry), 1e8 (n - 1) = 5792105 / (238.0185 - s^2)
        + 167917 / (57.362 - s^2).

    Returns
    -------
    ndarray
        n [-], the shape of ``wavelength_nm``.
    """
    check_choice("method", method, REFRACTIVE_INDEX_METHODS)
    wl = as_wavelengths(wavelength_nm)
    shape = np.shape(wavelength_nm)
    if method == "survey":
        n = np.full_like(wl, N_AIR_SURVEY)  # [KRZ06] eq. 6
    else:
        s2 = (1000.0 / wl) ** 2  # sigma^2 [um^-2]
        if method == "peck_reeves1972":
            n = 1.0 + 1e-8 * (8060.51 + 2480990.0 / (132.274 - s2) + 17455.7 / (39.32957 - s2))  # [PR72] eq. 2
        else:
            n = 1.0 + 1e-8 * (5792105.0 / (238.0185 - s2) + 167917.0 / (57.362 - s2))  # [Cid96] eq. 1
    return n.reshape(shape)


def rayleigh_k(refractive_index=N_AIR_SURVEY, number_density_m3: float = N_S_SURVEY) -> np.ndarray:
    """The constant K of survey eq. 4, K = 2 pi^2 (n^2 - 1)^2 / (3 N_s)  [m^3].

    With survey eq. 2, I(lambda, theta) = I0 K rho F_r(theta) / lambda^4 (lambda in m).
    """
    n = np.asarray(refractive_index, dtype=np.float64)
    check_number("number_density_m3", number_density_m3, 0.0, None, "m^-3", low_open=True)
    return 2.0 * np.pi**2 * (n * n - 1.0) ** 2 / (3.0 * number_density_m3)  # [KRZ06] eq. 4


def king_factor(depolarisation: float) -> float:
    """King correction factor F_K = (6 + 3 rho) / (6 - 7 rho) for depolarisation ratio rho
    [Pen57]; 1 for rho = 0 (the survey's eq. 8 omits it)."""
    rho = check_number("depolarisation", depolarisation, 0.0, 0.5)
    return (6.0 + 3.0 * rho) / (6.0 - 7.0 * rho)


def rayleigh_scattering_coefficient(wavelength_nm, *, refractive_index: str | float = "survey",
                                    number_density_m3: float = N_S_SURVEY,
                                    depolarisation: float = 0.0) -> np.ndarray:
    """Rayleigh attenuation (scattering) coefficient beta(lambda) at the reference density.

    Survey eq. 8: beta = 8 pi^3 (n^2 - 1)^2 / (3 N_s lambda^4) = 4 pi K / lambda^4,
    optionally multiplied by the King factor (6 + 3 rho)/(6 - 7 rho) [Pen57].

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength [nm].
    refractive_index : str or float
        A method of :func:`refractive_index_air` or a constant n.
    number_density_m3 : float
        Molecular number density N_s [m^-3]; survey eq. 5: 2.545e25.
    depolarisation : float
        Depolarisation ratio rho in [0, 0.5]; 0 reproduces the survey (Table 1); 0.0279
        is Bates' value for air at 550 nm [Bat84].

    Returns
    -------
    ndarray
        beta [m^-1], the shape of ``wavelength_nm``.

    Examples
    --------
    Survey Table 1: beta(700 nm) = 4.184e-6 m^-1.
    """
    wl = np.asarray(as_wavelengths(wavelength_nm)).reshape(np.shape(wavelength_nm))
    if isinstance(refractive_index, str):
        n = refractive_index_air(wl, refractive_index)
    else:
        n = check_number("refractive_index", refractive_index, 1.0, 1.01, low_open=True)
    lam_m = wl * 1e-9
    k = rayleigh_k(n, number_density_m3)
    return 4.0 * np.pi * k / lam_m**4 * king_factor(depolarisation)  # [KRZ06] eq. 8


def rayleigh_phase(cos_theta) -> np.ndarray:
    """Survey eq. 3: F_r(theta) = 3/4 (1 + cos^2 theta) (normalised to 4 pi over the sphere:
    its mean over all directions is 1)."""
    c = np.asarray(cos_theta, dtype=np.float64)
    return 0.75 * (1.0 + c * c)  # [KRZ06] eq. 3


def rayleigh_phase_normalised(cos_theta, depolarisation: float = 0.0) -> np.ndarray:
    """Rayleigh phase function normalised to 1 over the sphere [sr^-1].

    p(theta) = 3 / (16 pi) (1 + cos^2 theta) for rho = 0, i.e. survey eq. 3 divided by
    4 pi. With depolarisation rho, Chandrasekhar's form
    p = 3 / (16 pi) / (1 + 2 g) ((1 + 3 g) + (1 - g) cos^2 theta),
    g = rho / (2 - rho) (Chandrasekhar 1950, Radiative Transfer, sec. 18; Hansen & Travis
    1974, eq. 2.15), which keeps the normalisation.
    """
    c = np.asarray(cos_theta, dtype=np.float64)
    rho = check_number("depolarisation", depolarisation, 0.0, 0.5)
    gamma = rho / (2.0 - rho)
    return 3.0 / (16.0 * np.pi) * 1.0 / (1.0 + 2.0 * gamma) * ((1.0 + 3.0 * gamma) + (1.0 - gamma) * c * c)
