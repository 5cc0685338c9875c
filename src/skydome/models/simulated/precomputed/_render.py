"""Rendering from the tables: the observer's sky ([Bru17] GetSkyRadiance, with the ground and
GetSunAndSkyIrradiance) and aerial perspective ([Bru17] GetSkyRadianceToPoint); the 4-D
tables' mu axis on :func:`._mapping.mu_unit`.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.models.simulated.precomputed._geometry import (clamp_cos, distance_to_ground,
                                                             distance_to_top, hits_ground, point_along)
from skydome.models.simulated.precomputed._lookup import (columns_at, columns_segment,
                                                           irradiance_lookup_acc, sky_lookup_acc)
from skydome.models.simulated.precomputed._mapping import _split, mu_frame, mu_index_framed
from skydome.models.simulated.precomputed._multiple import slice_index
from skydome.transport._vexp import exp_neg_many
from skydome.transport._phase import phase_fill_coded

INV_PI = 1.0 / math.pi



# -- rendering --------------------------------------------------------------------------------------
@njit(parallel=True, cache=True, fastmath=True)
def render_observer(dirs, r, sun, ss_slice, pc, pp, pt, ms_slice, col, beta_e, albedo, E, scale, R,
                    Rt, mu_s_min, alpha, geom, out):
    """Radiance [scale units] from each direction for an observer at radius r on the +z axis.

    ``ss_slice`` (nsc, n_mu, n_nu, nl) is multiplied by each constituent's phase function
    at nu (codes pc, parameters pp, per-wavelength table pt where tabulated); it and ``ms_slice`` (n_mu, n_nu, nl) are the 4-D tables
    already interpolated at the observer's r and mu_s (multilinear interpolation is
    separable, so the result equals the full 4-D lookup). With ``geom[0] > 0``, ``ms_slice``
    is instead the observer's sky map (n_ground + n_sky, n_phi, nl) of
    :func:`multiple_scattering_slice`, indexed by :func:`slice_index` (``geom`` = (n_ground,
    n_sky, horizon zenith angle, single-scattering flag, the ground's and the sky's linear
    share of the rows' mapping: :func:`._multiple.map_nodes`)); with ``geom[3] > 0`` too,
    ``ss_slice`` is on that sky map as well (:func:`._twilight.single_scattering_slice`, shape
    (nsc, n_ground + n_sky, n_phi, nl)). Ground-hitting rays add the
    Lambertian ground lit by the sun and the sky ([Bru17] GetSunAndSkyIrradiance) times the
    transmittance to the ground: both exponentials (sun to the ground point, observer to the
    ground point) are taken at once for all wavelengths by the vectorised
    :func:`skydome.transport._vexp.exp_neg_many` (the core's one vectorised exp)."""
    n = dirs.shape[0]
    nsc = ss_slice.shape[0]
    n_mu = ss_slice.shape[1]
    n_nu = ss_slice.shape[2]
    n_mu_ms = ms_slice.shape[0]
    n_nu_ms = ms_slice.shape[1]
    sky_map = geom[0] > 0.0
    ss_map = sky_map and geom.shape[0] > 3 and geom[3] > 0.0
    sh = math.sqrt(sun[0] * sun[0] + sun[1] * sun[1])
    nl = out.shape[1]
    nc = col.shape[0]
    mu_s = sun[2]
    frame = mu_frame(r, R)
    block = 256
    for ib in prange((n + block - 1) // block):
        w1 = np.empty(nc)
        w2 = np.empty(nc)
        cs = np.empty(nc)
        acc = np.empty(nl)
        pw = np.empty(nl)
        eg = np.empty(nl)
        xb = np.empty(2 * nl)
        eb = np.empty(2 * nl)
        ibuf = np.empty(2 * nl, dtype=np.int64)
        for i in range(ib * block, min(n, (ib + 1) * block)):
            mu = dirs[i, 2]
            nu = clamp_cos(dirs[i, 0] * sun[0] + dirs[i, 1] * sun[1] + dirs[i, 2] * sun[2])
            ground = hits_ground(r, mu, R)
            im, b = mu_index_framed(mu, ground, n_mu, frame)
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
                jm, bm = mu_index_framed(mu, ground, n_mu_ms, frame)
                jn, f = _split((nu + 1.0) * 0.5 * (n_nu_ms - 1), n_nu_ms)
            for l in range(nl):
                acc[l] = ((1.0 - bm) * ((1.0 - f) * ms_slice[jm, jn, l] + f * ms_slice[jm, jn + 1, l])
                          + bm * ((1.0 - f) * ms_slice[jm + 1, jn, l] + f * ms_slice[jm + 1, jn + 1, l]))
            if ss_map:
                # single scattering on the observer's sky map too (twilight: _twilight)
                im, inu = jm, jn
                w00 = (1.0 - bm) * (1.0 - f)
                w01 = (1.0 - bm) * f
                w10 = bm * (1.0 - f)
                w11 = bm * f
            for k in range(nsc):
                phase_fill_coded(pc, pp, pt, k, nu, pw)
                s = ss_slice[k]
                for l in range(nl):
                    acc[l] += pw[l] * (w00 * s[im, inu, l] + w01 * s[im, inu + 1, l]
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
                exp_neg_many(xb, 2 * nl, eb, ibuf, ibuf.view(np.float64))
                for l in range(nl):
                    eg[l] = f * eb[l]
                irradiance_lookup_acc(E, R, mu_g, R, Rt, mu_s_min, 1.0, eg)
                for l in range(nl):
                    acc[l] += eb[nl + l] * albedo[l] * INV_PI * eg[l]
            for l in range(nl):
                out[i, l] = max(acc[l], 0.0) * scale[l]


@njit(parallel=True, cache=True, fastmath=True)
def aerial_perspective(dirs, dist, r, sun, ss, pc, pp, pt, ms, col, beta_e, R, Rt, mu_s_min,
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
        sky_lookup_acc(True, ss, pc, pp, pt, ms, r, mu, mu_s, nu, ground, R, Rt, mu_s_min, 1.0,
                       s0)
        sky_lookup_acc(False, ss, pc, pp, pt, ms, r, mu, mu_s, nu, ground, R, Rt, mu_s_min, 1.0,
                       s0)
        if d < d_end:
            sky_lookup_acc(True, ss, pc, pp, pt, ms, rp, mup, mu_sp, nu, ground, R, Rt, mu_s_min,
                           1.0, s1)
            sky_lookup_acc(False, ss, pc, pp, pt, ms, rp, mup, mu_sp, nu, ground, R, Rt, mu_s_min,
                           1.0, s1)
        for l in range(nl):
            inscat[i, l] = max(s0[l] - trans[i, l] * s1[l], 0.0)
