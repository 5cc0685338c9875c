"""numba kernels of the ``precomputed`` model (Bruneton 2017 tables, spectral, on the CPU).

Private: plain floats and arrays, no options, no units. Lengths in metres, angles as
cosines, every radiance and irradiance *per unit extraterrestrial solar irradiance*
(multiply by E_sun(lambda) [W m^-2 nm^-1] to get W m^-2 sr^-1 nm^-1 or W m^-2 nm^-1).

Notation ([Bru17] = E. Bruneton, "Precomputed Atmospheric Scattering: a New
Implementation", 2017, atmosphere/functions.glsl, which derives every formula used here;
[BN08] = Bruneton & Neyret 2008, EGSR): R the ground radius, Rt the top radius,
H = sqrt(Rt^2 - R^2) the distance to the top along the horizon from the ground, r the
distance of a point from the planet's centre, rho = sqrt(r^2 - R^2) the distance to the
horizon, mu the cosine of the view ray's zenith angle (the ray points to where the light
comes from), mu_s the cosine of the sun's zenith angle, nu the cosine of the angle between
view ray and sun.

4-D tables are indexed [r, mu, mu_s, nu, lambda] with Bruneton's texel-centre mappings
(GetScatteringTextureUvwzFromRMuMuSNu): the node i of an axis of size n sits at the
unit-range coordinate x = i / (n - 1):

* r:    x_r = rho / H;
* mu:   the first half of the axis holds rays that hit the ground (node 0 = horizon,
        node n/2-1 = nadir), x = (d - d_min) / (d_max - d_min) with d the distance to the
        ground, d_min = r - R, d_max = rho; the second half rays that do not (node n/2 =
        zenith, node n-1 = horizon), d the distance to the top, d_min = Rt - r,
        d_max = rho + H. Interpolation never mixes the two halves (Bruneton's texture
        filtering does, a known horizon artefact, issue #26 / PR #32 of his repository);
* mu_s: x = max(1 - a / A, 0) / (1 + a), a = (d - d_min) / (d_max - d_min) with d the
        distance to the top from the ground towards the sun, d_min = Rt - R, d_max = H, and
        A the value of a at mu_s_min;
* nu:   x = (nu + 1) / 2 (nodes clamped to the range allowed by mu and mu_s).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skydome.transport._kernels import (exp_neg_array, phase_value, profile_density,
                                       table_coords)

INV_PI = 1.0 / math.pi


# -- geometry ([Bru17] "Distance to the top/bottom atmosphere boundary") --------------------------
@njit(cache=True)
def clamp_cos(x):
    return min(max(x, -1.0), 1.0)


@njit(cache=True)
def distance_to_top(r, mu, Rt):
    """Distance from (r, mu) to the top of the atmosphere along the ray [m] (r <= Rt)."""
    disc = r * r * (mu * mu - 1.0) + Rt * Rt
    return max(-r * mu + math.sqrt(max(disc, 0.0)), 0.0)


@njit(cache=True)
def distance_to_ground(r, mu, R):
    """Distance from (r, mu) to the ground along the ray [m] (valid where it hits)."""
    disc = r * r * (mu * mu - 1.0) + R * R
    return max(-r * mu - math.sqrt(max(disc, 0.0)), 0.0)


@njit(cache=True)
def hits_ground(r, mu, R):
    """[Bru17] RayIntersectsGround."""
    return mu < 0.0 and r * r * (mu * mu - 1.0) + R * R >= 0.0


@njit(cache=True)
def point_along(r, mu, t, R, Rt):
    """Radius of the point at distance t along the ray (law of cosines), clamped to the shell."""
    rt = math.sqrt(max(t * t + 2.0 * r * mu * t + r * r, 0.0))
    return min(max(rt, R), Rt)


# -- columns and transmittance --------------------------------------------------------------------
@njit(cache=True)
def columns_at(col, r, mu, R, Rt, out):
    """Column density of every constituent from (r, mu) to the top [m], bilinear in the
    (n_c, n_r, n_mu) table of :func:`skydome.transport._kernels.build_column_table`."""
    n_r = col.shape[1]
    n_mu = col.shape[2]
    x_r, x_mu = table_coords(r, mu, R, Rt)
    fr = x_r * (n_r - 1)
    fm = x_mu * (n_mu - 1)
    i = min(int(fr), n_r - 2)
    j = min(int(fm), n_mu - 2)
    a = fr - i
    b = fm - j
    for c in range(col.shape[0]):
        out[c] = ((1.0 - a) * ((1.0 - b) * col[c, i, j] + b * col[c, i, j + 1])
                  + a * ((1.0 - b) * col[c, i + 1, j] + b * col[c, i + 1, j + 1]))


@njit(cache=True)
def transmittance_at(trans, r, mu, R, Rt, w, out):
    """out[l] = w x transmittance from (r, mu) to the top, bilinear in the per-wavelength
    table trans[r, mu, l] (Bruneton's transmittance texture, same mapping as the columns)."""
    n_r = trans.shape[0]
    n_mu = trans.shape[1]
    x_r, x_mu = table_coords(r, mu, R, Rt)
    fr = x_r * (n_r - 1)
    fm = x_mu * (n_mu - 1)
    i = min(int(fr), n_r - 2)
    j = min(int(fm), n_mu - 2)
    a = fr - i
    b = fm - j
    w00 = w * (1.0 - a) * (1.0 - b)
    w01 = w * (1.0 - a) * b
    w10 = w * a * (1.0 - b)
    w11 = w * a * b
    for l in range(out.shape[0]):
        out[l] = (w00 * trans[i, j, l] + w01 * trans[i, j + 1, l]
                  + w10 * trans[i + 1, j, l] + w11 * trans[i + 1, j + 1, l])


@njit(cache=True)
def columns_segment(col, r, mu, d, ground, R, Rt, w1, w2, out):
    """Columns between (r, mu) and the point at distance d along the ray ([Bru17]
    GetTransmittance): differences of columns to the top; for rays that hit the ground
    both rays are reversed so that neither does."""
    rd = point_along(r, mu, d, R, Rt)
    mud = clamp_cos((r * mu + d) / rd)
    if ground:
        columns_at(col, rd, -mud, R, Rt, w1)
        columns_at(col, r, -mu, R, Rt, w2)
    else:
        columns_at(col, r, mu, R, Rt, w1)
        columns_at(col, rd, mud, R, Rt, w2)
    for c in range(out.shape[0]):
        out[c] = max(w1[c] - w2[c], 0.0)


@njit(cache=True)
def sun_visible_fraction(r, mu_s, R, alpha):
    """Fraction of the sun's disc (angular radius alpha [rad]) above the horizon seen
    from radius r ([Bru17] GetTransmittanceToSun, smoothstep over the disc)."""
    sin_h = R / r
    cos_h = -math.sqrt(max(1.0 - sin_h * sin_h, 0.0))
    e = sin_h * alpha
    x = (mu_s - cos_h + e) / (2.0 * e)
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    return x * x * (3.0 - 2.0 * x)


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


# -- table mappings -------------------------------------------------------------------------------
@njit(cache=True)
def mu_s_unit(mu_s, R, Rt, mu_s_min):
    """[Bru17] mu_s mapping to [0, 1] (0 at mu_s_min, 1 at the zenith)."""
    H = math.sqrt(Rt * Rt - R * R)
    d_min = Rt - R
    d_max = H
    a = (distance_to_top(R, mu_s, Rt) - d_min) / (d_max - d_min)
    A = (distance_to_top(R, mu_s_min, Rt) - d_min) / (d_max - d_min)
    return max(1.0 - a / A, 0.0) / (1.0 + a)


@njit(cache=True)
def mu_s_from_unit(x, R, Rt, mu_s_min):
    """Inverse of :func:`mu_s_unit`."""
    H = math.sqrt(Rt * Rt - R * R)
    d_min = Rt - R
    d_max = H
    A = (distance_to_top(R, mu_s_min, Rt) - d_min) / (d_max - d_min)
    a = (A - x * A) / (1.0 + x * A)
    d = d_min + min(a, A) * (d_max - d_min)
    if d == 0.0:
        return 1.0
    return clamp_cos((H * H - d * d) / (2.0 * R * d))


@njit(cache=True)
def cell_r(ir, n_r, R, Rt):
    H = math.sqrt(Rt * Rt - R * R)
    rho = H * ir / (n_r - 1.0)
    return math.sqrt(rho * rho + R * R)


@njit(cache=True)
def cell_mu(imu, n_mu, r, R, Rt):
    """(mu, hits_ground) of node imu of the mu axis at radius r (inverse mapping)."""
    H = math.sqrt(Rt * Rt - R * R)
    rho = math.sqrt(max(r * r - R * R, 0.0))
    half = n_mu // 2
    if imu < half:
        x = (half - 1.0 - imu) / (half - 1.0)
        d_min = r - R
        d_max = rho
        d = d_min + x * (d_max - d_min)
        if d <= 0.0:
            return -1.0, True
        return clamp_cos(-(rho * rho + d * d) / (2.0 * r * d)), True
    x = (imu - half) / (half - 1.0)
    d_min = Rt - r
    d_max = rho + H
    d = d_min + x * (d_max - d_min)
    if d <= 0.0:
        return 1.0, False
    return clamp_cos((H * H - rho * rho - d * d) / (2.0 * r * d)), False


@njit(cache=True)
def cell_nu(inu, n_nu, mu, mu_s):
    nu = -1.0 + 2.0 * inu / (n_nu - 1.0)
    s = math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))
    return min(max(nu, mu * mu_s - s), mu * mu_s + s)


@njit(cache=True)
def _split(f, n):
    """Integer node and fraction of a continuous index f on an axis of n nodes."""
    f = min(max(f, 0.0), n - 1.0)
    i = min(int(f), n - 2)
    return i, f - i


@njit(cache=True)
def r_index(r, n_r, R, Rt):
    H = math.sqrt(Rt * Rt - R * R)
    rho = math.sqrt(max(r * r - R * R, 0.0))
    return _split(rho / H * (n_r - 1), n_r)


@njit(cache=True)
def mu_index(r, mu, ground, n_mu, R, Rt):
    """Node and fraction on the mu axis, staying in the half of the ray's kind."""
    H = math.sqrt(Rt * Rt - R * R)
    rho = math.sqrt(max(r * r - R * R, 0.0))
    half = n_mu // 2
    rmu = r * mu
    disc = rmu * rmu - r * r + R * R
    if ground:
        d = -rmu - math.sqrt(max(disc, 0.0))
        d_min = r - R
        d_max = rho
        x = 0.0 if d_max <= d_min else (d - d_min) / (d_max - d_min)
        i, b = _split((half - 1.0) * (1.0 - x), half)
        return i, b
    d = -rmu + math.sqrt(max(disc + H * H, 0.0))
    d_min = Rt - r
    d_max = rho + H
    x = (d - d_min) / (d_max - d_min)
    i, b = _split(x * (half - 1.0), half)
    return i + half, b


@njit(cache=True)
def _quad_acc(tab, ir, a, imu, b, ims, c, inu, e, w, out):
    """out[l] += w x quadrilinear interpolation of tab[r, mu, mu_s, nu, l]."""
    nl = out.shape[0]
    for dr in range(2):
        wr = a if dr else 1.0 - a
        if wr == 0.0:
            continue
        for dm in range(2):
            wm = b if dm else 1.0 - b
            if wm == 0.0:
                continue
            for ds in range(2):
                ws = c if ds else 1.0 - c
                if ws == 0.0:
                    continue
                for dn in range(2):
                    wn = e if dn else 1.0 - e
                    if wn == 0.0:
                        continue
                    wt = w * wr * wm * ws * wn
                    for l in range(nl):
                        out[l] += wt * tab[ir + dr, imu + dm, ims + ds, inu + dn, l]


@njit(cache=True)
def sky_lookup_acc(first, ss, pc, pp, delta, r, mu, mu_s, nu, ground, R, Rt, mu_s_min, w, out):
    """out += w x radiance of one scattering order arriving at r from (mu) ([Bru17]
    GetScattering): order 1 from the single-scattering tables times each constituent's
    phase function at nu; higher orders from the full-radiance table ``delta``."""
    if first:
        n_r, n_mu, n_ms, n_nu = ss.shape[1], ss.shape[2], ss.shape[3], ss.shape[4]
    else:
        n_r, n_mu, n_ms, n_nu = delta.shape[0], delta.shape[1], delta.shape[2], delta.shape[3]
    ir, a = r_index(r, n_r, R, Rt)
    imu, b = mu_index(r, mu, ground, n_mu, R, Rt)
    ims, c = _split(mu_s_unit(mu_s, R, Rt, mu_s_min) * (n_ms - 1), n_ms)
    inu, e = _split((nu + 1.0) * 0.5 * (n_nu - 1), n_nu)
    if first:
        for k in range(ss.shape[0]):
            p = phase_value(pc[k], pp[k], nu)
            _quad_acc(ss[k], ir, a, imu, b, ims, c, inu, e, w * p, out)
    else:
        _quad_acc(delta, ir, a, imu, b, ims, c, inu, e, w, out)


@njit(cache=True)
def irradiance_lookup_acc(E, r, mu_s, R, Rt, w, out):
    """out += w x bilinear lookup of the irradiance table E[r, mu_s, l] ([Bru17]
    GetIrradianceTextureUvFromRMuS: x_r = (r - R) / (Rt - R), x_mu_s = (mu_s + 1) / 2)."""
    n_r = E.shape[0]
    n_m = E.shape[1]
    i, a = _split((r - R) / (Rt - R) * (n_r - 1), n_r)
    j, b = _split((mu_s + 1.0) * 0.5 * (n_m - 1), n_m)
    for l in range(out.shape[0]):
        out[l] += w * ((1.0 - a) * ((1.0 - b) * E[i, j, l] + b * E[i, j + 1, l])
                       + a * ((1.0 - b) * E[i + 1, j, l] + b * E[i + 1, j + 1, l]))


# -- quadrature along a ray -------------------------------------------------------------------------
@njit(cache=True)
def ray_nodes(r, mu, d, n, ts, t_out, w_out):
    """Midpoint nodes in v = ln(1 + u / ts) on the two pieces of the ray [0, d] split at its
    lowest point (as in :mod:`skydome.transport._kernels`); returns the node count."""
    t_low = min(max(-r * mu, 0.0), d)
    m = 0
    for piece in range(2):
        if piece == 0:
            a, b = 0.0, t_low
        else:
            a, b = t_low, d
        length = b - a
        if length <= 0.0:
            continue
        dv = math.log1p(length / ts) / n
        for k in range(n):
            u = ts * math.expm1((k + 0.5) * dv)
            t_out[m] = b - u if piece == 0 else a + u
            w_out[m] = (u + ts) * dv
            m += 1
    return m


# -- precomputation ---------------------------------------------------------------------------------
@njit(parallel=True, cache=True, fastmath=True)
def single_scattering_table(col, trans, codes, p0s, p1s, beta_s_sc, beta_e, sc_idx, R, Rt,
                            mu_s_min, alpha, n_q, ts, out):
    """Single scattering per scattering constituent, without its phase function ([Bru17]
    ComputeSingleScattering, [BN08] eq. 4 without P):

    out[k, r, mu, mu_s, nu, l] = beta_s,k(l) int_0^d rho_k(r_t) T(r, mu, t) T_sun(r_t, mu_s_t) dt

    per unit solar irradiance, for every node of the 4-D table. T along the view ray from
    the column table (exact exponent), T_sun interpolated in the (float32) transmittance
    table trans[r, mu, l] (as [Bru17] does).

    Loop order: per view ray, the quadrature nodes outside and every (mu_s, nu) node inside,
    so that the view-ray transmittance, the densities and the r-dependent parts of the
    transmittance-table mapping and of the sun's visibility are computed once per node and
    shared by all sun geometries; the wavelength axis is innermost and contiguous (float32,
    accumulated in float32: 2 x 20 positive terms, relative rounding < 1e-6)."""
    nsc, n_r, n_mu, n_ms, n_nu, nl = out.shape
    nc = codes.shape[0]
    n_rT, n_muT = trans.shape[0], trans.shape[1]
    H = math.sqrt(Rt * Rt - R * R)
    nk = n_ms * n_nu
    mus = np.empty(n_ms)
    for ims in range(n_ms):
        mus[ims] = mu_s_from_unit(ims / (n_ms - 1.0), R, Rt, mu_s_min)
    for idx in prange(n_r * n_mu):
        ir = idx // n_mu
        imu = idx % n_mu
        tq = np.empty(2 * n_q)
        wq = np.empty(2 * n_q)
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        cs = np.empty(nc)
        tview = np.empty(nl, dtype=np.float32)
        dens = np.empty(nsc, dtype=np.float32)
        tsun = np.empty(nl, dtype=np.float32)
        acc = np.zeros((nk, nsc, nl), dtype=np.float32)
        nus = np.empty(nk)
        r = cell_r(ir, n_r, R, Rt)
        mu, ground = cell_mu(imu, n_mu, r, R, Rt)
        for ims in range(n_ms):
            for inu in range(n_nu):
                nus[ims * n_nu + inu] = cell_nu(inu, n_nu, mu, mus[ims])
        d = distance_to_ground(r, mu, R) if ground else distance_to_top(r, mu, Rt)
        nq = ray_nodes(r, mu, d, n_q, ts, tq, wq)
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
            for k in range(nk):
                mu_s_t = clamp_cos((r * mus[k // n_nu] + t * nus[k]) * inv_rt)
                xv = (mu_s_t - cos_h + eps) / (2.0 * eps)
                if xv <= 0.0:
                    continue
                vis = 1.0 if xv >= 1.0 else xv * xv * (3.0 - 2.0 * xv)
                disc = rt * rt * (mu_s_t * mu_s_t - 1.0) + Rt * Rt
                dd = max(-rt * mu_s_t + math.sqrt(max(disc, 0.0)), 0.0)
                x_mu = 0.0 if span <= 0.0 else min(max((dd - d_min) / span, 0.0), 1.0)
                fm = x_mu * (n_muT - 1)
                j = min(int(fm), n_muT - 2)
                b = fm - j
                w00 = np.float32(vis * (1.0 - a) * (1.0 - b))
                w01 = np.float32(vis * (1.0 - a) * b)
                w10 = np.float32(vis * a * (1.0 - b))
                w11 = np.float32(vis * a * b)
                for l in range(nl):
                    tsun[l] = tview[l] * (w00 * trans[i, j, l] + w01 * trans[i, j + 1, l]
                                          + w10 * trans[i + 1, j, l] + w11 * trans[i + 1, j + 1, l])
                for kk in range(nsc):
                    dk = dens[kk]
                    o = acc[k, kk]
                    for l in range(nl):
                        o[l] += dk * tsun[l]
        for k in range(nk):
            for kk in range(nsc):
                for l in range(nl):
                    out[kk, ir, imu, k // n_nu, k % n_nu, l] = beta_s_sc[kk, l] * acc[k, kk, l]


@njit(parallel=True, cache=True, fastmath=True)
def incident_radiance(first, ss, pc, pp, delta, dE, col, beta_e, albedo, R, Rt, mu_s_min, alpha,
                      n_r, n_ms, th_in, ph_in, out):
    """Radiance of the previous order arriving at each (r, mu_s) node of the 4-D table
    from the incident directions, including the light reflected once more by the ground
    ([Bru17] ComputeScatteringDensity, inner loop): out[i, r, mu_s, l] (the incident
    direction first: the right-hand side of the matrix product that gives J).

    The incident directions are given in the sun's frame: th_in the angle from the sun
    (so nu = cos th_in), ph_in the azimuth about the sun measured from the sun's vertical
    plane, on the zenith side (so that mu = cos th mu_s + sin th cos ph sin theta_s). The
    aerosol aureole (the forward peak of the previous order) is then resolved along one
    axis of the grid, at every sun elevation alike."""
    n_th = th_in.shape[0]
    n_ph = ph_in.shape[0]
    nl = out.shape[3]
    nc = col.shape[0]
    for idx in prange(n_r * n_ms):
        ir = idx // n_ms
        ims = idx % n_ms
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        cs = np.empty(nc)
        tg = np.empty(nl)
        eg = np.empty(nl)
        r = cell_r(ir, n_r, R, Rt)
        mu_s = mu_s_from_unit(ims / (n_ms - 1.0), R, Rt, mu_s_min)
        sin_s = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
        for a in range(n_th):
            nu = math.cos(th_in[a])
            sg = math.sin(th_in[a])
            for b in range(n_ph):
                i = a * n_ph + b
                ct = clamp_cos(nu * mu_s + sg * math.cos(ph_in[b]) * sin_s)
                ground = hits_ground(r, ct, R)
                o = out[i, ir, ims]
                o[:] = 0.0
                sky_lookup_acc(first, ss, pc, pp, delta, r, ct, mu_s, nu, ground, R, Rt, mu_s_min,
                               1.0, o)
                if ground:
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
                        irradiance_lookup_acc(dE, R, mu_g, R, Rt, 1.0, eg)
                    for l in range(nl):
                        o[l] += tg[l] * eg[l]


@njit(parallel=True, cache=True)
def phase_matrix(code, param, th_out, ph_out, th_in, ph_in, d_omega, out):
    """out[o, i] = dOmega_i (P(w_o . w_i) + P(w_o . w_i')) with w_i' the mirror image of w_i
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
                out[o, a * n_pi + b] = d_omega[a] * (phase_value(code, param, c1)
                                                     + phase_value(code, param, c2))


@njit(parallel=True, cache=True, fastmath=True)
def indirect_irradiance(first, ss, pc, pp, delta, R, Rt, mu_s_min, th, ph, d_omega, out):
    """Irradiance on a horizontal surface from the sky of one scattering order ([Bru17]
    ComputeIndirectIrradiance, [BN08] eq. 9 for one order): out[r, mu_s, l] =
    sum over the upper hemisphere of L(w) cos(theta) dOmega (phi over [0, pi], doubled)."""
    n_r, n_m, nl = out.shape
    for idx in prange(n_r * n_m):
        ir = idx // n_m
        im = idx % n_m
        r = R + (Rt - R) * ir / (n_r - 1.0)
        mu_s = -1.0 + 2.0 * im / (n_m - 1.0)
        sin_s = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
        o = out[ir, im]
        o[:] = 0.0
        for a in range(th.shape[0]):
            ct = math.cos(th[a])
            st = math.sin(th[a])
            for b in range(ph.shape[0]):
                nu = clamp_cos(sin_s * st * math.cos(ph[b]) + mu_s * ct)
                sky_lookup_acc(first, ss, pc, pp, delta, r, ct, mu_s, nu, False, R, Rt, mu_s_min,
                               2.0 * ct * d_omega[a], o)


@njit(cache=True, fastmath=True)
def node_weights(col, r, mu, t, ground, rt, w_q, R, Rt, codes, p0s, p1s, sc_idx, beta_e, w1, w2,
                 cs, tw):
    """Quadrature weight x transmittance from the ray's start to the node at distance t, per
    scattering constituent k times its density at the node: tw[k, l] (the weights of J_k
    in the ray integrals of :func:`multiple_scattering_table` and
    :func:`multiple_scattering_slice`)."""
    nl = tw.shape[1]
    nc = col.shape[0]
    columns_segment(col, r, mu, t, ground, R, Rt, w1, w2, cs)
    for l in range(nl):
        s = 0.0
        for c in range(nc):
            s += beta_e[c, l] * cs[c]
        tw[0, l] = w_q * math.exp(-s)
    for kk in range(tw.shape[0] - 1, -1, -1):
        c = sc_idx[kk]
        dk = profile_density(codes[c], p0s[c], p1s[c], rt - R)
        for l in range(nl):
            tw[kk, l] = tw[0, l] * dk


@njit(cache=True, fastmath=True)
def density_mu_s_index(mu_s_t, R, Rt, d_min_s, inv_span_s, A, n_msj):
    """Node and fraction of mu_s_t on the scattering density's mu_s axis ([Bru17] mu_s
    mapping, constants d_min_s, inv_span_s, A hoisted by the caller)."""
    disc = R * R * (mu_s_t * mu_s_t - 1.0) + Rt * Rt
    dtop = max(-R * mu_s_t + math.sqrt(max(disc, 0.0)), 0.0)
    a_s = (dtop - d_min_s) * inv_span_s
    return _split(max(1.0 - a_s / A, 0.0) / (1.0 + a_s) * (n_msj - 1), n_msj)


@njit(cache=True, fastmath=True)
def density_phi_index(nu, mu_s_t, mt, n_pj):
    """Node and fraction of the azimuth about the sun, measured from the sun's vertical plane
    on the zenith side, of a ray with local zenith cosine mt and sun cosine nu (local sun
    zenith cosine mu_s_t), on the scattering density's phi axis over [0, pi]."""
    den = math.sqrt(max((1.0 - nu * nu) * (1.0 - mu_s_t * mu_s_t), 0.0))
    cphi = 1.0 if den < 1e-9 else clamp_cos((mt - nu * mu_s_t) / den)
    return _split(math.acos(cphi) / math.pi * (n_pj - 1), n_pj)


@njit(parallel=True, cache=True, fastmath=True)
def multiple_scattering_table(J, codes, p0s, p1s, sc_idx, col, beta_e, R, Rt, mu_s_min, n_q,
                              ts, out):
    """One scattering order, full radiance ([Bru17] ComputeMultipleScattering, [BN08] eq. 8):
    out[r, mu, mu_s, nu, l] = int_0^d sum_k rho_k(r_t) J_k(r_t, mu_t, mu_s_t, nu) T(r, mu, t) dt.

    J_k is the scattering density of scattering constituent k (constituent sc_idx[k] of the
    profile arrays) per unit number density, which is smooth in r; its density profile
    rho_k is applied exactly at each quadrature node (the r nodes of the table do not
    resolve the 1.2 km aerosol layer: interpolating rho_k J_k between them overestimated
    the aerosol's multiple scattering by up to 20 %).

    J (float32) is tabulated on [k, theta, phi, r, mu_s, l] in the sun's frame (theta the
    angle between the view ray and the sun, acos nu, uniform in [0, pi]; phi the azimuth of
    the view ray about the sun from the sun's vertical plane, uniform in [0, pi]; r and mu_s
    on the scattering-table nodes): at fixed (theta, phi) J varies smoothly with mu_s, while
    in a zenith frame the aerosol aureole sweeps across the coarse mu_s nodes (that
    overestimated order 2 by up to 66 % at AOD 0.5) and interpolated quadrilinearly. Loop order: per view ray,
    the quadrature nodes outside (their r, theta, weights and view transmittance computed
    once and the J rows they touch staying in cache) and every (mu_s, nu) node inside; the
    wavelength axis innermost and contiguous, accumulated in float32 (at most 16 x 20
    positive terms per value)."""
    n_r, n_mu, n_ms, n_nu, nl = out.shape
    nc = col.shape[0]
    nsc, n_tj, n_pj, n_rj, n_msj, _ = J.shape
    H = math.sqrt(Rt * Rt - R * R)
    # [Bru17] mu_s mapping (mu_s_unit) with its constants hoisted
    d_min_s = Rt - R
    inv_span_s = 1.0 / (H - d_min_s)
    A = (distance_to_top(R, mu_s_min, Rt) - d_min_s) * inv_span_s
    nk = n_ms * n_nu
    mus = np.empty(n_ms)
    for ims in range(n_ms):
        mus[ims] = mu_s_from_unit(ims / (n_ms - 1.0), R, Rt, mu_s_min)
    for idx in prange(n_r * n_mu):
        ir = idx // n_mu
        imu = idx % n_mu
        tq = np.empty(2 * n_q)
        wq = np.empty(2 * n_q)
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        cs = np.empty(nc)
        tw = np.empty((nsc, nl), dtype=np.float32)
        acc = np.zeros((nk, nl), dtype=np.float32)
        nus = np.empty(nk)
        jts = np.empty(nk, dtype=np.int64)
        jbs = np.empty(nk)
        r = cell_r(ir, n_r, R, Rt)
        mu, ground = cell_mu(imu, n_mu, r, R, Rt)
        for ims in range(n_ms):
            for inu in range(n_nu):
                k = ims * n_nu + inu
                nus[k] = cell_nu(inu, n_nu, mu, mus[ims])
                # the angle from the sun (acos nu) is the same at every node of the ray
                jts[k], jbs[k] = _split(math.acos(nus[k]) / math.pi * (n_tj - 1), n_tj)
        d = distance_to_ground(r, mu, R) if ground else distance_to_top(r, mu, Rt)
        nq = ray_nodes(r, mu, d, n_q, ts, tq, wq)
        for q in range(nq):
            t = tq[q]
            rt = point_along(r, mu, t, R, Rt)
            mt = clamp_cos((r * mu + t) / rt)
            jr, ja = r_index(rt, n_rj, R, Rt)
            node_weights(col, r, mu, t, ground, rt, wq[q], R, Rt, codes, p0s, p1s, sc_idx, beta_e,
                         w1, w2, cs, tw)
            inv_rt = 1.0 / rt
            for k in range(nk):
                nu = nus[k]
                mu_s_t = clamp_cos((r * mus[k // n_nu] + t * nu) * inv_rt)
                ims_j, c = density_mu_s_index(mu_s_t, R, Rt, d_min_s, inv_span_s, A, n_msj)
                # J in the sun's frame: angle from the sun (acos nu) and azimuth about the
                # sun from its vertical plane (zenith side)
                jt = jts[k]
                jb = jbs[k]
                ip, e = density_phi_index(nu, mu_s_t, mt, n_pj)
                o = acc[k]
                for kk in range(nsc):
                    twk = tw[kk]
                    Jk = J[kk]
                    for dt in range(2):
                        wt = jb if dt else 1.0 - jb
                        for dr in range(2):
                            wr = ja if dr else 1.0 - ja
                            for ds in range(2):
                                ws = c if ds else 1.0 - c
                                w0 = wt * wr * ws
                                row0 = Jk[jt + dt, ip, jr + dr, ims_j + ds]
                                row1 = Jk[jt + dt, ip + 1, jr + dr, ims_j + ds]
                                wa = np.float32(w0 * (1.0 - e))
                                wb = np.float32(w0 * e)
                                for l in range(nl):
                                    o[l] += (wa * row0[l] + wb * row1[l]) * twk[l]
        for k in range(nk):
            for l in range(nl):
                out[ir, imu, k // n_nu, k % n_nu, l] = acc[k, l]


@njit(parallel=True, cache=True, fastmath=True)
def multiple_scattering_slice(J, codes, p0s, p1s, sc_idx, col, beta_e, R, Rt, mu_s_min, r, mu_s,
                              n_q, ts, mu_nodes, ground_nodes, cphi_nodes, out):
    """Orders 2..N seen by an observer at radius r with the sun at mu_s, on a sky map of view
    directions: view zenith cosines ``mu_nodes`` (with ``ground_nodes``: does the ray end on
    the ground) x azimuths from the sun's with cosines ``cphi_nodes``:
    out[mu, phi, l] = int_0^d sum_k rho_k(r_t) J_k(r_t, mu_t, mu_s_t, nu) T(r, mu, t) dt
    ([BN08] eq. 8 with J summed over the orders), J as in :func:`multiple_scattering_table`.
    (The map is uniform in view zenith angle and azimuth, see :func:`slice_index`: the
    table's own (mu, nu) mapping is coarse near the zenith and near the sun.)

    Integrating at the observer's own r and mu_s (instead of interpolating the 4-D table)
    keeps the multiply scattered aerosol aureole, which is sharp in the angle from the sun,
    out of the coarse mu_s interpolation: at AOD 0.5 that interpolation overestimated the
    zenith sky by 16 % with the sun at 60 deg."""
    n_mu, n_nu, nl = out.shape
    nc = col.shape[0]
    nsc, n_tj, n_pj, n_rj, n_msj, _ = J.shape
    H = math.sqrt(Rt * Rt - R * R)
    d_min_s = Rt - R
    inv_span_s = 1.0 / (H - d_min_s)
    A = (distance_to_top(R, mu_s_min, Rt) - d_min_s) * inv_span_s
    for imu in prange(n_mu):
        tq = np.empty(2 * n_q)
        wq = np.empty(2 * n_q)
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        cs = np.empty(nc)
        tw = np.empty((nsc, nl))
        acc = np.zeros((n_nu, nl))
        mu = mu_nodes[imu]
        ground = ground_nodes[imu]
        s_v = math.sqrt(max(1.0 - mu * mu, 0.0)) * math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
        d = distance_to_ground(r, mu, R) if ground else distance_to_top(r, mu, Rt)
        nq = ray_nodes(r, mu, d, n_q, ts, tq, wq)
        for q in range(nq):
            t = tq[q]
            rt = point_along(r, mu, t, R, Rt)
            mt = clamp_cos((r * mu + t) / rt)
            jr, ja = r_index(rt, n_rj, R, Rt)
            node_weights(col, r, mu, t, ground, rt, wq[q], R, Rt, codes, p0s, p1s, sc_idx, beta_e,
                         w1, w2, cs, tw)
            for inu in range(n_nu):
                nu = clamp_cos(mu * mu_s + s_v * cphi_nodes[inu])
                mu_s_t = clamp_cos((r * mu_s + t * nu) / rt)
                ims_j, c = density_mu_s_index(mu_s_t, R, Rt, d_min_s, inv_span_s, A, n_msj)
                jt, jb = _split(math.acos(nu) / math.pi * (n_tj - 1), n_tj)
                ip, e = density_phi_index(nu, mu_s_t, mt, n_pj)
                o = acc[inu]
                for kk in range(nsc):
                    Jk = J[kk]
                    for dt in range(2):
                        wt = jb if dt else 1.0 - jb
                        for dr in range(2):
                            wr = ja if dr else 1.0 - ja
                            for ds in range(2):
                                ws = c if ds else 1.0 - c
                                w0 = wt * wr * ws
                                row0 = Jk[jt + dt, ip, jr + dr, ims_j + ds]
                                row1 = Jk[jt + dt, ip + 1, jr + dr, ims_j + ds]
                                wa = w0 * (1.0 - e)
                                wb = w0 * e
                                for l in range(nl):
                                    o[l] += (wa * row0[l] + wb * row1[l]) * tw[kk, l]
        for inu in range(n_nu):
            for l in range(nl):
                out[imu, inu, l] = acc[inu, l]


@njit(cache=True)
def slice_index(mu, cphi, ground, geom):
    """(node, fraction) on the view-zenith axis and on the azimuth axis of the observer's
    sky map of :func:`multiple_scattering_slice`. ``geom`` = (n_ground, n_sky, theta_h):
    nodes 0..n_ground-1 run uniformly in view zenith angle from the nadir to the horizon
    (theta_h), nodes n_ground.. from the horizon to the zenith; azimuth from the sun's,
    n_phi nodes uniform over [0, pi]."""
    n_g = int(geom[0])
    n_s = int(geom[1])
    th_h = geom[2]
    th = math.acos(clamp_cos(mu))
    if ground:
        x = (math.pi - th) / max(math.pi - th_h, 1e-12)
        i, b = _split(x * (n_g - 1.0), n_g)
    else:
        x = (th_h - th) / th_h
        i, b = _split(x * (n_s - 1.0), n_s)
        i += n_g
    return i, b


# -- rendering --------------------------------------------------------------------------------------
@njit(parallel=True, cache=True, fastmath=True)
def render_observer(dirs, r, sun, ss_slice, pc, pp, ms_slice, col, beta_e, albedo, E, scale, R,
                    Rt, alpha, geom, out):
    """Radiance [scale units] from each direction for an observer at radius r on the +z axis.

    ``ss_slice`` (nsc, n_mu, n_nu, nl) and ``ms_slice`` (n_mu, n_nu, nl) are the 4-D tables
    already interpolated at the observer's r and mu_s (multilinear interpolation is
    separable, so the result equals the full 4-D lookup). With ``geom[0] > 0``, ``ms_slice``
    is instead the observer's sky map (n_ground + n_sky, n_phi, nl) of
    :func:`multiple_scattering_slice`, indexed by :func:`slice_index`. Ground-hitting rays add the
    Lambertian ground lit by the sun and the sky ([Bru17] GetSunAndSkyIrradiance) times the
    transmittance to the ground: both exponentials (sun to the ground point, observer to the
    ground point) are taken at once for all wavelengths by the vectorised
    :func:`skydome.transport._kernels.exp_neg_array` (relative error < 1e-8)."""
    n = dirs.shape[0]
    nsc = ss_slice.shape[0]
    n_mu = ss_slice.shape[1]
    n_nu = ss_slice.shape[2]
    n_mu_ms = ms_slice.shape[0]
    n_nu_ms = ms_slice.shape[1]
    sky_map = geom[0] > 0.0
    sh = math.sqrt(sun[0] * sun[0] + sun[1] * sun[1])
    nl = out.shape[1]
    nc = col.shape[0]
    mu_s = sun[2]
    block = 256
    for ib in prange((n + block - 1) // block):
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        cs = np.empty(nc)
        acc = np.empty(nl)
        eg = np.empty(nl)
        xb = np.empty(2 * nl)
        eb = np.empty(2 * nl)
        ibuf = np.empty(2 * nl, dtype=np.int64)
        for i in range(ib * block, min(n, (ib + 1) * block)):
            mu = dirs[i, 2]
            nu = clamp_cos(dirs[i, 0] * sun[0] + dirs[i, 1] * sun[1] + dirs[i, 2] * sun[2])
            ground = hits_ground(r, mu, R)
            im, b = mu_index(r, mu, ground, n_mu, R, Rt)
            inu, e = _split((nu + 1.0) * 0.5 * (n_nu - 1), n_nu)
            w00 = (1.0 - b) * (1.0 - e)
            w01 = (1.0 - b) * e
            w10 = b * (1.0 - e)
            w11 = b * e
            if sky_map:
                dh = math.sqrt(dirs[i, 0] * dirs[i, 0] + dirs[i, 1] * dirs[i, 1])
                cphi = 1.0
                if dh * sh > 1e-12:
                    cphi = clamp_cos((dirs[i, 0] * sun[0] + dirs[i, 1] * sun[1]) / (dh * sh))
                jm, bm = slice_index(mu, cphi, ground, geom)
                jn, f = _split(math.acos(cphi) / math.pi * (n_nu_ms - 1), n_nu_ms)
            else:
                jm, bm = mu_index(r, mu, ground, n_mu_ms, R, Rt)
                jn, f = _split((nu + 1.0) * 0.5 * (n_nu_ms - 1), n_nu_ms)
            for l in range(nl):
                acc[l] = ((1.0 - bm) * ((1.0 - f) * ms_slice[jm, jn, l] + f * ms_slice[jm, jn + 1, l])
                          + bm * ((1.0 - f) * ms_slice[jm + 1, jn, l] + f * ms_slice[jm + 1, jn + 1, l]))
            for k in range(nsc):
                p = phase_value(pc[k], pp[k], nu)
                s = ss_slice[k]
                for l in range(nl):
                    acc[l] += p * (w00 * s[im, inu, l] + w01 * s[im, inu + 1, l]
                                   + w10 * s[im + 1, inu, l] + w11 * s[im + 1, inu + 1, l])
            if ground:
                dg = distance_to_ground(r, mu, R)
                mu_g = clamp_cos((r * mu_s + dg * nu) / R)
                # direct sun on the ground point ([Bru17] ComputeDirectIrradiance, as in
                # direct_irradiance_acc): average cosine over the disc x transmittance
                if mu_g < -alpha:
                    f = 0.0
                elif mu_g > alpha:
                    f = mu_g
                else:
                    f = (mu_g + alpha) * (mu_g + alpha) / (4.0 * alpha)
                columns_at(col, R, mu_g, R, Rt, cs)
                for l in range(nl):
                    s = 0.0
                    for c in range(nc):
                        s += beta_e[c, l] * cs[c]
                    xb[l] = -s
                # transmittance observer -> ground point
                columns_segment(col, r, mu, dg, True, R, Rt, w1, w2, cs)
                for l in range(nl):
                    s = 0.0
                    for c in range(nc):
                        s += beta_e[c, l] * cs[c]
                    xb[nl + l] = -s
                exp_neg_array(xb, eb, ibuf)
                for l in range(nl):
                    eg[l] = f * eb[l]
                irradiance_lookup_acc(E, R, mu_g, R, Rt, 1.0, eg)
                for l in range(nl):
                    acc[l] += eb[nl + l] * albedo[l] * INV_PI * eg[l]
            for l in range(nl):
                out[i, l] = max(acc[l], 0.0) * scale[l]


@njit(parallel=True, cache=True, fastmath=True)
def aerial_perspective(dirs, dist, r, sun, ss, pc, pp, ms, col, beta_e, R, Rt, mu_s_min,
                       trans, inscat):
    """Transmittance and in-scattered radiance between the observer (radius r, +z axis) and
    the point at distance dist[i] along dirs[i] ([Bru17] GetSkyRadianceToPoint):
    S(r, mu, mu_s, nu) - T S(r_p, mu_p, mu_s_p, nu), clamped at 0; the distance is clamped
    to the end of the ray (ground or top of the atmosphere)."""
    n = dirs.shape[0]
    nl = trans.shape[1]
    nc = col.shape[0]
    mu_s = sun[2]
    for i in prange(n):
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        cs = np.empty(nc)
        s0 = np.zeros(nl)
        s1 = np.zeros(nl)
        mu = dirs[i, 2]
        nu = clamp_cos(dirs[i, 0] * sun[0] + dirs[i, 1] * sun[1] + dirs[i, 2] * sun[2])
        ground = hits_ground(r, mu, R)
        d_end = distance_to_ground(r, mu, R) if ground else distance_to_top(r, mu, Rt)
        d = min(max(dist[i], 0.0), d_end)
        columns_segment(col, r, mu, d, ground, R, Rt, w1, w2, cs)
        for l in range(nl):
            s = 0.0
            for c in range(nc):
                s += beta_e[c, l] * cs[c]
            trans[i, l] = math.exp(-s)
        rp = point_along(r, mu, d, R, Rt)
        mup = clamp_cos((r * mu + d) / rp)
        mu_sp = clamp_cos((r * mu_s + d * nu) / rp)
        sky_lookup_acc(True, ss, pc, pp, ms, r, mu, mu_s, nu, ground, R, Rt, mu_s_min, 1.0, s0)
        sky_lookup_acc(False, ss, pc, pp, ms, r, mu, mu_s, nu, ground, R, Rt, mu_s_min, 1.0, s0)
        if d < d_end:
            sky_lookup_acc(True, ss, pc, pp, ms, rp, mup, mu_sp, nu, ground, R, Rt, mu_s_min,
                           1.0, s1)
            sky_lookup_acc(False, ss, pc, pp, ms, rp, mup, mu_sp, nu, ground, R, Rt, mu_s_min,
                           1.0, s1)
        for l in range(nl):
            inscat[i, l] = max(s0[l] - trans[i, l] * s1[l], 0.0)
