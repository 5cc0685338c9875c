"""Direct ([Bru17] ComputeDirectIrradiance) and indirect ([Bru17] ComputeIndirectIrradiance,
[BN08] eq. 9) irradiance on a horizontal surface, per unit solar irradiance (the sky
radiance read from the 4-D table, mu on :func:`._mapping.mu_unit`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skydome.models.simulated.precomputed._geometry import clamp_cos
from skydome.models.simulated.precomputed._lookup import columns_at, sky_lookup_acc
from skydome.models.simulated.precomputed._mapping import mu_s_frame
from skydome.models.simulated.precomputed._multiple import ray_integral, ray_scratch



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
        mu_s = -1.0 + 2.0 * im / (n_m - 1.0)
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
def indirect_irradiance_rays(J, codes, p0s, p1s, sc_idx, col, beta_e, R, Rt, mu_s_min, n_q, ts,
                             th, ph, d_omega, out):
    """:func:`indirect_irradiance` for an order >= 2 whose radiance is not tabulated: the
    radiance of each hemisphere direction integrated along its ray from that order's
    scattering density ``J`` ([BN08] eq. 8 and 9, :func:`._multiple.ray_integral`, the
    quadrature of the multiple-scattering table), on the irradiance table's nodes."""
    n_r, n_m, nl = out.shape
    nc = col.shape[0]
    nsc = J.shape[0]
    frame = mu_s_frame(mu_s_min)
    for idx in prange(n_r * n_m):
        ir = idx // n_m
        im = idx % n_m
        tq, wq, w1, w2, cs, tw = ray_scratch(n_q, nc, nsc, nl)
        acc = np.zeros(nl)
        one = np.empty(nl)
        r = R + (Rt - R) * ir / (n_r - 1.0)
        mu_s = -1.0 + 2.0 * im / (n_m - 1.0)
        sin_s = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
        for a in range(th.shape[0]):
            ct = math.cos(th[a])
            st = math.sin(th[a])
            w = 2.0 * ct * d_omega[a]
            for b in range(ph.shape[0]):
                nu = clamp_cos(sin_s * st * math.cos(ph[b]) + mu_s * ct)
                one[:] = 0.0
                ray_integral(J, codes, p0s, p1s, sc_idx, col, beta_e, R, Rt, frame, r, ct, mu_s,
                             nu, False, n_q, ts, tq, wq, w1, w2, cs, tw, one)
                for l in range(nl):
                    acc[l] += w * one[l]
        for l in range(nl):
            out[ir, im, l] = acc[l]
