"""Phase functions of the numerical core: one definition each (numba, scalar).

Every phase function is normalised over the sphere (integral of p dOmega = 1, so the
unit is sr^-1) and takes ``c``, the cosine of the scattering angle theta between the
direction of propagation before and after scattering (c = 1 forward).

* Rayleigh with depolarisation ratio rho ([Cha50]; Hansen & Travis 1974 eq. 2.15, element
  P11): 3/(16 pi) ((1 + 3 gamma) + (1 - gamma) c^2) / (1 + 2 gamma), gamma = rho / (2 - rho),
  identical to 3/(8 pi) ((1 + rho) + (1 - rho) c^2) / (2 + rho) ([KRZ06] eq. 3 over 4 pi for
  rho = 0).
* Henyey-Greenstein ([KRZ06] eq. 10 over 4 pi): (1 - g^2) / (1 + g^2 - 2 g c)^1.5 / (4 pi).
* Cornette-Shanks ([KRZ06] eq. 11 over 4 pi):
  3 (1 - g^2) / (2 (2 + g^2)) (1 + c^2) / (1 + g^2 - 2 g c)^1.5 / (4 pi).
* isotropic: 1 / (4 pi).
* tabulated: a table per constituent and wavelength on the uniform grid
  theta_k = pi k / (na - 1), k = 0..na-1 (Lorenz-Mie from :mod:`skydome.atmosphere.mie`,
  or measured), linearly interpolated in theta; sampled by inverting its cumulative
  distribution (:func:`skydome.transport._medium.phase_cdf_table`).

The constituent's ``phase_param`` is g for HG and CS, gamma = rho / (2 - rho) for Rayleigh.
"""

from __future__ import annotations

import math

from skydome._kernel_cache import njit

from skydome.transport._geometry import clamp_cosine

# phase codes (mirror of skydome.atmosphere.PHASE_CODES)
RAYLEIGH, HENYEY_GREENSTEIN, CORNETTE_SHANKS, ISOTROPIC, TABULATED = 0, 1, 2, 3, 4

INV_4PI = 1.0 / (4.0 * math.pi)


@njit(cache=True)
def rayleigh_gamma(rho):
    """gamma = rho / (2 - rho) of depolarisation ratio rho in [0, 0.5] ([Cha50])."""
    return rho / (2.0 - rho)


@njit(cache=True)
def rayleigh_rho(gamma):
    """Inverse of :func:`rayleigh_gamma`: rho = 2 gamma / (1 + gamma)."""
    return 2.0 * gamma / (1.0 + gamma)


@njit(cache=True)
def rayleigh_phase(gamma, c):
    """Rayleigh phase function with depolarisation [sr^-1] (Hansen & Travis 1974 eq. 2.15;
    [KRZ06] eq. 3 / 4 pi at gamma = 0); gamma = rho / (2 - rho)."""
    return 3.0 / (16.0 * math.pi) * 1.0 / (1.0 + 2.0 * gamma) * ((1.0 + 3.0 * gamma)
                                                               + (1.0 - gamma) * c * c)


@njit(cache=True)
def henyey_greenstein(g, c):
    """Henyey-Greenstein phase function [sr^-1] ([KRZ06] eq. 10 / 4 pi), g in (-1, 1)."""
    d = 1.0 + g * g - 2.0 * g * c
    return (1.0 - g * g) / (d * math.sqrt(d)) * INV_4PI


@njit(cache=True)
def cornette_shanks(g, c):
    """Cornette-Shanks phase function [sr^-1] ([KRZ06] eq. 11 / 4 pi), g in (-1, 1)."""
    d = 1.0 + g * g - 2.0 * g * c
    return 3.0 * (1.0 - g * g) / (2.0 * (2.0 + g * g)) * (1.0 + c * c) / (d * math.sqrt(d)) * INV_4PI


@njit(cache=True)
def phase_value(code, param, c):
    """Analytic phase function ``code`` with parameter ``param`` at cosine c [sr^-1];
    isotropic for ISOTROPIC and any other code (a tabulated constituent is evaluated with
    :func:`phase_of`)."""
    if code == RAYLEIGH:
        return rayleigh_phase(param, c)
    if code == HENYEY_GREENSTEIN:
        return henyey_greenstein(param, c)
    if code == CORNETTE_SHANKS:
        return cornette_shanks(param, c)
    return INV_4PI


@njit(cache=True)
def angle_cell(c, na):
    """(k, f): node and fraction of the scattering angle acos(c) on the uniform grid of na
    nodes over [0, pi]."""
    x = math.acos(clamp_cosine(c)) / math.pi * (na - 1)
    k = min(int(x), na - 2)
    return k, x - k


@njit(cache=True)
def tabulated_phase(table, ci, l, c):
    """Tabulated phase function table[ci, :, l] [sr^-1] at cosine c (linear in angle)."""
    k, f = angle_cell(c, table.shape[1])
    return (1.0 - f) * table[ci, k, l] + f * table[ci, k + 1, l]


@njit(cache=True)
def phase_coded(codes, params, table, ci, l, c):
    """Phase function of constituent ci of the arrays (codes, params, table) at wavelength
    index l and cosine c [sr^-1] (``table`` is read only where codes[ci] is TABULATED)."""
    if codes[ci] == TABULATED:
        return tabulated_phase(table, ci, l, c)
    return phase_value(codes[ci], params[ci], c)


@njit(cache=True)
def phase_of(m, ci, l, c):
    """Phase function of constituent ci of the medium m at wavelength index l [sr^-1]."""
    return phase_coded(m.phase_code, m.phase_param, m.phase_table, ci, l, c)


@njit(cache=True)
def phase_is_spectral(m, ci):
    """True where constituent ci's phase function depends on the wavelength."""
    return m.phase_code[ci] == TABULATED


@njit(cache=True)
def phase_fill_coded(codes, params, table, ci, c, out):
    """out[l] = phase function of constituent ci of the arrays (codes, params, table) at
    cosine c for every wavelength [sr^-1]."""
    if codes[ci] == TABULATED:
        k, f = angle_cell(c, table.shape[1])
        for l in range(out.shape[0]):
            out[l] = (1.0 - f) * table[ci, k, l] + f * table[ci, k + 1, l]
    else:
        p = phase_value(codes[ci], params[ci], c)
        for l in range(out.shape[0]):
            out[l] = p


@njit(cache=True)
def phase_fill(m, ci, c, out):
    """out[l] = phase function of constituent ci at cosine c for every wavelength [sr^-1]."""
    phase_fill_coded(m.phase_code, m.phase_param, m.phase_table, ci, c, out)


@njit(cache=True)
def phase_matrix_fill(m, c, out):
    """out[ci, l] = phase function of every constituent at cosine c [sr^-1]."""
    for ci in range(m.phase_code.shape[0]):
        phase_fill(m, ci, c, out[ci])


# -- sampling ----------------------------------------------------------------------------------
@njit(cache=True)
def sample_henyey_greenstein(g, u):
    """Cosine drawn from the HG phase function by inverting its CDF at u in [0, 1)
    (Henyey & Greenstein 1941; isotropic for |g| < 1e-6)."""
    if abs(g) < 1e-6:
        return 2.0 * u - 1.0
    s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
    return clamp_cosine((1.0 + g * g - s * s) / (2.0 * g))


@njit(cache=True)
def sample_tabulated(cdf, ci, l, u):
    """Cosine drawn from the tabulated phase function of constituent ci at wavelength l by
    inverting its cumulative distribution cdf[ci, :, l] (uniform grid in angle over
    [0, pi]) at u in [0, 1): binary search for the cell, linear inside it."""
    na = cdf.shape[1]
    lo = 0
    hi = na - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if cdf[ci, mid, l] <= u:
            lo = mid
        else:
            hi = mid
    c0 = cdf[ci, lo, l]
    c1 = cdf[ci, hi, l]
    f = 0.5 if c1 <= c0 else (u - c0) / (c1 - c0)
    theta = (lo + min(max(f, 0.0), 1.0)) * math.pi / (na - 1)
    return math.cos(theta)


@njit(cache=True)
def phase_values_many(m, cos_theta, out):
    """out[i, c, l] = phase function of constituent c at wavelength l and cosine
    cos_theta[i] [sr^-1] (every constituent of the medium m)."""
    for i in range(cos_theta.shape[0]):
        for ci in range(m.phase_code.shape[0]):
            phase_fill(m, ci, cos_theta[i], out[i, ci])
