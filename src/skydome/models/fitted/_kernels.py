"""The numba kernel of the ``fitted`` model: per-direction lookups in the angular table of
one configuration.

The table (N_SKY + N_GROUND, N_PHI, C) holds C channels (wavelengths, XYZ or luminance) on
the view grid of :mod:`._grid`; a direction's value is the bilinear interpolation between
its four nodes. One specialisation (float64, C-contiguous) serves every channel count, so
the first use compiles once (and numba's cache keeps it).

This module imports numba: the model imports it lazily, in its evaluation methods.
"""

from __future__ import annotations

import math

from numba import njit, prange

from skydome.models.fitted._grid import A_PHI, EPS, N_GROUND, N_PHI, N_SKY


@njit(parallel=True, cache=True, fastmath=True)
def lookup(d, table, theta_h, sin_az, cos_az, out):
    """out[i, :] = the table at direction d[i] ((N, 3), finite and non-zero; each divided
    by its length here).

    theta_h: the horizon's zenith angle [rad]; (sin_az, cos_az): the sun's azimuth, from
    north towards east. Inverse mappings of :mod:`._grid`: sky x = sqrt(1 - theta /
    (theta_h - EPS)), ground x = sqrt((theta - theta_h - EPS) / (pi - theta_h - EPS)),
    azimuth t from phi / pi = A t + (1 - A) t^2 (the positive root); x clamped at 0
    between the two end nodes."""
    n, c = d.shape[0], table.shape[2]
    a = A_PHI
    b = 1.0 - A_PHI
    for i in prange(n):
        x, y, z = d[i, 0], d[i, 1], d[i, 2]
        r = math.sqrt(x * x + y * y + z * z)
        x, y, z = x / r, y / r, z / r
        if z > 1.0:
            z = 1.0
        elif z < -1.0:
            z = -1.0
        th = math.acos(z)
        if th < theta_h:
            u = math.sqrt(max(1.0 - th / (theta_h - EPS), 0.0)) * (N_SKY - 1)
            base, nu = 0, N_SKY
        else:
            u = math.sqrt(max((th - theta_h - EPS) / (math.pi - theta_h - EPS), 0.0)) * (
                N_GROUND - 1)
            base, nu = N_SKY, N_GROUND
        iu = min(int(u), nu - 2)
        fu = u - iu
        # azimuth from the sun's vertical plane, folded into [0, pi]
        cp = x * sin_az + y * cos_az
        sp = abs(x * cos_az - y * sin_az)
        phi = math.atan2(sp, cp) / math.pi
        t = (-a + math.sqrt(a * a + 4.0 * b * phi)) / (2.0 * b) * (N_PHI - 1)
        it = min(int(t), N_PHI - 2)
        ft = t - it
        if ft < 0.0:
            ft = 0.0
        r0 = base + iu
        w00 = (1.0 - fu) * (1.0 - ft)
        w01 = (1.0 - fu) * ft
        w10 = fu * (1.0 - ft)
        w11 = fu * ft
        for k in range(c):
            out[i, k] = (w00 * table[r0, it, k] + w01 * table[r0, it + 1, k]
                         + w10 * table[r0 + 1, it, k] + w11 * table[r0 + 1, it + 1, k])
