"""Table lookups of the precomputed model: columns and transmittance ([Bru17]
GetTransmittance), the sun's visible fraction, the 4-D scattering and 2-D irradiance tables
([Bru17] GetScattering, GetIrradiance; mu on :func:`._mapping.mu_unit`), and the
transmittance-weighted quadrature weights.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit

from skydome.models.simulated.precomputed._geometry import clamp_cos, point_along
from skydome.models.simulated.precomputed._mapping import _split, mu_index, mu_s_unit, r_index
from skydome.transport._kernels import profile_density_many
from skydome.transport._medium import density
from skydome.transport._vexp import exp_neg_many
from skydome.transport._phase import phase_fill_coded
from skydome.transport._tables import lookup_columns as columns_at



# -- columns and transmittance --------------------------------------------------------------------
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
def _quad_acc(tab, ir, a, imu, b, ims, c, inu, e, w, pw, out):
    """out[l] += w pw[l] x quadrilinear interpolation of tab[r, mu, mu_s, nu, l]."""
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
                        out[l] += wt * pw[l] * tab[ir + dr, imu + dm, ims + ds, inu + dn, l]


@njit(cache=True)
def sky_lookup_acc(first, ss, pc, pp, pt, delta, r, mu, mu_s, nu, ground, R, Rt, mu_s_min, w,
                   out):
    """out += w x radiance of one scattering order arriving at r from (mu) ([Bru17]
    GetScattering): order 1 from the single-scattering tables times each constituent's
    phase function at nu (codes pc, parameters pp, per-wavelength table pt where tabulated:
    :func:`skydome.transport._phase.phase_fill_coded`); higher orders from the
    full-radiance table ``delta``."""
    if first:
        n_r, n_mu, n_ms, n_nu = ss.shape[1], ss.shape[2], ss.shape[3], ss.shape[4]
    else:
        n_r, n_mu, n_ms, n_nu = delta.shape[0], delta.shape[1], delta.shape[2], delta.shape[3]
    ir, a = r_index(r, n_r, R, Rt)
    imu, b = mu_index(r, mu, ground, n_mu, R, Rt)
    ims, c = _split(mu_s_unit(mu_s, mu_s_min) * (n_ms - 1), n_ms)
    inu, e = _split((nu + 1.0) * 0.5 * (n_nu - 1), n_nu)
    pw = np.ones(out.shape[0])
    if first:
        for k in range(ss.shape[0]):
            phase_fill_coded(pc, pp, pt, k, nu, pw)
            _quad_acc(ss[k], ir, a, imu, b, ims, c, inu, e, w, pw, out)
    else:
        _quad_acc(delta, ir, a, imu, b, ims, c, inu, e, w, pw, out)


@njit(cache=True)
def geometric_lerp(lo, hi, b):
    """The value a fraction b of the way from lo to hi: geometric, lo (hi / lo)^b, where
    both are positive (exact for a quantity exponential in the coordinate, as the sky's
    irradiance is in the sun's elevation in twilight, falling by a factor of about 2.5 per
    degree), linear otherwise (a zero node)."""
    if b <= 0.0:
        return lo
    if b >= 1.0:
        return hi
    if lo > 0.0 and hi > 0.0:
        return lo * math.exp(b * math.log(hi / lo))
    return lo + b * (hi - lo)


@njit(cache=True)
def irradiance_lookup_acc(E, r, mu_s, R, Rt, mu_s_min, w, out):
    """out += w x the irradiance table E[r, mu_s, l] at (r, mu_s): linear in r ([Bru17]
    GetIrradianceTextureUvFromRMuS, x_r = (r - R) / (Rt - R)); the mu_s axis on the 4-D
    tables' sun mapping (:func:`._mapping.mu_s_unit`, clamped at mu_s_min), not [Bru17]'s
    x_mu_s = (mu_s + 1) / 2, and geometric between its two nodes (:func:`geometric_lerp`):
    the twilight irradiance falls exponentially with the sun's depression, and [Bru17]'s
    64 linear nodes over [-1, 1] left it 54 % RMS off at sun -6 to -12 deg (docs/models.md,
    "The sky irradiance table in twilight")."""
    n_r = E.shape[0]
    n_m = E.shape[1]
    i, a = _split((r - R) / (Rt - R) * (n_r - 1), n_r)
    j, b = _split(mu_s_unit(mu_s, mu_s_min) * (n_m - 1), n_m)
    for l in range(out.shape[0]):
        lo = (1.0 - a) * E[i, j, l] + a * E[i + 1, j, l]
        hi = (1.0 - a) * E[i, j + 1, l] + a * E[i + 1, j + 1, l]
        out[l] += w * geometric_lerp(lo, hi, b)


@njit(cache=True, fastmath=True)
def ray_weights(col, m, sc_idx, r, mu, ground, nq, w, s):
    """The weights of the scattering density J_k at the ``nq`` quadrature nodes (distances
    s.tq, weights s.wq) of one ray from radius r, zenith cosine mu (``ground``: the ray
    ends on the ground) in the medium m (:class:`skydome.transport._medium.Medium`, its
    column table ``col``, its scattering constituents sc_idx):
    s.tw[q, k, l] = w wq[q] T(r, mu; tq[q])[l] rho_k(r_q), the
    transmittance from the ray's start to the node times scattering constituent k's density
    there (the weights of every ray integral: :func:`._multiple.ray_integral`,
    :func:`._multiple.multiple_scattering_table`, :func:`._multiple.multiple_scattering_slice`,
    :func:`._irradiance.indirect_irradiance_rays`), in the precision of ``tw``; s.rts[q]
    the radius of node q.

    The whole ray at once: its columns node by node ([Bru17] GetTransmittance, for rays to
    the ground both ends reversed, as in :func:`columns_segment`), then the optical depths
    of every node and wavelength in one vectorised exp pass
    (:func:`skydome.transport._vexp.exp_neg_many`, to a few units in the last place; numba's
    math.exp is a scalar libm call) and the densities of every node per constituent in one
    more (:func:`skydome.transport._kernels.profile_density_many`): 18 % of the orders'
    ray integrals against one node at a time. Scratch ``s``: the
    :class:`._multiple.RayWork` of :func:`._multiple.ray_scratch`."""
    tq = s.tq
    w1 = s.w1
    w2 = s.w2
    rts = s.rts
    cs = s.cs
    R = m.R
    Rt = m.Rt
    nc = col.shape[0]
    columns_at(col, r, -mu if ground else mu, R, Rt, w2)
    for q in range(nq):
        rt = point_along(r, mu, tq[q], R, Rt)
        rts[q] = rt
        mt = clamp_cos((r * mu + tq[q]) / rt)
        columns_at(col, rt, -mt if ground else mt, R, Rt, w1)
        for c in range(nc):
            cs[q, c] = max(w1[c] - w2[c], 0.0) if ground else max(w2[c] - w1[c], 0.0)
    weights_from_columns(m, sc_idx, nq, w, s)


@njit(cache=True)
def columns_along(m, r, mu, t0, t1, gx, gw, acc):
    """acc[c] += the column of constituent c of the medium m between the distances t0 and
    t1 along the ray from radius r, zenith cosine mu: the integral of its relative density
    ([KRZ06] eq. 12 without beta) by the rule (gx, gw) on [0, 1] (Gauss-Legendre,
    :func:`skydome.transport._quadrature.gauss_legendre_unit`) over [t0, t1]."""
    h = t1 - t0
    if h <= 0.0:
        return
    for i in range(gx.shape[0]):
        alt = point_along(r, mu, t0 + gx[i] * h, m.R, m.Rt) - m.R
        for c in range(acc.shape[0]):
            acc[c] += gw[i] * h * density(m, c, alt)


@njit(cache=True)
def ray_weights_integrated(m, sc_idx, r, mu, nq, w, gx, gw, s):
    """:func:`ray_weights` with the columns from the ray's start to its nodes integrated
    along the ray itself (:func:`columns_along` from node to node in order of distance,
    the rule (gx, gw) between each two) instead of the difference of two columns to the
    top read from the column table. Along a grazing ray from an observer inside haze those
    two columns exceed 100 optical depths while the first kilometre holds about 0.3, and
    their linear interpolation in r makes the difference piecewise constant in the
    observer's altitude: the horizon of the observer's sky map stepped by about 10 % where
    the observer crossed a node of the column table (docs/models.md, "The observer's own
    columns")."""
    tq = s.tq
    rts = s.rts
    cs = s.cs
    nc = cs.shape[1]
    acc = s.w1
    acc[:] = 0.0
    t_prev = 0.0
    order = np.argsort(tq[:nq])
    for k in range(nq):
        q = order[k]
        columns_along(m, r, mu, t_prev, tq[q], gx, gw, acc)
        t_prev = max(t_prev, tq[q])
        rts[q] = point_along(r, mu, tq[q], m.R, m.Rt)
        for c in range(nc):
            cs[q, c] = acc[c]
    weights_from_columns(m, sc_idx, nq, w, s)


@njit(cache=True)
def weights_from_columns(m, sc_idx, nq, w, s):
    """The second half of :func:`ray_weights`: s.tw from the columns s.cs and the radii
    s.rts of the ray's ``nq`` nodes."""
    wq = s.wq
    rts = s.rts
    cs = s.cs
    xs = s.xs
    es = s.es
    ib = s.ib
    dk = s.dk
    tw = s.tw
    R = m.R
    codes = m.profile_code
    p0s = m.profile_p0
    p1s = m.profile_p1
    beta_e = m.extinction
    nl = tw.shape[2]
    for q in range(nq):
        for l in range(nl):
            xs[q * nl + l] = -_optical_depth(beta_e, cs[q], l)
    fb = ib.view(np.float64)
    exp_neg_many(xs, nq * nl, es, ib, fb)
    for kk in range(sc_idx.shape[0]):
        c = sc_idx[kk]
        profile_density_many(codes[c], p0s[c], p1s[c], rts, R, nq, dk[kk], ib, fb)
    for q in range(nq):
        for kk in range(sc_idx.shape[0]):
            g = w * wq[q] * dk[kk, q]
            for l in range(nl):
                tw[q, kk, l] = g * es[q * nl + l]


@njit(cache=True, inline="always")
def _optical_depth(beta_e, cs, l):
    """sum_c beta_e[c, l] cs[c]: the optical depth at wavelength l of the columns cs."""
    s = 0.0
    for c in range(cs.shape[0]):
        s += beta_e[c, l] * cs[c]
    return s
