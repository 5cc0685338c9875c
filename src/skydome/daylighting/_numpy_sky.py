"""The Perez sky matrix in numpy, for a process that need not start numba (private).

The same arithmetic as :func:`skydome.daylighting._kernels.fill_perez_sky` with a fixed
patch rule (one quadrature rule for every patch, e.g. order 0, gendaymtx's one point at each
patch centre) or a tiered one (the adaptive rule: see :func:`_refine_tiers`), in the same
order of operations per value, but vectorised over blocks of
lit hours x nodes with numpy's ufuncs instead of one numba loop per hour. It needs no
``import numba`` (0.4-0.5 s of CPU on a 2-core EPYC, the start-up floor of any numba path),
and numpy's vectorised ``arccos``/``exp`` are faster than the scalar libm calls of the strict
IEEE kernel. Results equal the kernel's to rounding (relative 1e-12): ``arccos``/``exp``
differ from libm's by a few units in the last place, cos(gamma) and the horizontal sums are
matrix products (added in another order, fused multiply-adds), and a one-node patch mean is
the node's value (the kernel's (w lv) / w may differ from it in the last bit); the sun's
nearest patches are chosen by the kernel's own dot products, in its order of operations,
with its tie-break (the lower patch index first).

The values are computed for blocks of lit hours (several days', gathered) and written run of
consecutive hours by run into a zero-filled array in Radiance's file order (patches, hours,
components), e.g. the memory map of a matrix file's body
(:func:`skydome.daylighting.radiance_io.matrix_file`), as the kernel does: no intermediate
matrix of patch values is held (an annual MF:4 one is 161 MB of float64, whose first touch
alone cost 0.06-0.4 s of system time on the 2-core EPYC of docs/performance.md).
"""

from __future__ import annotations

import numpy as np

#: Nodes x lit hours per vectorised block (the work arrays stay in the cache): about four days
#: at MF:4. An annual MF:4 matrix's values took 0.07-0.084 s in such blocks of lit hours,
#: 0.103-0.108 s day by day (one run of lit hours per block, 2^16), and 0.15-0.18 s in blocks
#: of 2^18 (out of the cache): 2-core EPYC, three rounds each.
_BLOCK = 1 << 17
#: Most hours per matrix product that writes a run of hours (its diagonal factor matrix
#: holds run x run x components values).
_RUN = 32
#: Rows of patches below and above the sun's altitude where its nearest patches are sought
#: first (see :func:`nearest_patches`).
_NEAR_ROWS = 2
#: Multiply-adds (m n k) per thread of an OpenBLAS matrix product (numpy's BLAS): it gives a
#: product m n k / (65536 x GEMM_MULTITHREAD_THRESHOLD, 4 by default) threads
#: (interface/gemm.c), so one of at most 2^18 runs on one thread.
_BLAS_ONE_THREAD = 1 << 18


def _runs(hours):
    """(start, stop) positions in ``hours`` (ascending indices) of its runs of consecutive
    hours, split to at most ``_RUN`` hours."""
    cuts = np.flatnonzero(np.diff(hours) != 1) + 1
    out = []
    for a, b in zip(np.append(0, cuts).tolist(), np.append(cuts, hours.size).tolist()):
        out += [(j, min(b, j + _RUN)) for j in range(a, b, _RUN)]
    return out


def perez_patch_values(nodes, weights, offsets, s_dist, coef, lit, e_diff, out_scale,
                       cz_min, tiers=None):
    """The sky patches' unnormalised means and their per-hour scale, block of lit hours by
    block.

    ``nodes`` (M, 3), ``weights`` (M,) [sr], ``offsets`` (P + 1,): one rule for all patches
    (patch k owns nodes offsets[k]:offsets[k + 1]); ``s_dist`` (H, 3) the sun vector of the
    distribution, ``coef`` (H, 5) (a, b, c, d, e), ``lit`` (H,) bool, ``e_diff`` (H,) [lx].
    Yields (hours, means, scale) for blocks of lit hours (of about ``_BLOCK`` node values,
    several days' lit hours, in order): ``hours`` (n,) their indices, ``means`` (P, n), patch
    k's mean of lv in row k (the layout of the file's rows), and ``scale`` (n,), e_diff / (the
    horizontal integral) times ``out_scale``; the kernel's ``v`` is means * scale. Both are
    overwritten by the next block.

    ``tiers``: None (one rule), or (offsets (T, P + 1), cos_tier (T, P), centres (P, 3)) of
    a tiered rule (the adaptive one, :func:`skydome.daylighting.patches.tiered_nodes`): the
    last (far) rule, whose nodes are a contiguous block of ``nodes``, is computed for every
    patch and hour as above, then the patch-hours nearer the sun are recomputed with their
    finer rule (see :func:`_refine_tiers`)."""
    if tiers is not None:
        t_off, cos_tier, centres = tiers
        f0, f1 = int(t_off[-1, 0]), int(t_off[-1, -1])
        all_nodes, all_weights = nodes, weights
        nodes, weights, offsets = nodes[f0:f1], weights[f0:f1], t_off[-1] - f0
    n_p = offsets.shape[0] - 1
    m = nodes.shape[0]
    one = m == n_p and tiers is None  # one node per patch (order 0): the mean is lv itself
    z = np.ascontiguousarray(nodes[:, 2])
    # the nodes come in runs of equal altitude: one gradation term per run
    first = np.flatnonzero(np.concatenate([[True], z[1:] != z[:-1]]))
    reps = np.diff(np.append(first, m))
    zc = np.maximum(z[first], cz_min)[:, None]
    wz = weights * z
    starts = offsets[:-1]
    wsum = np.add.reduceat(weights, starts)[:, None]
    lit_h = np.flatnonzero(lit)
    coef_t = np.ascontiguousarray(coef[lit_h].T)  # the lit hours only, gathered
    s_t = np.ascontiguousarray(s_dist[lit_h].T)
    e_lit = e_diff[lit_h]
    step = max(1, _BLOCK // m)
    for i0 in range(0, lit_h.size, step):
        i1 = min(i0 + step, lit_h.size)
        a, b, c, dd, e = coef_t[:, i0:i1]
        cg = nodes @ s_t[:, i0:i1]   # cos(gamma), (nodes, hours)
        np.clip(cg, -1.0, 1.0, out=cg)
        lv = np.arccos(cg)
        lv *= dd
        np.exp(lv, out=lv)
        lv *= c
        lv += 1.0                    # [PSM93] eq. 1: 1 + c exp(d gamma) + e cos^2(gamma)
        cg *= cg
        cg *= e
        lv += cg
        grad = np.exp(b / zc)        # 1 + a exp(b / cos zeta), once per run of equal altitude
        grad *= a
        grad += 1.0
        lv *= np.repeat(grad, reps, axis=0)
        np.maximum(lv, 0.0, out=lv)  # a negative lv is clipped to 0 (per node)
        if one:
            horiz = wz @ lv          # sum of w lv cos(zeta) [sr]
            means = lv
        else:
            lv *= weights[:, None]
            horiz = z @ lv
            means = np.add.reduceat(lv, starts, axis=0)
            means /= wsum
        if tiers is not None:
            _refine_tiers(means, horiz, lv, z, offsets, all_nodes, all_weights, t_off,
                          cos_tier, centres, s_t[:, i0:i1], coef_t[:, i0:i1], cz_min)
        flat = horiz <= 1e-6         # gendaymtx: a zero sky is made uniform, normalised by pi
        if flat.any():
            means[:, flat] = 1.0
            horiz[flat] = np.pi
        scale = e_lit[i0:i1] / horiz * out_scale  # the sky's horizontal illuminance is Dh
        yield lit_h[i0:i1], means, scale


def _ragged(first, counts):
    """Indices first[i] + 0 .. counts[i] - 1, concatenated, and the start of each run."""
    starts = np.cumsum(counts) - counts
    return np.repeat(first - starts, counts) + np.arange(int(counts.sum())), starts


def _refine_tiers(means, horiz, lv_far, z_far, off_far, nodes, weights, t_off, cos_tier,
                  centres, s_t, coef_t, cz_min):
    """The finer rules of a tiered rule, in place, for one block of hours: ``means`` (P, n)
    and ``horiz`` (n,) hold the far rule's patch means and horizontal integrals, ``lv_far``
    (M_far, n) its node values times their weights, ``z_far`` and ``off_far`` its nodes'
    cos(zeta) and the patches' offsets into them. Patch k at hour j takes rule t, the first t
    < T - 1 with cos(angle between its centre and the sun) > cos_tier[t, k] (the kernel's
    choice, from the same dot products cx sx + cy sy + cz sz in the kernel's order): its
    mean is recomputed with rule t's nodes, and the hour's integral takes rule t's share of
    the patch in place of the far rule's. The few such patch-hours (those within about 10
    deg of the sun) are gathered node by node."""
    n_t = t_off.shape[0]
    sx, sy, sz = s_t
    d = centres[:, 0:1] * sx
    d += centres[:, 1:2] * sy
    d += centres[:, 2:3] * sz
    tier = np.full(d.shape, n_t - 1, dtype=np.int64)
    for t in range(n_t - 2, -1, -1):  # the first (finest) rule that applies wins
        tier[d > cos_tier[t][:, None]] = t
    a, b, c, dd, e = coef_t
    for t in range(n_t - 1):
        kk, jj = np.nonzero(tier == t)
        if not kk.size:
            continue
        idx, st = _ragged(t_off[t, kk], t_off[t, kk + 1] - t_off[t, kk])
        jr = np.repeat(jj, t_off[t, kk + 1] - t_off[t, kk])
        nd = nodes[idx]
        nz = nd[:, 2]
        cg = nd[:, 0] * sx[jr]
        cg += nd[:, 1] * sy[jr]
        cg += nz * sz[jr]
        np.clip(cg, -1.0, 1.0, out=cg)
        lv = np.exp(dd[jr] * np.arccos(cg))
        lv *= c[jr]
        lv += 1.0                    # [PSM93] eq. 1: 1 + c exp(d gamma) + e cos^2(gamma)
        lv += e[jr] * (cg * cg)
        lv *= 1.0 + a[jr] * np.exp(b[jr] / np.maximum(nz, cz_min))
        np.maximum(lv, 0.0, out=lv)  # a negative lv is clipped to 0 (per node)
        w = weights[idx]
        lv *= w
        means[kk, jj] = np.add.reduceat(lv, st) / np.add.reduceat(w, st)
        lv *= nz
        fidx, fst = _ragged(off_far[kk], off_far[kk + 1] - off_far[kk])
        fj = np.repeat(jj, off_far[kk + 1] - off_far[kk])
        far = np.add.reduceat(lv_far[fidx, fj] * z_far[fidx], fst)
        np.add.at(horiz, jj, np.add.reduceat(lv, st) - far)


def _candidates(s, c_t, n_c):
    """Indices of the ``n_c`` largest of s @ c_t in each row (rounded dot products), and the
    ``n_c``-th largest of each row."""
    d = s @ c_t
    r = np.arange(d.shape[0])
    cand = np.empty((d.shape[0], n_c), dtype=np.int64)
    last = None
    for j in range(n_c):
        cand[:, j] = np.argmax(d, axis=1)
        last = d[r, cand[:, j]]
        d[r, cand[:, j]] = -np.inf
    return cand, last


def nearest_patches(centres, s_true, hours, nsuns):
    """Indices (len(hours), nsuns) and dot products of the ``nsuns`` patch centres nearest
    the sun of each of ``hours`` (gendaymtx AddDirect), nearest first, as the kernel chooses
    them: its dot products (cx sx + cy sy + cz sz, in that order, no fused multiply-add),
    among equal ones the lower index first (its insertion takes strictly greater ones). The
    candidates are the nsuns + 2 nearest by a matrix product (rounded otherwise), re-ranked
    by the kernel's dot products.

    The candidates are sought first among the patches of the ``_NEAR_ROWS`` rows below and
    above the sun's altitude (the patches come row by row, upwards): a patch of any other row
    is at least the altitude gap to the nearest row left out from the sun, so the search is
    kept for an hour whose last candidate's dot product exceeds the cosine of that gap (by
    1e-9, far above the products' rounding), and made over every patch otherwise. At MF:4 the
    rows searched hold about a fifth of the patches."""
    n_c = nsuns + 2
    s_all = s_true[hours]
    c_t = np.ascontiguousarray(centres.T)
    cand = np.empty((hours.size, n_c), dtype=np.int64)
    z = centres[:, 2]
    first = np.flatnonzero(np.concatenate([[True], z[1:] != z[:-1]]))
    bounds = np.append(first, z.size)
    n_rows = first.size
    alt_row = np.arcsin(np.clip(z[first], -1.0, 1.0))
    alt_sun = np.arcsin(np.clip(s_all[:, 2], -1.0, 1.0))
    row = np.searchsorted(alt_row, alt_sun)  # the first row at or above the sun
    lo = np.maximum(row - _NEAR_ROWS, 0)     # rows lo .. hi - 1 are searched
    hi = np.minimum(row + _NEAR_ROWS, n_rows)
    gap = np.full(hours.size, np.pi)
    j = lo > 0
    gap[j] = alt_sun[j] - alt_row[lo[j] - 1]
    j = hi < n_rows
    gap[j] = np.minimum(gap[j], alt_row[hi[j]] - alt_sun[j])
    bound = np.cos(gap) + 1e-9
    done = np.zeros(hours.size, dtype=bool)
    step = max(1, _BLOCK // centres.shape[0])
    for key in np.unique(row):
        g = np.flatnonzero(row == key)
        k0, k1 = bounds[lo[g[0]]], bounds[hi[g[0]]]
        if k1 - k0 < n_c:
            continue
        for i0 in range(0, g.size, 4 * step):
            gi = g[i0:i0 + 4 * step]
            cg, last = _candidates(s_all[gi], c_t[:, k0:k1], n_c)
            ok = last > bound[gi]
            cand[gi[ok]] = cg[ok] + k0
            done[gi[ok]] = True
    rest = np.flatnonzero(~done)
    for i0 in range(0, rest.size, step):
        gi = rest[i0:i0 + step]
        cand[gi] = _candidates(s_all[gi], c_t, n_c)[0]
    cand.sort(axis=1)                # index order: a stable sort by dot keeps it for ties
    c = centres[cand]                # (hours, n_c, 3)
    exact = c[..., 0] * s_all[:, 0:1]
    exact += c[..., 1] * s_all[:, 1:2]
    exact += c[..., 2] * s_all[:, 2:3]
    pick = np.argsort(-exact, axis=1, kind="stable")[:, :nsuns]
    r = np.arange(hours.size)[:, None]
    return cand[r, pick], exact[r, pick]


def fill_perez_sky(out, lit, nodes, weights, offsets, s_dist, coef, e_diff, cz_min, centres,
                   dom, s_true, e_dir, rho, tint, grey, out_scale, nsuns, fixed_sa,
                   tiers=None):
    """Fill the sky matrix ``out`` (P + 1, H, C), zero-filled, in Radiance's file order (row
    0 the ground): the patch values of :func:`perez_patch_values` times the tint, the ground
    and the sun, with the kernel's per-hour inputs (see
    :func:`skydome.daylighting._kernels.fill_perez_sky`), computed in float64 as the kernel
    does. Unlit hours are not touched (they stay zero).

    Each run of hours is written by one matrix product (BLAS) whose output is the run's block
    of the file: the patch means (P, h) times the diagonal (h, h x C) of the hours' factors
    scale x tint; its rows are the file's contiguous (hours x components) values, and each
    value is a single rounded product (one nonzero term per sum). Three elementwise products
    into the strided components instead make numpy loop over one run's hours (about 12 values)
    per patch and component, 2.5 million inner loops over an MF:4 year (0.03 s more). A
    float64 ``out`` takes float64 products (rounded once, as the kernel's); a float32 ``out``
    (a "float" file) takes float32 products of the patch mean and the factor each rounded to
    float32 (mixed types would make numpy cast through a buffer: in a profile of the annual
    MF:4 matrix + file that cast and its copies took a third of the samples): up to about 2
    units in the last place of float32 from the kernel's once-rounded value (2.4e-7
    relative). The sun's patches keep the kernel's rounding (their float64 sum is rounded
    once).

    Every value is checked before it is written (each block's largest, in cache): a value that
    is not finite in ``out``'s type raises ValueError, so that a file filled this way needs
    no second reading of its memory map for nan or inf."""
    ncomp = tint.shape[0]
    # every value written is checked (finite, and representable in out's type): the largest
    # of each block, in float64, against half the type's largest (a margin for the rounding)
    limit = 0.5 * float(np.finfo(out.dtype).max)
    t_max = float(tint.max()) if ncomp else 0.0
    hours = np.flatnonzero(lit)
    # the sun: the nsuns patches nearest it, weight 1 / (1.002 - cos) (gendaymtx AddDirect)
    sun_h = hours[e_dir[hours] > 1e-4] if nsuns > 0 else hours[:0]
    near, ndot = nearest_patches(centres, s_true, sun_h, max(nsuns, 1))
    near, ndot = near[:, :nsuns], ndot[:, :nsuns]
    at = np.full(lit.shape[0], -1)
    at[sun_h] = np.arange(sun_h.size)
    v_near = np.empty(near.shape)    # the sky values of the sun's patches, in float64
    rows = out.reshape(out.shape[0], -1)[1:]  # the sky patches' rows, a view (C-contiguous)
    ar = np.arange(_BLOCK)
    for hrs, means, scale in perez_patch_values(nodes, weights, offsets, s_dist, coef, lit,
                                                e_diff, out_scale, cz_min, tiers):
        if not means.max() * scale.max() * t_max <= limit:  # False for a nan
            raise ValueError("matrix holds nan or inf values")
        # value (k, h, c) = means[k, h] x (scale[h] tint[c]), written run of consecutive
        # hours by run (a day's) by one matrix product whose result is the run's block of the
        # file, rows of (hours x components) contiguous values, with the factors on the
        # diagonal of (hours, hours x components): every sum has one nonzero term, so each
        # value is the rounded product (the same bits as a multiply)
        m_t = means.astype(out.dtype, copy=False)
        for j0, j1 in _runs(hrs):
            n = j1 - j0
            h0 = hrs[j0]
            diag = np.zeros((n, n, ncomp), dtype=out.dtype)
            diag[ar[:n], ar[:n]] = scale[j0:j1, None] * tint
            d2 = diag.reshape(n, n * ncomp)
            # in blocks of patches of at most 2^18 multiply-adds, each on one thread: as one
            # product per run, OpenBLAS took both cores, and in a process without
            # OPENBLAS_NUM_THREADS=1 the MF:4 matrix + file cost 1.2-1.9 s of CPU against
            # 0.3-0.4 s (3 rounds each, 2-core EPYC shared with another load)
            step = max(16, _BLAS_ONE_THREAD // (n * n * ncomp))
            for k0 in range(0, m_t.shape[0], step):
                np.matmul(m_t[k0:k0 + step, j0:j1], d2,
                          out=rows[k0:k0 + step, h0 * ncomp:(h0 + n) * ncomp])
        k = at[hrs]
        j = np.flatnonzero(k >= 0)
        if j.size:
            v_near[k[j]] = means[near[k[j]], j[:, None]] * scale[j, None]
    # the ground, patch 0: rho (Dh + Dn sin a) / pi
    g = np.where(s_true[:, 2] > 0.0, e_diff + e_dir * s_true[:, 2], e_diff)
    g = np.where(lit, g * (rho / np.pi * out_scale), 0.0)
    _check(g[:, None] * grey, limit)
    for c in range(ncomp):
        out[0, :, c] = g * grey[c]
    if sun_h.size and nsuns > 0:
        wt = 1.0 / (1.002 - ndot)
        wtot = np.zeros(sun_h.size)
        for j in range(nsuns):       # summed in the kernel's order
            wtot += wt[:, j]
        sa = np.full(near.shape, fixed_sa) if fixed_sa > 0.0 else dom[near]
        v_sun = (wt * e_dir[sun_h][:, None]) * out_scale / (wtot[:, None] * sa)
        # the sun's patches (distinct within an hour): sky value plus the sun's share
        v = v_near[..., None] * tint + v_sun[..., None] * grey
        _check(v, limit)
        out[near + 1, sun_h[:, None]] = v


def _check(values, limit):
    """Raise ValueError unless every value is finite and within +-limit."""
    if values.size and not np.abs(values).max() <= limit:
        raise ValueError("matrix holds nan or inf values")
