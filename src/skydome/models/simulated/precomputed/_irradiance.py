"""Direct ([Bru17] ComputeDirectIrradiance) and indirect ([Bru17] ComputeIndirectIrradiance,
[BN08] eq. 9) irradiance on a horizontal surface, per unit solar irradiance (the sky
radiance read from the 4-D table, mu on :func:`._mapping.mu_unit`).
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.models.simulated.precomputed._geometry import clamp_cos, distance_to_top
from skydome.models.simulated.precomputed._lookup import (columns_at, ray_weights,
                                                           sky_lookup_acc)
from skydome.models.simulated.precomputed._mapping import (_split, density_mu_s_index,
                                                            density_phi_index, mu_s_frame,
                                                            mu_s_from_unit, r_index)
from skydome.models.simulated.precomputed._multiple import density_acc, ray_scratch
from skydome.transport._quadrature import ray_nodes_rule



@njit(cache=True)
def direct_irradiance_acc(col, beta_e, r, mu_s, R, Rt, alpha, scale, cs, out):
    """Add scale x the direct solar irradiance on a horizontal surface at r ([Bru17]
    ComputeDirectIrradiance: transmittance x the average cosine over the disc)."""
    if mu_s < -alpha:
        return
    if mu_s > alpha:
        f = mu_s
    else:
        f = (mu_s + alpha) * (mu_s + alpha) / (4.0 * alpha)
    columns_at(col, r, mu_s, R, Rt, cs)
    for l in range(out.shape[0]):
        s = 0.0
        for c in range(cs.shape[0]):
            s += beta_e[c, l] * cs[c]
        out[l] += scale * f * math.exp(-s)


@njit(parallel=True, cache=True, fastmath=True)
def indirect_irradiance(ss, pc, pp, pt, R, Rt, mu_s_min, th, ph, d_omega, out):
    """Irradiance on a horizontal surface from the single-scattered sky (table ``ss``), the
    ground irradiance of order 2 ([Bru17] ComputeIndirectIrradiance, [BN08] eq. 9 for one
    order; orders >= 3: :func:`indirect_irradiance_rays`): out[r, mu_s, l] = sum over the
    upper hemisphere of L(w) cos(theta) dOmega (phi over [0, pi], doubled)."""
    n_r, n_m, nl = out.shape
    for idx in prange(n_r * n_m):
        ir = idx // n_m
        im = idx % n_m
        r = R + (Rt - R) * ir / (n_r - 1.0)
        mu_s = mu_s_from_unit(im / (n_m - 1.0), mu_s_min)
        sin_s = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
        o = out[ir, im]
        o[:] = 0.0
        for a in range(th.shape[0]):
            ct = math.cos(th[a])
            st = math.sin(th[a])
            for b in range(ph.shape[0]):
                nu = clamp_cos(sin_s * st * math.cos(ph[b]) + mu_s * ct)
                # first=True: only ss is read (ss[0] stands in for the unused order table)
                sky_lookup_acc(True, ss, pc, pp, pt, ss[0], r, ct, mu_s, nu, False, R, Rt, mu_s_min,
                               2.0 * ct * d_omega[a], o)


@njit(parallel=True, cache=True, fastmath=True)
def indirect_irradiance_rays(J, m, sc_idx, col, mu_s_min, rx, rw, ts, th, ph, d_omega, out,
                             n_r_table):
    """:func:`indirect_irradiance` for an order >= 2 whose radiance is not tabulated: the
    radiance of each hemisphere direction integrated along its ray from that order's
    scattering density ``J`` ([BN08] eq. 8 and 9, :func:`._multiple.ray_integral`, the
    integrand of the multiple-scattering table on the nodes of the rule (rx, rw) in v per
    piece of each ray, :func:`skydome.transport._quadrature.ray_nodes_rule`), on the
    irradiance table's nodes, in the medium m (:class:`skydome.transport._medium.Medium`,
    its scattering constituents sc_idx, its column table ``col``).

    A hemisphere direction's ray, its quadrature nodes, their radii, local zenith cosines
    and transmittance-weighted density weights depend on (r, theta) alone, not on the sun
    (mu_s) nor on the azimuth from it: they are computed once per (r, theta) work item and
    shared by its n_mu_s x n_phi rays (the same sums as one :func:`._multiple.ray_integral`
    per ray, without its per-ray columns and exponentials).

    ``out`` holds the first out.shape[0] r rows of a table of ``n_r_table`` rows (the
    precomputation's orders need the ground's row alone, the stored table every row)."""
    n_r, n_m, nl = out.shape
    n_th = th.shape[0]
    n_ph = ph.shape[0]
    nc = col.shape[0]
    nsc, n_tj, n_pj, n_rj, n_msj, _ = J.shape
    R = m.R
    Rt = m.Rt
    frame = mu_s_frame(mu_s_min)
    part = np.zeros((n_r * n_th, n_m, nl))
    for idx in prange(n_r * n_th):
        ir = idx // n_th
        a = idx % n_th
        w = ray_scratch(rx.size, nc, nsc, nl, np.empty((2 * rx.size, nsc, nl)))
        tq = w.tq
        rts = w.rts
        tws = w.tw
        r = R + (Rt - R) * ir / (n_r_table - 1.0)
        ct = math.cos(th[a])
        st = math.sin(th[a])
        nq = ray_nodes_rule(r, ct, distance_to_top(r, ct, Rt), rx, rw, ts, tq, w.wq)
        ray_weights(col, m, sc_idx, r, ct, False, nq, 2.0 * ct * d_omega[a], w)
        mts = np.empty(nq)
        jrs = np.empty(nq, dtype=np.int64)
        jas = np.empty(nq)
        for q in range(nq):
            mts[q] = clamp_cos((r * ct + tq[q]) / rts[q])
            jrs[q], jas[q] = r_index(rts[q], n_rj, R, Rt)
        acc = part[idx]
        for im in range(n_m):
            mu_s = mu_s_from_unit(im / (n_m - 1.0), mu_s_min)
            sin_s = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
            for b in range(n_ph):
                nu = clamp_cos(sin_s * st * math.cos(ph[b]) + mu_s * ct)
                jt, jb = _split(math.acos(nu) / math.pi * (n_tj - 1), n_tj)
                for q in range(nq):
                    mu_s_t = clamp_cos((r * mu_s + tq[q] * nu) / rts[q])
                    ims_j, c = density_mu_s_index(mu_s_t, frame, n_msj)
                    ip, e = density_phi_index(nu, mu_s_t, mts[q], n_pj)
                    density_acc(J, tws[q], jt, jb, ip, e, jrs[q], jas[q], ims_j, c, acc[im])
    for ir in range(n_r):
        for im in range(n_m):
            for l in range(nl):
                s = 0.0
                for a in range(n_th):
                    s += part[ir * n_th + a, im, l]
                out[ir, im, l] = s
