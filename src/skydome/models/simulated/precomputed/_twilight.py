"""Single scattering at the observer's own r and mu_s for a sun below the horizon: the
observer's sky map of :func:`._multiple.multiple_scattering_slice`, each ray split where it
crosses the boundary of the earth's shadow.

In twilight the 4-D single-scattering table is the largest error of the sky: its rays share
their quadrature nodes between every (mu_s, nu) node, so they cannot be split at each sun
geometry's shadow boundary, where the integrand jumps; and the sky read from it is
interpolated in mu_s, while in twilight it falls about e-fold per degree of the sun's
depression (docs/models.md, "Twilight: single scattering at the observer"). Here every
ray of the map is integrated for the observer's own sun, piece by piece between its ends,
its lowest point and its shadow crossings ([BN08] eq. 4 without the phase function, as in
:func:`._single.single_scattering_table`).
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.models.simulated.precomputed._geometry import (clamp_cos, distance_to_ground,
                                                             distance_to_top, point_along)
from skydome.models.simulated.precomputed._lookup import (_optical_depth, columns_along,
                                                           columns_at, columns_segment,
                                                           sun_visible_fraction)
from skydome.transport._geometry import lowest_point
from skydome.transport._kernels import view_break_points
from skydome.transport._medium import profile_density
from skydome.transport._quadrature import piece_half, piece_nodes_rule
from skydome.transport._vexp import exp_neg_many

# Gauss-Legendre nodes per piece of a ray (ends, lowest point, shadow crossings) in
# v = ln(1 + u / ts), dense at the piece's end nearer the lowest point or the shadow
# boundary; convergence measured in docs/models.md ("Twilight: single scattering at the
# observer")
TWILIGHT_SS_NODES = 24


@njit(parallel=True, cache=True, fastmath=True)
def single_scattering_slice(col, m, sc_idx, beta_s, alpha, r, mu_s, ts, rx, rw, mu_nodes,
                            ground_nodes, cphi_nodes, out, gx, gw):
    """out[k, mu, phi, l] = beta_s,k(l) int_0^d rho_k(r_t) T(r, mu, t) T_sun(r_t, mu_s_t)
    v(r_t, mu_s_t) dt ([BN08] eq. 4 without the phase function; v the visible fraction of
    the sun's disc, :func:`._lookup.sun_visible_fraction`, alpha its angular radius) in the
    medium m (:class:`skydome.transport._medium.Medium`; its scattering constituents
    ``sc_idx``, beta_s,k = beta_s[k]) for an observer at radius r,
    the sun at zenith cosine mu_s, on the sky map of view zenith cosines ``mu_nodes``
    (``ground_nodes``: the ray ends on the ground) x azimuths from the sun's with cosines
    ``cphi_nodes``. Both transmittances from the column table ``col`` (exact exponent);
    the ray split at its lowest point and where it crosses the shadow's boundary
    (:func:`skydome.transport._kernels.view_break_points`), the rule (rx, rw) on [0, 1]
    (:func:`skydome.transport._quadrature.gauss_legendre_unit`) in v = ln(1 + u / ts) on
    every piece (:func:`skydome.transport._quadrature.piece_nodes_rule`).

    (gx, gw): empty, the view ray's transmittance from the observer to a node is the
    difference of two columns read from ``col`` (:func:`._lookup.columns_segment`); a
    Gauss-Legendre rule on [0, 1], its columns are integrated along the ray itself with it,
    from node to node in order of distance (:func:`._lookup.columns_along`; the model's
    ``observer_columns``). The sun's transmittance is read from ``col`` either way."""
    nsc, n_mu, n_phi, nl = out.shape
    nc = col.shape[0]
    integrated = gx.shape[0] > 0
    n_x = rx.shape[0]
    R, Rt = m.R, m.Rt
    max_pts = 10 * n_x              # at most 5 pieces, each on two halves
    for imu in prange(n_mu):
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        run = np.empty(nc)          # the integrated view columns from the observer
        csun = np.empty(nc)
        acc = np.empty((nsc, nl))
        brk = np.empty(6)
        tq = np.empty(n_x)
        tw = np.empty(n_x)
        cx = np.empty(nc)
        xs = np.empty(nl)
        es = np.empty(nl)
        ib = np.empty(nl, dtype=np.int64)
        fb = ib.view(np.float64)
        # the ray's nodes (distance, weight, radius, view columns, densities of the
        # scatterers): they depend on the ray's break points alone, which are the same at
        # every azimuth whose ray crosses no shadow boundary, so they are kept from one
        # azimuth to the next while its break points are (the same values, computed once)
        pt_t = np.empty(max_pts)
        pt_w = np.empty(max_pts)
        pt_r = np.empty(max_pts)
        pt_cv = np.empty((max_pts, nc))
        pt_dens = np.empty((max_pts, nsc))
        kept_brk = np.empty(6)
        n_kept_brk = -1
        n_pts = 0
        mu = mu_nodes[imu]
        ground = ground_nodes[imu]
        d = distance_to_ground(r, mu, R) if ground else distance_to_top(r, mu, Rt)
        s_v = math.sqrt(max(1.0 - mu * mu, 0.0)) * math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
        tmin = lowest_point(r, mu, 0.0, d)
        for iphi in range(n_phi):
            nu = clamp_cos(mu * mu_s + s_v * cphi_nodes[iphi])
            acc[:] = 0.0
            nbrk = view_break_points(r, mu, mu_s, nu, R, 0.0, d, brk)
            same = nbrk == n_kept_brk
            if same:
                for q in range(nbrk):
                    if brk[q] != kept_brk[q]:
                        same = False
                        break
            if not same:
                n_kept_brk = nbrk
                for q in range(nbrk):
                    kept_brk[q] = brk[q]
                n_pts = 0
                run[:] = 0.0
                t_run = 0.0
                for q in range(nbrk - 1):
                    a = brk[q]
                    b = brk[q + 1]
                    if b - a <= 0.0:
                        continue
                    # the piece from the observer down to the lowest point on two halves,
                    # each dense at its own end (transport._quadrature.piece_half)
                    split = b <= tmin and a == 0.0
                    for half in range(2 if split else 1):
                        ha, hb, hd = piece_half(a, b, b <= tmin, split, half)
                        piece_nodes_rule(ha, hb, hd, rx, rw, ts, tq, tw, 0)
                        # the nodes in order of distance (the rule lays them from its
                        # dense end)
                        rev = tq[0] > tq[n_x - 1]
                        for kk_ in range(n_x):
                            k = n_x - 1 - kk_ if rev else kk_
                            t = tq[k]
                            if integrated:
                                columns_along(m, r, mu, t_run, t, gx, gw, run)
                                t_run = max(t_run, t)
                            rt = point_along(r, mu, t, R, Rt)
                            pt_t[n_pts] = t
                            pt_w[n_pts] = tw[k]
                            pt_r[n_pts] = rt
                            if integrated:
                                pt_cv[n_pts, :] = run
                            else:
                                columns_segment(col, r, mu, t, ground, R, Rt, w1, w2,
                                                pt_cv[n_pts])
                            for kk in range(nsc):
                                c = sc_idx[kk]
                                pt_dens[n_pts, kk] = profile_density(
                                    m.profile_code[c], m.profile_p0[c], m.profile_p1[c],
                                    rt - R)
                            n_pts += 1
            for p in range(n_pts):
                t = pt_t[p]
                rt = pt_r[p]
                mu_s_t = clamp_cos((r * mu_s + t * nu) / rt)
                vis = sun_visible_fraction(rt, mu_s_t, R, alpha)
                if vis <= 0.0:
                    continue
                columns_at(col, rt, mu_s_t, R, Rt, csun)
                # exp(-tau) of every wavelength in one vectorised pass (the core's
                # exp_neg_many: within a few units in the last place of libm's)
                for c in range(nc):
                    cx[c] = pt_cv[p, c] + csun[c]
                for l in range(nl):
                    xs[l] = -_optical_depth(m.extinction, cx, l)
                exp_neg_many(xs, nl, es, ib, fb)
                g = pt_w[p] * vis
                for kk in range(nsc):
                    dk = pt_dens[p, kk]
                    for l in range(nl):
                        acc[kk, l] += dk * (g * es[l])
            for kk in range(nsc):
                for l in range(nl):
                    out[kk, imu, iphi, l] = beta_s[kk, l] * acc[kk, l]
