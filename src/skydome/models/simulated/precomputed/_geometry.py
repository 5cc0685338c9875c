"""Ray/shell geometry of the precomputed model ([Bru17] "Distance to the top/bottom atmosphere
boundary"), from the shared core :mod:`skydome.transport._geometry`, and the quadrature
nodes along a ray (the core's geometric rule on the two pieces of the ray). Lengths in
metres, angles as cosines.
"""

from __future__ import annotations

from numba import njit

from skydome.transport._geometry import clamp_cosine as clamp_cos  # noqa: F401
from skydome.transport._geometry import (distance_to_ground, distance_to_top,  # noqa: F401
                                        point_along)
from skydome.transport._geometry import ray_hits_ground as hits_ground  # noqa: F401
from skydome.transport._quadrature import geometric_node, geometric_step


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
        dv = geometric_step(length, n, ts)
        for k in range(n):
            u, w = geometric_node(k, dv, ts)
            t_out[m] = b - u if piece == 0 else a + u
            w_out[m] = w
            m += 1
    return m
