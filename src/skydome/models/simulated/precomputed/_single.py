"""Single scattering tables ([Bru17] ComputeSingleScattering, [BN08] eq. 4), per scattering
constituent, without the phase function. The view rays are the nodes of the 4-D table
(:func:`._mapping.table_ray`: mu on :func:`._mapping.mu_unit`); the sun's transmittance is
looked up in the transmittance table on [Bru17]'s distance-to-the-top mapping.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.models.simulated.precomputed._geometry import clamp_cos, point_along
from skydome.models.simulated.precomputed._lookup import columns_segment
from skydome.models.simulated.precomputed._mapping import mu_s_nodes, table_ray
from skydome.transport._kernels import profile_density



# -- precomputation ---------------------------------------------------------------------------------
@njit(cache=True)
def single_scattering_table(col, trans, m, sc_idx, beta_s_sc, mu_s_min, alpha, n_q, ts, out):
    """Single scattering per scattering constituent, without its phase function ([Bru17]
    ComputeSingleScattering, [BN08] eq. 4 without P):

    out[k, r, mu, mu_s, nu, l] = beta_s,k(l) int_0^d rho_k(r_t) T(r, mu, t) T_sun(r_t, mu_s_t) dt

    per unit solar irradiance, for every node of the 4-D table, in the medium m
    (:class:`skydome.transport._medium.Medium`; beta_s,k = beta_s_sc[k], its scattering
    constituents sc_idx, its column table ``col``). T along the view ray from
    the column table (exact exponent), T_sun interpolated in the (float32) transmittance
    table trans[r, mu, l] (as [Bru17] does).

    Loop order: per view ray, the quadrature nodes outside and every (mu_s, nu) node inside,
    so that the view-ray transmittance, the densities and the r-dependent parts of the
    transmittance-table mapping and of the sun's visibility are computed once per node and
    shared by all sun geometries; the wavelength axis is innermost and contiguous (float32,
    accumulated in float32: 2 x 20 positive terms, relative rounding < 1e-6). A nu node
    that :func:`._mapping.cell_nu` clamps onto its neighbour's nu (about 12 % of them at
    the default sizes) is the same ray and sun geometry: copied, not integrated again.

    The whole table: :func:`single_scattering_rows` from r node 0."""
    single_scattering_rows(col, trans, m, sc_idx, beta_s_sc, mu_s_min, alpha, n_q, ts,
                           out.shape[1], 0, out)


@njit(parallel=True, cache=True, fastmath=True)
def single_scattering_rows(col, trans, m, sc_idx, beta_s_sc, mu_s_min, alpha, n_q, ts, n_r,
                          r0, out):
    """The r nodes r0 .. r0 + out.shape[1] - 1 of the n_r-node table of
    :func:`single_scattering_table` (the same values, bit for bit: the same loop body),
    into ``out`` (scattering, rows, mu, mu_s, nu, wavelength); the observer's two r nodes
    cost 2 / n_r of the table."""
    nsc, n_rows, n_mu, n_ms, n_nu, nl = out.shape
    R = m.R
    Rt = m.Rt
    codes = m.profile_code
    p0s = m.profile_p0
    p1s = m.profile_p1
    beta_e = m.extinction
    nc = codes.shape[0]
    n_rT, n_muT = trans.shape[0], trans.shape[1]
    H = math.sqrt(Rt * Rt - R * R)
    nk = n_ms * n_nu
    mus = mu_s_nodes(n_ms, mu_s_min)
    # the rays interleaved over the threads' static shares of the loop (the cost varies
    # with r and mu): work item j is ray (j % g) * s + j // g, s = 16 rays per group
    n_rays = n_rows * n_mu
    s_grp = 16 if n_rays % 16 == 0 else 1
    n_grp = n_rays // s_grp
    order = np.empty(n_rays, dtype=np.int64)
    for j in range(n_rays):
        order[j] = (j % n_grp) * s_grp + j // n_grp
    for jdx in prange(n_rays):
        idx = r0 * n_mu + order[jdx]
        tq = np.empty(3 * n_q)                # ray_nodes: up to 3 n_q
        wq = np.empty(3 * n_q)
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        cs = np.empty(nc)
        tview = np.empty(nl, dtype=np.float32)
        dens = np.empty(nsc, dtype=np.float32)
        tsun = np.empty(nl, dtype=np.float32)
        trow = np.empty((n_muT, nl), dtype=np.float32)
        acc = np.zeros((nk, nsc, nl), dtype=np.float32)
        nus = np.empty(nk)
        js = np.empty(nk, dtype=np.int64)
        u0s = np.empty(nk, dtype=np.float32)
        u1s = np.empty(nk, dtype=np.float32)
        ir, imu, r, mu, ground, nq = table_ray(idx, n_r, n_mu, R, Rt, mus, n_nu, n_q, ts, tq,
                                               wq, nus)
        for q in range(nq):
            t = tq[q]
            rt = point_along(r, mu, t, R, Rt)
            columns_segment(col, r, mu, t, ground, R, Rt, w1, w2, cs)
            for l in range(nl):
                s = 0.0
                for c in range(nc):
                    s += beta_e[c, l] * cs[c]
                tview[l] = wq[q] * math.exp(-s)
            for kk in range(nsc):
                c = sc_idx[kk]
                dens[kk] = profile_density(codes[c], p0s[c], p1s[c], rt - R)
            # r-dependent parts of the transmittance-table mapping (table_coords) and of
            # sun_visible_fraction, once per node
            rho = math.sqrt(max(rt * rt - R * R, 0.0))
            fr = rho / H * (n_rT - 1)
            i = min(int(fr), n_rT - 2)
            a = fr - i
            d_min = Rt - rt
            span = rho + H - d_min
            sin_h = R / rt
            cos_h = -math.sqrt(max(1.0 - sin_h * sin_h, 0.0))
            eps = sin_h * alpha
            inv_rt = 1.0 / rt
            inv_2eps = 1.0 / (2.0 * eps)
            inv_span = 0.0 if span <= 0.0 else 1.0 / span
            # the transmittance table's row at rt (linear in r), times the view ray's
            # transmittance and quadrature weight: every sun geometry of this node reads it
            fa = np.float32(a)
            fa1 = np.float32(1.0 - a)
            for jj in range(n_muT):
                for l in range(nl):
                    trow[jj, l] = tview[l] * (fa1 * trans[i, jj, l] + fa * trans[i + 1, jj, l])
            # the sun's geometry of every (mu_s, nu) node at this point: one vectorisable
            # pass (square roots and divisions 8-wide), then the gathers
            for k in range(nk):
                mu_s_t = clamp_cos((r * mus[k // n_nu] + t * nus[k]) * inv_rt)
                xv = (mu_s_t - cos_h + eps) * inv_2eps
                vis = min(max(xv, 0.0), 1.0)
                vis = vis * vis * (3.0 - 2.0 * vis)
                disc = rt * rt * (mu_s_t * mu_s_t - 1.0) + Rt * Rt
                dd = max(-rt * mu_s_t + math.sqrt(max(disc, 0.0)), 0.0)
                x_mu = min(max((dd - d_min) * inv_span, 0.0), 1.0)
                fm = x_mu * (n_muT - 1)
                jk = min(int(fm), n_muT - 2)
                bk = fm - jk
                js[k] = jk
                u0s[k] = np.float32(vis * (1.0 - bk))
                u1s[k] = np.float32(vis * bk)
            for k in range(nk):
                if u0s[k] == 0.0 and u1s[k] == 0.0:
                    continue
                if k % n_nu and nus[k] == nus[k - 1]:
                    continue    # a nu node clamped to its neighbour's nu: copied below
                j = js[k]
                u0 = u0s[k]
                u1 = u1s[k]
                for l in range(nl):
                    tsun[l] = u0 * trow[j, l] + u1 * trow[j + 1, l]
                for kk in range(nsc):
                    dk = dens[kk]
                    o = acc[k, kk]
                    for l in range(nl):
                        o[l] += dk * tsun[l]
        for k in range(nk):
            if k % n_nu and nus[k] == nus[k - 1]:
                acc[k] = acc[k - 1]
            for kk in range(nsc):
                for l in range(nl):
                    out[kk, ir - r0, imu, k // n_nu, k % n_nu, l] = (beta_s_sc[kk, l]
                                                                     * acc[k, kk, l])
