"""numba kernel of the ``kaneda1991`` model (private; imported lazily by the model).

Single scattering along view rays from an observer on the ground of a spherical earth.
Sample points are placed where the view ray crosses a set of spherical shells (the
altitudes are chosen by the model from the density profiles), each shell interval is
split further so that no piece is optically thicker than ``max_dtau``, and each piece is
integrated by Simpson's rule. Optical depths towards the sun come from the transport
engine's column table; the optional fog layer's light-path column is computed here
(closed form for a uniform layer, the Chapman function for an exponential one).
Lengths in metres, coefficients in m^-1.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.transport._geometry import distance_to_sphere_far, ray_hits_ground, safe_sqrt
from skydome.transport._medium import UNIFORM, profile_density
from skydome.transport._tables import lookup_column


@njit(cache=True)
def erfcx(y):
    """Scaled complementary error function exp(y^2) erfc(y) for y >= 0 (asymptotic
    series 1/(y sqrt(pi)) (1 - 1/(2y^2) + 3/(4y^4) - 15/(8y^6)) beyond y = 26, where the
    next term is below 1e-9 relative)."""
    if y < 26.0:
        return math.exp(y * y) * math.erfc(y)
    z = 1.0 / (y * y)
    return (1.0 - 0.5 * z + 0.75 * z * z - 1.875 * z * z * z) / (y * math.sqrt(math.pi))


@njit(cache=True)
def fog_column(code, hf, r, mu, R, Rt, n, ts):
    """Column of the fog (relative density x length) from (r, mu) to the top or ground:
    the chord of the layer for a uniform fog; for an exponential fog of scale height hf
    the Chapman-function column H exp(-h/H) Ch(r/H, mu) with
    Ch ~ sqrt(pi x/2) erfcx(sqrt(x/2) mu) (Huestis 2001 eq. 8; for mu < 0 through the
    lowest point of the ray), top of the atmosphere at infinity (relative error ~H/r)."""
    if code < 0:
        return 0.0
    if code == UNIFORM:
        Rf = R + hf
        if r <= Rf:
            return distance_to_sphere_far(r, mu, Rf)
        if mu >= 0.0:
            return 0.0
        disc = r * r * (mu * mu - 1.0) + Rf * Rf
        if disc <= 0.0:
            return 0.0
        return 2.0 * math.sqrt(disc)
    H = hf
    x = r / H
    up = math.sqrt(0.5 * math.pi * x) * erfcx(math.sqrt(0.5 * x) * abs(mu))
    if mu >= 0.0:
        return H * math.exp(-(r - R) / H) * up
    r_low = r * safe_sqrt(1.0 - mu * mu)
    x0 = r_low / H
    return H * (2.0 * math.sqrt(0.5 * math.pi * x0) * math.exp((R - r_low) / H)
                - math.exp(-(r - R) / H) * up)


@njit(cache=True)
def _light(table, nc_a, fog_code, fog_h, R, Rt, beta_e, r, mu_s, nl, out_tau):
    """Optical depth to the sun from (r, mu_s) per wavelength; False when in shadow."""
    if ray_hits_ground(r, mu_s, R):
        return False
    fcol = fog_column(fog_code, fog_h, r, mu_s, R, Rt, 0, 0.0)
    for l in range(nl):
        out_tau[l] = 0.0
    for c in range(nc_a):
        col = lookup_column(table, c, r, mu_s, R, Rt)
        for l in range(nl):
            out_tau[l] += beta_e[c, l] * col
    if fog_code >= 0:
        for l in range(nl):
            out_tau[l] += beta_e[nc_a, l] * fcol
    return True


@njit(cache=True)
def _dens(codes, p0s, p1s, h, rho):
    """rho[c] = relative density of every profile at altitude h [m] (the record's arrays
    passed one by one in the hot loop)."""
    for c in range(codes.shape[0]):
        rho[c] = profile_density(codes[c], p0s[c], p1s[c], h)


@njit(parallel=True, cache=True, fastmath=True)
def kaneda_rays(dirs, t_end, sun, m, shells, table, nc_a, fog_code, fog_h, max_dtau, max_sub, bmax,
                acc, trans):
    """For every ray i: ``acc[i, c, l]`` = integral over the view ray of rho_c(t)
    exp(-tau_view(t) - tau_sun(t)) dt [m] and ``trans[i, l]`` = exp(-tau_view(t_max)).

    dirs (n, 3) with dirs[i, 2] >= 0; t_end (n,) path length limit (inf: to the top);
    shells: ascending altitudes [m] from 0 to Rt - R; the medium m holds every constituent
    (the fog last when fog_code >= 0); table: column table of the first nc_a constituents;
    bmax (nc,): the largest extinction of each row [m^-1], which sizes the pieces (for a row
    that folds several constituents, the sum of theirs, so that folding leaves the pieces
    as they were).
    """
    R = m.R
    Rt = m.Rt
    beta_e = m.extinction
    codes = m.profile_code
    p0s = m.profile_p0
    p1s = m.profile_p1
    n = dirs.shape[0]
    nc = codes.shape[0]
    nl = beta_e.shape[1]
    ns = shells.shape[0]
    for i in prange(n):
        mu = dirs[i, 2]
        nu = dirs[i, 0] * sun[0] + dirs[i, 1] * sun[1] + dirs[i, 2] * sun[2]
        rho_a = np.empty(nc)
        rho_q = np.empty(nc)
        rho_m = np.empty(nc)
        rho_q3 = np.empty(nc)
        rho_b = np.empty(nc)
        col = np.zeros(nc)          # view column eye -> current point
        col_m = np.empty(nc)
        ts_a = np.empty(nl)
        ts_m = np.empty(nl)
        ts_b = np.empty(nl)
        g_a = np.zeros((nc, nl))    # integrand at the start of the piece
        lit_a = False
        for c in range(nc):
            for l in range(nl):
                acc[i, c, l] = 0.0
        t_top = distance_to_sphere_far(R, mu, Rt)
        t_max = min(t_top, t_end[i])
        # integrand at t = 0
        _dens(codes, p0s, p1s, 0.0, rho_a)
        lit_a = _light(table, nc_a, fog_code, fog_h, R, Rt, beta_e, R, sun[2], nl, ts_a)
        for c in range(nc):
            for l in range(nl):
                g_a[c, l] = rho_a[c] * math.exp(-ts_a[l]) if lit_a else 0.0
        t_a = 0.0
        for k in range(1, ns):
            if t_a >= t_max:
                break
            rk = R + shells[k]
            t_k = -R * mu + safe_sqrt(R * R * mu * mu + rk * rk - R * R)   # shell crossing
            if k == ns - 1:
                t_k = t_top
            t_k = min(t_k, t_max)
            if t_k <= t_a:
                continue
            # split the shell interval so that no piece is optically thicker than max_dtau
            hm = math.sqrt(R * R + 2.0 * R * mu * 0.5 * (t_a + t_k) + 0.25 * (t_a + t_k) ** 2) - R
            dtau = 0.0
            for c in range(nc):
                dtau += bmax[c] * max(profile_density(codes[c], p0s[c], p1s[c], hm), rho_a[c])
            dtau *= (t_k - t_a)
            n_pc = min(max(int(math.ceil(dtau / max_dtau)), 1), max_sub)
            h = (t_k - t_a) / n_pc
            for j in range(n_pc):
                ta = t_a + j * h
                tb = ta + h if j < n_pc - 1 else t_k
                hh = tb - ta
                tq = ta + 0.25 * hh
                tm = ta + 0.5 * hh
                tq3 = ta + 0.75 * hh
                rq = math.sqrt(R * R + 2.0 * R * mu * tq + tq * tq)
                rm = math.sqrt(R * R + 2.0 * R * mu * tm + tm * tm)
                rq3 = math.sqrt(R * R + 2.0 * R * mu * tq3 + tq3 * tq3)
                rb = math.sqrt(R * R + 2.0 * R * mu * tb + tb * tb)
                _dens(codes, p0s, p1s, rq - R, rho_q)
                _dens(codes, p0s, p1s, rm - R, rho_m)
                _dens(codes, p0s, p1s, rq3 - R, rho_q3)
                _dens(codes, p0s, p1s, rb - R, rho_b)
                # view columns at the midpoint and the end (Simpson on each half)
                for c in range(nc):
                    col_m[c] = col[c] + hh / 12.0 * (rho_a[c] + 4.0 * rho_q[c] + rho_m[c])
                    col[c] = col_m[c] + hh / 12.0 * (rho_m[c] + 4.0 * rho_q3[c] + rho_b[c])
                lit_m = _light(table, nc_a, fog_code, fog_h, R, Rt, beta_e, rm,
                               (R * sun[2] + tm * nu) / rm, nl, ts_m)
                lit_b = _light(table, nc_a, fog_code, fog_h, R, Rt, beta_e, rb,
                               (R * sun[2] + tb * nu) / rb, nl, ts_b)
                for l in range(nl):
                    sv_m = 0.0
                    sv_b = 0.0
                    for c in range(nc):
                        sv_m += beta_e[c, l] * col_m[c]
                        sv_b += beta_e[c, l] * col[c]
                    e_m = math.exp(-sv_m - ts_m[l]) if lit_m else 0.0
                    e_b = math.exp(-sv_b - ts_b[l]) if lit_b else 0.0
                    for c in range(nc):
                        g_m = rho_m[c] * e_m
                        g_b = rho_b[c] * e_b
                        acc[i, c, l] += hh / 6.0 * (g_a[c, l] + 4.0 * g_m + g_b)   # Simpson
                        g_a[c, l] = g_b
                for c in range(nc):
                    rho_a[c] = rho_b[c]
            t_a = t_k
            # early exit: beyond a view optical depth of 40 at every wavelength the rest of
            # the ray adds less than exp(-40) = 4e-18 of what came before
            s_min = 1e300
            for l in range(nl):
                s = 0.0
                for c in range(nc):
                    s += beta_e[c, l] * col[c]
                s_min = min(s_min, s)
            if s_min > 40.0:
                break
        for l in range(nl):
            s = 0.0
            for c in range(nc):
                s += beta_e[c, l] * col[c]
            trans[i, l] = math.exp(-s)


@njit(cache=True)
def sun_transmittance(m, mu_s, table, nc_a, fog_code, fog_h, out):
    """Transmittance from the ground towards the sun (0 when below the horizon)."""
    nl = m.extinction.shape[1]
    tau = np.empty(nl)
    if not _light(table, nc_a, fog_code, fog_h, m.R, m.Rt, m.extinction, m.R, mu_s, nl, tau):
        for l in range(nl):
            out[l] = 0.0
        return
    for l in range(nl):
        out[l] = math.exp(-tau[l])
