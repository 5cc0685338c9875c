"""numba kernels of the sky matrices (private; validated and broadcast by skymatrix.py).

One call fills every hour of a sky matrix: the Perez patch means of
:func:`skydome.models.analytic._kernels_analytic.perez1993_patch_row_tiered` (finer rules for
the patches nearer the sun; a fixed order is one rule for all), the
normalisation to
the diffuse horizontal illuminance, the sky tint, the ground patch and gendaymtx's sun
spreading, in parallel over hours. Units and conventions: see skymatrix.py.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.models.analytic._kernels_analytic import perez1993_patch_row_tiered

MAX_SUN_PATCHES = 4


#: Hours per tile of the sky-matrix kernel: a tile is computed into a thread-local buffer and
#: copied out patch by patch, so that a (patches, hours) file-order output is written in runs
#: of TILE_HOURS contiguous values rather than one value per memory page.
TILE_HOURS = 32


@njit(cache=True)  # strict IEEE: see perez1993_patch_row
def _perez_hour(dest, h, nodes, weights, offsets, cos_tier, centres, dom, s_dist, s_true,
                coef, e_diff, e_dir, rho, tint, grey, out_scale, nsuns, fixed_sa, cz_min, means,
                near, ndot):
    """One hour's patch values (ground first) into ``dest`` (P + 1, C); ``means`` (P,),
    ``near`` and ``ndot`` (MAX_SUN_PATCHES,) are work space of the caller's thread."""
    n_patch = offsets.shape[1] - 1
    ncomp = dest.shape[1]
    horiz = perez1993_patch_row_tiered(nodes, weights, offsets, centres, cos_tier, s_dist[h],
                                       coef[h], cz_min, means)
    if horiz <= 1e-6:  # gendaymtx: a zero sky is made uniform, normalised by pi
        for k in range(n_patch):
            means[k] = 1.0
        horiz = math.pi
    scale = e_diff[h] / horiz * out_scale  # the sky's horizontal illuminance is Dh
    for k in range(n_patch):
        v = means[k] * scale
        for c in range(ncomp):
            dest[k + 1, c] = v * tint[c]
    sz = s_true[h, 2]
    g = e_diff[h]
    if sz > 0.0:
        g += e_dir[h] * sz
    g *= rho[h] / math.pi * out_scale  # ground: rho (Dh + Dn sin a) / pi
    for c in range(ncomp):
        dest[0, c] = g * grey[c]
    if nsuns == 0 or e_dir[h] <= 1e-4:
        return
    # gendaymtx AddDirect: the nsuns patches nearest the sun, weight 1 / (1.002 - cos)
    for j in range(MAX_SUN_PATCHES):
        near[j] = -1
        ndot[j] = -2.0
    sx, sy, szz = s_true[h, 0], s_true[h, 1], s_true[h, 2]
    for k in range(n_patch):
        d = centres[k, 0] * sx + centres[k, 1] * sy + centres[k, 2] * szz
        if d <= ndot[nsuns - 1]:  # not among the nearest so far (the common case)
            continue
        for j in range(nsuns):
            if d > ndot[j]:
                for jj in range(nsuns - 1, j, -1):
                    ndot[jj] = ndot[jj - 1]
                    near[jj] = near[jj - 1]
                ndot[j] = d
                near[j] = k
                break
    wtot = 0.0
    for j in range(nsuns):
        wtot += 1.0 / (1.002 - ndot[j])
    for j in range(nsuns):
        k = near[j]
        sa = fixed_sa if fixed_sa > 0.0 else dom[k]
        v = (1.0 / (1.002 - ndot[j])) * e_dir[h] * out_scale / (wtot * sa)
        for c in range(ncomp):
            dest[k + 1, c] += v * grey[c]


@njit(parallel=True, cache=True)  # strict IEEE: see perez1993_patch_row
def fill_perez_sky(out, day, nodes, weights, offsets, cos_tier, centres, dom, s_dist, s_true,
                   coef, e_diff, e_dir, rho, tint, grey, out_scale, nsuns, fixed_sa, cz_min,
                   n_threads):
    """Fill ``out[:, h]`` (P + 1, C) for each hour h with ``day[h]``; other hours are left as
    they are (zero).

    ``out`` (P + 1, H, C) is in Radiance's file order (rows = patches), e.g. the memory map
    of the output file, or a (P + 1, H, C) view of an (H, P + 1, C) array. The hours are
    split into ``n_threads`` contiguous runs (numba.get_num_threads()); each thread computes tiles of TILE_HOURS hours
    into one float64 work buffer of its own (allocated once) and copies a tile out patch by
    patch, in runs of TILE_HOURS contiguous hours. Patch k's mean takes rule t of ``offsets``
    (T, P + 1) by its angle to s_dist and ``cos_tier`` (T, P) (see
    perez1993_patch_row_tiered). s_dist (H, 3): sun vector of the
    distribution (zenith clamped); s_true (H, 3): the true sun (ground term, nearest
    patches); coef (H, 5); e_diff, e_dir (H,) [lx]; rho (H,); tint, grey (C,); nsuns 0 = no
    sun in the matrix; fixed_sa > 0 replaces the patches' solid angles for the sun
    (gendaymtx -5)."""
    n_row = out.shape[0]
    n_h = out.shape[1]
    ncomp = out.shape[2]
    n_tiles = (n_h + TILE_HOURS - 1) // TILE_HOURS
    n_run = max(1, min(n_tiles, n_threads))
    for r in prange(n_run):
        t_a = r * n_tiles // n_run
        t_b = (r + 1) * n_tiles // n_run
        buf = np.empty((TILE_HOURS, n_row, ncomp))
        means = np.empty(n_row - 1)
        near = np.empty(MAX_SUN_PATCHES, dtype=np.int64)
        ndot = np.empty(MAX_SUN_PATCHES)
        for t in range(t_a, t_b):
            h0 = t * TILE_HOURS
            h1 = min(n_h, h0 + TILE_HOURS)
            any_day = False
            for h in range(h0, h1):
                any_day = any_day or day[h]
            if not any_day:
                continue
            for h in range(h0, h1):
                if day[h]:
                    _perez_hour(buf[h - h0], h, nodes, weights, offsets, cos_tier, centres,
                                dom, s_dist, s_true, coef, e_diff, e_dir, rho, tint, grey,
                                out_scale, nsuns, fixed_sa, cz_min, means, near, ndot)
            for k in range(n_row):  # patch by patch: runs of hours in the file order
                for j in range(h1 - h0):
                    if day[h0 + j]:
                        for c in range(ncomp):
                            out[k, h0 + j, c] = buf[j, k, c]
