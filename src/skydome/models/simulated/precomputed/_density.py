"""The scattering density J ([Bru17] ComputeScatteringDensity, [BN08] eq. 7): the radiance of
the previous order arriving at each node (with one more ground reflection) and the phase
matrix of the quadrature over the sphere. The previous order is read from the 4-D table
(:func:`._lookup.sky_lookup_acc`: mu on :func:`._mapping.mu_unit`).
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.models.simulated.precomputed._geometry import clamp_cos, distance_to_ground, hits_ground
from skydome.models.simulated.precomputed._irradiance import direct_irradiance_acc
from skydome.models.simulated.precomputed._lookup import (_quad_acc, columns_segment,
                                                           irradiance_lookup_acc)
from skydome.models.simulated.precomputed._mapping import (_split, cell_r, mu_frame,
                                                            mu_index_framed, mu_s_frame,
                                                            mu_s_from_unit, mu_s_unit_framed,
                                                            r_index)
from skydome.models.simulated.precomputed._multiple import ray_integral, ray_scratch
from skydome.transport._kernels import phase_value
from skydome.transport._phase import phase_coded, phase_fill_coded

INV_PI = 1.0 / math.pi



@njit(cache=True)
def _on_node(cell, n):
    """A cell and fraction (i, f) within 1e-9 of a node snapped onto it (fraction 0): the
    density's (r, mu_s) nodes lie on the single-scattering table's when the grids are the
    same (the defaults), and the lookups then read 4 corners instead of 16 (the value
    changes by <= 1e-9 of the difference of two nodes)."""
    i, f = cell
    if f < 1e-9:
        return i, 0.0
    if f > 1.0 - 1e-9:
        return (i + 1, 0.0) if i + 1 < n - 1 else (i, 1.0)
    return i, f


@njit(cache=True)
def density_node(ir, ims, n_r, n_ms, R, Rt, mu_s_min):
    """(r, mu_s, sin theta_s) of the scattering density's node (ir, ims)."""
    r = cell_r(ir, n_r, R, Rt)
    mu_s = mu_s_from_unit(ims / (n_ms - 1.0), mu_s_min)
    return r, mu_s, math.sqrt(max(1.0 - mu_s * mu_s, 0.0))


@njit(cache=True)
def incident_direction(th, ph, r, mu_s, sin_s, R):
    """(nu, mu, hits_ground) of the incident direction at angle th from the sun and azimuth
    ph about it (from the sun's vertical plane, zenith side), at radius r with the sun at
    mu_s."""
    nu = math.cos(th)
    mu = clamp_cos(nu * mu_s + math.sin(th) * math.cos(ph) * sin_s)
    return nu, mu, hits_ground(r, mu, R)


@njit(cache=True, fastmath=True)
def ground_reflected_acc(first, dE, col, beta_e, albedo, R, Rt, mu_s_min, alpha, r, ct, mu_s, nu, w1,
                         w2, cs, tg, eg, out):
    """out[l] += radiance reflected by the (Lambertian) ground towards r along the ray of
    zenith cosine ct (which hits the ground) and sun cosine nu, the sun at mu_s: transmittance
    to the ground x albedo / pi x the ground irradiance of the previous order (``first``: the
    direct sun's, else the table ``dE``) ([Bru17] ComputeScatteringDensity, ground term)."""
    nl = out.shape[0]
    nc = col.shape[0]
    dg = distance_to_ground(r, ct, R)
    columns_segment(col, r, ct, dg, True, R, Rt, w1, w2, cs)
    for l in range(nl):
        s = 0.0
        for c in range(nc):
            s += beta_e[c, l] * cs[c]
        tg[l] = math.exp(-s) * albedo[l] * INV_PI
    mu_g = clamp_cos((r * mu_s + dg * nu) / R)
    eg[:] = 0.0
    if first:
        direct_irradiance_acc(col, beta_e, R, mu_g, R, Rt, alpha, 1.0, cs, eg)
    else:
        irradiance_lookup_acc(dE, R, mu_g, R, Rt, mu_s_min, 1.0, eg)
    for l in range(nl):
        out[l] += tg[l] * eg[l]


@njit(parallel=True, cache=True, fastmath=True)
def incident_radiance(ss, pc, pp, pt, col, beta_e, albedo, R, Rt, mu_s_min, alpha, n_r, n_ms,
                      th_in, ph_in, out):
    """Single scattering arriving at each (r, mu_s) node of the scattering density from the
    incident directions (looked up in the single-scattering table ``ss``), plus the direct
    sun's light reflected by the ground: the source of order 2 ([Bru17]
    ComputeScatteringDensity, inner loop; orders >= 3: :func:`incident_radiance_rays`):
    out[i, r, mu_s, l] (the incident direction first: the right-hand side of the matrix
    product that gives J).

    The incident directions are given in the sun's frame: th_in the angle from the sun
    (so nu = cos th_in), ph_in the azimuth about the sun measured from the sun's vertical
    plane, on the zenith side (so that mu = cos th mu_s + sin th cos ph sin theta_s). The
    aerosol aureole (the forward peak of the previous order) is then resolved along one
    axis of the grid, at every sun elevation alike.

    The quadrilinear lookup of :func:`._lookup.sky_lookup_acc` with its fixed parts
    hoisted: the phase functions and the nu cell depend on th_in alone (once per kernel),
    the r and mu_s cells and the mu mapping's constants on the node alone (once per node);
    per direction, the 16 corners (:func:`._lookup._quad_acc`) are summed per constituent in
    float64 and multiplied by the phase function once (the result equals the lookup's to float32 rounding)."""
    n_th = th_in.shape[0]
    n_ph = ph_in.shape[0]
    nl = out.shape[3]
    nc = col.shape[0]
    nsc = ss.shape[0]
    n_rt, n_mu, n_mst, n_nu = ss.shape[1], ss.shape[2], ss.shape[3], ss.shape[4]
    # per angle from the sun: phase functions [a, k, l] and nu cell
    pw = np.empty((n_th, nsc, nl))
    inus = np.empty(n_th, dtype=np.int64)
    es = np.empty(n_th)
    for a in range(n_th):
        nu = math.cos(th_in[a])
        for k in range(nsc):
            phase_fill_coded(pc, pp, pt, k, nu, pw[a, k])
        inus[a], es[a] = _split((nu + 1.0) * 0.5 * (n_nu - 1), n_nu)
    frame_s = mu_s_frame(mu_s_min)
    for idx in prange(n_r * n_ms):
        ir = idx // n_ms
        ims = idx % n_ms
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        cs = np.empty(nc)
        tg = np.empty(nl)
        eg = np.empty(nl)
        acc = np.empty(nl)
        ones = np.ones(nl)
        r, mu_s, sin_s = density_node(ir, ims, n_r, n_ms, R, Rt, mu_s_min)
        jr, fa = _on_node(r_index(r, n_rt, R, Rt), n_rt)
        js, fc = _on_node(_split(mu_s_unit_framed(mu_s, frame_s) * (n_mst - 1), n_mst), n_mst)
        frame = mu_frame(r, R)
        for a in range(n_th):
            inu = inus[a]
            fe = es[a]
            for b in range(n_ph):
                i = a * n_ph + b
                nu, ct, ground = incident_direction(th_in[a], ph_in[b], r, mu_s, sin_s, R)
                jm, fb = mu_index_framed(ct, ground, n_mu, frame)
                o = out[i, ir, ims]
                o[:] = 0.0
                for k in range(nsc):
                    acc[:] = 0.0
                    _quad_acc(ss[k], jr, fa, jm, fb, js, fc, inu, fe, 1.0, ones, acc)
                    pk = pw[a, k]
                    for l in range(nl):
                        o[l] += pk[l] * acc[l]
                if ground:
                    # the direct sun's irradiance (eg is its unused irradiance table)
                    ground_reflected_acc(True, eg.reshape(1, 1, -1), col, beta_e, albedo, R, Rt,
                                         mu_s_min, alpha, r, ct, mu_s, nu, w1, w2, cs, tg, eg, o)


@njit(parallel=True, cache=True, fastmath=True)
def incident_radiance_rays(J, dE, m, sc_idx, col, mu_s_min, rx, rw, ts, n_r, n_ms, th_in, ph_in,
                           out):
    """Radiance of the previous order arriving at each (r, mu_s) node of the scattering
    density from the incident directions, as :func:`incident_radiance` for orders >= 3 but
    integrated along each incident ray from the previous order's scattering density ``J``
    ([BN08] eq. 8, :func:`._multiple.ray_integral`: the quadrature and exact density
    profiles of :func:`._multiple.multiple_scattering_table`) instead of interpolated from
    a 4-D table of that order, plus the light the ground reflects once more (irradiance
    table ``dE`` of the order before), in the medium m
    (:class:`skydome.transport._medium.Medium`: its extinction and ground albedo on J's
    wavelengths, its scattering constituents sc_idx, its column table ``col``); the
    quadrature rule (rx, rw) in v per piece of each
    ray (:func:`skydome.transport._quadrature.ray_nodes_rule`). out[i, r, mu_s, l]
    (float32), directions as in :func:`incident_radiance`. One work item per (theta, r, mu_s),
    theta outermost (no per-ray allocation); the sums in float32."""
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
    # work items ordered by the angle from the sun first: every ray of one theta reads
    # J's two theta slabs only (the angle from the sun is constant along a ray), which
    # then stay in cache over all the (r, mu_s) nodes of that theta
    # ... and the thetas in the order 0, 2, 4, ..., 1, 3, 5, ...: the threads' static
    # shares of the loop (halves with 2 threads) then both hold small and large angles
    # from the sun (the second half of the angles cost 15 % more than the first)
    h = n_th // 2
    for idx in prange(n_th * n_nodes):
        k = idx // n_nodes
        a = 2 * (k % h) + k // h if k < 2 * h else k
        ir = (idx % n_nodes) // n_ms
        ims = idx % n_ms
        # float32 weights and sums (the precision of J and of the output; 20-40 positive
        # terms per value): the wavelength loops of density_acc vectorise 8-wide
        w = ray_scratch(rx.size, nc, nsc, nl,
                        np.empty((2 * rx.size, nsc, nl), dtype=np.float32))
        acc = np.empty(nl, dtype=np.float32)
        tg = np.empty(nl)
        eg = np.empty(nl)
        r, mu_s, sin_s = density_node(ir, ims, n_r, n_ms, R, Rt, mu_s_min)
        for b in range(n_ph):
            nu, ct, ground = incident_direction(th_in[a], ph_in[b], r, mu_s, sin_s, R)
            acc[:] = 0.0
            ray_integral(J, m, sc_idx, col, frame, r, ct, mu_s, nu, ground, rx, rw, ts, w, acc)
            if ground:
                ground_reflected_acc(False, dE, col, beta_e, albedo, R, Rt, mu_s_min, 0.0, r, ct,
                                     mu_s, nu, w.w1, w.w2, w.cs[0], tg, eg, acc)
            o = out[a * n_ph + b, ir, ims]
            for l in range(nl):
                o[l] = acc[l]


@njit(parallel=True, cache=True)
def phase_matrix(codes, params, table, k, l, th_out, ph_out, th_in, ph_in, d_omega, out):
    """out[o, i] = dOmega_i (P(w_o . w_i) + P(w_o . w_i')), P the phase function of
    constituent k of (codes, params, table) at wavelength index l
    (:func:`skydome.transport._phase.phase_coded`; l matters only for a tabulated phase),
    with w_i' the mirror image of w_i
    in the sun's vertical plane (the incident field is symmetric about it), so that
    J(w_o) = sum_i out[o, i] L(w_i) is [Bru17] ComputeScatteringDensity's quadrature over the
    sphere ([BN08] eq. 7) evaluated on a fixed grid of outgoing directions."""
    n_to = th_out.shape[0]
    n_po = ph_out.shape[0]
    n_ti = th_in.shape[0]
    n_pi = ph_in.shape[0]
    for o in prange(n_to * n_po):
        ct_o = math.cos(th_out[o // n_po])
        st_o = math.sin(th_out[o // n_po])
        cp_o = math.cos(ph_out[o % n_po])
        sp_o = math.sin(ph_out[o % n_po])
        for a in range(n_ti):
            ct = math.cos(th_in[a])
            st = math.sin(th_in[a])
            for b in range(n_pi):
                cp = math.cos(ph_in[b])
                sp = math.sin(ph_in[b])
                c1 = clamp_cos(st_o * st * (cp_o * cp + sp_o * sp) + ct_o * ct)
                c2 = clamp_cos(st_o * st * (cp_o * cp - sp_o * sp) + ct_o * ct)
                out[o, a * n_pi + b] = d_omega[a] * (phase_coded(codes, params, table, k, l, c1)
                                                     + phase_coded(codes, params, table, k, l, c2))


def quadratic_phase_factors(code, param, th_out, ph_out, th_in, ph_in, d_omega, P):
    """(left, right) with left @ right == P (the phase matrix of
    :func:`phase_matrix`) when the phase function is a polynomial of
    degree <= 2 in the cosine (Rayleigh, isotropic); None otherwise.

    P[o, i] = dOmega_i (p(o.w_i) + p(o.w_i')), w_i' the mirror image of w_i (y -> -y), and
    p(c) = a0 + a1 c + a2 c^2 with (o.w)^2 = sum_m o_m^2 w_m^2 + 2 sum_{m<n} o_m o_n w_m w_n."""
    if code not in (0, 3):
        return None
    fm, f0, fp = (phase_value(code, param, c) for c in (-1.0, 0.0, 1.0))
    a0, a1, a2 = f0, 0.5 * (fp - fm), 0.5 * (fp + fm) - f0

    def unit(th, ph):
        T, F = np.meshgrid(th, ph, indexing="ij")
        return np.stack([np.sin(T) * np.cos(F), np.sin(T) * np.sin(F), np.cos(T)], -1).reshape(-1, 3)

    o = unit(th_out, ph_out)
    w = unit(th_in, ph_in)
    ox, oy, oz = o.T
    left = np.stack([np.ones_like(ox), ox, oy, oz, ox * ox, oy * oy, oz * oz, ox * oy, ox * oz,
                     oy * oz], axis=1)

    def feats(x, y, z):
        return np.stack([np.full_like(x, a0), a1 * x, a1 * y, a1 * z, a2 * x * x, a2 * y * y,
                         a2 * z * z, 2 * a2 * x * y, 2 * a2 * x * z, 2 * a2 * y * z])

    wx, wy, wz = w.T
    right = (feats(wx, wy, wz) + feats(wx, -wy, wz)) * np.repeat(d_omega, ph_in.size)[None, :]
    if np.abs(left @ right - P).max() > 1e-9 * np.abs(P).max():
        return None
    return left, right


@njit(parallel=True, cache=True)
def azimuth_modes(codes, params, table, k, l, th_out, th_in, d_omega, n_ph, shift, out):
    """The phase matrix of :func:`phase_matrix` in the azimuthal Fourier basis:
    out[n, o, a] = dOmega_a sum_{d=0}^{2 N - 1} P(cos th_o cos th_a + sin th_o sin th_a
    cos psi_d) cos(n psi_d), psi_d = (d + shift) pi / N, N = ``n_ph`` incident azimuths on
    [0, pi], n = 0 .. out.shape[0] - 1 (P the phase function of constituent k at wavelength
    index l, as in :func:`phase_matrix`).

    The incident azimuths (b + 1/2) pi / N, mirrored onto (pi, 2 pi), are a cyclic group of
    2 N; where an outgoing azimuth minus every incident one runs over the same 2 N angles
    psi_d (shift 1/2: the outgoing azimuth a multiple of pi / N; shift 0: an odd multiple of
    pi / (2 N)), the sum over incident azimuths is a cyclic convolution, diagonal in the
    discrete cosine modes cos(n phi) of the (mirror-symmetric) incident field: J(th_o, ph_o)
    = sum_n cos(n ph_o) sum_a out[n, o, a] c_n(a), c_n the incident radiance's cosine
    coefficients (docs/models.md, "precomputed", "The scattering density's azimuthal
    modes")."""
    n_m = out.shape[0]
    n_to = th_out.shape[0]
    n_ti = th_in.shape[0]
    n_d = 2 * n_ph
    cos_nd = np.empty((n_m, n_d))
    for n in range(n_m):
        for d in range(n_d):
            cos_nd[n, d] = math.cos(n * (d + shift) * math.pi / n_ph)
    for idx in prange(n_to * n_ti):
        o = idx // n_ti
        a = idx % n_ti
        cc = math.cos(th_out[o]) * math.cos(th_in[a])
        ss = math.sin(th_out[o]) * math.sin(th_in[a])
        h = np.empty(n_d)
        for d in range(n_d):
            h[d] = phase_coded(codes, params, table, k, l,
                               clamp_cos(cc + ss * math.cos((d + shift) * math.pi / n_ph)))
        for n in range(n_m):
            s = 0.0
            for d in range(n_d):
                s += h[d] * cos_nd[n, d]
            out[n, o, a] = d_omega[a] * s
