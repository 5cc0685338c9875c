"""The numba kernel of the ``fitted`` model: per-direction lookups in the angular table of
one configuration.

The table (N_SKY + N_GROUND, N_PHI, C) holds C channels (wavelengths, XYZ or luminance) on
the view grid of :mod:`._grid`; a direction's value is the bilinear interpolation between
its four nodes. One specialisation (float64, C-contiguous) serves every channel count, so
the first use compiles once (and numba's cache keeps it).

The two angles of a direction (its zenith angle and its azimuth from the sun's vertical)
are computed by :func:`_atan2_pos`, an arctangent of our own made of arithmetic alone
(no library call, so that the loop stays inline): the same angles as ``math.atan2`` within
a few units in the last place (tests/test_fitted_kernels.py checks it against
``math.atan2``, and the lookups against the inverse mappings written with numpy).

The kernel works in blocks of :data:`BLOCK` directions: first the cells and weights of the
whole block, in a loop of arithmetic and selects only (no call, no branch), which LLVM
vectorises (SIMD across the block's directions), then the table reads. It also counts
the non-finite and zero-length rows itself (on the bits of the floats, which fastmath
leaves alone), so that the caller needs no separate pass over the directions to check
them; such rows are looked up as the zenith meanwhile and the caller raises.

This module imports numba: the model imports it lazily, in its evaluation methods.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skydome.models.fitted._grid import A_PHI, EPS, N_GROUND, N_PHI, N_SKY

# atan(t) = k pi/12 + atan((t - c_k) / (1 + t c_k)), c_k = tan(k pi/12), k = 0..3 chosen
# so that the reduced argument lies within tan(pi/24) = 0.1317 of zero; there the Taylor
# series t - t^3/3 + ... to t^17/17 leaves a remainder below t^19/19 < 1.0e-18.
_T15 = math.tan(math.pi / 12.0)
_T30 = math.tan(math.pi / 6.0)
_B1 = math.tan(math.pi / 24.0)            # boundaries of the four reductions
_B2 = math.tan(3.0 * math.pi / 24.0)
_B3 = math.tan(5.0 * math.pi / 24.0)
_A15 = math.pi / 12.0
_A30 = math.pi / 6.0
_A45 = math.pi / 4.0


@njit(inline="always", fastmath=False, cache=True)
def _atan2_pos(s, c):
    """atan2(s, c) for s >= 0 (not both zero), in [0, pi], with arithmetic alone and no
    branch (selects only: random directions would mispredict branches)."""
    ac = abs(c)
    swap = s > ac
    lo = min(s, ac)
    hi = max(s, ac)
    # t = lo / hi in [0, 1] (compared as lo >= B hi): reduce to |r| <= tan(pi/24),
    # r = (t - c_k) / (1 + t c_k) = (lo - c_k hi) / (hi + c_k lo)
    ck = 0.0
    base = 0.0
    ck = _T15 if lo >= _B1 * hi else ck
    base = _A15 if lo >= _B1 * hi else base
    ck = _T30 if lo >= _B2 * hi else ck
    base = _A30 if lo >= _B2 * hi else base
    ck = 1.0 if lo >= _B3 * hi else ck
    base = _A45 if lo >= _B3 * hi else base
    r = (lo - ck * hi) / (hi + ck * lo)
    r2 = r * r
    p = 1.0 / 17.0
    p = p * r2 - 1.0 / 15.0
    p = p * r2 + 1.0 / 13.0
    p = p * r2 - 1.0 / 11.0
    p = p * r2 + 1.0 / 9.0
    p = p * r2 - 1.0 / 7.0
    p = p * r2 + 1.0 / 5.0
    p = p * r2 - 1.0 / 3.0
    a = base + (r + r * r2 * p)
    a = (0.5 * math.pi - a) if swap else a
    return (math.pi - a) if c < 0.0 else a


@njit(cache=True)
def atan2_pos(s, c):
    """:func:`_atan2_pos` callable from Python (for tests)."""
    return _atan2_pos(s, c)


#: Directions per block of the lookup: the block's cells and weights are computed in one
#: loop without calls or branches (vectorised over the block), then the table is read.
BLOCK = 256
_EXP = 0x7FF0000000000000       # the exponent bits of a float64: all set for inf and NaN
_MAG = 0x7FFFFFFFFFFFFFFF       # all bits but the sign: zero for +0.0 and -0.0
_BIG = 2.0 ** -600              # exact rescaling of lengths beyond 1e150 / below 1e-150
_SMALL = 2.0 ** 600


@njit(parallel=True, cache=True, fastmath=True)
def lookup(d, bits, table, c, theta_h, sin_az, cos_az, out):
    """out[i, :] = the table at direction d[i] (its length does not matter); returns the
    numbers of rows of ``d`` with a non-finite entry and of zero-length rows, so that the
    caller raises the checks' errors (those rows get the zenith's value meanwhile).

    d: (N, 3) float64, C-contiguous; bits: the same memory as int64 (``d.view(np.int64)``:
    the finiteness test on the exponent bits, which fastmath keeps); table: the angular
    table (N_SKY + N_GROUND, N_PHI, c) flattened; out: (N, c).

    theta_h: the horizon's zenith angle [rad]; (sin_az, cos_az): the sun's azimuth, from
    north towards east. Inverse mappings of :mod:`._grid`: sky x = sqrt(1 - theta /
    (theta_h - EPS)), ground x = sqrt((theta - theta_h - EPS) / (pi - theta_h - EPS)),
    azimuth t from phi / pi = A t + (1 - A) t^2 (the positive root); x clamped at 0
    between the two end nodes. theta = atan2(sqrt(x^2 + y^2), z) and phi = atan2(|sin|,
    cos) need no normalised vector."""
    n = d.shape[0]
    a = A_PHI
    b = 1.0 - A_PHI
    inv_sky = 1.0 / (theta_h - EPS)
    inv_ground = 1.0 / (math.pi - theta_h - EPS)
    th_g = theta_h + EPS
    row_c = N_PHI * c
    n_blocks = (n + BLOCK - 1) // BLOCK
    n_bad = 0
    n_zero = 0
    for blk in prange(n_blocks):
        i0 = blk * BLOCK
        m = min(BLOCK, n - i0)
        idx = np.empty(BLOCK, np.int64)
        fu_ = np.empty(BLOCK)
        ft_ = np.empty(BLOCK)
        bad_b = 0
        zero_b = 0
        # pass 1: cell and weights of every direction of the block (selects only)
        for j in range(m):
            i = i0 + j
            bx, by, bz = bits[i, 0], bits[i, 1], bits[i, 2]
            bad = ((bx & _EXP) == _EXP) | ((by & _EXP) == _EXP) | ((bz & _EXP) == _EXP)
            zero = ((bx & _MAG) | (by & _MAG) | (bz & _MAG)) == 0
            bad_b += 1 if bad else 0
            zero_b += 1 if (zero and not bad) else 0
            skip = bad | zero
            x = 0.0 if skip else d[i, 0]
            y = 0.0 if skip else d[i, 1]
            z = 1.0 if skip else d[i, 2]
            mx = max(abs(x), abs(y), abs(z))
            # squares that would overflow or vanish: scale by a power of two (exact)
            s = _BIG if mx > 1e150 else 1.0
            s = _SMALL if mx < 1e-150 else s
            x, y, z = x * s, y * s, z * s
            th = _atan2_pos(math.sqrt(x * x + y * y), z)
            sky = th < theta_h
            q = (1.0 - th * inv_sky) if sky else (th - th_g) * inv_ground
            u = math.sqrt(max(q, 0.0)) * ((N_SKY - 1) if sky else (N_GROUND - 1))
            iu = min(int(u), (N_SKY - 2) if sky else (N_GROUND - 2))
            # azimuth from the sun's vertical plane, folded into [0, pi]
            cp = x * sin_az + y * cos_az
            sp = abs(x * cos_az - y * sin_az)
            # the zenith or the nadir (sp = cp = 0): any azimuth, phi = 0
            cp = 1.0 if (sp == 0.0 and cp == 0.0) else cp
            phi = _atan2_pos(sp, cp) * (1.0 / math.pi)
            t = (-a + math.sqrt(a * a + 4.0 * b * phi)) / (2.0 * b) * (N_PHI - 1)
            it = min(int(t), N_PHI - 2)
            idx[j] = ((iu if sky else iu + N_SKY) * N_PHI + it) * c
            fu_[j] = min(u - iu, 1.0)
            ft_[j] = min(max(t - it, 0.0), 1.0)
        n_bad += bad_b
        n_zero += zero_b
        # pass 2: the bilinear interpolation, v = lerp(lerp(t00, t01), lerp(t10, t11))
        if c == 1:
            for j in range(m):
                k = idx[j]
                fu, ft = fu_[j], ft_[j]
                p0 = table[k] + ft * (table[k + 1] - table[k])
                p1 = table[k + N_PHI] + ft * (table[k + N_PHI + 1] - table[k + N_PHI])
                out[i0 + j, 0] = p0 + fu * (p1 - p0)
        elif c == 3:
            for j in range(m):
                k = idx[j]
                fu, ft = fu_[j], ft_[j]
                for ch in range(3):
                    t0 = table[k + ch]
                    t1 = table[k + 3 + ch]
                    t2 = table[k + row_c + ch]
                    t3 = table[k + row_c + 3 + ch]
                    p0 = t0 + ft * (t1 - t0)
                    p1 = t2 + ft * (t3 - t2)
                    out[i0 + j, ch] = p0 + fu * (p1 - p0)
        else:
            for j in range(m):
                k = idx[j]
                fu, ft = fu_[j], ft_[j]
                for ch in range(c):
                    t0 = table[k + ch]
                    t1 = table[k + c + ch]
                    t2 = table[k + row_c + ch]
                    t3 = table[k + row_c + c + ch]
                    p0 = t0 + ft * (t1 - t0)
                    p1 = t2 + ft * (t3 - t2)
                    out[i0 + j, ch] = p0 + fu * (p1 - p0)
    return n_bad, n_zero
