"""The sky of Hoffman & Preetham (2002) over many directions and wavelengths in one parallel
pass (:class:`skydome.models.analytic.hoffman_preetham2002.HoffmanPreetham2002`).

The same equations, in the same order of operations, as the module's NumPy functions
(:func:`~skydome.models.analytic.hoffman_preetham2002.aerial_perspective` along the shell
path of :func:`~skydome.models.analytic.hoffman_preetham2002.shell_path_length`), per view
direction v and wavelength l ([HP02]):

    s = -R u + sqrt(R^2 u^2 + 2 R H + H^2),  u = max(v_z, 0)      (path through the shell)
    F_ex = exp(-(beta_R + beta_M) s)
    beta(theta) = beta_R 3 / (16 pi) (1 + cos^2 theta) + beta_M num / (4 pi (1 + g^2 - 2 g cos theta)^1.5)
    L_in = beta(theta) / (beta_R + beta_M) E_sun (1 - F_ex)

with num = (1 - g)^2 ([HP02]'s form) or 1 - g^2 ([HG41]). The exponentials of a block of
directions are taken together by the kernel core's vectorised exp
(:func:`skydome.transport._vexp.exp_neg_many`, within a few units in the last place of the
C library's), where NumPy's ``exp`` took most of the NumPy path's time: 41 wavelengths of a
4096 x 2048 map are 172 M of them. Zero below the horizon; negative values clamped to zero.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.transport._vexp import exp_neg_many

_BLOCK = 128          # directions per block (their exponentials in one vectorised call)


@njit(parallel=True, cache=True)
def hoffman_preetham_sky(d, sun, radius, thickness, beta_r, beta_m, beta, e_sun, g, num,
                         out):
    """``out`` (N, L) = [HP02]'s in-scattered radiance along the shell path of each
    direction of ``d`` (N, 3; validated, not necessarily unit: each row is divided by its
    length here), for the coefficients ``beta_r``, ``beta_m`` (L,) [1/m], ``beta`` = their
    sum and the attenuated solar irradiance ``e_sun`` (L,); ``sun`` the unit vector to the
    sun, ``g`` and ``num`` the Mie phase's asymmetry and numerator."""
    n = d.shape[0]
    nl = beta.shape[0]
    R, H = radius, thickness
    c_ray = 3.0 / (16.0 * np.pi)
    c_mie = 4.0 * np.pi
    g2 = 1.0 + g * g
    n_blocks = (n + _BLOCK - 1) // _BLOCK
    for b in prange(n_blocks):
        i0 = b * _BLOCK
        i1 = min(n, i0 + _BLOCK)
        m = (i1 - i0) * nl
        x = np.empty(m)
        f = np.empty(m)
        ibuf = np.empty(m, dtype=np.int64)
        fbuf = ibuf.view(np.float64)
        for i in range(i0, i1):
            vx, vy, vz = d[i, 0], d[i, 1], d[i, 2]
            r = math.sqrt(vx * vx + vy * vy + vz * vz)
            u = max(vz / r, 0.0)
            s = -R * u + math.sqrt(R * R * u * u + 2.0 * R * H + H * H)
            k = (i - i0) * nl
            for j in range(nl):
                x[k + j] = -beta[j] * s
        exp_neg_many(x, m, f, ibuf, fbuf)
        for i in range(i0, i1):
            vx, vy, vz = d[i, 0], d[i, 1], d[i, 2]
            r = math.sqrt(vx * vx + vy * vy + vz * vz)
            vx, vy, vz = vx / r, vy / r, vz / r
            if vz < 0.0:
                for j in range(nl):
                    out[i, j] = 0.0
                continue
            c = vx * sun[0] + vy * sun[1] + vz * sun[2]
            c = min(max(c, -1.0), 1.0)
            p_ray = c_ray * (1.0 + c * c)                                  # [HP02] beta_R(theta)
            p_mie = num / (c_mie * (g2 - 2.0 * g * c) ** 1.5)             # [HP02] beta_M(theta)
            k = (i - i0) * nl
            for j in range(nl):
                if beta[j] > 0.0:
                    v = ((beta_r[j] * p_ray + beta_m[j] * p_mie) / beta[j]) * e_sun[j] \
                        * (1.0 - f[k + j])                                 # [HP02] L_in
                    out[i, j] = v if v > 0.0 else 0.0
                else:
                    out[i, j] = 0.0
