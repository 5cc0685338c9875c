"""The numba kernel of the ``fitted`` model: per-direction lookups in the angular table of
one configuration.

The table (N_SKY + N_GROUND, N_PHI, C) holds C channels (wavelengths, XYZ or luminance) on
the view grid of :mod:`._grid`; a direction's value is cubic along the zenith angle and
linear along the azimuth: the Catmull-Rom spline (Catmull & Rom 1974; Keys 1981 with a =
-1/2) through the four rows of nodes around it, in the mapped coordinate u of its part of
the grid (the sky or the ground: the horizon is never interpolated across), each row read
linearly between its two azimuth nodes. At a part's first and last cell the row beyond
the end is the straight line through the end's two rows (p[-1] = 2 p[0] - p[1]), folded
into the weights. The spline goes through the nodes and reproduces a quadratic in u; the
bilinear lookup of the earlier kernel missed the curvature of a sky that bends within a
few rows (next to the horizon of an observer aloft in twilight: docs/models.md,
"fitted", "The lookup between the view grid's rows"). Where it overshoots below zero the
value is clamped at 0. One specialisation (float64, C-contiguous) serves every channel
count, so the first use compiles once (and numba's cache keeps it).

The two angles of a direction (its zenith angle and its azimuth from the sun's vertical)
are computed by :func:`_atan2_pos`, an arctangent of our own made of arithmetic alone
(no library call, so that the loop stays inline): the same angles as ``math.atan2`` within
a few units in the last place (tests/test_fitted_kernels.py checks it against
``math.atan2``, and the lookups against the inverse mappings written with numpy).

The kernel works in blocks of :data:`BLOCK` directions: first the block's directions copied
into contiguous arrays, then the cells and weights of the whole block, in a loop of
arithmetic and selects only (no call, no branch, no float -> int conversion, contiguous
loads), which LLVM vectorises (SIMD across the block's directions) on AVX2 and AVX-512
targets alike, then the table reads (with numpy's error model: Python's puts a zero test
that raises before every division, and the loop stayed scalar, 28 M directions/s against
83 on a 2-core AMD EPYC), with unsigned indices (no test for a negative index before each
read: XYZ 31 -> 41 M directions/s on one thread of the same machine, output written
before). It also counts the non-finite rows (on the bits of the floats, which fastmath
leaves alone) and the zero-length rows itself, so that the caller needs no separate pass
over the directions to check them; such rows are looked up as the zenith meanwhile and the
caller raises.

This module imports numba: the model imports it lazily, in its evaluation methods.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit

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
#: The rows of a block's scratch array, one allocation of 9 BLOCK floats: the direction's
#: x, y, z (pass 0), its cell's first table index, the four row weights and the azimuth
#: fraction (pass 1). One array with constant offsets rather than nine: LLVM then sees that
#: the rows cannot overlap, where nine arrays' pointers would need run-time overlap checks
#: before the vectorised loop (measured 10 % faster on one thread, 2-core AMD EPYC).
_X, _Y, _Z, _IDX, _WA, _WB, _WC, _WD, _FT = (k * BLOCK for k in range(9))
#: Unsigned offsets for the table and array reads of passes 0 and 2. numba indexes with a
#: signed integer through a test for a negative index (Python's wrap-around: a compare and
#: a conditional move per read, 72 instructions per direction for XYZ); an unsigned index
#: has none. Every offset of such an index must be unsigned too: numba promotes uint64 +
#: int64 to float64.
_U1, _U2, _U3 = np.uint64(1), np.uint64(2), np.uint64(3)
_U_PHI, _U_PHI2, _U_PHI3 = np.uint64(N_PHI), np.uint64(2 * N_PHI), np.uint64(3 * N_PHI)
_EXP = 0x7FF0000000000000       # the exponent bits of a float64: all set for inf and NaN
_BIG = 2.0 ** -600              # exact rescaling of lengths beyond 1e150 / below 1e-150
_SMALL = 2.0 ** 600


@njit(nogil=True, cache=True, fastmath=True, error_model="numpy")
def lookup_blocks(d, bits, table, c, theta_h, sin_az, cos_az, out, b0, b1):
    """out[i, :] = the table at direction d[i] (its length does not matter) for the
    directions of blocks b0 .. b1 - 1 (:data:`BLOCK` directions each); returns the numbers
    of their rows with a non-finite entry and of zero-length rows, so that the caller
    raises the checks' errors (those rows get the zenith's value meanwhile). Serial and
    without the interpreter lock: :func:`lookup` runs it on several threads.

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
    cf = float(c)
    n_bad = 0
    n_zero = 0
    # flat views of the C-contiguous arrays, read and written with unsigned indices
    flat_bits = bits.reshape(bits.size)
    flat_d = d.reshape(d.size)
    flat_out = out.reshape(out.size)
    cu = np.uint64(c)
    ru = np.uint64(row_c)
    ru2 = ru + ru
    ru3 = ru2 + ru
    sc = np.empty(9 * BLOCK)    # the block's scratch (one per call: the call is serial)
    for blk in range(b0, b1):
        i0 = blk * BLOCK
        m = min(BLOCK, n - i0)
        bad_b = 0
        zero_b = 0
        # pass 0: the block's directions copied into three contiguous rows. Read in place
        # (x, y, z three floats apart), pass 1 would need strided loads that LLVM's cost
        # model for AVX2 targets (AMD Zen 3) judged too dear: it left pass 1 scalar there,
        # 3-4 times slower (it vectorised it on AVX-512 targets anyway); docs/performance.md,
        # "The fitted lookup on AVX2". First the block's 3 m floats (contiguous: a
        # vectorised loop) are tested for a non-finite entry; only a block that has one
        # is copied row by row, its bad rows counted and replaced by the zenith. The
        # zero-length rows are counted in pass 1.
        nf = 0
        for k in range(3 * i0, 3 * (i0 + m)):
            nf += 1 if (flat_bits[k] & _EXP) == _EXP else 0
        if nf == 0:
            for j in range(m):
                o = np.uint64(i0 + j) * _U3
                sc[_X + j] = flat_d[o]
                sc[_Y + j] = flat_d[o + _U1]
                sc[_Z + j] = flat_d[o + _U2]
        else:
            for j in range(m):
                i = i0 + j
                bx, by, bz = bits[i, 0], bits[i, 1], bits[i, 2]
                bad = ((bx & _EXP) == _EXP) | ((by & _EXP) == _EXP) | ((bz & _EXP) == _EXP)
                bad_b += 1 if bad else 0
                sc[_X + j] = 0.0 if bad else d[i, 0]
                sc[_Y + j] = 0.0 if bad else d[i, 1]
                sc[_Z + j] = 1.0 if bad else d[i, 2]
        # pass 1: cell and weights of every direction of the block (selects only)
        for j in range(m):
            x = sc[_X + j]
            y = sc[_Y + j]
            z = sc[_Z + j]
            mx = max(abs(x), abs(y), abs(z))
            # squares that would overflow or vanish: scale by a power of two (exact)
            s = _BIG if mx > 1e150 else 1.0
            s = _SMALL if mx < 1e-150 else s
            x, y, z = x * s, y * s, z * s
            # a zero-length row (x = y = z = 0): counted, looked up as the zenith meanwhile
            zero_b += 1 if mx == 0.0 else 0
            z = 1.0 if mx == 0.0 else z
            th = _atan2_pos(math.sqrt(x * x + y * y), z)
            sky = th < theta_h
            q = (1.0 - th * inv_sky) if sky else (th - th_g) * inv_ground
            u = math.sqrt(max(q, 0.0)) * ((N_SKY - 1) if sky else (N_GROUND - 1))
            last = (N_SKY - 2) if sky else (N_GROUND - 2)
            # the cell as a float (np.floor): AVX2 has no packed float64 -> int64 conversion,
            # so an int here would keep the loop scalar; pass 2 converts the index
            iu = min(max(np.floor(u), 0.0), float(last))
            # Catmull-Rom weights of the rows iu - 1, iu, iu + 1, iu + 2 at f = u - iu
            f = min(u - iu, 1.0)
            f2 = f * f
            f3 = f2 * f
            wm = -0.5 * f3 + f2 - 0.5 * f
            w0 = 1.5 * f3 - 2.5 * f2 + 1.0
            w1 = -1.5 * f3 + 2.0 * f2 + 0.5 * f
            w2 = 0.5 * f3 - 0.5 * f2
            # four consecutive rows r0 .. r0 + 3 of the part: inside, r0 = iu - 1; in the
            # first cell r0 = 0 with p[-1] = 2 p[0] - p[1] folded in; in the last r0 = iu - 2
            # with p[iu + 2] = 2 p[iu + 1] - p[iu]
            lo = iu == 0
            hi = iu == last
            a0 = (w0 + 2.0 * wm) if lo else (0.0 if hi else wm)
            a1 = (w1 - wm) if lo else (wm if hi else w0)
            a2 = w2 if lo else ((w0 - w2) if hi else w1)
            a3 = 0.0 if lo else ((w1 + 2.0 * w2) if hi else w2)
            r0 = 0.0 if lo else ((iu - 2.0) if hi else (iu - 1.0))
            # azimuth from the sun's vertical plane, folded into [0, pi]
            cp = x * sin_az + y * cos_az
            sp = abs(x * cos_az - y * sin_az)
            # the zenith or the nadir (sp = cp = 0): any azimuth, phi = 0
            cp = 1.0 if (sp == 0.0 and cp == 0.0) else cp
            phi = _atan2_pos(sp, cp) * (1.0 / math.pi)
            t = (-a + math.sqrt(a * a + 4.0 * b * phi)) / (2.0 * b) * (N_PHI - 1)
            # t is 0 at phi = 0 in exact arithmetic, but fastmath may rearrange the root
            # (the constants divided through) and give -1e-16: floor would then make the
            # cell -1, and the read before it fall outside the table for the sky's first
            # cell (a weight of 1e-16 times whatever lies there: 1e216 and NaN were seen).
            # The cell is clamped to the table as the shaders' int() does.
            it = min(max(np.floor(t), 0.0), float(N_PHI - 2))
            sc[_IDX + j] = ((r0 if sky else r0 + N_SKY) * N_PHI + it) * cf
            sc[_WA + j] = a0
            sc[_WB + j] = a1
            sc[_WC + j] = a2
            sc[_WD + j] = a3
            sc[_FT + j] = min(max(t - it, 0.0), 1.0)
        n_bad += bad_b
        n_zero += zero_b
        # pass 2: per row r0 .. r0 + 3 the linear interpolation in azimuth, the rows weighted
        # by the spline's weights: v = sum_r a_r (T[r, it] + ft (T[r, it + 1] - T[r, it])).
        # XYZ written out channel by channel: the six values of a row (three channels at it
        # and at it + 1) are contiguous
        if c == 1:
            for j in range(m):
                k = np.uint64(int(sc[_IDX + j]))
                ft = sc[_FT + j]
                wa, wb, wc, wd = sc[_WA + j], sc[_WB + j], sc[_WC + j], sc[_WD + j]
                p0 = (wa * table[k] + wb * table[k + _U_PHI]
                      + wc * table[k + _U_PHI2] + wd * table[k + _U_PHI3])
                k1 = k + _U1
                p1 = (wa * table[k1] + wb * table[k1 + _U_PHI]
                      + wc * table[k1 + _U_PHI2] + wd * table[k1 + _U_PHI3])
                flat_out[np.uint64(i0 + j)] = max(p0 + ft * (p1 - p0), 0.0)
        elif c == 3:
            for j in range(m):
                k = np.uint64(int(sc[_IDX + j]))
                ft = sc[_FT + j]
                wa, wb, wc, wd = sc[_WA + j], sc[_WB + j], sc[_WC + j], sc[_WD + j]
                ka, kb, kc, kd = k, k + ru, k + ru2, k + ru3
                x0 = wa * table[ka] + wb * table[kb] + wc * table[kc] + wd * table[kd]
                ka, kb, kc, kd = ka + _U1, kb + _U1, kc + _U1, kd + _U1
                y0 = wa * table[ka] + wb * table[kb] + wc * table[kc] + wd * table[kd]
                ka, kb, kc, kd = ka + _U1, kb + _U1, kc + _U1, kd + _U1
                z0 = wa * table[ka] + wb * table[kb] + wc * table[kc] + wd * table[kd]
                ka, kb, kc, kd = ka + _U1, kb + _U1, kc + _U1, kd + _U1
                x1 = wa * table[ka] + wb * table[kb] + wc * table[kc] + wd * table[kd]
                ka, kb, kc, kd = ka + _U1, kb + _U1, kc + _U1, kd + _U1
                y1 = wa * table[ka] + wb * table[kb] + wc * table[kc] + wd * table[kd]
                ka, kb, kc, kd = ka + _U1, kb + _U1, kc + _U1, kd + _U1
                z1 = wa * table[ka] + wb * table[kb] + wc * table[kc] + wd * table[kd]
                o = np.uint64(i0 + j) * _U3
                flat_out[o] = max(x0 + ft * (x1 - x0), 0.0)
                flat_out[o + _U1] = max(y0 + ft * (y1 - y0), 0.0)
                flat_out[o + _U2] = max(z0 + ft * (z1 - z0), 0.0)
        else:
            for j in range(m):
                k = np.uint64(int(sc[_IDX + j]))
                ft = sc[_FT + j]
                wa, wb, wc, wd = sc[_WA + j], sc[_WB + j], sc[_WC + j], sc[_WD + j]
                o = np.uint64(i0 + j) * cu
                for ch in range(c):
                    kk = k + np.uint64(ch)
                    p0 = (wa * table[kk] + wb * table[kk + ru]
                          + wc * table[kk + ru2] + wd * table[kk + ru3])
                    kk += cu
                    p1 = (wa * table[kk] + wb * table[kk + ru]
                          + wc * table[kk + ru2] + wd * table[kk + ru3])
                    flat_out[o + np.uint64(ch)] = max(p0 + ft * (p1 - p0), 0.0)
    return n_bad, n_zero


#: Blocks per thread below which :func:`lookup` runs on the calling thread alone (32768
#: directions).
MIN_BLOCKS_PER_THREAD = 128


def lookup(d, bits, table, c, theta_h, sin_az, cos_az, out):
    """:func:`lookup_blocks` over every direction of ``d`` on numba's thread count of
    threads (:func:`skydome._threads.run_ranges`); returns the numbers of non-finite and of
    zero-length rows.

    The threads are Python's, each running the serial kernel without the interpreter lock,
    rather than a numba ``prange``: the parallel kernel compiled in 5.8-11.6 s on a 2-core
    AMD EPYC (Zen 3), the serial one in 1.8-3.8 s (a first use without numba's cache: issue
    29, "no multi-second compilation"; docs/performance.md, "Kernels on Python threads")."""
    from skydome._threads import run_ranges

    n_blocks = (d.shape[0] + BLOCK - 1) // BLOCK
    counts = run_ranges(lookup_blocks, n_blocks,
                        (d, bits, table, c, theta_h, sin_az, cos_az, out),
                        MIN_BLOCKS_PER_THREAD)
    return sum(b for b, _ in counts), sum(z for _, z in counts)
