"""numba evaluation kernel of the Dobashi et al. (1995) cosine-series sky.

Per ray: the elevation rings around it (two for linear interpolation in elevation, four for
the cubic Hermite form), cos(n phi) by the Chebyshev recurrence, and on each ring only its
own number of cosine terms ([DNKY95]: the minimum number of terms that meets the error
criterion), summed over all wavelengths; the ring values are blended with the interpolation
weights. The coefficients handed in are already interpolated to the actual sun altitude
(done once per call in the model, as the numpy reference does). Parallel over rays for
large batches, serial for smaller ones (on a busy 2-core machine a parallel launch costs
more than it gains below about 10^5 rays).

Imported lazily by skydome.models.simulated.dobashi1995 (never at module import time).
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.transport._geometry import clamp_cosine

#: Below this many rays the serial kernel is used (measured on a busy 2-core machine: at
#: 32768 rays the parallel launch was slower than one thread; at 262144 about even).
PARALLEL_MIN_RAYS = 131072


@njit(cache=True, fastmath=True, inline="always")
def ring_weights(elev, rings_deg, cubic):
    """Index of the lowest ring used and the weights of rings j-1, j, j+1, j+2 for an
    elevation [deg]: linear (weights on j, j+1 only) or cubic Hermite with finite-difference
    slopes on the non-uniform ring grid (one-sided slope at the first and last interval)."""
    nr = rings_deg.shape[0]
    lo = 0
    hi = nr
    while lo < hi:                 # first index with rings[k] > elev (searchsorted 'right')
        mid = (lo + hi) // 2
        if rings_deg[mid] > elev:
            hi = mid
        else:
            lo = mid + 1
    j = lo - 1
    if j < 0:
        j = 0
    elif j > nr - 2:
        j = nr - 2
    e1 = rings_deg[j]
    e2 = rings_deg[j + 1]
    h = e2 - e1
    t = (elev - e1) / h
    if t < 0.0:
        t = 0.0
    elif t > 1.0:
        t = 1.0
    if not cubic:
        return j, 0.0, 1.0 - t, t, 0.0
    t2 = t * t
    t3 = t2 * t
    h00 = 2.0 * t3 - 3.0 * t2 + 1.0
    h10 = t3 - 2.0 * t2 + t
    h01 = -2.0 * t3 + 3.0 * t2
    h11 = t3 - t2
    w0 = 0.0
    w1 = h00
    w2 = h01
    w3 = 0.0
    # slope at e1: (y2 - y0) / (e2 - e0), or (y2 - y1) / h on the first interval
    if j > 0:
        s = h10 * h / (e2 - rings_deg[j - 1])
        w0 -= s
        w2 += s
    else:
        w1 -= h10
        w2 += h10
    # slope at e2: (y3 - y1) / (e3 - e1), or (y2 - y1) / h on the last interval
    if j + 2 < nr:
        s = h11 * h / (rings_deg[j + 2] - e1)
        w3 += s
        w1 -= s
    else:
        w2 += h11
        w1 -= h11
    return j, w0, w1, w2, w3


@njit(cache=True, inline="always")
def ring_of(q, j, w0, w1, w2, w3, nr):
    """(ring index, weight) of the q-th (0..3) of the rings j-1 .. j+2 of
    :func:`ring_weights`; weight 0 for a ring outside the nr rings."""
    r = j - 1 + q
    w = w0 if q == 0 else (w1 if q == 1 else (w2 if q == 2 else w3))
    if r < 0 or r >= nr:
        return r, 0.0
    return r, w


@njit(cache=True, fastmath=True, inline="always")
def _elevation_cphi(d, i, sin_az, cos_az):
    """Elevation [deg] of ray i and cos(phi), phi = its azimuth - the solar azimuth (azimuth
    from north (+y) towards east (+x))."""
    x, y, z = d[i, 0], d[i, 1], d[i, 2]
    elev = math.asin(clamp_cosine(z)) * (180.0 / math.pi)
    hh = math.sqrt(x * x + y * y)
    if hh > 0.0:
        return elev, clamp_cosine((y * cos_az + x * sin_az) / hh)
    return elev, cos_az              # atan2(0, 0) = 0, as the reference


@njit(cache=True, fastmath=True, inline="always")
def _ray(d, i, coef, terms, rings_deg, sin_az, cos_az, cubic, out):
    nr = rings_deg.shape[0]
    nl = coef.shape[2]
    elev, cphi = _elevation_cphi(d, i, sin_az, cos_az)
    j, w0, w1, w2, w3 = ring_weights(elev, rings_deg, cubic)
    for l in range(nl):
        out[i, l] = 0.0
    for q in range(4):
        r, w = ring_of(q, j, w0, w1, w2, w3, nr)
        if w == 0.0:
            continue
        t_prev = 1.0
        t_cur = cphi
        for k in range(terms[r]):  # this ring's own number of terms
            if k == 0:
                a = w
            else:
                a = w * t_cur
                t_next = 2.0 * cphi * t_cur - t_prev
                t_prev = t_cur
                t_cur = t_next
            for l in range(nl):
                out[i, l] += a * coef[r, k, l]
    for l in range(nl):
        if out[i, l] < 0.0:
            out[i, l] = 0.0


@njit(parallel=True, cache=True, fastmath=True)
def _evaluate_parallel(d, coef, terms, rings_deg, sin_az, cos_az, cubic):
    out = np.empty((d.shape[0], coef.shape[2]))
    for i in prange(d.shape[0]):
        _ray(d, i, coef, terms, rings_deg, sin_az, cos_az, cubic, out)
    return out


@njit(cache=True, fastmath=True)
def _evaluate_serial(d, coef, terms, rings_deg, sin_az, cos_az, cubic):
    out = np.empty((d.shape[0], coef.shape[2]))
    for i in range(d.shape[0]):
        _ray(d, i, coef, terms, rings_deg, sin_az, cos_az, cubic, out)
    return out


def evaluate(d, coef, terms, rings_deg, sun_azimuth_rad, cubic=True):
    """Radiance per ray, shape (N, n_lambda).

    Parameters
    ----------
    d : (N, 3) float64
        Unit directions (ENU).
    coef : (n_rings, n_terms_max, n_lambda) float64
        Cosine-series coefficients a_n of every ring at the sun's altitude.
    terms : (n_rings,) int
        Terms used on each ring (the coefficients beyond are zero).
    rings_deg : (n_rings,) float64
        Ring elevations [deg], increasing.
    sun_azimuth_rad : float
        Solar azimuth [rad].
    cubic : bool
        Cubic Hermite interpolation between rings (else linear, as the paper).
    """
    d = np.ascontiguousarray(d, dtype=np.float64)
    args = (d, np.ascontiguousarray(coef, dtype=np.float64),
            np.ascontiguousarray(terms, dtype=np.int64),
            np.ascontiguousarray(rings_deg, dtype=np.float64),
            math.sin(sun_azimuth_rad), math.cos(sun_azimuth_rad), bool(cubic))
    if d.shape[0] >= PARALLEL_MIN_RAYS:
        return _evaluate_parallel(*args)
    return _evaluate_serial(*args)


# -- vertex-grid evaluation: the series evaluated once per ring on a fine azimuth grid ------
@njit(parallel=True, cache=True, fastmath=True)
def ring_table(coef, terms, n_az):
    """Cosine series of every ring evaluated at n_az azimuths phi_k = k pi / (n_az - 1)
    relative to the sun, shape (n_rings, n_az, n_lambda); each ring uses its own number of
    terms."""
    nr = coef.shape[0]
    nl = coef.shape[2]
    out = np.zeros((nr, n_az, nl))
    for idx in prange(nr * n_az):
        r = idx // n_az
        k_az = idx - r * n_az
        cphi = math.cos(k_az * math.pi / (n_az - 1))
        t_prev = 1.0
        t_cur = cphi
        for k in range(terms[r]):
            if k == 0:
                a = 1.0
            else:
                a = t_cur
                t_next = 2.0 * cphi * t_cur - t_prev
                t_prev = t_cur
                t_cur = t_next
            for l in range(nl):
                out[r, k_az, l] += a * coef[r, k, l]
    return out


@njit(cache=True, fastmath=True, inline="always")
def _ray_grid(d, i, table, rings_deg, sin_az, cos_az, cubic, out):
    nr = rings_deg.shape[0]
    n_az = table.shape[1]
    nl = table.shape[2]
    elev, cphi = _elevation_cphi(d, i, sin_az, cos_az)
    u = math.acos(cphi) * ((n_az - 1) / math.pi)      # fractional azimuth index
    k0 = int(u)
    if k0 > n_az - 2:
        k0 = n_az - 2
    fu = u - k0
    gu = 1.0 - fu
    j, w0, w1, w2, w3 = ring_weights(elev, rings_deg, cubic)
    for l in range(nl):
        out[i, l] = 0.0
    for q in range(4):
        r, w = ring_of(q, j, w0, w1, w2, w3, nr)
        if w == 0.0:
            continue
        a0 = w * gu
        a1 = w * fu
        for l in range(nl):
            out[i, l] += a0 * table[r, k0, l] + a1 * table[r, k0 + 1, l]
    for l in range(nl):
        if out[i, l] < 0.0:
            out[i, l] = 0.0


@njit(parallel=True, cache=True, fastmath=True)
def _grid_parallel(d, table, rings_deg, sin_az, cos_az, cubic):
    out = np.empty((d.shape[0], table.shape[2]))
    for i in prange(d.shape[0]):
        _ray_grid(d, i, table, rings_deg, sin_az, cos_az, cubic, out)
    return out


@njit(cache=True, fastmath=True)
def _grid_serial(d, table, rings_deg, sin_az, cos_az, cubic):
    out = np.empty((d.shape[0], table.shape[2]))
    for i in range(d.shape[0]):
        _ray_grid(d, i, table, rings_deg, sin_az, cos_az, cubic, out)
    return out


def evaluate_grid(d, table, rings_deg, sun_azimuth_rad, cubic=True):
    """Radiance per ray, shape (N, n_lambda), from a :func:`ring_table`: the ring
    interpolation of :func:`evaluate` in elevation, linear interpolation in azimuth."""
    d = np.ascontiguousarray(d, dtype=np.float64)
    args = (d, np.ascontiguousarray(table, dtype=np.float64),
            np.ascontiguousarray(rings_deg, dtype=np.float64),
            math.sin(sun_azimuth_rad), math.cos(sun_azimuth_rad), bool(cubic))
    if d.shape[0] >= PARALLEL_MIN_RAYS:
        return _grid_parallel(*args)
    return _grid_serial(*args)
