"""Relative optical air mass: one home for every formula, named after its source.

The relative air mass m(Z) is the optical path of a ray through the atmosphere at zenith
angle Z relative to the vertical path (1 at the zenith, about 38 at the horizon). The
formulas below are empirical fits to the refracted path through a standard atmosphere;
each is valid up to a zenith angle just past 90 deg where its denominator vanishes.
Callers clip or validate the angle as their model prescribes.

References
----------
.. [K66] Kasten, F. (1966). A new table and approximation formula for the relative optical
   air mass. Arch. Meteorol. Geophys. Bioklimatol. B 14, 206-223 (as given by Iqbal 1983,
   An Introduction to Solar Radiation, eq. 5.7.2).
.. [KY89] Kasten, F., Young, A. T. (1989). Revised optical air mass tables and
   approximation formula. Applied Optics 28(22), 4735-4738, eq. 3.
"""

from __future__ import annotations

import numpy as np

from skydome._validate import check_choice

__all__ = ["kasten1966", "kastenyoung1989", "relative_airmass", "MODELS"]


def kasten1966(zenith_deg) -> np.ndarray:
    """``m = 1 / (cos Z + 0.15 (93.885 - Z)^-1.253)``, Z [deg] in [0, 93.885) [K66].

    The form of Preetham et al. 1999 (appendix A.1), Perez et al. 1990 and Radiance's
    gendaylit."""
    z = np.asarray(zenith_deg, dtype=np.float64)
    return 1.0 / (np.cos(np.radians(z)) + 0.15 * (93.885 - z) ** -1.253)   # [K66]


def kastenyoung1989(zenith_deg) -> np.ndarray:
    """``m = 1 / (cos Z + 0.50572 (96.07995 - Z)^-1.6364)``, Z [deg] in [0, 96.07995)
    [KY89] eq. 3 (38.09 at the horizon)."""
    z = np.asarray(zenith_deg, dtype=np.float64)
    return 1.0 / (np.cos(np.radians(z)) + 0.50572 * (96.07995 - z) ** -1.6364)  # [KY89] eq. 3


#: The formulas by name (author + year, as pvlib's ``get_relative_airmass``).
MODELS = {"kasten1966": kasten1966, "kastenyoung1989": kastenyoung1989}


def relative_airmass(zenith_deg, model: str = "kastenyoung1989") -> np.ndarray:
    """Relative optical air mass [-] of the (apparent) zenith angle ``zenith_deg`` [deg] by
    the formula ``model`` ("kastenyoung1989" or "kasten1966"); NaN beyond the formula's
    range (zenith angles past the horizon where its denominator vanishes)."""
    check_choice("model", model, tuple(MODELS))
    z = np.asarray(zenith_deg, dtype=np.float64)
    limit = 96.07995 if model == "kastenyoung1989" else 93.885
    with np.errstate(invalid="ignore", divide="ignore"):
        m = MODELS[model](np.where(z < limit, z, 0.0))
    return np.where((z >= 0.0) & (z < limit), m, np.nan)
