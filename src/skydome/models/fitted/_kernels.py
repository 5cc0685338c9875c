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

This module imports numba: the model imports it lazily, in its evaluation methods.
"""

from __future__ import annotations

import math

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


@njit(parallel=True, cache=True, fastmath=True)
def lookup(d, table, theta_h, sin_az, cos_az, out):
    """out[i, :] = the table at direction d[i] ((N, 3), finite and non-zero; its length
    does not matter).

    theta_h: the horizon's zenith angle [rad]; (sin_az, cos_az): the sun's azimuth, from
    north towards east. Inverse mappings of :mod:`._grid`: sky x = sqrt(1 - theta /
    (theta_h - EPS)), ground x = sqrt((theta - theta_h - EPS) / (pi - theta_h - EPS)),
    azimuth t from phi / pi = A t + (1 - A) t^2 (the positive root); x clamped at 0
    between the two end nodes. theta = atan2(sqrt(x^2 + y^2), z) and phi = atan2(|sin|,
    cos) need no normalised vector."""
    n, c = d.shape[0], table.shape[2]
    a = A_PHI
    b = 1.0 - A_PHI
    inv_sky = 1.0 / (theta_h - EPS)
    inv_ground = 1.0 / (math.pi - theta_h - EPS)
    for i in prange(n):
        x, y, z = d[i, 0], d[i, 1], d[i, 2]
        m = max(abs(x), abs(y), abs(z))
        if m > 1e150 or m < 1e-150:          # squares would overflow or vanish: rescale
            x, y, z = x / m, y / m, z / m
        th = _atan2_pos(math.sqrt(x * x + y * y), z)
        sky = th < theta_h
        u_sky = math.sqrt(max(1.0 - th * inv_sky, 0.0)) * (N_SKY - 1)
        u_ground = math.sqrt(max((th - theta_h - EPS) * inv_ground, 0.0)) * (N_GROUND - 1)
        u = u_sky if sky else u_ground
        base = 0 if sky else N_SKY
        nu = N_SKY if sky else N_GROUND
        iu = min(int(u), nu - 2)
        fu = u - iu
        # azimuth from the sun's vertical plane, folded into [0, pi]
        cp = x * sin_az + y * cos_az
        sp = abs(x * cos_az - y * sin_az)
        # the zenith or the nadir (sp = cp = 0): any azimuth, phi = 0
        zero = sp == 0.0 and cp == 0.0
        phi = _atan2_pos(sp, 1.0 if zero else cp) * (1.0 / math.pi)
        t = (-a + math.sqrt(a * a + 4.0 * b * phi)) / (2.0 * b) * (N_PHI - 1)
        it = min(int(t), N_PHI - 2)
        ft = max(t - it, 0.0)
        r0 = base + iu
        w00 = (1.0 - fu) * (1.0 - ft)
        w01 = (1.0 - fu) * ft
        w10 = fu * (1.0 - ft)
        w11 = fu * ft
        for k in range(c):
            out[i, k] = (w00 * table[r0, it, k] + w01 * table[r0, it + 1, k]
                         + w10 * table[r0 + 1, it, k] + w11 * table[r0 + 1, it + 1, k])
