"""numba kernels for the analytic luminance models (CIE 1994 / 2003, ASRC-CIE, Perez 1993,
Preetham 1999).

Each kernel takes the directions as a C-contiguous (N, 3) float64 array of vectors (ENU,
where the light comes from; checked by ``flat_directions``, normalised inside the kernel) and
returns the model's value per direction, evaluating the same formulas, in the same order, as
the numpy reference code kept in each model module (they agree to round-off;
tests/test_analytic_kernels.py checks 1e-12 relative). The loops run in parallel over
directions (``prange``).

This module imports numba: the model modules import it lazily inside their evaluation
methods, never at module import time.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

_OPTS = dict(parallel=True, cache=True, fastmath=True)


@njit(cache=True, fastmath=True, inline="always")
def _clamp1(x):
    """Clamp a cosine to [-1, 1]."""
    if x > 1.0:
        return 1.0
    if x < -1.0:
        return -1.0
    return x


@njit(parallel=True, cache=True)
def _check(d):
    """Counts of rows of ``d`` (N, 3) with a non-finite entry and of zero-length rows (no
    fastmath here, so that the finiteness test is kept)."""
    n_bad = 0
    n_zero = 0
    for i in prange(d.shape[0]):
        x, y, z = d[i, 0], d[i, 1], d[i, 2]
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
            n_bad += 1
        elif x == 0.0 and y == 0.0 and z == 0.0:
            n_zero += 1
    return n_bad, n_zero


@njit(cache=True, fastmath=True, inline="always")
def _unit(d, i):
    """Row i of ``d`` divided by its Euclidean length (as skydome._validate.as_directions)."""
    x, y, z = d[i, 0], d[i, 1], d[i, 2]
    r = math.sqrt(x * x + y * y + z * z)
    return x / r, y / r, z / r


# -- CIE 1994 overcast: L/Lz = (1 + 2 cos theta) / 3 (survey eq. 13) ---------------------------
@njit(**_OPTS)
def cie_overcast(d, scale):
    n = d.shape[0]
    out = np.empty(n)
    for i in prange(n):
        x, y, z = _unit(d, i)
        if z >= 0.0:
            out[i] = scale * ((1.0 + 2.0 * z) / 3.0)
        else:
            out[i] = 0.0
    return out


# -- Kittler-type clear sky: f(gamma) = f0 + f1 exp(-3 gamma) + f2 cos^2 gamma,
#    phi(theta) = 1 - exp(-0.32 / cos theta) (survey eq. 14; Matsuura's turbid clear sky) ----
@njit(cache=True, fastmath=True, inline="always")
def _kittler(z, cg, f0, f1, f2, norm):
    gamma = math.acos(cg)
    if z > 0.0:
        grad = -math.expm1(-0.32 / z)
    else:
        grad = 1.0
    return (f0 + f1 * math.exp(-3.0 * gamma) + f2 * cg * cg) * grad / norm


@njit(**_OPTS)
def cie_kittler(d, s, f0, f1, f2, norm, scale):
    n = d.shape[0]
    out = np.empty(n)
    sx, sy, sz = s[0], s[1], s[2]
    for i in prange(n):
        x, y, z = _unit(d, i)
        if z >= 0.0:
            cg = _clamp1(x * sx + y * sy + z * sz)
            out[i] = scale * _kittler(z, cg, f0, f1, f2, norm)
        else:
            out[i] = 0.0
    return out


# -- CIE intermediate sky (gensky +i, skybright.cal intersky) ---------------------------------
@njit(cache=True, fastmath=True, inline="always")
def _intermediate(z, cg, sin_zt, fz, norm):
    """``fz`` = (1.562 - zt), ``sin_zt`` = sin(4.396 - 2.6 zt)."""
    eta = math.acos(_clamp1(z))
    gamma = math.acos(cg)
    num = ((1.35 * math.sin(5.631 - 3.59 * eta) + 3.12) * sin_zt + 6.37 - eta) / 2.326
    g = num * math.exp(-0.563 * gamma * ((2.629 - eta) * fz + 0.812))
    return max(g, 0.0) / norm


@njit(**_OPTS)
def cie_intermediate(d, s, zt, norm, scale):
    n = d.shape[0]
    out = np.empty(n)
    sx, sy, sz = s[0], s[1], s[2]
    sin_zt = math.sin(4.396 - 2.6 * zt)
    fz = 1.562 - zt
    for i in prange(n):
        x, y, z = _unit(d, i)
        if z >= 0.0:
            cg = _clamp1(x * sx + y * sy + z * sz)
            out[i] = scale * _intermediate(z, cg, sin_zt, fz, norm)
        else:
            out[i] = 0.0
    return out


# -- CIE 2003 general sky: gradation x indicatrix ([CIE03] eqs. 2-3) ---------------------------
@njit(**_OPTS)
def cie2003(d, s, a, b, c, dd, e, norm, scale):
    n = d.shape[0]
    out = np.empty(n)
    sx, sy, sz = s[0], s[1], s[2]
    edp = math.exp(dd * math.pi / 2.0)
    for i in prange(n):
        x, y, z = _unit(d, i)
        if z >= 0.0:
            cchi = _clamp1(x * sx + y * sy + z * sz)
            chi = math.acos(cchi)
            f = 1.0 + c * (math.exp(dd * chi) - edp) + e * cchi * cchi        # eq. 3
            if z > 0.0:
                phi = 1.0 + a * math.exp(b / z)                               # eq. 2
            else:
                phi = 1.0
            rel = f * phi / norm
            out[i] = scale * max(rel, 0.0)
        else:
            out[i] = 0.0
    return out


# -- ASRC-CIE mixture (Perez et al. 1990) ------------------------------------------------------
@njit(**_OPTS)
def asrc_cie(d, s, w, norms, zt, scale):
    """``w`` = weights (clear, turbid, intermediate, overcast), ``norms`` = the matching
    zenith normalisations (the overcast one unused)."""
    n = d.shape[0]
    out = np.empty(n)
    sx, sy, sz = s[0], s[1], s[2]
    wc, wt, wi, wo = w[0], w[1], w[2], w[3]
    nc, nt, ni = norms[0], norms[1], norms[2]
    sin_zt = math.sin(4.396 - 2.6 * zt)
    fz = 1.562 - zt
    for i in prange(n):
        x, y, z = _unit(d, i)
        if z < 0.0:
            out[i] = 0.0
            continue
        cg = _clamp1(x * sx + y * sy + z * sz)
        total = 0.0
        if wc > 0.0:
            total = total + wc * _kittler(z, cg, 0.91, 10.0, 0.45, nc)
        if wt > 0.0:
            total = total + wt * _kittler(z, cg, 0.856, 16.0, 0.3, nt)
        if wi > 0.0:
            total = total + wi * _intermediate(z, cg, sin_zt, fz, ni)
        if wo > 0.0:
            total = total + wo * ((1.0 + 2.0 * z) / 3.0)
        out[i] = scale * total
    return out


# -- Perez 1993 all-weather sky ([PSM93] eq. 1) -----------------------------------------------
@njit(**_OPTS)
def perez1993(d, s, a, b, c, dd, e, cz_min, scale):
    n = d.shape[0]
    out = np.empty(n)
    sx, sy, sz = s[0], s[1], s[2]
    for i in prange(n):
        x, y, z = _unit(d, i)
        if z >= 0.0:
            cg = _clamp1(x * sx + y * sy + z * sz)
            cz = max(z, cz_min)
            gamma = math.acos(cg)
            lv = (1.0 + a * math.exp(b / cz)) * (1.0 + c * math.exp(dd * gamma) + e * cg * cg)
            out[i] = max(lv * scale, 0.0)
        else:
            out[i] = 0.0
    return out


# -- Preetham 1999: Perez forms for Y, x, y ([PSS99] eq. 3) ------------------------------------
@njit(cache=True, fastmath=True, inline="always")
def _perez_form(c, cos_g, gamma, k):
    """F(theta, gamma) with coefficient row k of ``k`` (3, 5); ``c`` already floored."""
    return ((1.0 + k[0] * math.exp(k[1] / c))
            * (1.0 + k[2] * math.exp(k[3] * gamma) + k[4] * cos_g * cos_g))


@njit(**_OPTS)
def preetham(d, s, coef, zen, cos_floor, want_xyz):
    """``coef`` (3, 5): rows x, y, Y of A..E divided by nothing; ``zen`` (3,): zenith value
    divided by F(0, theta_s) for x, y, Y. Returns (N, 3) xyY, or XYZ when ``want_xyz``.
    Below the horizon: (x_z, y_z, 0), i.e. XYZ = 0."""
    n = d.shape[0]
    out = np.empty((n, 3))
    sx, sy, sz = s[0], s[1], s[2]
    kx = coef[0]
    ky = coef[1]
    kY = coef[2]
    for i in prange(n):
        x, y, z = _unit(d, i)
        if z < 0.0:
            if want_xyz:
                out[i, 0] = 0.0
                out[i, 1] = 0.0
                out[i, 2] = 0.0
            else:
                out[i, 0] = zen[3]
                out[i, 1] = zen[4]
                out[i, 2] = 0.0
            continue
        cg = _clamp1(x * sx + y * sy + z * sz)
        gamma = math.acos(cg)
        c = max(z, cos_floor)
        x = zen[0] * _perez_form(c, cg, gamma, kx)
        y = zen[1] * _perez_form(c, cg, gamma, ky)
        Y = max(zen[2] * _perez_form(c, cg, gamma, kY), 0.0)
        if want_xyz:
            out[i, 0] = x * Y / y
            out[i, 1] = Y
            out[i, 2] = (1.0 - x - y) * Y / y
        else:
            out[i, 0] = x
            out[i, 1] = y
            out[i, 2] = Y
    return out


def flat_directions(directions):
    """Validated directions as a C-contiguous (N, 3) array plus the leading shape.

    Same checks and messages as skydome._validate.as_directions, in one read-only pass; the
    kernels divide each vector by its length themselves (no normalised copy is made)."""
    d = np.asarray(directions, dtype=np.float64)
    if d.ndim == 0 or d.shape[-1] != 3:
        raise ValueError(f"directions must have shape (..., 3), got {d.shape}")
    lead = d.shape[:-1]
    flat = np.ascontiguousarray(d.reshape(-1, 3))
    n_bad, n_zero = _check(flat)
    if n_bad:
        raise ValueError("directions contains NaN or infinite values")
    if n_zero:
        raise ValueError("directions contains zero-length vectors")
    return flat, lead


# -- Hosek & Wilkie 2012: F(theta, gamma) L_M per channel ([HW12] eq. 9) ----------------------
@njit(**_OPTS)
def hosek_wilkie(d, s, cfg, rad):
    """``cfg`` (C, 9): the cooked coefficients A..I per channel; ``rad`` (C,): L_M.
    Returns (N, C): zero below the horizon, negatives of the fit clamped to zero."""
    n = d.shape[0]
    nc = cfg.shape[0]
    out = np.empty((n, nc))
    sx, sy, sz = s[0], s[1], s[2]
    for i in prange(n):
        x, y, z = _unit(d, i)
        if z < 0.0:
            for c in range(nc):
                out[i, c] = 0.0
            continue
        cg = _clamp1(x * sx + y * sy + z * sz)
        gamma = math.acos(cg)
        root_z = math.sqrt(z)
        for c in range(nc):
            A, B, C, D, E = cfg[c, 0], cfg[c, 1], cfg[c, 2], cfg[c, 3], cfg[c, 4]
            F, G, H, I = cfg[c, 5], cfg[c, 6], cfg[c, 7], cfg[c, 8]
            chi = (1.0 + cg * cg) / (1.0 + H * H - 2.0 * H * cg) ** 1.5       # eq. 9, chi
            grad = 1.0 + A * math.exp(B / (z + 0.01))
            ind = C + D * math.exp(E * gamma) + F * cg * cg + G * chi + I * root_z
            v = grad * ind * rad[c]
            out[i, c] = v if v > 0.0 else 0.0
    return out
# -- Perez 1993 over many suns and sky patches at once ([PSM93] eq. 1) --------------------------
# Strict IEEE arithmetic (no fastmath) in the sky-matrix path: fastmath lets LLVM contract and
# reorder differently in each compilation, and a matrix chunk compiled in a Dask worker then
# differs from the serial run in the last bit; without it every compilation gives the same bits.
@njit(cache=True)
def _perez_patch_nodes(nodes, weights, m0, m1, sx, sy, sz, a, b, c, dd, e, cz_min, tot,
                       z_last, grad):
    """Mean of lv over nodes m0:m1 (one patch) and ``tot`` + its sum of w lv cos(zeta); the
    gradation term is computed once per run of nodes of equal altitude (``z_last``, ``grad``
    carried from patch to patch). Returns (mean, tot, z_last, grad)."""
    acc = 0.0
    wsum = 0.0
    for m in range(m0, m1):
        x, y, z = nodes[m, 0], nodes[m, 1], nodes[m, 2]
        if z != z_last:  # nodes come in runs of equal altitude: one gradation per run
            z_last = z
            grad = 1.0 + a * math.exp(b / max(z, cz_min))
        cg = _clamp1(x * sx + y * sy + z * sz)
        gamma = math.acos(cg)
        lv = grad * (1.0 + c * math.exp(dd * gamma) + e * cg * cg)
        if lv < 0.0:
            lv = 0.0
        w = weights[m]
        acc += w * lv
        wsum += w
        tot += w * lv * z
    return acc / wsum, tot, z_last, grad


@njit(cache=True)
def perez1993_patch_row(nodes, weights, offsets, s, coef, cz_min, means):
    """Patch means of the relative luminance lv of one sky into ``means`` (P,).

    ``nodes`` (M, 3) unit vectors and ``weights`` (M,) [sr] of the quadrature nodes, patch k
    owning nodes offsets[k]:offsets[k + 1]; ``s`` (3,) the unit vector towards the sun and
    ``coef`` (5,) the (a, b, c, d, e). Negative lv is clipped to 0 per node. Returns the
    hemispherical integral of lv cos(zeta) dOmega [sr] taken with the same nodes (gendaymtx's
    CalcRelHorzIllum for one node a patch)."""
    sx, sy, sz = s[0], s[1], s[2]
    a, b, c, dd, e = coef[0], coef[1], coef[2], coef[3], coef[4]
    tot = 0.0
    z_last = 2.0
    grad = 0.0
    for k in range(offsets.shape[0] - 1):
        means[k], tot, z_last, grad = _perez_patch_nodes(
            nodes, weights, offsets[k], offsets[k + 1], sx, sy, sz, a, b, c, dd, e, cz_min,
            tot, z_last, grad)
    return tot


@njit(cache=True)
def perez1993_patch_row_tiered(nodes, weights, offsets, centres, cos_tier, s, coef, cz_min,
                               means):
    """:func:`perez1993_patch_row` with a rule per patch chosen by its angle to the sun.

    ``offsets`` (T, P + 1): T rules over the same patches, their nodes in ``nodes`` /
    ``weights``; patch k takes the first rule t < T - 1 with cos(angle between its centre
    ``centres[k]`` and the sun ``s``) > ``cos_tier[t, k]`` (finest, nearest rule first), the
    last rule otherwise. With T = 1 it is :func:`perez1993_patch_row`, bit for bit."""
    sx, sy, sz = s[0], s[1], s[2]
    a, b, c, dd, e = coef[0], coef[1], coef[2], coef[3], coef[4]
    n_t = offsets.shape[0]
    tot = 0.0
    z_last = 2.0
    grad = 0.0
    for k in range(offsets.shape[1] - 1):
        t = 0
        if n_t > 1:
            d = centres[k, 0] * sx + centres[k, 1] * sy + centres[k, 2] * sz
            while t < n_t - 1 and not d > cos_tier[t, k]:
                t += 1
        means[k], tot, z_last, grad = _perez_patch_nodes(
            nodes, weights, offsets[t, k], offsets[t, k + 1], sx, sy, sz, a, b, c, dd, e,
            cz_min, tot, z_last, grad)
    return tot


@njit(**_OPTS)
def perez1993_patch_means(nodes, weights, offsets, suns, coef, cz_min):
    """:func:`perez1993_patch_row` for many skies (``suns`` (H, 3), ``coef`` (H, 5)) in
    parallel: returns the patch means (H, P) and the horizontal integrals (H,) [sr]."""
    n_sky = suns.shape[0]
    means = np.empty((n_sky, offsets.shape[0] - 1))
    horiz = np.empty(n_sky)
    for h in prange(n_sky):
        horiz[h] = perez1993_patch_row(nodes, weights, offsets, suns[h], coef[h], cz_min,
                                       means[h])
    return means, horiz
