"""Aerosols: Mie phase-function approximations (survey eqs. 10-11) and extinction from
turbidity or the Angstrom law.

References
----------
.. [HG41] Henyey & Greenstein, "Diffuse radiation in the galaxy", ApJ 93, 70-83 (1941).
.. [CS92] Cornette & Shanks, "Physically reasonable analytic expression for the
   single-scattering phase function", Applied Optics 31(16), 3152-3160 (1992).
.. [PSS99] Preetham, Shirley & Smits, "A Practical Analytic Model for Daylight",
   SIGGRAPH 99 (turbidity and Angstrom beta, appendix A.2).
.. [Ang29] Angstrom, "On the atmospheric transmission of sun radiation and on dust in
   the air", Geografiska Annaler 11, 156-166 (1929).
"""

from __future__ import annotations

import numpy as np

from skydome._validate import as_wavelengths, check_number

__all__ = [
    "henyey_greenstein",
    "cornette_shanks",
    "henyey_greenstein_survey",
    "cornette_shanks_survey",
    "angstrom_beta_from_turbidity",
    "aerosol_optical_depth",
    "PHASE_FUNCTIONS",
]

PHASE_FUNCTIONS = ("henyey_greenstein", "cornette_shanks", "isotropic")


def _g(g) -> float:
    return check_number("g", g, -1.0, 1.0, low_open=True, high_open=True)


def henyey_greenstein_survey(cos_theta, g) -> np.ndarray:
    """Survey eq. 10 as printed: F_m = (1 - g^2) / (1 + g^2 - 2 g cos theta)^(3/2).

    Its mean over the sphere is 1 (normalisation constant 4 pi); see
    :func:`henyey_greenstein` for the form normalised to 1 over the sphere.
    """
    g = _g(g)
    c = np.asarray(cos_theta, dtype=np.float64)
    return (1.0 - g * g) / (1.0 + g * g - 2.0 * g * c) ** 1.5  # [KRZ06] eq. 10


def henyey_greenstein(cos_theta, g) -> np.ndarray:
    """Henyey-Greenstein phase function normalised over the sphere [sr^-1]:
    p = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^(3/2)) [HG41]; survey eq. 10 / (4 pi)."""
    return henyey_greenstein_survey(cos_theta, g) / (4.0 * np.pi)


def cornette_shanks_survey(cos_theta, g) -> np.ndarray:
    """Survey eq. 11 as printed:
    F_m = 3 (1 - g^2) / (2 (2 + g^2)) (1 + cos^2 theta) / (1 + g^2 - 2 g cos theta)^(3/2).

    Its mean over the sphere is 1 (normalisation constant 4 pi): with the prefactor
    3(1-g^2)/(2(2+g^2)) the integral over the sphere is exactly 4 pi for every g in
    (-1, 1) [CS92]. For g = 0 it is the Rayleigh phase 3/4 (1 + cos^2).
    """
    g = _g(g)
    c = np.asarray(cos_theta, dtype=np.float64)
    return (3.0 * (1.0 - g * g) / (2.0 * (2.0 + g * g))
            * (1.0 + c * c) / (1.0 + g * g - 2.0 * g * c) ** 1.5)  # [KRZ06] eq. 11


def cornette_shanks(cos_theta, g) -> np.ndarray:
    """Cornette-Shanks phase function normalised over the sphere [sr^-1]: survey eq. 11
    divided by 4 pi, i.e. 3 (1 - g^2)(1 + cos^2) / (8 pi (2 + g^2)(1 + g^2 - 2 g cos)^1.5)."""
    return cornette_shanks_survey(cos_theta, g) / (4.0 * np.pi)


def angstrom_beta_from_turbidity(turbidity: float) -> float:
    """Angstrom turbidity coefficient beta (aerosol optical depth at 1 um) from the
    Preetham turbidity T: beta = 0.04608 T - 0.04586 [PSS99] appendix A.2.

    T in [1, 32]. (T is the ratio of the optical thickness of haze plus molecules to that
    of molecules alone; the linear fit is the paper's.)
    """
    t = check_number("turbidity", turbidity, 1.0, 32.0)
    return 0.04608 * t - 0.04586


def aerosol_optical_depth(wavelength_nm, angstrom_beta: float, angstrom_alpha: float = 1.3) -> np.ndarray:
    """Vertical aerosol optical depth by the Angstrom law, tau(lambda) = beta
    (lambda / 1 um)^-alpha [Ang29]. alpha = 1.3 is Angstrom's and Preetham's default."""
    wl = as_wavelengths(wavelength_nm)
    beta = check_number("angstrom_beta", angstrom_beta, 0.0, 10.0)
    alpha = check_number("angstrom_alpha", angstrom_alpha, -1.0, 4.0)
    return (beta * (wl / 1000.0) ** (-alpha)).reshape(np.shape(wavelength_nm))
