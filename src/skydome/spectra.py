"""Wavelength grids, reference spectra and colorimetry.

Everything that turns a spectrum into a colour lives here: the default wavelength grid,
the extraterrestrial solar spectrum (ASTM G173-03), the CIE 1931 colour-matching
functions, the CIE daylight basis S0, S1, S2, Planck's law, and the chain spectral
radiance -> CIE XYZ -> xy / linear sRGB / ACEScg -> encoded sRGB.

Conventions
-----------
- Wavelengths are in nm, 1-D, and the wavelength axis of every spectrum is the last.
- Spectral radiance is in W m^-2 sr^-1 nm^-1; XYZ are absolute, Y is the luminance in
  cd m^-2 (``K_m = 683 lm/W``); linear RGB values carry the same absolute scale.
- A sampled spectrum is understood as the piecewise-linear function through its samples
  (``method="linear"``, the default of :func:`spectrum_to_xyz`), or as a Riemann sum of
  rectangles (``method="sum"``, what colour-science's ``'Integration'`` method does).

The tables are read from ``skydome/data`` on first use and cached; this module imports
nothing heavier than NumPy.

References
----------
.. [CIE15] CIE 015:2004 / CIE 015:2018, *Colorimetry*, 3rd / 4th ed. Commission
   Internationale de l'Eclairage, Vienna. (Daylight: section 3.1 and Table T.2; CMFs:
   Table T.4 / CIE 018:2019 1 nm table.)
.. [G173] ASTM G173-03 (2012), *Standard Tables for Reference Solar Spectral Irradiances:
   Direct Normal and Hemispherical on 37 deg Tilted Surface*; Gueymard, C. A. (2004),
   The sun's total and spectral irradiance for solar energy applications and solar
   radiation models, Solar Energy 76, 423-453.
.. [IEC] IEC 61966-2-1:1999, *Multimedia systems and equipment - Colour measurement and
   management - Part 2-1: Default RGB colour space - sRGB*.
.. [709] ITU-R BT.709-6 (2015), *Parameter values for the HDTV standards*.
.. [S2065] SMPTE ST 2065-1:2012 (ACES) and Academy S-2014-004 (ACEScg, AP1 primaries).
.. [RP177] SMPTE RP 177-1993, *Derivation of Basic Television Color Equations*.
.. [Lam85] Lam, K. M. (1985), Metamerism and colour constancy, PhD thesis, University of
   Bradford (the Bradford cone-response matrix); Hunt, R. W. G. & Pointer, M. R. (2011),
   *Measuring Colour*, 4th ed., Wiley, section 16.
.. [Planck] Planck, M. (1901), Ann. Phys. 309, 553-563; constants: CODATA 2018 (exact SI).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ._validate import as_wavelengths, check_choice, check_number
from .constants import K_BOLTZMANN, K_M
from .data import load_table

__all__ = [
    "wavelength_grid",
    "default_wavelengths",
    "resample",
    "interpolation_matrix",
    "cmf_1931",
    "daylight_basis",
    "solar_irradiance",
    "integration_weights",
    "spectrum_to_xyz",
    "solar_xyz_matrix",
    "luminance_from_spectrum",
    "xyz_to_xy",
    "xy_to_xyz",
    "xyz_to_linear_srgb",
    "linear_srgb_to_xyz",
    "srgb_encode",
    "srgb_decode",
    "xyz_to_acescg",
    "acescg_to_xyz",
    "spectrum_from_xyz_daylight",
    "blackbody",
    "normalised_primary_matrix",
    "D65_XY",
    "SRGB_WHITE_XY",
    "ACES_WHITE_XY",
]

# --------------------------------------------------------------------------------------
# Constants
# --------------------------------------------------------------------------------------

# Planck constant [J s] and speed of light in vacuum [m/s] (CODATA 2018, exact in the SI).
_H_PLANCK = 6.62607015e-34
_C_LIGHT = 299792458.0

# CIE standard illuminant D65 chromaticity, CIE 1931 2-degree observer, to 5 decimals
# ([CIE15] Table T.3). Returned by xyz_to_xy for black (X + Y + Z = 0).
D65_XY = (0.31271, 0.32902)

# sRGB / Rec. 709 reference white: D65 to 4 decimals as written in [IEC] and [709].
SRGB_WHITE_XY = (0.3127, 0.3290)

# Rec. 709 / sRGB primaries R, G, B ([709] item 1.3, [IEC] Table 1).
_SRGB_PRIMARIES_XY = ((0.640, 0.330), (0.300, 0.600), (0.150, 0.060))

# ACES AP1 primaries (ACEScg) and the ACES white point (~D60) ([S2065]).
_AP1_PRIMARIES_XY = ((0.713, 0.293), (0.165, 0.830), (0.128, 0.044))
ACES_WHITE_XY = (0.32168, 0.33767)

# Bradford cone-response matrix [Lam85] (rows: rho, gamma, beta from X, Y, Z).
_BRADFORD = np.array([[0.8951, 0.2664, -0.1614],
                      [-0.7502, 1.7135, 0.0367],
                      [0.0389, -0.0685, 1.0296]])

# Tabulated ranges of the shipped data [nm].
_CMF_RANGE = (360.0, 830.0)
_DAYLIGHT_RANGE = (300.0, 830.0)
_SOLAR_RANGE = (280.0, 4000.0)

# Default grid: 380-780 nm at 10 nm (41 samples), the visible range of [CIE15].
_DEFAULT_GRID = (380.0, 780.0, 10.0)


# --------------------------------------------------------------------------------------
# Grids
# --------------------------------------------------------------------------------------

def wavelength_grid(start_nm: float = 380.0, stop_nm: float = 780.0, n: int | None = None,
                    step_nm: float | None = None) -> np.ndarray:
    """Evenly spaced wavelengths from ``start_nm`` to ``stop_nm``, both ends included.

    Parameters
    ----------
    start_nm, stop_nm : float
        First and last wavelength [nm], within [200, 4000] and ``start_nm <= stop_nm``.
    n : int, optional
        Number of samples: >= 2 when ``start_nm < stop_nm``, exactly 1 when they are
        equal. Give ``n`` or ``step_nm``, not both.
    step_nm : float, optional
        Spacing [nm], > 0; ``stop_nm - start_nm`` must be a whole multiple of it (to 1e-9
        relative). Default 10 nm when neither ``n`` nor ``step_nm`` is given.

    Returns
    -------
    numpy.ndarray
        1-D float64 array of wavelengths [nm]; the default gives 41 samples, 380-780 nm.
    """
    start = check_number("start_nm", start_nm, 200.0, 4000.0, "nm")
    stop = check_number("stop_nm", stop_nm, 200.0, 4000.0, "nm")
    if stop < start:
        raise ValueError(f"stop_nm = {stop:g} nm is out of range [{start:g}, 4000] nm "
                         f"(it must not be below start_nm = {start:g} nm)")
    if n is not None and step_nm is not None:
        raise ValueError(f"give n or step_nm, not both (got n = {n!r}, step_nm = {step_nm!r})")
    if n is not None:
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
            raise TypeError(f"n must be an integer, got {n!r}")
        count = int(n)
        if count < 1 or (count == 1 and stop != start) or (count > 1 and stop == start):
            valid = "[1, 1]" if stop == start else "[2, inf)"
            raise ValueError(f"n = {count} is out of range {valid} for start_nm = {start:g} nm, "
                             f"stop_nm = {stop:g} nm")
        return np.linspace(start, stop, count)
    step = 10.0 if step_nm is None else check_number("step_nm", step_nm, 0.0, None, "nm",
                                                     low_open=True)
    span = stop - start
    k = span / step
    if abs(k - round(k)) > 1e-9 * max(1.0, k):
        raise ValueError(f"step_nm = {step:g} nm does not divide stop_nm - start_nm = "
                         f"{span:g} nm into whole steps")
    return np.linspace(start, stop, int(round(k)) + 1)


def default_wavelengths() -> np.ndarray:
    """The default wavelength grid: 380-780 nm at 10 nm, 41 samples [nm]."""
    return wavelength_grid(*_DEFAULT_GRID[:2], step_nm=_DEFAULT_GRID[2])


def _increasing(w: np.ndarray, name: str = "wavelengths_nm") -> np.ndarray:
    if w.size > 1 and np.any(np.diff(w) <= 0.0):
        raise ValueError(f"{name} must be strictly increasing, got [{w[0]:g}, {w[1]:g}, ...] "
                         f"with a step <= 0")
    return w


def _bin_edges(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each sample's own bin: half way to each neighbour; the end bins are symmetric
    about their sample (so a regular grid gives bins of equal width); a lone sample
    gets a 1 nm bin."""
    if w.size == 1:
        return w - 0.5, w + 0.5
    mid = 0.5 * (w[1:] + w[:-1])
    lo = np.concatenate(([w[0] - (mid[0] - w[0])], mid))
    hi = np.concatenate((mid, [w[-1] + (w[-1] - mid[-1])]))
    return lo, hi


# --------------------------------------------------------------------------------------
# Tables
# --------------------------------------------------------------------------------------

def _table(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths [nm], values (rows, columns)) of a shipped table."""
    _, values = load_table(name)
    return values[:, 0], values[:, 1:]


def resample(wavelengths_nm, table_nm, values, outside: str = "zero") -> np.ndarray:
    """A tabulated spectral quantity at other wavelengths: linear interpolation in
    wavelength, the one resampling convention of the library.

    Parameters
    ----------
    wavelengths_nm : array_like
        Where to evaluate [nm], any shape.
    table_nm : array_like
        The table's wavelengths (n,) [nm], increasing.
    values : array_like
        (n,) or (n, k): one or k columns tabulated at ``table_nm``.
    outside : {"zero", "hold"}
        Beyond the table: 0 (a quantity that vanishes there: colour-matching functions,
        daylight basis, absorption bands) or the end values held (a smooth quantity such
        as a cross section or a refractive index, whose table simply ends).

    Returns
    -------
    numpy.ndarray
        shape(wavelengths_nm) (+ (k,) for 2-D ``values``).
    """
    check_choice("outside", outside, ("zero", "hold"))
    x = np.asarray(wavelengths_nm, dtype=np.float64)
    xp = np.asarray(table_nm, dtype=np.float64)
    fp = np.asarray(values, dtype=np.float64)
    kw = {"left": 0.0, "right": 0.0} if outside == "zero" else {}
    if fp.ndim == 1:
        return np.interp(x, xp, fp, **kw)
    return np.stack([np.interp(x, xp, fp[:, j], **kw) for j in range(fp.shape[1])], axis=-1)


def interpolation_matrix(source_nm, target_nm) -> np.ndarray:
    """The matrix of :func:`resample`'s ``"hold"`` interpolation: W, (n_source, n_target),
    with ``values_target = values_source @ W`` for values (..., n_source) tabulated at
    ``source_nm`` (increasing): linear between the source wavelengths, the end values held
    beyond them (a single source wavelength is held everywhere). Each column has at most
    two non-zero weights, which sum to 1.

    Parameters
    ----------
    source_nm : array_like
        (n_source,) wavelengths of the table [nm], increasing.
    target_nm : array_like
        (n_target,) wavelengths to interpolate to [nm].
    """
    src = np.asarray(source_nm, dtype=np.float64).reshape(-1)
    dst = np.asarray(target_nm, dtype=np.float64).reshape(-1)
    W = np.zeros((src.size, dst.size))
    if src.size == 1:
        W[0, :] = 1.0
        return W
    x = np.clip(dst, src[0], src[-1])
    j = np.clip(np.searchsorted(src, x) - 1, 0, src.size - 2)
    f = (x - src[j]) / (src[j + 1] - src[j])
    cols = np.arange(dst.size)
    W[j, cols] = 1.0 - f
    W[j + 1, cols] += f
    return W


def _interp_columns(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """Every column of ``fp`` at ``x``, 0 outside ``xp`` (:func:`resample`)."""
    return resample(x, xp, fp, "zero")


def cmf_1931(wavelengths_nm) -> np.ndarray:
    """CIE 1931 2-degree colour-matching functions x-bar, y-bar, z-bar.

    Parameters
    ----------
    wavelengths_nm : array_like
        1-D wavelengths [nm] in [200, 4000].

    Returns
    -------
    numpy.ndarray
        Shape (n, 3), dimensionless; linear interpolation of the 1 nm table
        (360-830 nm), 0 outside it.

    References
    ----------
    [CIE15]; CIE 018:2019 1 nm table (data file ``cie1931_2deg_cmf.csv``).
    """
    w = as_wavelengths(wavelengths_nm)
    wt, v = _table("cie1931_2deg_cmf")
    return _interp_columns(w, wt, v)


def daylight_basis(wavelengths_nm) -> np.ndarray:
    """CIE daylight basis functions S0, S1, S2.

    Parameters
    ----------
    wavelengths_nm : array_like
        1-D wavelengths [nm] within the tabulated range [300, 830].

    Returns
    -------
    numpy.ndarray
        Shape (n, 3): S0, S1, S2 (relative spectral power, S0(560 nm) = 100), linearly
        interpolated in the 5 nm table.

    References
    ----------
    [CIE15] 3rd ed., Table T.2.
    """
    w = as_wavelengths(wavelengths_nm, *_DAYLIGHT_RANGE)
    wt, v = _table("cie_daylight_s012")
    return _interp_columns(w, wt, v)


@lru_cache(maxsize=1)
def _solar_cumulative() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    wt, v = _table("astm_g173_extraterrestrial")
    e = v[:, 0]
    c = np.concatenate(([0.0], np.cumsum(0.5 * (e[1:] + e[:-1]) * np.diff(wt))))
    return wt, e, c


def _solar_integral_to(x: np.ndarray) -> np.ndarray:
    """Integral of the linearly interpolated G173 AM0 table from 280 nm to ``x``
    (``x`` within the table) [W m^-2]: cumulative trapezoid plus the partial segment."""
    wt, e, c = _solar_cumulative()
    k = np.clip(np.searchsorted(wt, x, side="right") - 1, 0, wt.size - 2)
    ex = np.interp(x, wt, e)
    return c[k] + 0.5 * (x - wt[k]) * (e[k] + ex)


def solar_irradiance(wavelengths_nm, bandwidth_nm: float | None = None) -> np.ndarray:
    """Extraterrestrial solar spectral irradiance at 1 au, box-averaged [W m^-2 nm^-1].

    Each value is the mean of the linearly interpolated ASTM G173-03 AM0 table over a
    box around the sample: the exact integral of the interpolant (cumulative trapezoid)
    divided by the box width. This smooths the Fraunhofer lines to the resolution of the
    grid, so that a coarse grid carries the right energy per band.

    Parameters
    ----------
    wavelengths_nm : array_like
        1-D wavelengths [nm] in [280, 4000]; strictly increasing when
        ``bandwidth_nm`` is None and there is more than one.
    bandwidth_nm : float, optional
        Full width of the box centred on each sample [nm], in (0, 1000]. None (default):
        each sample's own bin, half way to each neighbour (end bins symmetric about their
        sample; 1 nm for a single wavelength). Boxes are clipped to the table's range
        280-4000 nm.

    Returns
    -------
    numpy.ndarray
        Shape (n,), irradiance on a plane normal to the Sun [W m^-2 nm^-1].

    Notes
    -----
    The table integrates to 1347.9 W m^-2 over 280-4000 nm; the full spectrum of
    [G173] (Gueymard 2004), extending beyond 4000 nm, integrates to 1366.1 W m^-2.
    Scale by :attr:`skydome.sun.Sun.irradiance_scale` for another Earth-Sun distance.

    References
    ----------
    [G173]
    """
    w = as_wavelengths(wavelengths_nm, *_SOLAR_RANGE)
    if bandwidth_nm is None:
        _increasing(w)
        lo, hi = _bin_edges(w)
    else:
        half = 0.5 * check_number("bandwidth_nm", bandwidth_nm, 0.0, 1000.0, "nm",
                                  low_open=True)
        lo, hi = w - half, w + half
    lo = np.clip(lo, *_SOLAR_RANGE)
    hi = np.clip(hi, *_SOLAR_RANGE)
    # mean over [lo, hi] = (F(hi) - F(lo)) / (hi - lo); a sample always lies inside its
    # clipped box, and the box keeps a positive width because it is centred on it.
    return (_solar_integral_to(hi) - _solar_integral_to(lo)) / (hi - lo)


# --------------------------------------------------------------------------------------
# Spectrum -> XYZ
# --------------------------------------------------------------------------------------

@lru_cache(maxsize=64)
def _weights_linear(key: tuple[float, ...]) -> np.ndarray:
    """W_i = integral cmf(l) hat_i(l) dl over [w_0, w_n-1] for the hat functions of the
    grid ``key``. Both factors are linear between the union of the grid nodes and the
    1 nm CMF nodes, so their product is quadratic there and Simpson's rule on each piece
    is exact (no fine grid needed)."""
    g = np.asarray(key)
    wt, v = _table("cie1931_2deg_cmf")
    W = np.zeros((g.size, 3))
    if g.size == 1:
        W[0] = _interp_columns(g, wt, v)[0] * 1.0  # a lone sample stands for 1 nm
        W.setflags(write=False)
        return W
    lo, hi = max(g[0], _CMF_RANGE[0]), min(g[-1], _CMF_RANGE[1])
    if lo < hi:  # outside [360, 830] the CMFs vanish: nothing to add there
        nodes = np.union1d(g[(g >= lo) & (g <= hi)], wt[(wt >= lo) & (wt <= hi)])
        nodes = np.union1d(nodes, [lo, hi])
        a, b = nodes[:-1], nodes[1:]
        m = 0.5 * (a + b)
        j = np.clip(np.searchsorted(g, m, side="right") - 1, 0, g.size - 2)
        g0, dg = g[j], g[j + 1] - g[j]
        span = (b - a)[:, None] / 6.0
        lower = np.zeros((a.size, 3))
        upper = np.zeros((a.size, 3))
        for x, simpson in ((a, 1.0), (m, 4.0), (b, 1.0)):
            c = _interp_columns(x, wt, v)
            t = ((x - g0) / dg)[:, None]
            lower += simpson * c * (1.0 - t)
            upper += simpson * c * t
        np.add.at(W, j, span * lower)
        np.add.at(W, j + 1, span * upper)
    W.setflags(write=False)
    return W


@lru_cache(maxsize=64)
def _weights_sum(key: tuple[float, ...]) -> np.ndarray:
    """W_i = cmf(l_i) * (width of sample i's bin): the rectangle (Riemann) rule."""
    g = np.asarray(key)
    lo, hi = _bin_edges(g)
    wt, v = _table("cie1931_2deg_cmf")
    W = _interp_columns(g, wt, v) * (hi - lo)[:, None]
    W.setflags(write=False)
    return W


_METHODS = ("linear", "sum")


def integration_weights(wavelengths_nm, method: str = "linear") -> np.ndarray:
    """Weights W such that ``XYZ = 683 * sum_i L_i W_i`` [nm].

    Parameters
    ----------
    wavelengths_nm : array_like
        1-D strictly increasing wavelengths [nm] in [200, 4000].
    method : {"linear", "sum"}
        ``"linear"`` (default): the spectrum is the piecewise-linear function through its
        samples and zero outside the grid, so ``W_i = integral x̄ȳz̄(l) hat_i(l) dl`` with the
        hat function ``hat_i`` of sample i (exact: see Notes). ``"sum"``: the rectangle
        rule ``W_i = cmf(l_i) * dl_i`` with ``dl_i`` the sample's bin (half way to each
        neighbour, end bins symmetric), which on a regular grid is colour-science's
        ``'Integration'`` method. A single wavelength gets ``W = cmf(l) * 1 nm`` by both.

    Returns
    -------
    numpy.ndarray
        Shape (n, 3), read-only, cached per grid.

    Notes
    -----
    With the CMFs linear between their 1 nm nodes and the hats linear between grid nodes,
    the integrand is a quadratic on each interval of the merged node set, and Simpson's
    rule on those intervals gives the integral to rounding error.
    """
    w = _increasing(as_wavelengths(wavelengths_nm))
    check_choice("method", method, _METHODS)
    key = tuple(float(x) for x in w)
    return _weights_linear(key) if method == "linear" else _weights_sum(key)


def _as_spectrum(spectral_radiance, n: int, name: str = "spectral_radiance") -> np.ndarray:
    L = np.asarray(spectral_radiance, dtype=np.float64)
    if L.ndim == 0 or L.shape[-1] != n:
        raise ValueError(f"{name} must have shape (..., {n}) to match wavelengths_nm, "
                         f"got {L.shape}")
    if not np.all(np.isfinite(L)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return L


def spectrum_to_xyz(spectral_radiance, wavelengths_nm, method: str = "linear") -> np.ndarray:
    """CIE 1931 XYZ of spectral radiance, Y in cd m^-2.

    ``X = K_m * integral L(l) x-bar(l) dl`` etc. with ``K_m = 683 lm/W`` [CIE15].

    Parameters
    ----------
    spectral_radiance : array_like
        Shape (..., n) [W m^-2 sr^-1 nm^-1], finite; wavelength axis last.
    wavelengths_nm : array_like
        Shape (n,), strictly increasing [nm] in [200, 4000].
    method : {"linear", "sum"}
        Quadrature, see :func:`integration_weights`.

    Returns
    -------
    numpy.ndarray
        Shape (..., 3): X, Y, Z [cd m^-2 for Y; X and Z on the same scale].
    """
    w = _increasing(as_wavelengths(wavelengths_nm))
    L = _as_spectrum(spectral_radiance, w.size)
    W = integration_weights(w, method)
    return K_M * (L @ W)


def solar_xyz_matrix(table_nm, wavelengths_nm=None, *, irradiance_scale: float = 1.0,
                     interpolation=None) -> np.ndarray:
    """K, (n_table, 3), with CIE 1931 XYZ [Y in cd m^-2] = ``S @ K`` for radiance per unit
    extraterrestrial solar irradiance S (..., n_table) [sr^-1] tabulated at ``table_nm``:
    :func:`spectrum_to_xyz` of the spectral radiance that S makes on ``wavelengths_nm``
    (default :func:`default_wavelengths`) as one matrix: S interpolated there
    (:func:`interpolation_matrix`, or the (n_table, n) matrix ``interpolation``), times
    :func:`solar_irradiance` there times ``irradiance_scale`` (the sun's distance), then
    integrated with the ``"linear"`` weights of :func:`integration_weights`, times K_m.
    Equal to integrating the spectrum itself within rounding, without the (..., n)
    spectrum between them."""
    wl = default_wavelengths() if wavelengths_nm is None else \
        _increasing(as_wavelengths(wavelengths_nm))
    W = interpolation_matrix(table_nm, wl) if interpolation is None else \
        np.asarray(interpolation, dtype=np.float64)
    return (W * (solar_irradiance(wl) * irradiance_scale)[None, :]) \
        @ (K_M * np.asarray(integration_weights(wl, "linear")))


def luminance_from_spectrum(spectral_radiance, wavelengths_nm, method: str = "linear"
                            ) -> np.ndarray:
    """Luminance ``Y = 683 * integral L(l) y-bar(l) dl`` [cd m^-2].

    Parameters and quadrature as :func:`spectrum_to_xyz`; returns shape (...,).
    """
    w = _increasing(as_wavelengths(wavelengths_nm))
    L = _as_spectrum(spectral_radiance, w.size)
    W = integration_weights(w, method)
    return K_M * (L @ W[:, 1])


# --------------------------------------------------------------------------------------
# Chromaticity and RGB
# --------------------------------------------------------------------------------------

def _as_triples(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=np.float64)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return a


def xyz_to_xy(xyz) -> np.ndarray:
    """CIE 1931 chromaticity ``x = X / (X + Y + Z)``, ``y = Y / (X + Y + Z)``.

    Parameters
    ----------
    xyz : array_like
        Shape (..., 3), finite.

    Returns
    -------
    numpy.ndarray
        Shape (..., 2). Where ``X + Y + Z = 0`` (black) the D65 white point
        ``D65_XY = (0.31271, 0.32902)`` is returned.
    """
    XYZ = _as_triples(xyz, "xyz")
    s = XYZ.sum(axis=-1, keepdims=True)
    black = s == 0.0
    xy = XYZ[..., :2] / np.where(black, 1.0, s)
    return np.where(black, np.asarray(D65_XY), xy)


def xy_to_xyz(xy, Y=1.0) -> np.ndarray:
    """XYZ from chromaticity (x, y) and luminance Y: ``X = x Y / y``, ``Z = (1 - x - y) Y / y``.

    Parameters
    ----------
    xy : array_like
        Shape (..., 2), finite, with y > 0 wherever Y != 0.
    Y : array_like
        Luminance (any unit, e.g. cd m^-2), broadcast against ``xy[..., 0]``. Default 1.

    Returns
    -------
    numpy.ndarray
        Shape (..., 3); zeros where Y = 0.
    """
    c = np.asarray(xy, dtype=np.float64)
    if c.ndim == 0 or c.shape[-1] != 2:
        raise ValueError(f"xy must have shape (..., 2), got {c.shape}")
    Yv = np.asarray(Y, dtype=np.float64)
    if not (np.all(np.isfinite(c)) and np.all(np.isfinite(Yv))):
        raise ValueError("xy or Y contains NaN or infinite values")
    x, y = np.broadcast_arrays(c[..., 0], c[..., 1])
    x, y, Yv = np.broadcast_arrays(x, y, Yv)
    if np.any((y <= 0.0) & (Yv != 0.0)):
        raise ValueError("xy: y must be in (0, 1] wherever Y != 0 (got y <= 0)")
    ratio = np.where(Yv == 0.0, 0.0, Yv / np.where(y > 0.0, y, 1.0))
    return np.stack([x * ratio, Yv, (1.0 - x - y) * ratio], axis=-1)


def _xy_to_white_xyz(xy) -> np.ndarray:
    x, y = xy
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


def normalised_primary_matrix(primaries_xy, white_xy) -> np.ndarray:
    """RGB -> XYZ matrix of an RGB space from its primaries and white chromaticities.

    ``M = P diag(S)``, where the columns of P are the primaries' XYZ at Y = 1 and
    ``S = P^-1 W`` scales them so that RGB = (1, 1, 1) gives the white W (Y = 1) [RP177].
    """
    P = np.stack([_xy_to_white_xyz(p) for p in primaries_xy], axis=1)
    S = np.linalg.solve(P, _xy_to_white_xyz(white_xy))
    return P * S[None, :]


def _bradford(src_xy, dst_xy) -> np.ndarray:
    """Von Kries adaptation in the Bradford cone space [Lam85]:
    ``M = B^-1 diag(rho_dst / rho_src) B`` with ``rho = B @ XYZ_white``."""
    rho_s = _BRADFORD @ _xy_to_white_xyz(src_xy)
    rho_d = _BRADFORD @ _xy_to_white_xyz(dst_xy)
    return np.linalg.solve(_BRADFORD, (rho_d / rho_s)[:, None] * _BRADFORD)


# Matrices derived (not pasted) from the primaries, at import: a few 3x3 solves.
_M_SRGB_TO_XYZ = normalised_primary_matrix(_SRGB_PRIMARIES_XY, SRGB_WHITE_XY)
_M_XYZ_TO_SRGB = np.linalg.inv(_M_SRGB_TO_XYZ)
_M_AP1_TO_XYZ = normalised_primary_matrix(_AP1_PRIMARIES_XY, ACES_WHITE_XY)
_M_D65_TO_ACES = _bradford(SRGB_WHITE_XY, ACES_WHITE_XY)
_M_XYZ_D65_TO_ACESCG = np.linalg.solve(_M_AP1_TO_XYZ, _M_D65_TO_ACES)
_M_ACESCG_TO_XYZ_D65 = np.linalg.inv(_M_XYZ_D65_TO_ACESCG)


def xyz_to_linear_srgb(xyz) -> np.ndarray:
    """Linear sRGB (Rec. 709 primaries, D65 white) from XYZ; no clipping, same scale.

    The matrix is the inverse of the normalised primary matrix of the [709]/[IEC]
    primaries and white (0.3127, 0.3290) [RP177], in double precision. Its inverse (RGB ->
    XYZ) rounds to the 4-decimal matrix printed in [IEC] (largest difference 3.9e-5); the
    printed XYZ -> RGB matrix, the inverse of the rounded one, differs from ours by up to
    3.7e-4 per entry.

    Parameters
    ----------
    xyz : array_like
        Shape (..., 3), finite (e.g. Y in cd m^-2).

    Returns
    -------
    numpy.ndarray
        Shape (..., 3), linear R, G, B (may be negative out of gamut or above 1).
    """
    return np.dot(_as_triples(xyz, "xyz"), _M_XYZ_TO_SRGB.T)   # = @, several times faster


def linear_srgb_to_xyz(rgb) -> np.ndarray:
    """XYZ from linear sRGB (inverse of :func:`xyz_to_linear_srgb`); shape (..., 3)."""
    return np.dot(_as_triples(rgb, "rgb"), _M_SRGB_TO_XYZ.T)


def xyz_to_acescg(xyz) -> np.ndarray:
    """ACEScg (AP1 primaries, ACES white ~D60) from D65-referred XYZ.

    XYZ is adapted from D65 (0.3127, 0.3290) to the ACES white (0.32168, 0.33767) with the
    Bradford transform [Lam85], then converted with the inverse AP1 normalised primary
    matrix [S2065], [RP177].

    Parameters
    ----------
    xyz : array_like
        Shape (..., 3), finite, D65-referred.

    Returns
    -------
    numpy.ndarray
        Shape (..., 3), linear ACEScg R, G, B on the scale of the input.
    """
    return np.dot(_as_triples(xyz, "xyz"), _M_XYZ_D65_TO_ACESCG.T)


def acescg_to_xyz(rgb) -> np.ndarray:
    """D65-referred XYZ from ACEScg (inverse of :func:`xyz_to_acescg`); shape (..., 3)."""
    return np.dot(_as_triples(rgb, "rgb"), _M_ACESCG_TO_XYZ_D65.T)


def srgb_encode(linear) -> np.ndarray:
    """The sRGB transfer function (linear -> encoded) [IEC] section 5.2.

    ``V = 12.92 L`` for ``L <= 0.0031308``, else ``1.055 L^(1/2.4) - 0.055``; the input
    is clipped to [0, 1] first (NaN is refused).

    Parameters
    ----------
    linear : array_like
        Linear values, any shape.

    Returns
    -------
    numpy.ndarray
        Encoded values in [0, 1], same shape.
    """
    L = np.asarray(linear, dtype=np.float64)
    if np.any(np.isnan(L)):
        raise ValueError("linear contains NaN values")
    L = np.clip(L, 0.0, 1.0)
    return np.where(L <= 0.0031308, 12.92 * L, 1.055 * np.power(L, 1.0 / 2.4) - 0.055)


def srgb_decode(encoded) -> np.ndarray:
    """Inverse of :func:`srgb_encode` [IEC] section 5.2: ``L = V / 12.92`` for
    ``V <= 0.04045``, else ``((V + 0.055) / 1.055)^2.4``; input clipped to [0, 1]."""
    V = np.asarray(encoded, dtype=np.float64)
    if np.any(np.isnan(V)):
        raise ValueError("encoded contains NaN values")
    V = np.clip(V, 0.0, 1.0)
    return np.where(V <= 0.04045, V / 12.92, np.power((V + 0.055) / 1.055, 2.4))


# --------------------------------------------------------------------------------------
# Spectra from colours and temperatures
# --------------------------------------------------------------------------------------

@lru_cache(maxsize=1)
def _daylight_luminance_basis() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """S0, S1, S2 at the 1 nm CMF nodes 360-830 nm, and the 'linear' weights of that grid."""
    g = wavelength_grid(_CMF_RANGE[0], _CMF_RANGE[1], step_nm=1.0)
    return g, daylight_basis(g), integration_weights(g)[:, 1]


def spectrum_from_xyz_daylight(xyz, wavelengths_nm) -> np.ndarray:
    """CIE daylight spectrum with the chromaticity of ``xyz``, scaled to its luminance.

    ``S = S0 + M1 S1 + M2 S2`` with ([CIE15] 3rd ed., eqs. 3.5-3.6 / section 3.1)::

        M  = 0.0241 + 0.2562 x - 0.7341 y
        M1 = (-1.3515 - 1.7703 x + 5.9114 y) / M
        M2 = ( 0.0300 - 31.4424 x + 30.0717 y) / M

    (the CIE rounds M1, M2 to 3 decimals when it builds the standard D illuminants; this
    function does not). Negative values of S (possible far from the daylight locus) are
    set to 0. The result is scaled so that the continuous spectrum - S linearly
    interpolated on its 5 nm table - has ``683 * integral L y-bar dl = Y`` over
    360-830 nm (1 nm CMFs, exact quadrature); it is then sampled at ``wavelengths_nm``.
    A coarse or partial grid therefore carries the true spectral radiance, and its own
    quadrature reproduces Y only to its discretisation error.

    Parameters
    ----------
    xyz : array_like
        Shape (..., 3), finite, Y >= 0 [Y in cd m^-2]. Meaningful for daylight
        chromaticities (correlated colour temperature 4000-25000 K, [CIE15]).
    wavelengths_nm : array_like
        1-D wavelengths [nm] within [300, 830] (the range of the basis table).

    Returns
    -------
    numpy.ndarray
        Shape (..., n): spectral radiance [W m^-2 sr^-1 nm^-1], >= 0; zeros where Y = 0.

    Raises
    ------
    ValueError
        For Y < 0, or a chromaticity so far from the daylight locus that M is near 0
        (|M| < 1e-3) or the clamped spectrum has no luminance.
    """
    XYZ = _as_triples(xyz, "xyz")
    w = as_wavelengths(wavelengths_nm, *_DAYLIGHT_RANGE)
    Y = XYZ[..., 1]
    if np.any(Y < 0.0):
        raise ValueError(f"xyz: Y = {float(Y.min()):g} cd/m^2 is out of range [0, inf)")
    xy = xyz_to_xy(XYZ)
    x, y = xy[..., 0], xy[..., 1]
    M = 0.0241 + 0.2562 * x - 0.7341 * y                        # [CIE15] eq. 3.6
    lit = Y > 0.0
    if np.any(lit & (np.abs(M) < 1e-3)):
        raise ValueError("xyz: chromaticity too far from the daylight locus "
                         "(M = 0.0241 + 0.2562 x - 0.7341 y is near 0)")
    Ms = np.where(np.abs(M) < 1e-3, 1.0, M)
    M1 = (-1.3515 - 1.7703 * x + 5.9114 * y) / Ms                # [CIE15] eq. 3.6
    M2 = (0.0300 - 31.4424 * x + 30.0717 * y) / Ms               # [CIE15] eq. 3.6
    coef = np.stack([np.ones_like(M1), M1, M2], axis=-1)         # (..., 3)

    # luminance of the clamped relative spectrum on the exact 1 nm quadrature
    _, basis_fine, wy = _daylight_luminance_basis()
    s_fine = np.maximum(coef @ basis_fine.T, 0.0)                # (..., 471)
    y_rel = K_M * (s_fine @ wy)
    if np.any(lit & (y_rel <= 0.0)):
        raise ValueError("xyz: chromaticity gives a daylight spectrum with no luminance")
    scale = np.where(lit, Y / np.where(y_rel > 0.0, y_rel, 1.0), 0.0)

    s = np.maximum(coef @ daylight_basis(w).T, 0.0)              # S0 + M1 S1 + M2 S2
    return s * scale[..., None]


def blackbody(wavelengths_nm, temperature_k) -> np.ndarray:
    """Planck's law: blackbody spectral radiance [W m^-2 sr^-1 nm^-1].

    ``B(l, T) = 2 h c^2 / l^5 / (exp(h c / (l k T)) - 1)`` [Planck], per nm of wavelength.

    Parameters
    ----------
    wavelengths_nm : array_like
        1-D wavelengths [nm] in [1, 1e6].
    temperature_k : array_like
        Temperature(s) [K] > 0, finite; any shape (...), broadcast.

    Returns
    -------
    numpy.ndarray
        Shape (..., n), >= 0.
    """
    w = as_wavelengths(wavelengths_nm, 1.0, 1.0e6)
    T = np.asarray(temperature_k, dtype=np.float64)
    if not np.all(np.isfinite(T)) or np.any(T <= 0.0):
        bad = T[~(np.isfinite(T) & (T > 0.0))].ravel()[0]
        raise ValueError(f"temperature_k = {bad:g} K is out of range (0, inf) K")
    lam = w * 1e-9                                                # [m]
    x = (_H_PLANCK * _C_LIGHT / K_BOLTZMANN) / (lam * T[..., None])
    with np.errstate(over="ignore"):
        b = 2.0 * _H_PLANCK * _C_LIGHT**2 / lam**5 / np.expm1(x)  # [W m^-2 sr^-1 m^-1]
    return b * 1e-9
