"""Perez, Seals & Michalsky (1993) all-weather sky luminance distribution.

The relative luminance of a sky element at zenith angle zeta and angle gamma from the sun is

    lv(zeta, gamma) = [1 + a exp(b / cos zeta)] [1 + c exp(d gamma) + e cos^2 gamma]

with five coefficients a..e that depend on the solar zenith angle Z, the sky clearness epsilon
and the sky brightness Delta (eight clearness bins of Table 1, with the erratum). The absolute
level comes from the diffuse horizontal illuminance, itself from the diffuse horizontal
irradiance and the Perez et al. (1990) luminous efficacy model: the distribution is scaled so
that its integral over the sky hemisphere, L cos(zeta) dOmega, reproduces it.

The sky parameters come from the measured direct normal and diffuse horizontal irradiances
(Perez et al. 1990), from the corresponding illuminances (as Radiance's ``gendaylit -L`` does),
or are given directly.

References
----------
.. [PSM93] R. Perez, R. Seals, J. Michalsky, "All-weather model for sky luminance distribution -
   preliminary configuration and validation", Solar Energy 50(3) 235-245 (1993); erratum Solar
   Energy 51(5) 423 (1993).
.. [PISMS90] R. Perez, P. Ineichen, R. Seals, J. Michalsky, R. Stewart, "Modeling daylight
   availability and irradiance components from direct and global irradiance", Solar Energy
   44(5) 271-289 (1990).
.. [KY89] F. Kasten, A. T. Young, "Revised optical air mass tables and approximation formula",
   Applied Optics 28(22) 4735-4738 (1989).
.. [K66] F. Kasten, "A new table and approximation formula for the relative optical air mass",
   Arch. Meteorol. Geophys. Bioklimatol. B14, 206-223 (1966).
.. [S71] J. W. Spencer, "Fourier series representation of the position of the sun", Search
   2(5) 172 (1971).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skydome._validate import check_choice, check_number, clamp_cosine
from skydome.constants import SOLAR_CONSTANT_WRC
from skydome.models import Parameter, SkyModel, register

__all__ = [
    "Perez1993",
    "LuminousEfficacy",
    "perez1990_luminous_efficacy",
    "perez1993_coefficients",
    "perez1993_relative_luminance",
    "sky_clearness",
    "sky_brightness",
    "air_mass",
    "eccentricity_correction",
    "precipitable_water_from_dew_point",
    "PerezSkyParameters",
    "perez1993_sky_parameters",
    "perez1993_coefficients_many",
    "clear_sky_limit_exceeded",
    "MAX_DIRECT_NORMAL_IRRADIANCE",
    "MAX_DIRECT_NORMAL_ILLUMINANCE",
]

# Extraterrestrial normal irradiance at 1 au used by [PISMS90] and by Radiance's gendaylit
# [W m^-2]. (The library's default, SOLAR_CONSTANT_GUEYMARD2018 = 1361.1 W m^-2, is not used
# here: the model's epsilon/Delta bins were fitted with the WRC's 1367 W m^-2.)
SOLAR_CONSTANT_PEREZ = SOLAR_CONSTANT_WRC
# Extraterrestrial normal illuminance used by gendaylit to start the -L iteration [lx].
SOLAR_ILLUMINANCE_CONSTANT = 127500.0
# Radiance's luminous efficacy of "white" light, WHTEFFICACY in color.h [lm W^-1].
from skydome.constants import RADIANCE_WHITE_EFFICACY as WHITE_EFFICACY  # noqa: E402
# Sky-clearness bin edges of [PSM93] Table 1 and [PISMS90] Table 4.
EPSILON_EDGES = (1.0, 1.065, 1.23, 1.5, 1.95, 2.8, 4.5, 6.2)
# Limits of the model's parameters, as gendaylit applies them (its check_parametrization).
EPSILON_MAX = 12.01
DELTA_MIN = 0.01
DELTA_MAX = 0.6
# Horizon guard of Radiance's perezlum.cal: cos(zeta) is not taken below 0.01 in the gradation
# term (the last 0.57 deg above the horizon).
COS_ZETA_MIN = 0.01
# The clear-sky limits gendaylit (Radiance 5.4, version 2.x) holds a direct beam to: its
# check_irradiances refuses a direct normal irradiance above its solar constant of 1367 W m^-2
# and its check_illuminances a direct normal illuminance above 127.5 klx (its
# solar_constant_l); both answer with an all-zero "error sky". See clear_sky_limit_exceeded.
MAX_DIRECT_NORMAL_IRRADIANCE = SOLAR_CONSTANT_WRC
MAX_DIRECT_NORMAL_ILLUMINANCE = SOLAR_ILLUMINANCE_CONSTANT
# Default dew point of gendaylit [deg C]: W = exp(0.07 Td - 0.075) = 2 cm.
DEFAULT_DEW_POINT_C = 10.97353115

# Tregenza patch centres used by gendaylit to normalise the distribution (defangle_theta and
# the number of patches per 12-deg band): zenith angle [deg], count. Azimuths are evenly spaced
# from the sun's azimuth.
_TREGENZA_BANDS = ((84.0, 30), (72.0, 30), (60.0, 24), (48.0, 24), (36.0, 18), (24.0, 12),
                   (12.0, 6), (0.0, 1))


# -- tables ---------------------------------------------------------------------------------
def _luminance_table() -> np.ndarray:
    """(8, 5, 4) array of [PSM93] Table 1: bin, coefficient a..e, index 1..4."""
    from skydome.data import load_table

    _, values = load_table("perez1993_coefficients")
    return values[:, 3:23].reshape(8, 5, 4)


def _efficacy_table() -> np.ndarray:
    """(8, 3, 4) array of [PISMS90] Table 4: bin, (global, diffuse, direct), a..d."""
    from skydome.data import load_table

    _, values = load_table("perez1990_efficacy")
    return values[:, 3:15].reshape(8, 3, 4)


def _bin_index(epsilon) -> np.ndarray:
    """0-based clearness bin of ``epsilon`` (bins closed below, open above; last open-ended)."""
    eps = np.asarray(epsilon, dtype=np.float64)
    return np.clip(np.searchsorted(EPSILON_EDGES, eps, side="right") - 1, 0, 7)


# -- atmosphere helpers -----------------------------------------------------------------------
def air_mass(sun_zenith_deg, model: str = "kastenyoung1989"):
    """Relative optical air mass [-].

    Parameters
    ----------
    sun_zenith_deg : array_like
        Solar zenith angle [deg], clipped to [0, 90].
    model : {"kastenyoung1989", "kasten1966"}
        ``kastenyoung1989``: 1 / (cos Z + 0.50572 (96.07995 - Z)^-1.6364) [KY89];
        ``kasten1966``: 1 / (cos Z + 0.15 (93.885 - Z)^-1.253) [K66], the form used by
        [PISMS90] and by Radiance's gendaylit.
    """
    check_choice("air_mass", model, ("kastenyoung1989", "kasten1966"))
    z = np.clip(np.asarray(sun_zenith_deg, dtype=np.float64), 0.0, 90.0)
    from skydome.atmosphere.airmass import MODELS

    return MODELS[model](z)  # [KY89] eq. 3 or [K66]


def eccentricity_correction(day_of_year):
    """Earth-sun distance factor E0 = (r0 / r)^2 of Spencer's series [S71] [-].

    ``day_of_year`` 1..366; day 0 gives the same value as day 365 (the series is periodic).
    """
    from skydome.sun import eccentricity_correction_spencer1971

    return eccentricity_correction_spencer1971(day_of_year)  # [S71]


def precipitable_water_from_dew_point(dew_point_c):
    """Atmospheric precipitable water W [cm] from the surface dew point Td [deg C].

    W = exp(0.07 Td - 0.075) ([PISMS90] eq. 3, after Wright, Perez & Michalsky 1989).
    """
    return np.exp(0.07 * np.asarray(dew_point_c, dtype=np.float64) - 0.075)


def sky_clearness(dni, dhi, sun_zenith_deg):
    """Perez sky clearness epsilon [-] ([PISMS90] eq. 1).

    epsilon = ((Dh + I) / Dh + 1.041 Z^3) / (1 + 1.041 Z^3), Z in radians; Dh = diffuse
    horizontal and I = direct normal irradiance (or illuminance-derived irradiance) [W m^-2].
    Returns +inf where Dh = 0.
    """
    dni = np.asarray(dni, dtype=np.float64)
    dhi = np.asarray(dhi, dtype=np.float64)
    k = 1.041 * np.radians(np.asarray(sun_zenith_deg, dtype=np.float64)) ** 3
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(dhi > 0.0, (dhi + dni) / np.where(dhi > 0.0, dhi, 1.0), np.inf)
    return (ratio + k) / (1.0 + k)  # [PISMS90] eq. 1


def sky_brightness(dhi, sun_zenith_deg, day_of_year=172, air_mass_model="kastenyoung1989"):
    """Perez sky brightness Delta = Dh m / I0 [-] ([PISMS90] eq. 2).

    I0 = 1367 W m^-2 times the eccentricity correction of ``day_of_year`` [S71].
    """
    m = air_mass(sun_zenith_deg, air_mass_model)
    i0 = SOLAR_CONSTANT_PEREZ * eccentricity_correction(day_of_year)
    return np.asarray(dhi, dtype=np.float64) * m / i0  # [PISMS90] eq. 2


class LuminousEfficacy(NamedTuple):
    """Luminous efficacies of [PISMS90] [lm W^-1]."""

    direct: np.ndarray
    diffuse: np.ndarray
    global_horizontal: np.ndarray


def perez1990_luminous_efficacy(epsilon, delta, sun_zenith_deg, precipitable_water_cm=2.0):
    """Perez et al. (1990) luminous efficacy of direct, diffuse and global irradiance.

    Parameters
    ----------
    epsilon : array_like
        Sky clearness [-], >= 1 (values above the last bin edge use the last bin).
    delta : array_like
        Sky brightness [-], > 0.
    sun_zenith_deg : array_like
        Solar zenith angle [deg], in [0, 90].
    precipitable_water_cm : array_like
        Atmospheric precipitable water W [cm], >= 0 (default 2 cm, gendaylit's default).

    Returns
    -------
    LuminousEfficacy
        ``direct`` (per unit direct normal irradiance), ``diffuse`` (per unit diffuse
        horizontal irradiance) and ``global_horizontal`` [lm W^-1], broadcast arrays.

    Notes
    -----
    global, diffuse: K = a + b W + c cos Z + d ln Delta ([PISMS90] eqs. 6-7);
    direct: K = a + b W + c exp(5.73 Z - 5) + d Delta ([PISMS90] eq. 8), Z in radians;
    coefficients from Table 4. The direct efficacy is floored at 0 (as gendaylit does): the
    fit turns negative only far outside its data (e.g. bin 1 at Z > 85 deg).
    """
    eps = np.asarray(epsilon, dtype=np.float64)
    dl = np.asarray(delta, dtype=np.float64)
    z = np.asarray(sun_zenith_deg, dtype=np.float64)
    w = np.asarray(precipitable_water_cm, dtype=np.float64)
    if np.any(~np.isfinite(eps)) or np.any(eps < 1.0):
        raise ValueError(f"epsilon = {eps.min():g} is out of range [1, inf)")
    if np.any(~np.isfinite(dl)) or np.any(dl <= 0.0):
        raise ValueError(f"delta = {dl.min():g} is out of range (0, inf)")
    if np.any(~np.isfinite(z)) or np.any(z < 0.0) or np.any(z > 90.0):
        raise ValueError(f"sun_zenith_deg = {z.max():g} deg is out of range [0, 90] deg")
    if np.any(~np.isfinite(w)) or np.any(w < 0.0):
        raise ValueError(f"precipitable_water_cm = {w.min():g} cm is out of range [0, inf) cm")
    tab = _efficacy_table()[_bin_index(eps)]  # (..., 3, 4)
    zr = np.radians(z)
    g = tab[..., 0, :]
    f = tab[..., 1, :]
    s = tab[..., 2, :]
    k_glob = g[..., 0] + g[..., 1] * w + g[..., 2] * np.cos(zr) + g[..., 3] * np.log(dl)  # eq. 6
    k_diff = f[..., 0] + f[..., 1] * w + f[..., 2] * np.cos(zr) + f[..., 3] * np.log(dl)  # eq. 7
    k_dir = s[..., 0] + s[..., 1] * w + s[..., 2] * np.exp(5.73 * zr - 5.0) + s[..., 3] * dl  # eq. 8
    return LuminousEfficacy(direct=np.maximum(k_dir, 0.0), diffuse=k_diff,
                            global_horizontal=k_glob)


def clear_sky_limit_exceeded(dni, dhi, sun_zenith_deg, day_of_year=172,
                             dew_point_c=DEFAULT_DEW_POINT_C, dni_illuminance=None):
    """Where a direct beam is brighter than a clear sky allows, by gendaylit's rule.

    Radiance's gendaylit (version 2.x, ``-W`` input; ``gendaylit.c``: check_irradiances,
    check_parametrization, direct_n_effi_PEREZ, check_illuminances) refuses an hour, printing
    its all-zero "error sky", when

    1. the direct normal irradiance I exceeds its solar constant, I > 1367 W m^-2; or
    2. the direct normal illuminance it derives, I K_b, exceeds its illuminance solar
       constant, I K_b > 127 500 lx, with K_b the direct luminous efficacy of [PISMS90]
       eq. 8 (Table 4, floored at 0) for epsilon and Delta from eqs. 1-2, computed as
       gendaylit does: the sun's altitude capped at 87 deg (Z >= 3 deg), Kasten's 1966 air
       mass [K66], 1367 W m^-2 times Spencer's eccentricity correction [S71], epsilon
       clamped to [1, 12.009] (an epsilon of infinity, Dh = 0, becomes 12.009) and Delta to
       [0.01, 0.6], W = exp(0.07 Td - 0.075) [cm] (gendaylit's default Td gives 2 cm).

    Rule 2 is what refuses a clear beam at a low sun: at 20 deg elevation 1358 W m^-2 with
    Dh = 20 W m^-2 gives K_b = 95.9 lm/W and 130.2 klx (refused), with Dh = 100 W m^-2
    K_b = 90.9 lm/W and 123.5 klx (accepted; day 1). Negative irradiances count as 0 (gendaylit
    sets them to 0 with a warning). With ``dni_illuminance`` given (input ``-L``) rule 2 is
    applied to it directly. (gendaylit's other error skies, zero irradiance with the sun up
    and a positive Perez b, are not weather that cannot be; :class:`Perez1993` handles b > 0
    through ``invalid``.)

    Parameters
    ----------
    dni, dhi : array_like
        Direct normal and diffuse horizontal irradiance [W m^-2].
    sun_zenith_deg : array_like
        True solar zenith angle [deg].
    day_of_year : array_like
        1..366 (the eccentricity correction of I0 in Delta).
    dew_point_c : array_like
        Surface dew point [deg C].
    dni_illuminance : array_like, optional
        Direct normal illuminance [lx] when it was given instead of derived.

    Returns
    -------
    numpy.ndarray of bool
        True where the hour is beyond the clear-sky limit (broadcast shape).
    """
    dni, dhi, z, doy, td = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (
        dni, dhi, sun_zenith_deg, day_of_year, dew_point_c)))
    dni = np.where(dni > 0.0, dni, 0.0)  # gendaylit: "direct irradiance < 0. Using 0.0"
    dhi = np.where(dhi > 0.0, dhi, 0.0)
    over = dni > MAX_DIRECT_NORMAL_IRRADIANCE  # rule 1 (check_irradiances)
    zc = np.clip(np.nan_to_num(z, nan=90.0), 3.0, 90.0)  # altitude <= 87 deg; air mass Z <= 90
    m = air_mass(zc, "kasten1966")  # [K66], gendaylit's air_mass()
    i0 = SOLAR_CONSTANT_PEREZ * eccentricity_correction(doy)  # [S71]
    delta = np.clip(dhi * m / i0, DELTA_MIN, DELTA_MAX)  # [PISMS90] eq. 2, clamped
    with np.errstate(invalid="ignore"):
        eps = sky_clearness(dni, dhi, zc)  # [PISMS90] eq. 1
    eps = np.where(np.isnan(eps) | (eps < 1.0), 1.0,
                   np.where(eps > EPSILON_MAX, EPSILON_MAX - 0.001, eps))
    if dni_illuminance is None:
        w = precipitable_water_from_dew_point(td)  # [PISMS90] eq. 3
        e_dir = dni * perez1990_luminous_efficacy(eps, delta, zc, w).direct  # eq. 8
    else:
        e_dir = np.broadcast_to(np.asarray(dni_illuminance, dtype=np.float64), dni.shape)
    return over | (e_dir > MAX_DIRECT_NORMAL_ILLUMINANCE)  # rule 2 (check_illuminances)


# -- the luminance distribution ---------------------------------------------------------------
def perez1993_coefficients(sun_zenith_rad: float, epsilon: float, delta: float,
                           delta_floor: bool = True) -> tuple[float, float, float, float, float]:
    """Coefficients (a, b, c, d, e) of the [PSM93] distribution.

    Parameters
    ----------
    sun_zenith_rad : float
        Solar zenith angle Z [rad].
    epsilon : float
        Sky clearness [-], in [1, 12.01].
    delta : float
        Sky brightness [-], in [0.01, 0.6].
    delta_floor : bool
        Raise Delta to 0.2 inside the clearness range 1.065 < epsilon < 2.8 (the adjustment
        Radiance's gendaylit applies before evaluating the coefficients; see Notes).

    Notes
    -----
    Bins 2-8: x = x1 + x2 Z + Delta (x3 + x4 Z) ([PSM93] eq. 2 and Table 1). Bin 1:
    c = exp((Delta (c1 + c2 Z))^c3) - c4 and d = -exp(Delta (d1 + d2 Z)) + d3 + Delta d4.
    Without the Delta floor the intermediate bins give b > 0 and a negative gradation term for
    low Delta (e.g. epsilon = 1.5, Delta = 0.05, Z = 30 deg: a = -0.89, b = +0.18, so
    1 + a exp(b / cos zeta) = -0.07 at the zenith), which is why gendaylit applies it.
    """
    eps = float(epsilon)
    dl = float(delta)
    z = float(sun_zenith_rad)
    if delta_floor and 1.065 < eps < 2.8 and dl < 0.2:
        dl = 0.2
    k = int(_bin_index(eps))
    x = _luminance_table()[k]
    lin = x[:, 0] + x[:, 1] * z + dl * (x[:, 2] + x[:, 3] * z)  # [PSM93] eq. 2
    a, b, c, d, e = (float(v) for v in lin)
    if k == 0:  # [PSM93] Table 1, first bin: special forms of c and d
        c = math.exp((dl * (x[2, 0] + x[2, 1] * z)) ** x[2, 2]) - x[2, 3]
        d = -math.exp(dl * (x[3, 0] + x[3, 1] * z)) + x[3, 2] + dl * x[3, 3]
    return a, b, c, d, e


def perez1993_relative_luminance(cos_zeta, cos_gamma, coefficients):
    """Relative luminance lv of [PSM93] eq. 1 (unnormalised, dimensionless).

    Parameters
    ----------
    cos_zeta : array_like
        Cosine of the element's zenith angle; values below 0.01 are taken as 0.01 in the
        gradation term (Radiance perezlum.cal's horizon guard).
    cos_gamma : array_like
        Cosine of the angle between the element and the sun.
    coefficients : tuple of 5 floats
        (a, b, c, d, e) from :func:`perez1993_coefficients`.
    """
    a, b, c, d, e = coefficients
    cz = np.maximum(np.asarray(cos_zeta, dtype=np.float64), COS_ZETA_MIN)
    cg = clamp_cosine(np.asarray(cos_gamma, dtype=np.float64))
    gamma = np.arccos(cg)
    gradation = 1.0 + a * np.exp(b / cz)  # [PSM93] eq. 1, first factor
    indicatrix = 1.0 + c * np.exp(d * gamma) + e * cg * cg  # [PSM93] eq. 1, second factor
    return gradation * indicatrix


def _horizontal_integral(sun_zenith_rad: float, coefficients, method: str) -> float:
    """Integral of lv cos(zeta) dOmega over the sky hemisphere [sr], in the sun's frame."""
    sz, cz_sun = math.sin(sun_zenith_rad), math.cos(sun_zenith_rad)
    if method == "gendaylit":
        # gendaylit integ_lv: 145 Tregenza patch centres, sum lv cos(theta) * 2 pi / 145.
        theta, phi = [], []
        for th, n in _TREGENZA_BANDS:
            theta.extend([th] * n)
            phi.extend(np.arange(n) * 360.0 / n)
        th = np.radians(np.array(theta))
        ph = np.radians(np.array(phi))
        cg = cz_sun * np.cos(th) + sz * np.sin(th) * np.cos(ph)
        lv = perez1993_relative_luminance(np.cos(th), cg, coefficients)
        return float(np.sum(lv * np.cos(th)) * (2.0 * np.pi / 145.0))
    # The horizontal plane's nodes of skydome.illuminance (Gauss-Legendre in the zenith
    # angle, 128 nodes, times the midpoint rule over 256 azimuths relative to the sun);
    # the weights include cos(zeta).
    from skydome.illuminance import sky_quadrature

    d, w = sky_quadrature((0.0, 0.0, 1.0), 128, 256)
    cg = cz_sun * d[:, 2] + sz * d[:, 1]          # the sun at azimuth 0 (+y)
    lv = np.maximum(perez1993_relative_luminance(d[:, 2], cg, coefficients), 0.0)
    return float(np.sum(lv * w))


@register
class Perez1993(SkyModel):
    """Perez, Seals & Michalsky (1993) all-weather sky luminance distribution.

    Parameters
    ----------
    sun : skydome.Sun
        Position of the sun. With the sun below the horizon (elevation < 0) the model does
        not apply and the sky is black (luminance 0 everywhere), as gendaylit's "error sky".
    epsilon, delta : float, optional
        Sky clearness [-] in [1, 12.01] and sky brightness [-] in [0.01, 0.6], given together.
        The absolute level then follows from the implied irradiances,
        Dh = Delta I0 / m and I = Dh (epsilon - 1)(1 + 1.041 Z^3).
    dni, dhi : float, optional
        Direct normal irradiance [W m^-2] in [0, 1415] and diffuse horizontal irradiance
        [W m^-2] in [0, 1000], given together.
    dni_illuminance, dhi_illuminance : float, optional
        Direct normal and diffuse horizontal illuminance [lx], given together; epsilon and
        Delta are found by the fixed-point iteration of gendaylit -L (irradiance = illuminance /
        efficacy, 9 iterations). Exactly one of the three pairs must be given.
    day_of_year : int
        Day of the year 1..366 for the eccentricity correction of I0 [S71] (default 172).
    dew_point_c : float
        Surface dew point [deg C] in [-40, 40]; W = exp(0.07 Td - 0.075) [cm] enters the
        efficacy model. The default 10.9735 deg C gives W = 2 cm, as gendaylit.
    air_mass : {"kastenyoung1989", "kasten1966"}
        Air mass formula for Delta. gendaylit and [PISMS90] use Kasten 1966.
    scaling : {"perez1990", "white179", "relative"}
        Absolute level: ``perez1990`` scales to the diffuse horizontal illuminance
        Dh x K_diffuse ([PISMS90] efficacy) or to ``dhi_illuminance`` when given;
        ``white179`` uses Dh x 179 lm/W (Radiance's WHTEFFICACY; gendaylit -O1 x 179);
        ``relative`` returns lv / lv(zenith) (dimensionless, 1 at the zenith).
    normalization : {"quadrature", "gendaylit"}
        How the hemispherical integral of L cos(zeta) is taken: an accurate 128 x 256
        quadrature (:func:`skydome.illuminance.sky_quadrature`), or gendaylit's sum over the 145 Tregenza patch
        centres, sum lv cos(theta) 2 pi / 145 (see docs: up to a few per cent different).
    invalid : {"raise", "black"}
        For weather that cannot be (a direct beam beyond the clear-sky limit, by gendaylit's
        rule: :func:`clear_sky_limit_exceeded`) and for inputs where the fitted
        coefficients give no meaningful sky (b > 0, i.e. a
        luminance that grows without bound towards the horizon, which gendaylit answers with
        an all-zero "error sky"; or a distribution that is negative over the whole sky):
        ``raise`` a ValueError naming epsilon, Delta, Z and b, or return a ``black`` sky
        (luminance 0, as gendaylit). Where the formula is negative over only part of the
        sky, those directions get 0 (as gendaymtx does) and the normalisation uses the
        clipped distribution.

    Attributes
    ----------
    sky_clearness, sky_brightness : float
        epsilon and Delta actually used (after gendaylit's limits [1, 12.01), [0.01, 0.6]).
    coefficients : tuple
        (a, b, c, d, e) of eq. 1.
    diffuse_illuminance, direct_illuminance : float
        Horizontal diffuse and normal direct illuminance [lx] (nan for ``relative``).
    diffuse_irradiance, direct_irradiance : float
        Horizontal diffuse and normal direct irradiance [W m^-2].
    zenith_luminance : float
        Luminance at the zenith [cd m^-2].

    References
    ----------
    [PSM93] eqs. 1-2 and Table 1 (with erratum); [PISMS90] eqs. 1-3, 6-8 and Table 4.
    """

    name = "perez1993"
    reference = ("R. Perez, R. Seals, J. Michalsky, 'All-weather model for sky luminance "
                 "distribution - preliminary configuration and validation', Solar Energy 50(3) "
                 "235-245 (1993); erratum Solar Energy 51(5) 423 (1993)")
    native = "luminance"
    summary = "Perez all-weather sky luminance from irradiances, illuminances or (epsilon, Delta)"
    parameters = (
        Parameter("epsilon", "", None, 1.0, EPSILON_MAX, "sky clearness (with delta)"),
        Parameter("delta", "", None, DELTA_MIN, DELTA_MAX, "sky brightness (with epsilon)"),
        Parameter("dni", "W/m^2", None, 0.0, 1415.0, "direct normal irradiance (with dhi)"),
        Parameter("dhi", "W/m^2", None, 0.0, 1000.0, "diffuse horizontal irradiance (with dni)"),
        Parameter("dni_illuminance", "lx", None, 0.0, 135000.0,
                  "direct normal illuminance (with dhi_illuminance)"),
        Parameter("dhi_illuminance", "lx", None, 0.0, 150000.0,
                  "diffuse horizontal illuminance (with dni_illuminance)"),
        Parameter("day_of_year", "", 172, 1, 366, "day of year for the sun-earth distance",
                  kind="int"),
        Parameter("dew_point_c", "degC", DEFAULT_DEW_POINT_C, -40.0, 40.0,
                  "surface dew point (precipitable water for the efficacy model)"),
        Parameter("air_mass", "", "kastenyoung1989", doc="air mass formula", kind="choice",
                  choices=("kastenyoung1989", "kasten1966")),
        Parameter("scaling", "", "perez1990", doc="absolute scaling", kind="choice",
                  choices=("perez1990", "white179", "relative")),
        Parameter("normalization", "", "quadrature", doc="hemispherical integral",
                  kind="choice", choices=("quadrature", "gendaylit")),
        Parameter("invalid", "", "raise", doc="what to do outside the fit's domain",
                  kind="choice", choices=("raise", "black")),
    )

    sun_elevation_range_deg = (0.0, 90.0)
    sun_outside_range = "black"    # gendaylit's "error sky"

    def _setup(self, p, params):
        pairs = {"epsilon/delta": ("epsilon", "delta"), "dni/dhi": ("dni", "dhi"),
                 "dni_illuminance/dhi_illuminance": ("dni_illuminance", "dhi_illuminance")}
        given = []
        for label, (k1, k2) in pairs.items():
            n = (p[k1] is not None) + (p[k2] is not None)
            if n == 1:
                raise ValueError(f"{k1} and {k2} must be given together")
            if n == 2:
                given.append(label)
        if len(given) != 1:
            raise ValueError("give exactly one of epsilon/delta, dni/dhi or "
                             f"dni_illuminance/dhi_illuminance (got {', '.join(given) or 'none'})")
        for k, v in p.items():
            setattr(self, k, v)
        self.input_mode = given[0]
        self._sky_parameters()

    # -- set-up: sky parameters, coefficients, scale ----------------------------------------
    def _sky_parameters(self) -> None:
        self.precipitable_water_cm = float(precipitable_water_from_dew_point(self.dew_point_c))
        self._black = self.sun.elevation_deg < 0.0
        z_deg = min(max(self.sun.zenith_deg, 0.0), 90.0)
        self._sun_zenith_deg = z_deg
        nan = float("nan")
        self.diffuse_irradiance = self.direct_irradiance = nan
        self.diffuse_illuminance = self.direct_illuminance = nan
        self.sky_clearness = self.sky_brightness = nan
        self.coefficients = (nan,) * 5
        self.zenith_luminance = 0.0
        self._scale = 0.0
        self.valid = True
        if self._black:
            self.diffuse_irradiance = self.direct_irradiance = 0.0
            self.diffuse_illuminance = self.direct_illuminance = 0.0
            return
        m = float(air_mass(z_deg, self.air_mass))
        i0 = SOLAR_CONSTANT_PEREZ * float(eccentricity_correction(self.day_of_year))
        k3 = 1.041 * math.radians(z_deg) ** 3
        W = self.precipitable_water_cm

        def limits(eps, dl):  # gendaylit check_parametrization
            eps = 1.0 if eps < 1.0 else (EPSILON_MAX - 0.001 if eps > EPSILON_MAX else eps)
            return eps, min(max(dl, DELTA_MIN), DELTA_MAX)

        e_diff = None  # diffuse horizontal illuminance when given directly
        if self.input_mode == "epsilon/delta":
            eps, dl = limits(self.epsilon, self.delta)
            dhi = dl * i0 / m  # inverse of [PISMS90] eq. 2
            dni = dhi * (eps - 1.0) * (1.0 + k3)  # inverse of [PISMS90] eq. 1
        elif self.input_mode == "dni/dhi":
            dni, dhi = self.dni, self.dhi
            eps, dl = limits(float(sky_clearness(dni, dhi, z_deg)), dhi * m / i0)
        else:
            e_dir, e_diff = self.dni_illuminance, self.dhi_illuminance
            # gendaylit illu_to_irra_index: start from the extraterrestrial efficacy, then
            # alternate efficacy and (epsilon, Delta); its loop always runs 9 times.
            dhi = e_diff * SOLAR_CONSTANT_PEREZ / SOLAR_ILLUMINANCE_CONSTANT
            dni = e_dir * SOLAR_CONSTANT_PEREZ / SOLAR_ILLUMINANCE_CONSTANT
            eps, dl = limits(float(sky_clearness(dni, dhi, z_deg)), dhi * m / i0)
            for _ in range(9):
                eff = perez1990_luminous_efficacy(eps, dl, z_deg, W)
                dhi = e_diff / float(eff.diffuse) if eff.diffuse > 0 else 0.0
                dni = e_dir / float(eff.direct) if eff.direct >= 0.1 else 0.0
                eps, dl = limits(float(sky_clearness(dni, dhi, z_deg)), dhi * m / i0)
        self.sky_clearness, self.sky_brightness = eps, dl
        self.diffuse_irradiance, self.direct_irradiance = float(dhi), float(dni)
        # gendaylit's clear-sky limit (clear_sky_limit_exceeded) on weather: with -L it checks
        # only the given direct illuminance, with -W the irradiance and the derived
        # illuminance. (gendaylit -P applies it to the irradiances implied by epsilon and
        # Delta too; here (epsilon, Delta) describe a sky, not weather, and are not checked.)
        by_lux = self.input_mode == "dni_illuminance/dhi_illuminance"
        beyond = self.input_mode != "epsilon/delta" and bool(clear_sky_limit_exceeded(
            0.0 if by_lux else dni, dhi, self.sun.zenith_deg, self.day_of_year,
            self.dew_point_c, self.dni_illuminance if by_lux else None))
        if beyond:
            self.valid = False
            if self.invalid == "raise":
                given = (f"dni_illuminance = {self.dni_illuminance:g} lx" if by_lux else
                         f"dni = {dni:g} W/m^2 with dhi = {dhi:g} W/m^2")
                raise ValueError(
                    f"perez1993: {given} at sun elevation {self.sun.elevation_deg:g} deg is "
                    "beyond the clear-sky limit (direct normal irradiance <= "
                    f"{MAX_DIRECT_NORMAL_IRRADIANCE:g} W/m^2 and direct normal illuminance, "
                    "by the Perez et al. 1990 efficacy, <= "
                    f"{MAX_DIRECT_NORMAL_ILLUMINANCE:g} lx: gendaylit's rule); pass "
                    "invalid='black' for gendaylit's zero sky")
            self.diffuse_illuminance = self.direct_illuminance = 0.0
            self._black = True
            return
        z = math.radians(z_deg)
        self.coefficients = perez1993_coefficients(z, eps, dl)
        lv_zenith = float(perez1993_relative_luminance(1.0, math.cos(z), self.coefficients))
        integral = _horizontal_integral(z, self.coefficients, self.normalization)
        b = self.coefficients[1]
        if b > 0.0 or integral <= 0.0 or (self.scaling == "relative" and lv_zenith <= 0.0):
            self.valid = False
            if self.invalid == "raise":
                raise ValueError(
                    f"perez1993: epsilon = {eps:g}, delta = {dl:g} at sun zenith {z_deg:g} deg "
                    f"is outside the fitted model's domain (b = {b:.4g} > 0 or a sky that is "
                    "negative everywhere); pass invalid='black' for gendaylit's zero sky")
            self.diffuse_illuminance = self.direct_illuminance = 0.0
            self._black = True
            return
        if self.scaling == "relative":
            self._scale = 1.0 / lv_zenith if lv_zenith > 0 else 0.0
            self.zenith_luminance = 1.0
            return
        eff = perez1990_luminous_efficacy(eps, dl, z_deg, W)
        if e_diff is None:
            k_diff = float(eff.diffuse) if self.scaling == "perez1990" else WHITE_EFFICACY
            k_dir = float(eff.direct) if self.scaling == "perez1990" else WHITE_EFFICACY
            self.diffuse_illuminance = max(dhi * k_diff, 0.0)
            self.direct_illuminance = max(dni * k_dir, 0.0)
        else:
            self.diffuse_illuminance = float(e_diff)
            self.direct_illuminance = float(self.dni_illuminance)
        self._scale = self.diffuse_illuminance / integral if integral > 0 else 0.0
        self.zenith_luminance = max(self._scale * lv_zenith, 0.0)

    # -- evaluation -----------------------------------------------------------------------
    def luminance(self, directions) -> np.ndarray:
        """Sky luminance [cd m^-2] arriving from ``directions`` (unit vectors (..., 3), ENU).

        Directions below the horizon (z < 0) get 0; within 0.57 deg above it the gradation
        term uses cos(zeta) = 0.01 (perezlum.cal). ``scaling="relative"`` returns lv/lv(zenith)
        instead (dimensionless). Any negative value of the fitted formula is clipped to 0.
        """
        from skydome.models.analytic import _kernels_analytic as K

        flat, lead = K.flat_directions(directions)
        if self._black or self._scale == 0.0:
            return np.zeros(lead)
        a, b, c, d, e = (float(v) for v in self.coefficients)
        s = np.asarray(self.sun.direction, dtype=np.float64)
        # [PSM93] eq. 1 in a parallel numba kernel; _luminance_reference is the numpy form.
        return K.perez1993(flat, s, a, b, c, d, e, COS_ZETA_MIN, float(self._scale)).reshape(lead)

    def _luminance_reference(self, directions) -> np.ndarray:
        """numpy reference implementation of :meth:`luminance` (same result, slower)."""
        d = self._directions(directions)
        out = np.zeros(d.shape[:-1])
        if self._black or self._scale == 0.0:
            return out
        up = d[..., 2] >= 0.0
        cg = d @ self.sun.direction
        lv = perez1993_relative_luminance(d[..., 2], cg, self.coefficients)
        out[up] = np.maximum(lv[up] * self._scale, 0.0)
        return out

    def sun_luminance(self) -> float:
        """Mean luminance of the solar disc [cd m^-2]: direct normal illuminance spread over
        the disc's solid angle (as gendaylit's 'solar source'); 0 with the sun below the
        horizon or for ``scaling="relative"``."""
        if self._black or self.scaling == "relative":
            return 0.0
        return float(self.direct_illuminance / self.sun.solid_angle_sr)


# -- many suns and weather states at once ---------------------------------------------------
class PerezSkyParameters(NamedTuple):
    """Per-sky inputs of [PSM93] for many hours (arrays of one shape)."""

    sun_zenith_deg: np.ndarray  # zenith used by the distribution (clamped to [3, 90] deg)
    epsilon: np.ndarray  # sky clearness [-]
    delta: np.ndarray  # sky brightness [-]
    bin: np.ndarray  # 0-based clearness bin
    diffuse_illuminance: np.ndarray  # horizontal [lx]
    direct_illuminance: np.ndarray  # normal [lx]


def perez1993_sky_parameters(dni, dhi, sun_zenith_deg, day_of_year, dew_point_c=11.0,
                             air_mass_model: str = "kasten1966") -> PerezSkyParameters:
    """Sky clearness, brightness and illuminances of many hours from DNI and DHI.

    The conventions are gendaymtx's (Radiance 5.4): the solar zenith angle is clamped to
    [3, 90] deg (the fit does not reach the zenith; a sun below the horizon counts as on it),
    epsilon to [1, 11.9] and Delta to [0.01, 0.6]; the air mass is Kasten 1966 [K66] and the
    extraterrestrial irradiance 1367 W m^-2 times Spencer's eccentricity correction [S71].

    Parameters
    ----------
    dni, dhi : array_like
        Direct normal and diffuse horizontal irradiance [W m^-2], >= 0.
    sun_zenith_deg : array_like
        True solar zenith angle [deg].
    day_of_year : array_like
        1..366.
    dew_point_c : array_like
        Surface dew point [deg C] (gendaymtx's default 11 deg C for .wea input).
    air_mass_model : {"kasten1966", "kastenyoung1989"}

    Returns
    -------
    PerezSkyParameters
        Broadcast arrays; illuminances from the [PISMS90] efficacies (eqs. 7-8, Table 4).
    """
    dni, dhi, z, doy, td = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (
        dni, dhi, sun_zenith_deg, day_of_year, dew_point_c)))
    for name, v in (("dni", dni), ("dhi", dhi)):
        if np.any(~np.isfinite(v)) or np.any(v < 0.0):
            raise ValueError(f"{name} must be finite and >= 0 W/m^2 (min {np.nanmin(v):g})")
    zc = np.clip(z, 3.0, 90.0)  # gendaymtx ComputeSky: 3 deg <= Z <= 90 deg
    m = air_mass(zc, air_mass_model)
    i0 = SOLAR_CONSTANT_PEREZ * eccentricity_correction(doy)
    delta = np.clip(dhi * m / i0, DELTA_MIN, DELTA_MAX)  # [PISMS90] eq. 2
    eps = np.clip(sky_clearness(dni, dhi, zc), 1.0, 11.9)  # [PISMS90] eq. 1
    w = precipitable_water_from_dew_point(td)  # [PISMS90] eq. 3
    eff = perez1990_luminous_efficacy(eps, delta, zc, w)
    return PerezSkyParameters(zc, eps, delta, _bin_index(eps), dhi * eff.diffuse,
                              dni * eff.direct)


def perez1993_coefficients_many(sun_zenith_rad, epsilon, delta,
                                delta_floor: bool = True) -> np.ndarray:
    """(..., 5) coefficients a..e of [PSM93] eq. 2 for arrays of skies (vectorised
    :func:`perez1993_coefficients`, same formulas, same Delta floor)."""
    z, eps, dl = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (
        sun_zenith_rad, epsilon, delta)))
    k = _bin_index(eps)
    if delta_floor:
        dl = np.where((eps > 1.065) & (eps < 2.8) & (dl < 0.2), 0.2, dl)
    x = _luminance_table()[k]  # (..., 5, 4)
    zz = z[..., None]
    out = x[..., 0] + x[..., 1] * zz + dl[..., None] * (x[..., 2] + x[..., 3] * zz)  # eq. 2
    first = k == 0  # [PSM93] Table 1, first bin: special forms of c and d
    if np.any(first):
        xf, zf, df = x[first], z[first], dl[first]
        out[first, 2] = np.exp((df * (xf[:, 2, 0] + xf[:, 2, 1] * zf)) ** xf[:, 2, 2]) - xf[:, 2, 3]
        out[first, 3] = (-np.exp(df * (xf[:, 3, 0] + xf[:, 3, 1] * zf)) + xf[:, 3, 2]
                         + df * xf[:, 3, 3])
    return out
