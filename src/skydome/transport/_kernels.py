"""numba kernels of the transport engine: plain floats and arrays, no options, no units.

Everything here is private. The public NumPy functions in :mod:`skydome.transport.optical_depth`
and :mod:`skydome.transport.single` validate and broadcast their inputs, then call these.
Lengths are in metres, coefficients in m^-1, angles as cosines.

Geometry: the planet is a sphere of radius ``R`` centred on the origin, the atmosphere
ends at the sphere of radius ``Rt``. A point is described by its distance ``r`` from the
centre and a ray by ``mu``, the cosine of the angle between the ray and the local vertical.

Quadrature: every integral along a ray uses the same rule. The ray is split at the point
of lowest altitude (where the density of every profile that decreases with altitude is
largest); each piece is integrated by the midpoint rule in the variable
``v = ln(1 + u / ts)``, where ``u`` is the distance from the dense end, so that the nodes
are spaced geometrically away from the dense end (``dt = (u + ts) dv``). (The rule is
second order in dv: a constant density over a path of length L has the relative error
(ln(1 + L/ts) / n)^2 / 24; the tests check convergence to the closed forms.) This resolves
the 1.2 km aerosol scale height looking up and the 100 km-scale horizon path with the
same few nodes.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.transport._geometry import (distance_to_sphere_far, lowest_point,  # noqa: F401
                                        radius_along_above, ray_hits_ground, ray_segment,
                                        safe_sqrt, shadow_crossings)
from skydome.transport._medium import (EXPONENTIAL, GAUSSIAN, TENT, UNIFORM,  # noqa: F401
                                      profile_density)
from skydome.transport._phase import (CORNETTE_SHANKS, HENYEY_GREENSTEIN, INV_4PI,  # noqa: F401
                                     ISOTROPIC, RAYLEIGH, phase_fill, phase_value)
from skydome.transport._quadrature import (column_quadrature, geometric_node,  # noqa: F401
                                          geometric_step, medium_columns, piece_nodes,
                                          simpson)
from skydome.transport._tables import lookup_column as table_lookup  # noqa: F401
from skydome.transport._tables import cell as table_cell
from skydome.transport._tables import lookup_columns, lookup_columns_cell
from skydome.transport._tables import r_mu_from_transmittance_unit as table_rmu
from skydome.transport._vexp import exp_neg_many
from skydome.transport._tables import transmittance_unit_from_r_mu as table_coords  # noqa: F401


@njit(cache=True, inline="always")
def profile_density_many(code, p0, p1, r, R, n, out, ibuf, fbuf):
    """out[i] = profile_density(code, p0, p1, r[i] - R) for i < n (radii r [m]); the
    exponential profile ([KRZ06] eq. 7) in one vectorised pass of
    :func:`skydome.transport._vexp.exp_neg_many` (ibuf, fbuf its scratch)."""
    if code == EXPONENTIAL:
        for i in range(n):
            out[i] = -max(r[i] - R, 0.0) / p0
        exp_neg_many(out, n, out, ibuf, fbuf)
        return
    for i in range(n):
        out[i] = profile_density(code, p0, p1, r[i] - R)


# -- column-density table (Bruneton 2017 transmittance parametrisation) --------------------------
@njit(parallel=True, cache=True)
def build_column_table(codes, p0s, p1s, R, Rt, n_r, n_mu, n, ts):
    """Column densities to the top of the atmosphere, shape (n_c, n_r, n_mu), on the grid
    x_r = i/(n_r-1), x_mu = j/(n_mu-1) (rays that do not hit the ground)."""
    nc = codes.shape[0]
    out = np.zeros((nc, n_r, n_mu))
    for idx in prange(n_r * n_mu):
        i = idx // n_mu
        j = idx % n_mu
        r, mu = table_rmu(i / (n_r - 1.0), j / (n_mu - 1.0), R, Rt)
        # no entry hits the ground; the last column grazes it: integrate through
        for c in range(nc):
            out[c, i, j] = column_quadrature(codes[c], p0s[c], p1s[c], r, mu, R, Rt, n, ts, False)
    return out


@njit(cache=True)
def light_columns(table, m, r, mu_s, light_exact, n_light, ts, out):
    """Fill ``out[c]`` with the column of every constituent of the medium m from (r, mu_s)
    towards the sun [m]; returns False when the sun is hidden by the planet (earth
    shadow: the light ray hits the ground)."""
    if ray_hits_ground(r, mu_s, m.R):
        return False
    if light_exact:
        medium_columns(m, r, mu_s, n_light, ts, True, out)
        return True
    lookup_columns(table, r, mu_s, m.R, m.Rt, out)
    return True


@njit(cache=True)
def _sort_small(brk, n):
    """Insertion sort of the first n entries of brk in place (the few break points)."""
    for q in range(1, n):
        x = brk[q]
        j = q - 1
        while j >= 0 and brk[j] > x:
            brk[j + 1] = brk[j]
            j -= 1
        brk[j + 1] = x


@njit(cache=True)
def view_break_points(r0, mu, sz, nu, R, t0, t1, brk):
    """Break points of the view ray in brk (sorted), and their count: its ends, its lowest
    point and where it crosses the boundary of the earth's shadow (the integrand jumps
    there); each piece gets its own nodes."""
    tmin = lowest_point(r0, mu, t0, t1)
    brk[0] = t0
    nbrk = 1
    if t0 < tmin < t1:
        brk[nbrk] = tmin
        nbrk += 1
    nsh, sh1, sh2 = shadow_crossings(r0, mu, sz, nu, R)
    if nsh > 0 and t0 < sh1 < t1:
        brk[nbrk] = sh1
        nbrk += 1
    if nsh > 1 and t0 < sh2 < t1:
        brk[nbrk] = sh2
        nbrk += 1
    brk[nbrk] = t1
    nbrk += 1
    _sort_small(brk, nbrk)
    return nbrk


class _SingleWork(NamedTuple):
    """Work arrays of one thread of :func:`single_scattering` (allocated once per block)."""

    acc: np.ndarray        # (nc, nl) integral of rho_c exp(-tau) along the ray
    tau: np.ndarray        # (nl,) -optical depth of the current node
    dcol: np.ndarray       # (nc,) view-ray column from the observer
    scol: np.ndarray       # (nc,) light-path column
    rho_prev: np.ndarray   # (nc,) densities at the previous node
    rho_mid: np.ndarray    # (nc,) ... at the midpoint
    rho: np.ndarray        # (nc,) ... at the node
    ebuf: np.ndarray       # (nl,) exp(tau)
    scat: np.ndarray       # (nc,) 1 where the constituent scatters
    brk: np.ndarray        # (6,) break points
    phs: np.ndarray        # (nl,) phase function per wavelength
    node_t: np.ndarray     # (n_view,) distances of the nodes of the current piece
    node_w: np.ndarray     # (n_view,) their weights
    node_r: np.ndarray     # (2 n_view,) radii of the nodes, then of the midpoints before them
    node_rho: np.ndarray   # (nc, 2 n_view) densities there
    node_mus: np.ndarray   # (n_view,) cosine of the sun's zenith angle at the nodes
    node_xr: np.ndarray    # (n_view,) their column-table coordinates (x_r, x_mu)
    node_xmu: np.ndarray
    xbits: np.ndarray      # (max(2 n_view, nl),) int64 scratch of the vectorised exps
    xbits_f: np.ndarray    # its float64 view


@njit(parallel=True, cache=True, fastmath=True)
def single_scattering(dirs, r0, sun, m, e_sun, table, n_view, ts, light_exact, n_light, out):
    """Single-scattered radiance arriving at an observer at distance r0 from the centre
    (on the +z axis) from each direction ``dirs[i]`` ([NSTN93] eqs. 1-3, [KRZ06] eqs. 15-16):

    L(lambda) = E_sun sum_c beta_s,c P_c(theta, lambda) int rho_c(t) exp(-tau(0,t) - tau_sun(t)) dt
                + ground term,

    in the medium m (:class:`skydome.transport._medium.Medium`), with the view-ray optical
    depth tau(0,t) accumulated by Simpson's rule between the quadrature nodes, tau_sun from
    the column table (or exact quadrature when ``light_exact``), zero sunlight where the
    light ray hits the planet (earth shadow), and, where the view ray hits the ground, the
    Lambertian reflection of the attenuated direct sun:
    albedo / pi E_sun T_sun cos(theta_s) T(0, t_ground).
    """
    n = dirs.shape[0]
    nc = m.profile_code.shape[0]
    nl = e_sun.shape[0]
    block = 64
    n_blocks = (n + block - 1) // block
    for ib in prange(n_blocks):
        _ray_block(ib * block, min(n, (ib + 1) * block), dirs, r0, sun, m, e_sun, table,
                   n_view, ts, light_exact, n_light, out)


@njit(cache=True, fastmath=True)
def _ray_block(i0, i1, dirs, r0, sun, m, e_sun, table, n_view, ts, light_exact, n_light, out):
    """Rays i0..i1-1 of :func:`single_scattering` with one set of work arrays (made here,
    in a serial function: writes into the arrays of a NamedTuple built directly in a
    prange body were lost under numba 0.68's parfor lowering)."""
    nc = m.profile_code.shape[0]
    nl = e_sun.shape[0]
    xbits = np.zeros(max(2 * n_view, nl), dtype=np.int64)
    w = _SingleWork(np.zeros((nc, nl)), np.zeros(nl), np.zeros(nc), np.zeros(nc),
                    np.zeros(nc), np.zeros(nc), np.zeros(nc), np.zeros(nl),
                    np.zeros(nc), np.zeros(6), np.zeros(nl),
                    np.zeros(n_view), np.zeros(n_view), np.zeros(2 * n_view),
                    np.zeros((nc, 2 * n_view)), np.zeros(n_view), np.zeros(n_view),
                    np.zeros(n_view), xbits, xbits.view(np.float64))
    for c in range(nc):
        for l in range(nl):
            if m.scattering[c, l] > 0.0:
                w.scat[c] = 1.0       # 1 for constituents that scatter (ozone only absorbs)
    for i in range(i0, i1):
        _single_ray(i, dirs, r0, sun, m, e_sun, table, n_view, ts, light_exact, n_light, out, w)


@njit(cache=True, fastmath=True, inline="always")
def _view_ray_integral(r0, mu, nu, sun, m, table, n_view, ts, light_exact, n_light, t0, t1,
                       nbrk, w):
    """Accumulate w.acc[c, l] = int rho_c(t) exp(-tau(0,t) - tau_sun(t)) dt over the pieces
    between the break points, and w.dcol the view column to t1; returns (t_prev, rho at
    t_prev already in w.rho_prev) as the distance of the last node."""
    w_acc = w.acc
    w_brk = w.brk
    w_dcol = w.dcol
    w_ebuf = w.ebuf
    w_rho = w.rho
    w_rho_mid = w.rho_mid
    w_rho_prev = w.rho_prev
    w_scat = w.scat
    w_scol = w.scol
    w_tau = w.tau
    w_node_t = w.node_t
    w_node_w = w.node_w
    w_node_r = w.node_r
    w_node_rho = w.node_rho
    w_xbits = w.xbits
    w_xbits_f = w.xbits_f
    w_node_mus = w.node_mus
    w_node_xr = w.node_xr
    w_node_xmu = w.node_xmu
    m_R = m.R
    m_Rt = m.Rt
    n_r = table.shape[1]
    n_mu = table.shape[2]
    m_extinction = m.extinction
    m_profile_code = m.profile_code
    m_profile_p0 = m.profile_p0
    m_profile_p1 = m.profile_p1
    nc = m_profile_code.shape[0]
    nl = w_tau.shape[0]
    R = m_R
    codes = m_profile_code
    p0s = m_profile_p0
    p1s = m_profile_p1
    beta_e = m_extinction
    tmin = lowest_point(r0, mu, t0, t1)
    t_prev = t0
    r_prev = math.sqrt(r0 * r0 + 2.0 * r0 * mu * t0 + t0 * t0)
    for c in range(nc):
        w_rho_prev[c] = profile_density(codes[c], p0s[c], p1s[c], r_prev - R)
    for q in range(nbrk - 1):
        a = w_brk[q]
        b = w_brk[q + 1]
        dense_at_b = b <= tmin      # before the lowest point the density grows with t
        if b - a <= 0.0:
            continue
        # the nodes of the piece in increasing t (piece_nodes, its expm1 in one vectorised
        # pass), with the radii at them and at the midpoints before them (Simpson's rule
        # for the view column), then the densities of every constituent at all of them at
        # once (exp_neg_many: one vectorised pass)
        piece_nodes(a, b, dense_at_b, n_view, ts, True, w_node_t, w_node_w, 0, True, w_xbits,
                    w_xbits_f)
        for kk in range(n_view):
            t = w_node_t[kk]
            tp = w_node_t[kk - 1] if kk > 0 else t_prev
            w_node_r[kk] = radius_along_above(r0, mu, t, R)
            w_node_r[n_view + kk] = radius_along_above(r0, mu, 0.5 * (tp + t), R)
        for c in range(nc):
            profile_density_many(codes[c], p0s[c], p1s[c], w_node_r, R, 2 * n_view,
                                 w_node_rho[c], w_xbits, w_xbits_f)
        # the sun's zenith cosine at the nodes and their column-table coordinates
        for kk in range(n_view):
            mu_s = (r0 * sun[2] + w_node_t[kk] * nu) / w_node_r[kk]
            w_node_mus[kk] = mu_s
            w_node_xr[kk], w_node_xmu[kk] = table_coords(w_node_r[kk], mu_s, R, m_Rt)
        for kk in range(n_view):
            t = w_node_t[kk]
            wt = w_node_w[kk]
            rr = w_node_r[kk]
            h = t - t_prev
            for c in range(nc):
                w_rho[c] = w_node_rho[c, kk]
                w_dcol[c] += simpson(w_rho_prev[c], w_node_rho[c, n_view + kk], w_rho[c], h)
                w_rho_prev[c] = w_rho[c]
            t_prev = t
            # the light path's columns (light_columns, with the table cell from the
            # coordinates above)
            mu_s = w_node_mus[kk]
            if ray_hits_ground(rr, mu_s, R):
                continue
            if light_exact:
                medium_columns(m, rr, mu_s, n_light, ts, True, w_scol)
            else:
                ci, fa = table_cell(w_node_xr[kk], n_r)
                cj, fb = table_cell(w_node_xmu[kk], n_mu)
                lookup_columns_cell(table, ci, cj, fa, fb, w_scol)
            for l in range(nl):
                w_tau[l] = 0.0
            for c in range(nc):
                col = w_dcol[c] + w_scol[c]
                for l in range(nl):
                    w_tau[l] -= beta_e[c, l] * col
            exp_neg_many(w_tau, nl, w_ebuf, w_xbits, w_xbits_f)
            for c in range(nc):
                wr = wt * w_rho[c] * w_scat[c]
                if wr > 0.0:
                    for l in range(nl):
                        w_acc[c, l] += wr * w_ebuf[l]
    return t_prev


@njit(cache=True, fastmath=True, inline="always")
def _ground_term(i, r0, mu, nu, sun, m, e_sun, table, light_exact, n_light, ts, t_prev, t1,
                 out, w):
    """Add the Lambertian reflection of the attenuated direct sun at the ground point t1,
    finishing the view optical depth exactly there."""
    w_dcol = w.dcol
    w_rho = w.rho
    w_rho_mid = w.rho_mid
    w_rho_prev = w.rho_prev
    w_scol = w.scol
    m_R = m.R
    m_albedo = m.albedo
    m_extinction = m.extinction
    m_profile_code = m.profile_code
    m_profile_p0 = m.profile_p0
    m_profile_p1 = m.profile_p1
    nc = m_profile_code.shape[0]
    nl = e_sun.shape[0]
    R = m_R
    t = t1
    tm = 0.5 * (t_prev + t)
    rm = radius_along_above(r0, mu, tm, R)
    h = t - t_prev
    for c in range(nc):
        w_rho[c] = profile_density(m_profile_code[c], m_profile_p0[c], m_profile_p1[c], 0.0)
        w_rho_mid[c] = profile_density(m_profile_code[c], m_profile_p0[c], m_profile_p1[c], rm - R)
        w_dcol[c] += simpson(w_rho_prev[c], w_rho_mid[c], w_rho[c], h)
    mu_s = (r0 * sun[2] + t * nu) / R
    if mu_s > 0.0:
        light_columns(table, m, R * (1.0 + 1e-12), mu_s, light_exact, n_light, ts, w_scol)
        w_tau = w.tau
        w_ebuf = w.ebuf
        for l in range(nl):
            s = 0.0
            for c in range(nc):
                s += m_extinction[c, l] * (w_dcol[c] + w_scol[c])
            w_tau[l] = -s
        exp_neg_many(w_tau, nl, w_ebuf, w.xbits, w.xbits_f)
        for l in range(nl):
            out[i, l] += m_albedo[l] / math.pi * e_sun[l] * mu_s * w_ebuf[l]


@njit(cache=True, fastmath=True, inline="always")
def _single_ray(i, dirs, r0, sun, m, e_sun, table, n_view, ts, light_exact, n_light, out, w):
    """One ray of :func:`single_scattering` (work arrays w passed in, reset here)."""
    w_acc = w.acc
    w_brk = w.brk
    w_dcol = w.dcol
    w_phs = w.phs
    m_R = m.R
    m_Rt = m.Rt
    m_profile_code = m.profile_code
    m_scattering = m.scattering
    nc = m_profile_code.shape[0]
    nl = e_sun.shape[0]
    mu = dirs[i, 2]
    nu = dirs[i, 0] * sun[0] + dirs[i, 1] * sun[1] + dirs[i, 2] * sun[2]   # cos of the scattering angle
    for l in range(nl):
        out[i, l] = 0.0
        for c in range(nc):
            w_acc[c, l] = 0.0
    for c in range(nc):
        w_dcol[c] = 0.0
    t0, t1, hits_ground = ray_segment(r0, mu, m_R, m_Rt)
    if t1 < t0 or (t1 == t0 and not hits_ground):
        return
    nbrk = view_break_points(r0, mu, sun[2], nu, m_R, t0, t1, w_brk)
    t_prev = _view_ray_integral(r0, mu, nu, sun, m, table, n_view, ts, light_exact, n_light,
                                t0, t1, nbrk, w)
    # phase functions and scattering coefficients
    for c in range(nc):
        if w.scat[c] == 0.0:
            continue                 # absorbs only: no scattering term
        phase_fill(m, c, nu, w_phs)
        for l in range(nl):
            out[i, l] += e_sun[l] * m_scattering[c, l] * w_phs[l] * w_acc[c, l]
    if hits_ground:
        _ground_term(i, r0, mu, nu, sun, m, e_sun, table, light_exact, n_light, ts, t_prev, t1,
                     out, w)


@njit(parallel=True, cache=True)
def transmittance_to_top(r, mu, table, m, light_exact, n_light, ts, out):
    """Transmittance from (r[i], mu[i]) to the top of the atmosphere of the medium m,
    (n, nl); 0 where the ray hits the ground."""
    nc = m.profile_code.shape[0]
    nl = m.extinction.shape[1]
    for i in prange(r.shape[0]):
        col = np.zeros(nc)
        if not light_columns(table, m, r[i], mu[i], light_exact, n_light, ts, col):
            for l in range(nl):
                out[i, l] = 0.0
            continue
        for l in range(nl):
            s = 0.0
            for c in range(nc):
                s += m.extinction[c, l] * col[c]
            out[i, l] = math.exp(-s)


@njit(parallel=True, cache=True)
def columns_quadrature(codes, p0s, p1s, r, mu, R, Rt, n, ts, out):
    """Column densities (n_rays, n_c) by quadrature for arrays of (r, mu)."""
    for i in prange(r.shape[0]):
        for c in range(codes.shape[0]):
            out[i, c] = column_quadrature(codes[c], p0s[c], p1s[c], r[i], mu[i], R, Rt, n, ts)
