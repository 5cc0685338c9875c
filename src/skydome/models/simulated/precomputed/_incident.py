"""The incident rays of the orders >= 3 with their geometry computed once
(:func:`._density.incident_radiance_rays` split in two): every order's incident radiance is
a ray integral of that order's scattering density J along the same rays, from the same
nodes, with the same transmittance-weighted densities and the same cells of J. The geometry
(:func:`incident_ray_geometry`: the nodes' weights of J, :func:`._lookup.ray_weights`, and
their cells in J's axes; the ground's transmittance and the sun's cosine where a ray ends on
the ground) is stored once per precomputation, and each order's integral
(:func:`incident_radiance_stored`) reads it back and gathers that order's J: the same
arithmetic in the same order as :func:`._density.incident_radiance_rays`, with the
geometry's cost paid once instead of once per order (docs/performance.md, "A new atmosphere
as a command"). The result is that kernel's to the bit except at the scattering density's
mu_s node of the sun at the zenith, where the azimuth about the sun is singular and its
fraction (of order 1e-6 there) differs in its last bits between the two compiled kernels:
values within a few float32 units in the last place (docs/models.md, "precomputed").
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.models.simulated.precomputed._density import (INV_PI, density_node,
                                                            ground_reflected_acc,
                                                            incident_direction)
from skydome.models.simulated.precomputed._geometry import (clamp_cos, distance_to_ground,
                                                             distance_to_top)
from skydome.models.simulated.precomputed._lookup import (columns_segment, irradiance_lookup_acc,
                                                           ray_weights)
from skydome.models.simulated.precomputed._mapping import (_split, density_mu_s_index,
                                                            density_phi_index, mu_s_frame,
                                                            r_index)
from skydome.models.simulated.precomputed._multiple import (THETA_SNAP, density_acc, ray_integral,
                                                            ray_scratch)
from skydome.transport._quadrature import ray_nodes_rule


class IncidentRays(NamedTuple):
    """The stored geometry of the incident rays (:func:`incident_rays`); ray ``i`` is work
    item ``i // n_ph`` of :func:`._density.incident_radiance_rays`'s loop at incident azimuth
    ``i % n_ph``."""

    kept: np.ndarray     # (n_work,) bool: the work items whose geometry is stored
    start: np.ndarray    # (n_rays + 1,) int64: ray i's nodes are start[i] .. start[i + 1] - 1
    tw: np.ndarray       # (n_nodes, nsc, nl) float32: the weights of J at each node
    cell: np.ndarray     # (n_nodes, 3) int32: J's r, mu_s and phi cells of each node
    frac: np.ndarray     # (n_nodes, 3) float64: ... and the fractions within them
    tcell: np.ndarray    # (n_rays,) int64: J's theta cell of the ray
    tfrac: np.ndarray    # (n_rays,) float64: ... and the fraction within it (snapped)
    gidx: np.ndarray     # (n_rays,) int64: the ray's row in tg / mu_g, -1 if it ends in the sky
    tg: np.ndarray       # (n_ground, nl) float64: transmittance to the ground x albedo / pi
    mu_g: np.ndarray     # (n_ground,) float64: the sun's zenith cosine where the ray lands

    @property
    def nbytes(self):
        """The bytes of its arrays."""
        return sum(a.nbytes for a in self)


@njit(cache=True)
def _work_item(idx, n_th, n_nodes, n_ms):
    """(a, ir, ims) of work item idx: the order of :func:`._density.incident_radiance_rays`
    (the angles from the sun 0, 2, 4, ..., 1, 3, 5, ... outermost)."""
    h = n_th // 2
    k = idx // n_nodes
    a = 2 * (k % h) + k // h if k < 2 * h else k
    return a, (idx % n_nodes) // n_ms, idx % n_ms


@njit(parallel=True, cache=True)
def incident_ray_counts(R, Rt, mu_s_min, rx, rw, ts, n_r, n_ms, th_in, ph_in, nodes, ground):
    """nodes[i], ground[i]: the node count of ray i (:func:`ray_nodes_rule`) and whether it
    ends on the ground."""
    n_th = th_in.shape[0]
    n_ph = ph_in.shape[0]
    n_nodes = n_r * n_ms
    for idx in prange(n_th * n_nodes):
        a, ir, ims = _work_item(idx, n_th, n_nodes, n_ms)
        tq = np.empty(2 * rx.size)
        wq = np.empty(2 * rx.size)
        r, mu_s, sin_s = density_node(ir, ims, n_r, n_ms, R, Rt, mu_s_min)
        for b in range(n_ph):
            nu, ct, hit = incident_direction(th_in[a], ph_in[b], r, mu_s, sin_s, R)
            d = distance_to_ground(r, ct, R) if hit else distance_to_top(r, ct, Rt)
            nodes[idx * n_ph + b] = ray_nodes_rule(r, ct, d, rx, rw, ts, tq, wq)
            ground[idx * n_ph + b] = hit


@njit(parallel=True, cache=True, fastmath=True)
def incident_ray_geometry(m, sc_idx, col, mu_s_min, rx, rw, ts, n_r, n_ms, th_in, ph_in,
                          j_shape, kept, start, gidx, tw, cell, frac, tcell, tfrac, tg, mu_g):
    """Fills the arrays of :class:`IncidentRays` (``kept``, ``start`` and ``gidx`` given; the
    work items not kept are skipped) for a scattering
    density of shape ``j_shape`` = (n_theta, n_phi, n_r, n_mu_s) on its grid axes, as
    :func:`._multiple.ray_integral` and :func:`._density.ground_reflected_acc` compute them
    for each ray of :func:`._density.incident_radiance_rays` (the same expressions)."""
    n_th = th_in.shape[0]
    n_ph = ph_in.shape[0]
    nl = tw.shape[2]
    nc = col.shape[0]
    nsc = tw.shape[1]
    n_tj, n_pj, n_rj, n_msj = j_shape[0], j_shape[1], j_shape[2], j_shape[3]
    R = m.R
    Rt = m.Rt
    beta_e = m.extinction
    albedo = m.albedo
    frame = mu_s_frame(mu_s_min)
    n_nodes = n_r * n_ms
    for idx in prange(n_th * n_nodes):
        if not kept[idx]:
            continue
        a, ir, ims = _work_item(idx, n_th, n_nodes, n_ms)
        w = ray_scratch(rx.size, nc, nsc, nl,
                        np.empty((2 * rx.size, nsc, nl), dtype=np.float32))
        r, mu_s, sin_s = density_node(ir, ims, n_r, n_ms, R, Rt, mu_s_min)
        for b in range(n_ph):
            i = idx * n_ph + b
            nu, ct, ground = incident_direction(th_in[a], ph_in[b], r, mu_s, sin_s, R)
            # ray_integral's geometry
            d = distance_to_ground(r, ct, R) if ground else distance_to_top(r, ct, Rt)
            nq = ray_nodes_rule(r, ct, d, rx, rw, ts, w.tq, w.wq)
            jt, jb = _split(math.acos(nu) / math.pi * (n_tj - 1), n_tj)
            if jb < THETA_SNAP:
                jb = 0.0
            elif jb > 1.0 - THETA_SNAP:
                jt, jb = jt + 1, 0.0
            tcell[i] = jt
            tfrac[i] = jb
            ray_weights(col, m, sc_idx, r, ct, ground, nq, 1.0, w)
            o = start[i]
            for q in range(nq):
                t = w.tq[q]
                rt = w.rts[q]
                mt = clamp_cos((r * ct + t) / rt)
                jr, ja = r_index(rt, n_rj, R, Rt)
                mu_s_t = clamp_cos((r * mu_s + t * nu) / rt)
                ims_j, c = density_mu_s_index(mu_s_t, frame, n_msj)
                ip, e = density_phi_index(nu, mu_s_t, mt, n_pj)
                cell[o + q, 0] = jr
                cell[o + q, 1] = ims_j
                cell[o + q, 2] = ip
                frac[o + q, 0] = ja
                frac[o + q, 1] = c
                frac[o + q, 2] = e
                for kk in range(nsc):
                    for l in range(nl):
                        tw[o + q, kk, l] = w.tw[q, kk, l]
            if ground:
                # ground_reflected_acc's transmittance to the ground and landing point
                g = gidx[i]
                cs = w.cs[0]
                dg = distance_to_ground(r, ct, R)
                columns_segment(col, r, ct, dg, True, R, Rt, w.w1, w.w2, cs)
                for l in range(nl):
                    s = 0.0
                    for cc in range(nc):
                        s += beta_e[cc, l] * cs[cc]
                    tg[g, l] = math.exp(-s) * albedo[l] * INV_PI
                mu_g[g] = clamp_cos((r * mu_s + dg * nu) / R)


@njit(parallel=True, cache=True, fastmath=True)
def incident_radiance_stored(J, dE, m, sc_idx, col, mu_s_min, rx, rw, ts, n_r, n_ms, th_in, ph_in,
                             kept, start, tw, cell, frac, tcell, tfrac, gidx, tg, mu_g, out):
    """:func:`._density.incident_radiance_rays` (the same arguments, then the arrays of
    :class:`IncidentRays`): the work items whose geometry is stored (``kept``) read it
    back; the others compute it as that kernel does. out[i, r, mu_s, l] (float32), the sums
    in float32 in the same order (module docstring)."""
    n_th = th_in.shape[0]
    n_ph = ph_in.shape[0]
    nl = out.shape[3]
    nc = col.shape[0]
    nsc = J.shape[0]
    R = m.R
    Rt = m.Rt
    beta_e = m.extinction
    albedo = m.albedo
    frame = mu_s_frame(mu_s_min)
    n_nodes = n_r * n_ms
    for idx in prange(n_th * n_nodes):
        a, ir, ims = _work_item(idx, n_th, n_nodes, n_ms)
        acc = np.empty(nl, dtype=np.float32)
        eg = np.empty(nl)
        if kept[idx]:
            for b in range(n_ph):
                i = idx * n_ph + b
                acc[:] = 0.0
                jt = tcell[i]
                jb = tfrac[i]
                for q in range(start[i], start[i + 1]):
                    density_acc(J, tw[q], jt, jb, np.int64(cell[q, 2]), frac[q, 2],
                                np.int64(cell[q, 0]), frac[q, 0], np.int64(cell[q, 1]),
                                frac[q, 1], acc)
                g = gidx[i]
                if g >= 0:
                    eg[:] = 0.0
                    irradiance_lookup_acc(dE, R, mu_g[g], R, Rt, mu_s_min, 1.0, eg)
                    for l in range(nl):
                        acc[l] += tg[g, l] * eg[l]
                o = out[a * n_ph + b, ir, ims]
                for l in range(nl):
                    o[l] = acc[l]
        else:
            # as _density.incident_radiance_rays
            w = ray_scratch(rx.size, nc, nsc, nl,
                            np.empty((2 * rx.size, nsc, nl), dtype=np.float32))
            tgr = np.empty(nl)
            r, mu_s, sin_s = density_node(ir, ims, n_r, n_ms, R, Rt, mu_s_min)
            for b in range(n_ph):
                nu, ct, ground = incident_direction(th_in[a], ph_in[b], r, mu_s, sin_s, R)
                acc[:] = 0.0
                ray_integral(J, m, sc_idx, col, frame, r, ct, mu_s, nu, ground, rx, rw, ts, w,
                             acc)
                if ground:
                    ground_reflected_acc(False, dE, col, beta_e, albedo, R, Rt, mu_s_min, 0.0, r,
                                         ct, mu_s, nu, w.w1, w.w2, w.cs[0], tgr, eg, acc)
                o = out[a * n_ph + b, ir, ims]
                for l in range(nl):
                    o[l] = acc[l]


def incident_rays(J_shape, m, sc_idx, col, mu_s_min, rx, rw, ts, n_r, n_ms, th_in, ph_in,
                  budget=None):
    """The :class:`IncidentRays` of :func:`._density.incident_radiance_rays`'s arguments
    (``J_shape`` the scattering density's shape, [k, theta, phi, r, mu_s, l]), in at most
    ``budget`` bytes (None: no bound): where the whole geometry needs more, the geometry of
    an evenly spread share of the work items (one per (theta, r, mu_s)) is stored and the
    rest is computed again in each call."""
    n_work = th_in.size * n_r * n_ms
    n_ph = ph_in.size
    n_rays = n_work * n_ph
    nodes = np.empty(n_rays, dtype=np.int64)
    ground = np.empty(n_rays, dtype=np.bool_)
    incident_ray_counts(float(m.R), float(m.Rt), mu_s_min, rx, rw, ts, n_r, n_ms, th_in, ph_in,
                        nodes, ground)
    nsc, nl = J_shape[0], J_shape[-1]
    # bytes per work item: its nodes (weights, cells, fractions) and ground rows; per ray 32
    per_item = (nodes.reshape(n_work, n_ph).sum(1) * (4 * nsc * nl + 36)
                + ground.reshape(n_work, n_ph).sum(1) * (8 * nl + 8))
    f = 1.0
    if budget is not None and per_item.sum() > 0:
        f = min(max((budget - 32 * n_rays) / per_item.sum(), 0.0), 1.0)
    k = np.arange(n_work + 1, dtype=np.float64) * f
    kept = np.floor(k[1:] + 1e-9) > np.floor(k[:-1] + 1e-9) if f < 1.0 else np.ones(n_work, bool)
    keep_ray = np.repeat(kept, n_ph)
    nodes[~keep_ray] = 0
    ground &= keep_ray
    start = np.zeros(n_rays + 1, dtype=np.int64)
    np.cumsum(nodes, out=start[1:])
    gidx = np.where(ground, np.cumsum(ground) - 1, -1).astype(np.int64)
    n_g = int(ground.sum())
    g = IncidentRays(kept, start, np.empty((start[-1], nsc, nl), dtype=np.float32),
                     np.empty((start[-1], 3), dtype=np.int32), np.empty((start[-1], 3)),
                     np.empty(n_rays, dtype=np.int64), np.empty(n_rays), gidx,
                     np.empty((n_g, nl)), np.empty(n_g))
    incident_ray_geometry(m, sc_idx, col, mu_s_min, rx, rw, ts, n_r, n_ms, th_in, ph_in,
                          np.array(J_shape[1:5], dtype=np.int64), g.kept, g.start, g.gidx, g.tw,
                          g.cell, g.frac, g.tcell, g.tfrac, g.tg, g.mu_g)
    return g


def incident_radiance(J, dE, m, sc_idx, col, mu_s_min, rx, rw, ts, n_r, n_ms, th_in, ph_in, g,
                      out):
    """:func:`._density.incident_radiance_rays` (its arguments) on the stored geometry ``g``
    of its rays (:func:`incident_rays`): :func:`incident_radiance_stored`."""
    incident_radiance_stored(J, dE, m, sc_idx, col, mu_s_min, rx, rw, ts, n_r, n_ms, th_in, ph_in,
                             *g, out)
