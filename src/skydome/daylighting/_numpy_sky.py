"""The Perez sky matrix in numpy, for a process that need not start numba (private).

The same arithmetic as :func:`skydome.daylighting._kernels.fill_perez_sky` with a fixed
patch rule (one quadrature rule for every patch, e.g. order 0, gendaymtx's one point at each
patch centre), in the same order of operations per value, but vectorised over blocks of
lit hours x nodes with numpy's ufuncs instead of one numba loop per hour. It needs no
``import numba`` (0.4-0.5 s of CPU on a 2-core EPYC, the start-up floor of any numba path),
and numpy's vectorised ``arccos``/``exp`` are faster than the scalar libm calls of the strict
IEEE kernel. Results equal the kernel's to rounding (relative 1e-12): ``arccos``/``exp``
differ from libm's by a few units in the last place, cos(gamma) and the horizontal sums are
matrix products (added in another order, fused multiply-adds), and a one-node patch mean is
the node's value (the kernel's (w lv) / w may differ from it in the last bit); the sun's
nearest patches are chosen by the kernel's own dot products, in its order of operations,
with its tie-break (the lower patch index first).

The matrix is produced patch row by patch row in Radiance's file order (patches, hours,
components), so that a matrix file is written sequentially, with no zero-filled body and no
memory map (:func:`skydome.daylighting.radiance_io.write_matrix_rows`).
"""

from __future__ import annotations

import numpy as np

#: Nodes x hours per vectorised block (the work arrays stay in the cache).
_BLOCK = 1 << 16
#: Patch rows per block of the output.
_ROWS = 64
_ROWS = 64


def _runs(mask, longest):
    """(start, stop) of the runs of True in ``mask``, split to at most ``longest``."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.view(np.int8), [0]])))
    out = []
    for a, b in zip(edges[::2], edges[1::2]):
        out += [(h, min(b, h + longest)) for h in range(a, b, longest)]
    return out


def perez_patch_values(nodes, weights, offsets, s_dist, coef, lit, e_diff, out_scale,
                       cz_min):
    """The sky patches' values of every hour, normalised to the diffuse illuminance.

    ``nodes`` (M, 3), ``weights`` (M,) [sr], ``offsets`` (P + 1,): one rule for all patches
    (patch k owns nodes offsets[k]:offsets[k + 1]); ``s_dist`` (H, 3) the sun vector of the
    distribution, ``coef`` (H, 5) (a, b, c, d, e), ``lit`` (H,) bool, ``e_diff`` (H,) [lx].
    Returns v (P, H): patch mean of lv times e_diff / (its horizontal integral) times
    ``out_scale`` (the kernel's ``v``; zero in unlit hours). The hours are taken in runs of
    consecutive lit hours (a day's), each run's (hours x nodes) values in one pass per
    operation."""
    n_h = s_dist.shape[0]
    n_p = offsets.shape[0] - 1
    m = nodes.shape[0]
    one = m == n_p  # one node per patch (order 0): the mean is lv itself
    nodes_t = np.ascontiguousarray(nodes.T)
    z = np.ascontiguousarray(nodes[:, 2])
    # the nodes come in runs of equal altitude: one gradation term per run
    first = np.flatnonzero(np.concatenate([[True], z[1:] != z[:-1]]))
    reps = np.diff(np.append(first, m))
    zc = np.maximum(z[first], cz_min)
    wz = weights * z
    starts = offsets[:-1]
    wsum = np.add.reduceat(weights, starts)
    v = np.zeros((n_p, n_h))
    for h0, h1 in _runs(lit, max(1, _BLOCK // m)):
        s = s_dist[h0:h1]
        a, b, c, dd, e = (coef[h0:h1, i][:, None] for i in range(5))
        cg = s @ nodes_t             # cos(gamma), (hours, nodes)
        np.clip(cg, -1.0, 1.0, out=cg)
        lv = np.arccos(cg)
        lv *= dd
        np.exp(lv, out=lv)
        lv *= c
        lv += 1.0                    # [PSM93] eq. 1: 1 + c exp(d gamma) + e cos^2(gamma)
        q = cg * e
        q *= cg
        lv += q
        grad = np.exp(b / zc)        # 1 + a exp(b / cos zeta), once per run of equal altitude
        grad *= a
        grad += 1.0
        lv *= np.repeat(grad, reps, axis=1)
        np.maximum(lv, 0.0, out=lv)  # a negative lv is clipped to 0 (per node)
        if one:
            horiz = lv @ wz          # sum of w lv cos(zeta) [sr]
            means = lv
        else:
            lv *= weights
            horiz = lv @ z
            means = np.add.reduceat(lv, starts, axis=1)
            means /= wsum
        flat = horiz <= 1e-6         # gendaymtx: a zero sky is made uniform, normalised by pi
        if flat.any():
            means[flat] = 1.0
            horiz[flat] = np.pi
        scale = e_diff[h0:h1] / horiz * out_scale  # the sky's horizontal illuminance is Dh
        means *= scale[:, None]
        v[:, h0:h1] = means.T
    return v


def nearest_patches(centres, s_true, hours, nsuns):
    """Indices (len(hours), nsuns) and dot products of the ``nsuns`` patch centres nearest
    the sun of each of ``hours`` (gendaymtx AddDirect), nearest first, as the kernel chooses
    them: its dot products (cx sx + cy sy + cz sz, in that order, no fused multiply-add),
    among equal ones the lower index first (its insertion takes strictly greater ones). The
    candidates are the nsuns + 2 nearest by a matrix product (rounded otherwise), re-ranked
    by the kernel's dot products."""
    n_c = nsuns + 2
    near = np.empty((hours.size, nsuns), dtype=np.int64)
    ndot = np.empty((hours.size, nsuns))
    c_t = np.ascontiguousarray(centres.T)
    step = max(1, _BLOCK // centres.shape[0])
    for i0 in range(0, hours.size, step):
        s = s_true[hours[i0:i0 + step]]
        d = s @ c_t
        r = np.arange(d.shape[0])[:, None]
        cand = np.empty((d.shape[0], n_c), dtype=np.int64)
        for j in range(n_c):
            cand[:, j] = np.argmax(d, axis=1)
            d[r[:, 0], cand[:, j]] = -np.inf
        cand.sort(axis=1)            # index order: a stable sort by dot keeps it for ties
        c = centres[cand]            # (hours, n_c, 3)
        exact = c[..., 0] * s[:, 0:1]
        exact += c[..., 1] * s[:, 1:2]
        exact += c[..., 2] * s[:, 2:3]
        pick = np.argsort(-exact, axis=1, kind="stable")[:, :nsuns]
        near[i0:i0 + step] = cand[r, pick]
        ndot[i0:i0 + step] = exact[r, pick]
    return near, ndot


def perez_rows(v, lit, centres, dom, s_true, e_diff, e_dir, rho, tint, grey, out_scale,
               nsuns, fixed_sa, dtype, rows=_ROWS):
    """The sky matrix in Radiance's file order, as blocks of patch rows.

    Takes :func:`perez_patch_values`' ``v`` (P, H) and the kernel's per-hour inputs (see
    :func:`skydome.daylighting._kernels.fill_perez_sky`); yields (r0, block) with ``block``
    (r1 - r0, H, C) of ``dtype`` for rows r0:r1 (row 0 the ground): v tint, the ground and
    the sun, computed in float64 as the kernel does and rounded to ``dtype`` once."""
    n_p, n_h = v.shape
    ncomp = tint.shape[0]
    hours = np.flatnonzero(lit)
    # the ground, patch 0: rho (Dh + Dn sin a) / pi
    g = np.where(s_true[:, 2] > 0.0, e_diff + e_dir * s_true[:, 2], e_diff)
    g = np.where(lit, g * (rho / np.pi * out_scale), 0.0)
    # the sun: the nsuns patches nearest it, weight 1 / (1.002 - cos) (gendaymtx AddDirect)
    sun_h = hours[e_dir[hours] > 1e-4] if nsuns > 0 else hours[:0]
    near, ndot = nearest_patches(centres, s_true, sun_h, max(nsuns, 1))
    near, ndot = near[:, :nsuns], ndot[:, :nsuns]
    wt = 1.0 / (1.002 - ndot)
    wtot = np.zeros(sun_h.size)
    for j in range(nsuns):           # summed in the kernel's order
        wtot += wt[:, j]
    sa = np.full(near.shape, fixed_sa) if fixed_sa > 0.0 else dom[near]
    v_sun = ((wt * e_dir[sun_h][:, None]) * out_scale / (wtot[:, None] * sa)).ravel()
    sun_row = (near + 1).ravel()     # file rows of the sun's patches
    sun_col = np.repeat(sun_h, nsuns)
    order = np.argsort(sun_row, kind="stable")
    sun_row, sun_col, v_sun = sun_row[order], sun_col[order], v_sun[order]
    r_starts = list(range(0, n_p + 1, rows))
    bounds = np.searchsorted(sun_row, r_starts + [n_p + 1])
    for bi, r0 in enumerate(r_starts):
        r1 = min(n_p + 1, r0 + rows)
        blk = np.empty((r1 - r0, n_h, ncomp), dtype=dtype)
        k0 = max(r0, 1)              # first sky row of the block
        vb = v[k0 - 1:r1 - 1]
        for c in range(ncomp):       # v tint[c], in float64, rounded to dtype once
            np.multiply(vb, tint[c], out=blk[k0 - r0:, :, c], casting="unsafe")
            if r0 == 0:
                blk[0, :, c] = g * grey[c]
        a, b = bounds[bi], bounds[bi + 1]
        if b > a:                    # the sun's patches in this block (distinct per hour)
            rr, cc = sun_row[a:b], sun_col[a:b]
            blk[rr - r0, cc] = v[rr - 1, cc][:, None] * tint + v_sun[a:b, None] * grey
        yield r0, blk
