"""Ray/shell geometry of the precomputed model ([Bru17] "Distance to the top/bottom atmosphere
boundary") and the quadrature nodes along a ray. Lengths in metres, angles as cosines.
"""

from __future__ import annotations

import math

from numba import njit



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
