"""Multiple scattering ([Bru17] ComputeMultipleScattering, [BN08] eq. 8): orders 2..N on the
4-D table's nodes (the view rays of :func:`._mapping.table_ray`, mu on
:func:`._mapping.mu_unit`; every node by default, or, opt-in, a subset interpolated onto
the rest by :func:`table_from_coarse`), and on the observer's own sky map.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.models.simulated.precomputed._geometry import (clamp_cos, distance_to_ground,
                                                             distance_to_top)
from skydome.models.simulated.precomputed._lookup import ray_weights, ray_weights_integrated
from skydome.transport._quadrature import ray_nodes, ray_nodes_rule
from skydome.models.simulated.precomputed._mapping import (_split, cell_mu, cell_nu, cell_r,
                                                            density_mu_s_index,
                                                            density_phi_index, mu_s_frame,
                                                            mu_s_from_unit, mu_s_nodes, r_index)



# fraction of a theta cell of J within which a ray's angle from the sun is taken to be on
# the node (ray_integral)
THETA_SNAP = 1e-9


@njit(cache=True, fastmath=True)
def density_acc(J, tw, jt, jb, ip, e, jr, ja, ims_j, c, out):
    """out[l] += sum_k tw[k, l] J_k(theta, phi, r, mu_s)[l]: the scattering density J
    [k, theta, phi, r, mu_s, l] interpolated quadrilinearly in the cell (jt + jb, ip + e,
    jr + ja, ims_j + c), weighted per constituent by ``tw`` (:func:`._lookup.ray_weights`);
    the weights in the precision of ``out``; a theta row of weight 0 is not read (see
    :func:`ray_integral`)."""
    nl = out.shape[0]
    for kk in range(J.shape[0]):
        twk = tw[kk]
        Jk = J[kk]
        for dt in range(2):
            wt = jb if dt else 1.0 - jb
            if wt == 0.0:
                continue
            for dr in range(2):
                wr = ja if dr else 1.0 - ja
                for ds in range(2):
                    ws = c if ds else 1.0 - c
                    w0 = wt * wr * ws
                    row0 = Jk[jt + dt, ip, jr + dr, ims_j + ds]
                    row1 = Jk[jt + dt, ip + 1, jr + dr, ims_j + ds]
                    wa = out.dtype.type(w0 * (1.0 - e))
                    wb = out.dtype.type(w0 * e)
                    for l in range(nl):
                        out[l] += (wa * row0[l] + wb * row1[l]) * twk[l]



class RayWork(NamedTuple):
    """Scratch arrays of one work item's ray integrals (room for m = 3 n_q quadrature nodes:
    :func:`ray_nodes` lays up to 3 n_q, ``ray_nodes_rule`` 2 n_q,
    :func:`ray_scratch`)."""

    tq: np.ndarray     # (m,) distances of the nodes [m]
    wq: np.ndarray     # (m,) their weights [m]
    w1: np.ndarray     # (nc,) columns at a node (:func:`._lookup.ray_weights`)
    w2: np.ndarray     # (nc,) columns at the ray's start
    rts: np.ndarray    # (m,) radii of the nodes [m]
    cs: np.ndarray     # (m, nc) columns from the start to each node
    xs: np.ndarray     # (m nl,) -optical depths
    es: np.ndarray     # (m nl,) transmittances
    ib: np.ndarray     # (m max(nl, 1),) int64 scratch of the vectorised exp
    dk: np.ndarray     # (nsc, m) densities of the scattering constituents at the nodes
    tw: np.ndarray     # (m, nsc, nl) the weights of J (:func:`._lookup.ray_weights`)


@njit(cache=True)
def ray_scratch(n_q, nc, nsc, nl, tw):
    """The :class:`RayWork` of one work item's ray integrals (room for 3 n_q quadrature
    nodes, nc constituents, nsc scattering ones, nl wavelengths), with ``tw`` the array
    of J's weights, (3 n_q, nsc, nl) in the precision of the sums (2 n_q for the rule's
    2 n_q nodes at most)."""
    m = 3 * n_q                 # ray_nodes: up to 3 n_q
    return RayWork(np.empty(m), np.empty(m), np.empty(nc), np.empty(nc), np.empty(m),
                   np.empty((m, nc)), np.empty(m * nl), np.empty(m * nl),
                   np.empty(m * max(nl, 1), dtype=np.int64), np.empty((nsc, m)), tw)


@njit(cache=True, fastmath=True)
def ray_integral(J, m, sc_idx, col, frame, r, mu, mu_s, nu, ground, rx, rw, ts, w, acc):
    """acc[l] += int_0^d sum_k rho_k(r_t) J_k(r_t, mu_t, mu_s_t, nu) T(r, mu, t) dt along one
    ray ([BN08] eq. 8) from radius r in the direction of zenith cosine mu and sun cosine nu,
    the sun at zenith cosine mu_s, to the ground (``ground``) or the top: the integrand of
    :func:`multiple_scattering_table` (exact density profiles, J interpolated in the sun's
    frame) on the nodes of the rule (rx, rw) in v = ln(1 + u / ts) per piece of the ray
    (:func:`skydome.transport._quadrature.ray_nodes_rule`), for a single ray, in the
    medium m (:class:`skydome.transport._medium.Medium`; its scattering constituents
    sc_idx, its column table ``col``), without per-ray allocations (``w``: the
    :func:`ray_scratch` of rx.size nodes per piece, its ``tw`` in the precision of
    ``acc``)."""
    nsc, n_tj, n_pj, n_rj, n_msj, _ = J.shape
    R = m.R
    Rt = m.Rt
    tq = w.tq
    tw = w.tw
    d = distance_to_ground(r, mu, R) if ground else distance_to_top(r, mu, Rt)
    nq = ray_nodes_rule(r, mu, d, rx, rw, ts, tq, w.wq)
    jt, jb = _split(math.acos(nu) / math.pi * (n_tj - 1), n_tj)
    # an angle from the sun on a theta node of J to rounding (the incident directions of
    # the orders >= 3: (2i + 1) pi / (2 n_in) is node (2i + 1) n_out / n_in of J's
    # 2 n_out + 1 when n_in divides n_out, as at the defaults) reads that one theta row:
    # half the gathers, the value changed by <= 1e-9 of the difference of two rows
    if jb < THETA_SNAP:
        jb = 0.0
    elif jb > 1.0 - THETA_SNAP:
        jt, jb = jt + 1, 0.0
    # the transmittance-weighted densities of every node of the ray, then J's gathers
    ray_weights(col, m, sc_idx, r, mu, ground, nq, 1.0, w)
    rts = w.rts
    for q in range(nq):
        t = tq[q]
        rt = rts[q]
        mt = clamp_cos((r * mu + t) / rt)
        jr, ja = r_index(rt, n_rj, R, Rt)
        mu_s_t = clamp_cos((r * mu_s + t * nu) / rt)
        ims_j, c = density_mu_s_index(mu_s_t, frame, n_msj)
        ip, e = density_phi_index(nu, mu_s_t, mt, n_pj)
        density_acc(J, tw[q], jt, jb, ip, e, jr, ja, ims_j, c, acc)


@njit(parallel=True, cache=True, fastmath=True)
def multiple_scattering_table(J, m, sc_idx, col, mu_s_min, n_q, ts, mu_nodes, n_mu_full,
                              mu_s_nodes_sel, n_ms_full, r_first, n_r_full, out):
    """One scattering order, full radiance ([Bru17] ComputeMultipleScattering, [BN08] eq. 8):
    out[r, mu, mu_s, nu, l] = int_0^d sum_k rho_k(r_t) J_k(r_t, mu_t, mu_s_t, nu) T(r, mu, t) dt.

    J_k is the scattering density of scattering constituent k (constituent sc_idx[k] of the
    medium m, :class:`skydome.transport._medium.Medium`) per unit number density, which is
    smooth in r; its density profile rho_k is applied exactly at each quadrature node (the r
    nodes of the table do not resolve the 1.2 km aerosol layer: interpolating rho_k J_k between
    them overestimated the aerosol's multiple scattering by up to 20 %).

    J (float32) is tabulated on [k, theta, phi, r, mu_s, l] in the sun's frame (theta the
    angle between the view ray and the sun, acos nu, uniform in [0, pi]; phi the azimuth of
    the view ray about the sun from the sun's vertical plane, uniform in [0, pi]; r and mu_s
    on the scattering-table nodes): at fixed (theta, phi) J varies smoothly with mu_s, while
    in a zenith frame the aerosol aureole sweeps across the coarse mu_s nodes (that
    overestimated order 2 by up to 66 % at AOD 0.5) and interpolated quadrilinearly. Loop order: per view ray,
    the quadrature nodes outside (their r, theta, weights and view transmittance computed
    once and the J rows they touch staying in cache) and every (mu_s, nu) node inside; the
    wavelength axis innermost and contiguous, accumulated in float32 (at most 16 x 20
    positive terms per value).

    The table is computed on a subset of the nodes of a table of n_r x ``n_mu_full`` x
    ``n_ms_full`` x n_nu nodes: its mu nodes ``mu_nodes`` and mu_s nodes
    ``mu_s_nodes_sel`` (indices into the full axes, the same mappings) and n_nu uniform nu
    nodes (out[r, j, k, inu, l] at mu node mu_nodes[j], mu_s node mu_s_nodes_sel[k]); all of
    them (``arange``) give the full table. :func:`table_from_coarse` interpolates it onto
    the full grid. ``out`` holds the r nodes ``r_first`` .. ``r_first + out.shape[0] - 1``
    of the table's ``n_r_full`` (0 and n_r for the whole table: the rows are independent,
    so a table built slab by slab is the same to the bit)."""
    n_r, n_mu, n_ms, n_nu, nl = out.shape
    nc = col.shape[0]
    nsc, n_tj, n_pj, n_rj, n_msj, _ = J.shape
    R = m.R
    Rt = m.Rt
    nk = n_ms * n_nu
    frame = mu_s_frame(mu_s_min)
    mus = np.empty(n_ms)
    for k in range(n_ms):
        mus[k] = mu_s_from_unit(mu_s_nodes_sel[k] / (n_ms_full - 1.0), mu_s_min)
    for idx in prange(n_r * n_mu):
        w = ray_scratch(n_q, nc, nsc, nl, np.empty((3 * n_q, nsc, nl), dtype=np.float32))
        tq = w.tq
        tw = w.tw
        rts = w.rts
        acc = np.zeros((nk, nl), dtype=np.float32)
        nus = np.empty(nk)
        jts = np.empty(nk, dtype=np.int64)
        jbs = np.empty(nk)
        ks = np.empty(nk, dtype=np.int64)
        ir = idx // n_mu
        imu = idx % n_mu
        r = cell_r(r_first + ir, n_r_full, R, Rt)
        mu, ground = cell_mu(mu_nodes[imu], n_mu_full, r, R, Rt)
        for k in range(nk):
            nus[k] = cell_nu(k % n_nu, n_nu, mu, mus[k // n_nu])
        d = distance_to_ground(r, mu, R) if ground else distance_to_top(r, mu, Rt)
        nq = ray_nodes(r, mu, d, n_q, ts, tq, w.wq)
        for k in range(nk):
            # the angle from the sun (acos nu) is the same at every node of the ray
            jts[k], jbs[k] = _split(math.acos(nus[k]) / math.pi * (n_tj - 1), n_tj)
        # nu nodes outside the ray's range of nu are clamped to its ends (cell_nu): such a
        # node repeats its neighbour (about 12 % of them at the default sizes) and is
        # copied instead of integrated again; the rest in the order nu outer, mu_s inner
        # (successive nodes share the angle from the sun and read nearby rows of J)
        n_u = 0
        for kn in range(nk):
            k = (kn % n_ms) * n_nu + kn // n_ms
            if k % n_nu == 0 or nus[k] != nus[k - 1]:
                ks[n_u] = k
                n_u += 1
        ray_weights(col, m, sc_idx, r, mu, ground, nq, 1.0, w)
        for q in range(nq):
            t = tq[q]
            rt = rts[q]
            mt = clamp_cos((r * mu + t) / rt)
            jr, ja = r_index(rt, n_rj, R, Rt)
            inv_rt = 1.0 / rt
            for iu in range(n_u):
                k = ks[iu]
                nu = nus[k]
                mu_s_t = clamp_cos((r * mus[k // n_nu] + t * nu) * inv_rt)
                ims_j, c = density_mu_s_index(mu_s_t, frame, n_msj)
                # J in the sun's frame: angle from the sun (acos nu) and azimuth about the
                # sun from its vertical plane (zenith side)
                jt = jts[k]
                jb = jbs[k]
                ip, e = density_phi_index(nu, mu_s_t, mt, n_pj)
                density_acc(J, tw[q], jt, jb, ip, e, jr, ja, ims_j, c, acc[k])
        for k in range(nk):
            if k % n_nu and nus[k] == nus[k - 1]:
                acc[k] = acc[k - 1]
            for l in range(nl):
                out[ir, imu, k // n_nu, k % n_nu, l] = acc[k, l]


@njit(cache=True)
def _nu_range(mu, mu_s):
    """(lo, hi): the range of nu of a ray of zenith cosine mu, the sun at mu_s (the clamp of
    :func:`._mapping.cell_nu`)."""
    s = math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))
    return mu * mu_s - s, mu * mu_s + s


@njit(parallel=True, cache=True, fastmath=True)
def table_from_coarse(coarse, mu_nodes, mu_cell, mu_frac, mu_s_nodes_sel, ms_cell, ms_frac, R,
                      Rt, mu_s_min, out):
    """out[r, mu, mu_s, nu, l]: the table ``coarse`` of :func:`multiple_scattering_table`
    (computed at the mu nodes ``mu_nodes`` and mu_s nodes ``mu_s_nodes_sel`` of ``out``'s
    axes and on fewer uniform nu nodes) interpolated at every node of ``out``: along mu and
    mu_s between the computed nodes that bracket each node (fine node i between coarse
    nodes mu_cell[i] and mu_cell[i] + 1 at fraction mu_frac[i], linear in the node index,
    i.e. in the mappings' unit coordinates; never across the horizon), and in nu at the
    same relative position in each corner's own range of nu (the same azimuth from the
    sun), piecewise linear through that corner's samples (its nodes clamped to the range
    as :func:`._mapping.cell_nu` clamps them). A node that was computed is returned as it
    is. (The caller passes the logarithms of the values and takes the exponential of the
    result, :func:`._precompute.stored_multiple_scattering`.)"""
    n_r, n_mu, n_ms, n_nu, nl = out.shape
    n_nuc = coarse.shape[3]
    mus = mu_s_nodes(n_ms, mu_s_min)
    for idx in prange(n_r * n_mu):
        ir = idx // n_mu
        imu = idx % n_mu
        r = cell_r(ir, n_r, R, Rt)
        mu = cell_mu(imu, n_mu, r, R, Rt)[0]
        acc = np.empty(nl)
        jm = mu_cell[imu]
        b = mu_frac[imu]
        mu_c0 = cell_mu(mu_nodes[jm], n_mu, r, R, Rt)[0]
        mu_c1 = cell_mu(mu_nodes[jm + 1], n_mu, r, R, Rt)[0]
        for ims in range(n_ms):
            js = ms_cell[ims]
            c = ms_frac[ims]
            lo, hi = _nu_range(mu, mus[ims])
            for inu in range(n_nu):
                nu = cell_nu(inu, n_nu, mu, mus[ims])
                sv = 0.5 if hi - lo < 1e-12 else (nu - lo) / (hi - lo)
                acc[:] = 0.0
                for dm in range(2):
                    wm = b if dm else 1.0 - b
                    mc = mu_c1 if dm else mu_c0
                    for ds in range(2):
                        ws = c if ds else 1.0 - c
                        w = wm * ws
                        if w == 0.0:
                            continue
                        lo_c, hi_c = _nu_range(mc, mus[mu_s_nodes_sel[js + ds]])
                        x = lo_c + sv * (hi_c - lo_c)
                        jn = min(max(int((x + 1.0) * 0.5 * (n_nuc - 1)), 0), n_nuc - 2)
                        p0 = max(-1.0 + 2.0 * jn / (n_nuc - 1.0), lo_c)
                        p1 = min(-1.0 + 2.0 * (jn + 1) / (n_nuc - 1.0), hi_c)
                        e = 0.0 if p1 <= p0 else min(max((x - p0) / (p1 - p0), 0.0), 1.0)
                        row0 = coarse[ir, jm + dm, js + ds, jn]
                        row1 = coarse[ir, jm + dm, js + ds, jn + 1]
                        for l in range(nl):
                            acc[l] += w * ((1.0 - e) * row0[l] + e * row1[l])
                o = out[ir, imu, ims, inu]
                for l in range(nl):
                    o[l] = acc[l]


@njit(parallel=True, cache=True, fastmath=True)
def multiple_scattering_slice(J, ms0, n_msj, m, sc_idx, col, mu_s_min, r, mu_s, n_q, ts,
                              mu_nodes, ground_nodes, cphi_nodes, reach, out, gx, gw):
    """Orders 2..N seen by an observer at radius r with the sun at mu_s, on a sky map of view
    directions: view zenith cosines ``mu_nodes`` (with ``ground_nodes``: does the ray end on
    the ground) x azimuths from the sun's with cosines ``cphi_nodes``:
    out[mu, phi, l] = int_0^d sum_k rho_k(r_t) J_k(r_t, mu_t, mu_s_t, nu) T(r, mu, t) dt
    ([BN08] eq. 8 with J summed over the orders), J as in :func:`multiple_scattering_table`.
    (The map's rows are dense at the horizon (:func:`map_nodes`), its azimuths uniform,
    see :func:`slice_index`: the table's own (mu, nu) mapping is coarse near the zenith and
    near the sun.)

    Integrating at the observer's own r and mu_s (instead of interpolating the 4-D table)
    keeps the multiply scattered aerosol aureole, which is sharp in the angle from the sun,
    out of the coarse mu_s interpolation: at AOD 0.5 that interpolation overestimated the
    zenith sky by 16 % with the sun at 60 deg.

    ``J`` may hold a part of the scattering density's mu_s axis: its rows ``ms0`` ..
    ``ms0 + J.shape[4] - 1`` of the ``n_msj`` of the whole table (all of them: 0 and
    J.shape[4]), e.g. the rows the observer's rays reach (:func:`._reach.density_mu_s_rows`;
    the values are those of the whole table, bit for bit). ``reach[mu]`` receives the
    first and one past the last mu_s row (of the whole table) that the rays of view zenith
    node mu read; a node whose rows J does not hold is not read (its ray's value is then
    wrong, and ``reach`` says so: the caller checks it).

    (gx, gw): empty, the transmittance from the observer to each node is the difference of
    two columns read from the column table ``col`` (:func:`._lookup.ray_weights`, as the
    shaders compute it); a Gauss-Legendre rule on [0, 1], the columns are integrated along
    each ray itself with it between consecutive nodes
    (:func:`._lookup.ray_weights_integrated`; the model's ``observer_columns``)."""
    n_mu, n_nu, nl = out.shape
    nc = col.shape[0]
    nsc, n_tj, n_pj, n_rj, n_held, _ = J.shape
    R = m.R
    Rt = m.Rt
    frame = mu_s_frame(mu_s_min)
    for imu in prange(n_mu):
        w = ray_scratch(n_q, nc, nsc, nl, np.empty((3 * n_q, nsc, nl)))
        tq = w.tq
        tw = w.tw
        rts = w.rts
        acc = np.zeros((n_nu, nl))
        nus = np.empty(n_nu)
        jts = np.empty(n_nu, dtype=np.int64)
        jbs = np.empty(n_nu)
        lo_read = n_msj
        hi_read = 0
        mu = mu_nodes[imu]
        ground = ground_nodes[imu]
        s_v = math.sqrt(max(1.0 - mu * mu, 0.0)) * math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
        d = distance_to_ground(r, mu, R) if ground else distance_to_top(r, mu, Rt)
        nq = ray_nodes(r, mu, d, n_q, ts, tq, w.wq)
        if gx.shape[0] > 0:
            ray_weights_integrated(m, sc_idx, r, mu, nq, 1.0, gx, gw, w)
        else:
            ray_weights(col, m, sc_idx, r, mu, ground, nq, 1.0, w)
        # the angle from the sun and its theta cell in J depend on the azimuth alone
        for inu in range(n_nu):
            nu = clamp_cos(mu * mu_s + s_v * cphi_nodes[inu])
            nus[inu] = nu
            jts[inu], jbs[inu] = _split(math.acos(nu) / math.pi * (n_tj - 1), n_tj)
        for q in range(nq):
            t = tq[q]
            rt = rts[q]
            mt = clamp_cos((r * mu + t) / rt)
            jr, ja = r_index(rt, n_rj, R, Rt)
            for inu in range(n_nu):
                nu = nus[inu]
                mu_s_t = clamp_cos((r * mu_s + t * nu) / rt)
                ims_j, c = density_mu_s_index(mu_s_t, frame, n_msj)
                lo_read = min(lo_read, ims_j)
                hi_read = max(hi_read, ims_j + 2)
                if ims_j < ms0 or ims_j + 2 > ms0 + n_held:
                    continue                    # rows not held: reported in reach
                jt = jts[inu]
                jb = jbs[inu]
                ip, e = density_phi_index(nu, mu_s_t, mt, n_pj)
                density_acc(J, tw[q], jt, jb, ip, e, jr, ja, ims_j - ms0, c, acc[inu])
        reach[imu, 0] = lo_read
        reach[imu, 1] = hi_read
        for inu in range(n_nu):
            for l in range(nl):
                out[imu, inu, l] = acc[inu, l]


def map_nodes(n_ground, n_sky, theta_h, a_ground, a_sky):
    """View zenith angles [rad] of the observer's sky map's rows: the ground's n_ground from
    the nadir to the horizon theta_h, then the sky's n_sky from the horizon to the zenith.
    Each part runs in x uniform over [0, 1] from the horizon (0) to its far end (1) through
    u(x) = a x + (1 - a) x^2 (a = a_ground, a_sky; a = 1 uniform in angle): the rows are
    a times the uniform spacing at the horizon, where the sky changes fastest (the limb seen
    from altitude, the first degree above the horizon in haze), and 2 - a times it at the
    far end. :func:`slice_index` inverts it."""
    xs = np.arange(n_sky) / (n_sky - 1.0)
    xg = 1.0 - np.arange(n_ground) / (n_ground - 1.0)      # the nadir first
    ug = a_ground * xg + (1.0 - a_ground) * xg * xg
    us = a_sky * xs + (1.0 - a_sky) * xs * xs
    return np.concatenate([theta_h + (math.pi - theta_h) * ug, theta_h * (1.0 - us)])


@njit(cache=True)
def map_unit_inverse(u, a):
    """x in [0, 1] with a x + (1 - a) x^2 = u, u clamped to [0, 1], 0 < a <= 1 (the root in
    the form without cancellation)."""
    u = min(max(u, 0.0), 1.0)
    if u <= 0.0:
        return 0.0
    return 2.0 * u / (a + math.sqrt(a * a + 4.0 * (1.0 - a) * u))


@njit(cache=True)
def slice_index(mu, cphi, ground, geom):
    """(node, fraction) on the view-zenith axis and on the azimuth axis of the observer's
    sky map of :func:`multiple_scattering_slice`. ``geom`` = (n_ground, n_sky, theta_h,
    single-scattering flag, a_ground, a_sky): nodes 0..n_ground-1 run from the nadir to
    the horizon (theta_h), nodes n_ground.. from the horizon to the zenith, each part
    dense at the horizon as :func:`map_nodes` lays them; azimuth from the sun's, n_phi
    nodes uniform over [0, pi]."""
    n_g = int(geom[0])
    n_s = int(geom[1])
    th_h = geom[2]
    th = math.acos(clamp_cos(mu))
    if ground:
        y = map_unit_inverse((th - th_h) / max(math.pi - th_h, 1e-12), geom[4])
        i, b = _split((1.0 - y) * (n_g - 1.0), n_g)
    else:
        x = map_unit_inverse((th_h - th) / th_h, geom[5])
        i, b = _split(x * (n_s - 1.0), n_s)
        i += n_g
    return i, b
