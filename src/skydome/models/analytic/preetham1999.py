"""Preetham, Shirley & Smits (1999): "A Practical Analytic Model for Daylight".

The sky is a Perez-form fit (luminance Y and chromaticity x, y) to simulated skies, with
coefficients linear in the turbidity T (Appendix A.2); the spectrum is rebuilt from (x, y)
through the CIE daylight basis. The sun is the extraterrestrial spectrum attenuated by
Rayleigh scattering, Angstrom aerosol extinction, ozone, mixed gases and water vapour
(Appendix A.1, absorption coefficients of Table 2 after Iqbal 1983). Aerial perspective
follows section 5: exponential densities for molecules and haze over a flat earth,
extinction in closed form and in-scattering of sun and sky light along the path.

Conventions: angles in the East-North-Up frame, azimuth from north towards east; the
turbidity T is dimensionless; wavelengths in nm; spectral radiance in W m^-2 sr^-1 nm^-1;
luminance in cd m^-2.

Valid range (the paper's fits): T in [2, 10] and the sun at or above the horizon. Anything
else raises ValueError (see :class:`Preetham1999`). Directions below the horizon get zero
radiance (the model describes the sky dome only).

References
----------
.. [PSS99] A. J. Preetham, P. Shirley, B. Smits, "A Practical Analytic Model for Daylight",
   Proc. SIGGRAPH 99, pp. 91-100 (1999). Section 3 (sun), section 4 (sky), section 5
   (aerial perspective), Appendices A.1 (sun attenuation), A.2 (distribution coefficients
   and zenith values), A.3 (scattering by molecules and haze), Table 2.
.. [PSI93] R. Perez, R. Seals, J. Michalsky, "All-weather model for sky luminance
   distribution - preliminary configuration and validation", Solar Energy 50(3) (1993).
.. [Iqb83] M. Iqbal, "An Introduction to Solar Radiation", Academic Press (1983),
   chapter 6 (transmittances, absorption coefficients pp. 127-131).
.. [McC76] E. J. McCartney, "Optics of the Atmosphere", Wiley (1976), eqs. 4-48, 4-55,
   6-24, 6-30.
.. [ZWP07] G. Zotti, A. Wilkie, W. Purgathofer, "A Critical Review of the Preetham Skylight
   Model", WSCG 2007 Short Communications, pp. 23-30.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_choice, check_int, check_number
from skydome.data import load_table
from skydome.models import Parameter, SkyModel, register

__all__ = [
    "Preetham1999",
    "TURBIDITY_RANGE",
    "perez_coefficients",
    "perez_function",
    "zenith_luminance",
    "zenith_chromaticity",
    "relative_air_mass",
    "sun_transmittance",
    "extraterrestrial_sun_radiance",
    "sun_radiance",
    "rayleigh_coefficient",
    "rayleigh_angular_coefficient",
    "mie_coefficient",
    "mie_angular_coefficient",
    "mie_eta",
    "aerial_perspective",
    "ALPHA_HAZE",
    "ALPHA_MOLECULES",
]

#: Valid turbidity range of the paper's fits [PSS99] section 4 / Appendix A.2.
TURBIDITY_RANGE = (2.0, 10.0)

#: Wavelength range of Table 2 (absorption coefficients, K) [nm].
_TABLE2_RANGE = (380.0, 780.0)

# Sun attenuation constants [PSS99] Appendix A.1 (after [Iqb83]).
_RAYLEIGH_TAU = 0.008735          # Rayleigh optical depth at 1 um, exponent -4.08
_RAYLEIGH_EXP = 4.08
_ANGSTROM_ALPHA = 1.3             # wavelength exponent of the aerosol optical depth
OZONE_CM = 0.35                   # reduced ozone thickness l [cm NTP]
WATER_CM = 2.0                    # precipitable water vapour w [cm]

# Molecular scattering constants [PSS99] A.3 (after [McC76]).
_N_AIR = 1.0003                   # refractive index of air
_N_MOLECULES = 2.545e25           # molecules per m^3
_P_N = 0.035                      # depolarisation factor
_JUNGE_V = 4.0                    # Junge exponent of the haze size distribution

#: Exponential density decay constants [m^-1] of haze (1/1200 m) and molecules
#: (1/8803 m) used by the paper's aerial perspective (section 5, values of the authors'
#: example code, which are the paper's 1.2 km and 8.8 km scale heights).
ALPHA_HAZE = 0.83331810215394e-3
ALPHA_MOLECULES = 0.11360016092149e-3

# Floor on cos(view zenith) in the Perez gradation term exp(B / cos theta) (see Notes of
# perez_function): keeps B / cos finite at the horizon.
_COS_FLOOR = 1e-6


# --------------------------------------------------------------------------------------
# Tables
# --------------------------------------------------------------------------------------

@lru_cache(maxsize=1)
def _distribution_matrices() -> dict[str, np.ndarray]:
    """{'Y': (5, 2), 'x': (5, 2), 'y': (5, 2)}: columns (slope in T, intercept)."""
    _, a = load_table("preetham1999_distribution")
    return {"Y": a[:, 1:3].copy(), "x": a[:, 3:5].copy(), "y": a[:, 5:7].copy()}


@lru_cache(maxsize=1)
def _zenith_matrices() -> tuple[np.ndarray, np.ndarray]:
    """(M_x, M_y), each (3, 4): rows T^2, T, 1; columns theta^3, theta^2, theta, 1."""
    _, a = load_table("preetham1999_zenith_chromaticity")
    order = np.argsort(-a[:, 0])                    # rows T^2, T^1, T^0
    a = a[order]
    return a[:, 1:5].copy(), a[:, 5:9].copy()


@lru_cache(maxsize=1)
def _absorption_table() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    _, a = load_table("preetham1999_sun_absorption")
    return a[:, 0], a[:, 1], a[:, 2], a[:, 3]


@lru_cache(maxsize=1)
def _spectra_table() -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths [nm], K)."""
    _, a = load_table("preetham1999_spectra")
    return a[:, 0], a[:, 1]


@lru_cache(maxsize=1)
def _eta_table() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(theta [deg] (13,), wavelengths [nm] (5,), eta (13, 5))."""
    cols, a = load_table("preetham1999_mie_eta")
    wl = np.array([float(c.split("_")[1]) for c in cols[1:]])
    return a[:, 0], wl, a[:, 1:]


def _check_turbidity(turbidity) -> float:
    return check_number("turbidity", turbidity, *TURBIDITY_RANGE)


# --------------------------------------------------------------------------------------
# Sky: Perez distribution and zenith values [PSS99] section 4, Appendix A.2
# --------------------------------------------------------------------------------------

def perez_coefficients(turbidity: float) -> dict[str, np.ndarray]:
    """Perez coefficients A..E for Y, x and y at turbidity T.

    Parameters
    ----------
    turbidity : float
        Turbidity T [-], in [2, 10].

    Returns
    -------
    dict
        ``{'Y': (5,), 'x': (5,), 'y': (5,)}`` arrays (A, B, C, D, E), each linear in T
        ([PSS99] Appendix A.2, the three 5x2 matrices times (T, 1)).
    """
    T = _check_turbidity(turbidity)
    return {k: m[:, 0] * T + m[:, 1] for k, m in _distribution_matrices().items()}


def perez_function(cos_theta, gamma, coef) -> np.ndarray:
    """Perez et al. (1993) distribution F(theta, gamma) [PSI93], [PSS99] eq. 3.

    ``F = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma)``

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the view zenith angle [-]; values below ``1e-6`` are raised to it.
    gamma : array_like
        Angle between view direction and sun [rad].
    coef : sequence of 5 floats
        A, B, C, D, E.

    Notes
    -----
    With B < 0 (every T in [2, 10]) ``exp(B / cos theta)`` tends to 0 at the horizon; the
    floor on cos theta only keeps the division finite. (With B > 0, i.e. T < 1.2 for Y, the
    term would blow up at the horizon: one reason the model is refused there.)
    """
    A, B, C, D, E = coef
    c = np.maximum(np.asarray(cos_theta, dtype=np.float64), _COS_FLOOR)
    g = np.asarray(gamma, dtype=np.float64)
    cg = np.cos(g)
    return (1.0 + A * np.exp(B / c)) * (1.0 + C * np.exp(D * g) + E * cg * cg)


def zenith_luminance(turbidity: float, sun_zenith_rad) -> np.ndarray:
    """Absolute zenith luminance Y_z [cd m^-2] ([PSS99] Appendix A.2).

    ``chi = (4/9 - T/120)(pi - 2 theta_s)``,
    ``Y_z = (4.0453 T - 4.9710) tan(chi) - 0.2155 T + 2.4192`` [kcd m^-2].

    Parameters
    ----------
    turbidity : float
        T [-] in [2, 10].
    sun_zenith_rad : array_like
        Solar zenith angle theta_s [rad] in [0, pi/2].

    Returns
    -------
    numpy.ndarray
        Y_z [cd m^-2] (the paper's kcd m^-2 times 1000).
    """
    T = _check_turbidity(turbidity)
    ts = np.asarray(sun_zenith_rad, dtype=np.float64)
    if np.any((ts < 0.0) | (ts > 0.5 * np.pi + 1e-12)):
        raise ValueError("sun_zenith_rad is out of range [0, 1.5708] rad")
    chi = (4.0 / 9.0 - T / 120.0) * (np.pi - 2.0 * ts)               # [PSS99] A.2
    return 1000.0 * ((4.0453 * T - 4.9710) * np.tan(chi) - 0.2155 * T + 2.4192)


def zenith_chromaticity(turbidity: float, sun_zenith_rad) -> tuple[np.ndarray, np.ndarray]:
    """Zenith chromaticity (x_z, y_z) ([PSS99] Appendix A.2).

    ``x_z = [T^2 T 1] M_x [theta_s^3 theta_s^2 theta_s 1]^T`` and likewise y_z.

    Parameters
    ----------
    turbidity : float
        T [-] in [2, 10].
    sun_zenith_rad : array_like
        Solar zenith angle [rad] in [0, pi/2].

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        CIE 1931 x_z, y_z [-].
    """
    T = _check_turbidity(turbidity)
    ts = np.asarray(sun_zenith_rad, dtype=np.float64)
    Mx, My = _zenith_matrices()
    tv = np.array([T * T, T, 1.0])
    th = np.stack([ts ** 3, ts ** 2, ts, np.ones_like(ts)], axis=-1)
    return th @ (tv @ Mx), th @ (tv @ My)                            # [PSS99] A.2


# --------------------------------------------------------------------------------------
# Sun: [PSS99] section 3 and Appendix A.1
# --------------------------------------------------------------------------------------

def relative_air_mass(sun_zenith_deg) -> np.ndarray:
    """Relative optical air mass m [-] of [PSS99] Appendix A.1.

    ``m = 1 / (cos theta_s + 0.15 (93.885 - theta_s)^-1.253)``, theta_s in degrees (the
    Kasten 1966 formula as given by [Iqb83] eq. 5.7.2; about 38 at the horizon).

    Parameters
    ----------
    sun_zenith_deg : array_like
        Solar zenith angle [deg] in [0, 90].
    """
    z = np.asarray(sun_zenith_deg, dtype=np.float64)
    if np.any((z < 0.0) | (z > 90.0)):
        raise ValueError("sun_zenith_deg is out of range [0, 90] deg")
    from skydome.atmosphere.airmass import kasten1966

    return kasten1966(z)


def _interp_table(w, x, y):
    from skydome.spectra import resample

    return resample(w, x, y, "zero")


def sun_transmittance(wavelengths_nm, sun_zenith_deg: float, turbidity: float, *,
                      ozone_cm: float = OZONE_CM, water_cm: float = WATER_CM,
                      components: bool = False):
    """Spectral transmittance of the atmosphere for the direct sun ([PSS99] Appendix A.1).

    Product of (air mass m, lambda in um)::

        Rayleigh      exp(-0.008735 m lambda^-4.08)
        aerosol       exp(-beta m lambda^-alpha),  beta = 0.04608 T - 0.04586, alpha = 1.3
        ozone         exp(-k_o l m),               l = 0.35 cm
        mixed gases   exp(-1.41 k_g m / (1 + 118.93 k_g m)^0.45)
        water vapour  exp(-0.2385 k_wa w m / (1 + 20.07 k_wa w m)^0.45),  w = 2 cm

    with k_o, k_g, k_wa of Table 2 ([Iqb83]), linearly interpolated.

    Parameters
    ----------
    wavelengths_nm : array_like
        1-D wavelengths [nm] in [380, 780] (the range of Table 2).
    sun_zenith_deg : float
        Solar zenith angle [deg] in [0, 90].
    turbidity : float
        T [-] in [2, 10].
    ozone_cm, water_cm : float
        Ozone column l [cm NTP] in [0, 1] and precipitable water w [cm] in [0, 10].
    components : bool
        If True return a dict of the five transmittances as well.

    Returns
    -------
    numpy.ndarray or (numpy.ndarray, dict)
        Shape (n,), in (0, 1].
    """
    w = as_wavelengths(wavelengths_nm, *_TABLE2_RANGE)
    z = check_number("sun_zenith_deg", sun_zenith_deg, 0.0, 90.0, "deg")
    T = _check_turbidity(turbidity)
    l_oz = check_number("ozone_cm", ozone_cm, 0.0, 1.0, "cm")
    w_cm = check_number("water_cm", water_cm, 0.0, 10.0, "cm")
    m = float(relative_air_mass(z))
    lam_um = w * 1e-3
    wt, ko, kwa, kg = _absorption_table()
    ko, kwa, kg = (_interp_table(w, wt, k) for k in (ko, kwa, kg))
    beta = 0.04608 * T - 0.04586                                     # [PSS99] A.1
    t_r = np.exp(-_RAYLEIGH_TAU * m * lam_um ** -_RAYLEIGH_EXP)      # [PSS99] A.1 Rayleigh
    t_a = np.exp(-beta * m * lam_um ** -_ANGSTROM_ALPHA)             # [PSS99] A.1 aerosol
    t_o = np.exp(-ko * l_oz * m)                                     # [PSS99] A.1 ozone
    t_g = np.exp(-1.41 * kg * m / (1.0 + 118.93 * kg * m) ** 0.45)   # [PSS99] A.1 mixed gas
    t_wa = np.exp(-0.2385 * kwa * w_cm * m
                  / (1.0 + 20.07 * kwa * w_cm * m) ** 0.45)          # [PSS99] A.1 water
    total = t_r * t_a * t_o * t_g * t_wa
    if components:
        return total, {"rayleigh": t_r, "aerosol": t_a, "ozone": t_o, "mixed_gas": t_g,
                       "water_vapour": t_wa}
    return total


def extraterrestrial_sun_radiance(wavelengths_nm, sun=None) -> np.ndarray:
    """Mean radiance of the sun's disc outside the atmosphere [W m^-2 sr^-1 nm^-1].

    The ASTM G173 AM0 irradiance (:func:`skydome.spectra.solar_irradiance`, scaled by the
    sun's 1/d^2) divided by the disc's solid angle. (Table 2 of [PSS99] tabulates the same
    quantity from an older solar spectrum; see the tests for the comparison.)

    Parameters
    ----------
    wavelengths_nm : array_like
        1-D strictly increasing wavelengths [nm] in [280, 4000].
    sun : skydome.Sun, optional
        Gives the disc's solid angle and the Earth-sun distance; default: a sun of the
        standard radius at 1 au.
    """
    from skydome.spectra import solar_irradiance
    from skydome.sun import Sun

    if sun is None:
        sun = Sun(elevation_deg=90.0, azimuth_deg=0.0)
    return solar_irradiance(wavelengths_nm) * sun.irradiance_scale / sun.solid_angle_sr


def sun_radiance(wavelengths_nm, sun, turbidity: float, *, ozone_cm: float = OZONE_CM,
                 water_cm: float = WATER_CM) -> np.ndarray:
    """Spectral radiance of the sun's disc seen from the ground [W m^-2 sr^-1 nm^-1].

    Extraterrestrial radiance times :func:`sun_transmittance` ([PSS99] section 3). Zero
    when the sun is below the horizon (its disc is not seen).

    Parameters
    ----------
    wavelengths_nm : array_like
        1-D strictly increasing wavelengths [nm] in [380, 780].
    sun : skydome.Sun
        Sun position and disc.
    turbidity : float
        T [-] in [2, 10].
    ozone_cm, water_cm : float
        See :func:`sun_transmittance`.

    Returns
    -------
    numpy.ndarray
        Shape (n,), >= 0.
    """
    w = as_wavelengths(wavelengths_nm, *_TABLE2_RANGE)
    if sun.elevation_deg < 0.0:
        _check_turbidity(turbidity)
        return np.zeros_like(w)
    tr = sun_transmittance(w, sun.zenith_deg, turbidity, ozone_cm=ozone_cm, water_cm=water_cm)
    return extraterrestrial_sun_radiance(w, sun) * tr


# --------------------------------------------------------------------------------------
# Scattering coefficients [PSS99] Appendix A.3 (after [McC76])
# --------------------------------------------------------------------------------------

def rayleigh_coefficient(wavelengths_nm) -> np.ndarray:
    """Total Rayleigh scattering coefficient at sea level [m^-1] ([PSS99] A.3).

    ``beta = 8 pi^3 (n^2 - 1)^2 / (3 N lambda^4) (6 + 3 p_n) / (6 - 7 p_n)`` with
    n = 1.0003, N = 2.545e25 m^-3, p_n = 0.035 ([McC76] eq. 4-48).

    Parameters
    ----------
    wavelengths_nm : array_like
        Wavelengths [nm] in [200, 4000]; any shape.
    """
    w = np.asarray(wavelengths_nm, dtype=np.float64)
    as_wavelengths(w.ravel())
    lam = w * 1e-9
    king = (6.0 + 3.0 * _P_N) / (6.0 - 7.0 * _P_N)
    return 8.0 * np.pi ** 3 * (_N_AIR ** 2 - 1.0) ** 2 / (3.0 * _N_MOLECULES * lam ** 4) * king


def rayleigh_angular_coefficient(wavelengths_nm, cos_theta) -> np.ndarray:
    """Angular Rayleigh scattering coefficient [m^-1 sr^-1] ([PSS99] A.3).

    ``beta(theta) = pi^2 (n^2 - 1)^2 / (2 N lambda^4) (6 + 3 p_n)/(6 - 7 p_n) (1 + cos^2)``
    = ``beta 3 / (16 pi) (1 + cos^2 theta)`` ([McC76] eq. 4-55).

    Broadcasts ``cos_theta[..., None]`` against the wavelengths: shape (..., n).
    """
    c = np.asarray(cos_theta, dtype=np.float64)[..., None]
    return rayleigh_coefficient(wavelengths_nm) * (3.0 / (16.0 * np.pi)) * (1.0 + c * c)


def _mie_c_si(turbidity: float) -> float:
    """Haze concentration factor c in SI units.

    [PSS99] A.3 prints ``c = (0.6544 T - 0.6510) 1e-16`` in McCartney's units; the authors'
    example code converts it with the factor ``0.01^(v - 3)`` ("unit correction for c"),
    i.e. 1e-18 for v = 4. Without that factor the haze would be 100 times too dense (a
    T = 2 atmosphere would have a visual range of about 0.5 km instead of about 50 km).
    """
    return (0.6544 * turbidity - 0.6510) * 1e-16 * 0.01 ** (_JUNGE_V - 3.0)


def mie_coefficient(wavelengths_nm, turbidity: float) -> np.ndarray:
    """Total Mie (haze) scattering coefficient at sea level [m^-1] ([PSS99] A.3).

    ``beta_p = 0.434 c pi (2 pi / lambda)^(v - 2) K(lambda)``, v = 4, K from Table 2
    (linear interpolation, held constant outside 380-780 nm), c from
    :func:`_mie_c_si` ([McC76] eq. 6-30).

    Parameters
    ----------
    wavelengths_nm : array_like
        Wavelengths [nm] in [200, 4000]; any shape.
    turbidity : float
        T [-] in [2, 10].
    """
    T = _check_turbidity(turbidity)
    w = np.asarray(wavelengths_nm, dtype=np.float64)
    as_wavelengths(w.ravel())
    wt, K = _spectra_table()
    from skydome.spectra import resample

    k = resample(w, wt, K, "hold")
    lam = w * 1e-9
    return 0.434 * _mie_c_si(T) * np.pi * (2.0 * np.pi / lam) ** (_JUNGE_V - 2.0) * k


def mie_eta(theta_rad, wavelengths_nm) -> np.ndarray:
    """Mie angular factor eta(theta, lambda) of [PSS99] (v = 4), bilinear in the table.

    Angles below 1 deg take the 1 deg value; wavelengths outside 400-850 nm the nearest
    column. Shape ``theta.shape + (n,)``.
    """
    th, wl, eta = _eta_table()
    t = np.degrees(np.asarray(theta_rad, dtype=np.float64))
    w = np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64))
    # interpolate each table column in angle, then the columns in wavelength
    cols = np.stack([np.interp(t, th, eta[:, j]) for j in range(wl.size)], axis=-1)
    weights = _hat_weights(w, wl)                                    # (n, 5)
    return cols @ weights.T


def _hat_weights(x: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Linear-interpolation weights (len(x), len(nodes)), clamped at the ends."""
    W = np.zeros((x.size, nodes.size))
    xc = np.clip(x, nodes[0], nodes[-1])
    k = np.clip(np.searchsorted(nodes, xc, side="right") - 1, 0, nodes.size - 2)
    t = (xc - nodes[k]) / (nodes[k + 1] - nodes[k])
    W[np.arange(x.size), k] = 1.0 - t
    W[np.arange(x.size), k + 1] = t
    return W


def mie_angular_coefficient(wavelengths_nm, turbidity: float, theta_rad) -> np.ndarray:
    """Angular Mie scattering coefficient [m^-1 sr^-1] ([PSS99] A.3, [McC76] eq. 6-24).

    ``beta_p(theta) = 0.434 c (2 pi / lambda)^(v - 2) eta(theta, lambda) / 2``; shape
    ``theta.shape + (n,)``. Integrates over the sphere to about :func:`mie_coefficient`
    (to the accuracy with which the tabulated eta integrates to K, a few per cent).
    """
    T = _check_turbidity(turbidity)
    w = as_wavelengths(wavelengths_nm)
    lam = w * 1e-9
    prefix = 0.434 * _mie_c_si(T) * (2.0 * np.pi / lam) ** (_JUNGE_V - 2.0) * 0.5
    return mie_eta(theta_rad, w) * prefix


# --------------------------------------------------------------------------------------
# The sky model
# --------------------------------------------------------------------------------------

@register
class Preetham1999(SkyModel):
    """Preetham, Shirley & Smits (1999) analytic daylight model.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position; its elevation must be in [0, 90] deg (ValueError otherwise: the fits
        are undefined below the horizon, where chi < 0 and Y_z falls to negative values).
    turbidity : float
        Turbidity T [-], in [2, 10] (the range of the paper's fits; ValueError outside).

    Notes
    -----
    ``xyz(directions)`` is the native quantity: Y = Y_z F_Y(theta, gamma) / F_Y(0, theta_s)
    and likewise x, y ([PSS99] eq. 3 with A.2); X, Z follow from (x, y, Y). ``radiance``
    rebuilds the spectrum with the CIE daylight basis S0 + M1 S1 + M2 S2 ([PSS99]
    Appendix A.6) scaled to Y (base class, :func:`skydome.spectra.spectrum_from_xyz_daylight`).
    Directions below the horizon (z < 0) return 0. The horizon itself (z = 0) is evaluated
    with cos theta floored at 1e-6.

    Known weaknesses ([ZWP07]): the fit reproduces its own simulations poorly at low sun
    and high turbidity (horizon too bright against the zenith, the region opposite the sun
    too dark or too bright, unrealistic colours at sunset), and it has no twilight.
    """

    name = "preetham1999"
    reference = ("A. J. Preetham, P. Shirley, B. Smits, 'A Practical Analytic Model for "
                 "Daylight', Proc. SIGGRAPH 99, pp. 91-100 (1999)")
    native = "xyz"
    viewer_shader = "preetham1999"
    viewer_parameters = ("turbidity",)
    airlight = True                       # its section 5 (F_ex, L_in)
    summary = "Perez-form fit of sky luminance and chromaticity vs turbidity, with spectral sun"
    parameters = (
        Parameter("turbidity", "", 2.5, TURBIDITY_RANGE[0], TURBIDITY_RANGE[1],
                  "atmospheric turbidity T = (t_molecules + t_haze) / t_molecules"),
    )

    sun_elevation_range_deg = (0.0, 90.0)   # the fit has no twilight

    def _setup(self, vals, given):
        sun = self.sun
        for k, v in vals.items():
            setattr(self, k, v)
        T = self.turbidity
        self._theta_s = np.radians(sun.zenith_deg)
        self._coef = perez_coefficients(T)
        self._Yz = float(zenith_luminance(T, self._theta_s))
        xz, yz = zenith_chromaticity(T, self._theta_s)
        self._xz, self._yz = float(xz), float(yz)
        # F(0, theta_s): the Perez function at the zenith, gamma = theta_s
        self._norm = {k: float(perez_function(1.0, self._theta_s, c))
                      for k, c in self._coef.items()}

    def xyY(self, directions) -> np.ndarray:
        """(x, y, Y) per direction: chromaticity [-] and luminance [cd m^-2], shape (..., 3).

        Below the horizon (z < 0): (x_z, y_z, 0) (zero luminance, zenith chromaticity).
        """
        return self._kernel_eval(directions, False)

    def _kernel_eval(self, directions, want_xyz: bool) -> np.ndarray:
        # [PSS99] eq. 3 for x, y and Y in one parallel numba kernel; _xyY_reference is the
        # numpy form of the same formulas.
        from skydome.models.analytic import _kernels_analytic as K

        flat, lead = K.flat_directions(directions)
        if not hasattr(self, "_kcoef"):
            self._kcoef = np.ascontiguousarray(
                np.stack([self._coef[k] for k in ("x", "y", "Y")]), dtype=np.float64)
            self._kzen = np.array([self._xz / self._norm["x"], self._yz / self._norm["y"],
                                   self._Yz / self._norm["Y"], self._xz, self._yz])
        s = np.asarray(self.sun.direction, dtype=np.float64)
        out = K.preetham(flat, s, self._kcoef, self._kzen, _COS_FLOOR, want_xyz)
        return out.reshape(lead + (3,))

    def _xyY_reference(self, directions) -> np.ndarray:
        """numpy reference implementation of :meth:`xyY`."""
        d = as_directions(directions)
        cos_t = d[..., 2]
        cos_g = np.clip(d @ self.sun.direction, -1.0, 1.0)
        gamma = np.arccos(cos_g)
        out = []
        for key, zval in (("x", self._xz), ("y", self._yz), ("Y", self._Yz)):
            f = perez_function(cos_t, gamma, self._coef[key]) / self._norm[key]  # [PSS99] eq. 3
            out.append(zval * f)
        x, y, Y = out
        below = cos_t < 0.0
        x = np.where(below, self._xz, x)
        y = np.where(below, self._yz, y)
        Y = np.where(below, 0.0, np.maximum(Y, 0.0))
        return np.stack([x, y, Y], axis=-1)

    def xyz(self, directions) -> np.ndarray:
        """CIE 1931 XYZ with Y = luminance [cd m^-2], shape (..., 3); zero below the horizon."""
        return self._kernel_eval(directions, True)

    def _xyz_reference(self, directions) -> np.ndarray:
        """numpy reference implementation of :meth:`xyz`."""
        xyY = self._xyY_reference(directions)
        x, y, Y = xyY[..., 0], xyY[..., 1], xyY[..., 2]
        return np.stack([x * Y / y, Y, (1.0 - x - y) * Y / y], axis=-1)

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Spectral radiance of the sun's disc at the ground [W m^-2 sr^-1 nm^-1], shape (n,);
        wavelengths in [380, 780] nm. See :func:`sun_radiance`."""
        return sun_radiance(wavelengths_nm, self.sun, self.turbidity)

    def aerial_perspective(self, directions, distance_m, wavelengths_nm, **kwargs):
        """Extinction and in-scattered radiance along a view ray; see
        :func:`aerial_perspective` (this model's sun and turbidity)."""
        return aerial_perspective(directions, distance_m, wavelengths_nm, sun=self.sun,
                                  turbidity=self.turbidity, sky=self, **kwargs)


# --------------------------------------------------------------------------------------
# Aerial perspective [PSS99] section 5
# --------------------------------------------------------------------------------------

def _path_integral(alpha: float, u: np.ndarray, x: np.ndarray) -> np.ndarray:
    """integral_0^x exp(-alpha u t) dt = (1 - exp(-alpha u x)) / (alpha u); x where alpha u x
    is tiny (horizontal rays)."""
    a = alpha * u
    ax = a * x
    small = np.abs(ax) < 1e-9
    safe_a = np.where(small, 1.0, a)
    return np.where(small, x * (1.0 - 0.5 * ax), -np.expm1(-ax) / safe_a)


@lru_cache(maxsize=8)
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    t, w = np.polynomial.legendre.leggauss(n)
    return t, w


def _sky_grid(n_theta: int, n_phi: int) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint grid over the upper hemisphere: directions (k, 3) and solid angles (k,)."""
    dt = 0.5 * np.pi / n_theta
    dp = 2.0 * np.pi / n_phi
    th = (np.arange(n_theta) + 0.5) * dt
    ph = (np.arange(n_phi) + 0.5) * dp
    T, P = np.meshgrid(th, ph, indexing="ij")
    d = np.stack([np.sin(T) * np.sin(P), np.sin(T) * np.cos(P), np.cos(T)], axis=-1)
    # exact solid angle of each band cell: (cos t0 - cos t1) dphi
    dom = (np.cos(T - 0.5 * dt) - np.cos(T + 0.5 * dt)) * dp
    return d.reshape(-1, 3), dom.reshape(-1)


def check_distances(distance_m) -> np.ndarray:
    """Eye-object distances [m] as a float array; ValueError unless all are finite and
    >= 0 (the aerial perspective of this model and of Hoffman & Preetham's)."""
    s = np.asarray(distance_m, dtype=np.float64)
    if not np.all(np.isfinite(s)) or np.any(s < 0.0):
        raise ValueError("distance_m is out of range [0, inf) m (got a negative or "
                         "non-finite value)")
    return s


def aerial_perspective(directions, distance_m, wavelengths_nm, *, sun, turbidity: float,
                       observer_altitude_m: float = 0.0, include_skylight: bool = True,
                       sky=None, n_quadrature: int = 32, sky_samples: int = 16):
    """Transmittance and in-scattered radiance between the eye and an object
    ([PSS99] section 5).

    ``L = L_0 tau(s) + L_in(s)``. Molecules (R) and haze (M) have densities
    ``exp(-alpha_i h)`` over a flat earth, ``h = h_0 + x cos theta`` along the ray, so
    the optical depth is closed-form::

        tau(s) = exp(-sum_i beta_i exp(-alpha_i h_0) (1 - exp(-alpha_i s u)) / (alpha_i u))

    with u = cos theta of the view direction. The in-scattered radiance is
    ``L_in = sum_i A_i integral_0^s exp(-alpha_i h(x)) tau(x) dx`` with
    ``A_i = integral beta_i(psi) L(omega) d omega`` over the sun (its disc radiance times
    its solid angle) and, optionally, the sky dome (the Preetham sky radiance), both seen
    from the eye, psi being the angle between the view direction and omega.

    Parameters
    ----------
    directions : array_like
        Unit vector(s) (..., 3) from the eye towards the object (East-North-Up).
    distance_m : array_like
        Eye-object distance s [m], >= 0, broadcast against ``directions[..., 0]``.
    wavelengths_nm : array_like
        1-D strictly increasing wavelengths [nm] in [380, 780].
    sun : skydome.Sun
        Elevation in [0, 90] deg.
    turbidity : float
        T [-] in [2, 10].
    observer_altitude_m : float
        Eye height h_0 above the reference level [m], in [0, 20000]. The exponential
        densities continue below the reference level for rays that go down.
    include_skylight : bool
        Add the skylight term of A_i (default True).
    sky : Preetham1999, optional
        The sky model to use for the skylight term (default: built from sun, turbidity).
    n_quadrature : int
        Gauss-Legendre nodes of the in-scattering integral, in [4, 256].
    sky_samples : int
        Zenith bands of the skylight quadrature (2x as many azimuths), in [2, 64].

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        Transmittance tau [-] and in-scattered radiance L_in [W m^-2 sr^-1 nm^-1], both of
        shape (..., n).

    Notes
    -----
    Deviation: [PSS99] evaluates the in-scattering integral in closed form after
    approximating the extinction factor of the other constituent by a cubic in the
    density variable (and tabulates A_i on a 20 x 20 direction grid). We integrate the same
    integrand with Gauss-Legendre quadrature and evaluate A_i per direction, which is exact
    for the model up to quadrature error (< 1e-6 relative with 32 nodes for paths of a few
    optical depths). The haze concentration c is converted to SI as in :func:`_mie_c_si`.
    The sun's radiance seen from each point is that at the eye (the paper's assumption).
    """
    d = as_directions(directions, "directions")
    s = check_distances(distance_m)
    w = as_wavelengths(wavelengths_nm, *_TABLE2_RANGE)
    T = _check_turbidity(turbidity)
    h0 = check_number("observer_altitude_m", observer_altitude_m, 0.0, 20000.0, "m")
    nq = check_int("n_quadrature", n_quadrature, 4, 256)
    ns = check_int("sky_samples", sky_samples, 2, 64)
    check_choice("include_skylight", include_skylight, (True, False))
    if sun.elevation_deg < 0.0:
        raise ValueError(f"sun elevation_deg = {sun.elevation_deg:g} deg is out of range "
                         f"[0, 90] deg for the Preetham aerial perspective")
    shape = np.broadcast_shapes(d.shape[:-1], s.shape)
    d = np.broadcast_to(d, shape + (3,)).reshape(-1, 3)
    s = np.broadcast_to(s, shape).reshape(-1)

    beta = np.stack([mie_coefficient(w, T), rayleigh_coefficient(w)])        # (2, n)
    alpha = (ALPHA_HAZE, ALPHA_MOLECULES)
    ground = np.array([np.exp(-a * h0) for a in alpha])                       # (2,)
    u = d[:, 2]

    def optical_depth(x, uu):
        # [PSS99] section 5: sum_i beta_i exp(-alpha_i h0) (1 - exp(-alpha_i x u)) / (alpha_i u)
        return sum((ground[i] * _path_integral(alpha[i], uu, x))[..., None] * beta[i]
                   for i in range(2))

    tau = np.exp(-optical_depth(s, u))                                        # (V, n)

    # A_i: angular scattering of sun (and sky) light into the view direction
    L_sun = sun_radiance(w, sun, T) * sun.solid_angle_sr                      # (n,) irradiance
    cos_sun = np.clip(d @ sun.direction, -1.0, 1.0)
    A_m = mie_angular_coefficient(w, T, np.arccos(cos_sun)) * L_sun           # (V, n)
    A_r = rayleigh_angular_coefficient(w, cos_sun) * L_sun
    if include_skylight:
        if sky is None:
            sky = Preetham1999(sun=sun, turbidity=T)
        gd, dom = _sky_grid(ns, 2 * ns)
        Lsky = sky.radiance(gd, w) * dom[:, None]                             # (k, n)
        cos_k = np.clip(d @ gd.T, -1.0, 1.0)                                  # (V, k)
        A_r = A_r + rayleigh_coefficient(w) * (3.0 / (16.0 * np.pi)) * (
            (1.0 + cos_k * cos_k) @ Lsky)
        th_t, wl_t, eta_t = _eta_table()
        psi = np.degrees(np.arccos(cos_k))
        hats = _hat_weights(w, wl_t)                                          # (n, 5)
        lam = w * 1e-9
        prefix = 0.434 * _mie_c_si(T) * (2.0 * np.pi / lam) ** (_JUNGE_V - 2.0) * 0.5
        acc = np.zeros_like(A_m)
        for j in range(wl_t.size):
            if not np.any(hats[:, j]):
                continue
            acc += (np.interp(psi, th_t, eta_t[:, j]) @ Lsky) * hats[:, j]
        A_m = A_m + prefix * acc

    # L_in = sum_i A_i integral_0^s rho_i(x) tau(x) dx, Gauss-Legendre on [0, s]
    t, wq = _gauss_legendre(nq)
    x = 0.5 * s[:, None] * (t[None, :] + 1.0)                                 # (V, q)
    tau_x = np.exp(-optical_depth(x, u[:, None]))                                         # (V, q, n)
    L_in = np.zeros_like(tau)
    for i, A in enumerate((A_m, A_r)):
        rho = ground[i] * np.exp(-alpha[i] * u[:, None] * x)                  # (V, q)
        integral = 0.5 * s[:, None] * np.einsum("q,vq,vqn->vn", wq, rho, tau_x)
        L_in += A * integral
    n = w.size
    return tau.reshape(shape + (n,)), np.maximum(L_in, 0.0).reshape(shape + (n,))
