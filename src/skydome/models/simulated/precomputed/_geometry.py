"""Ray/shell geometry of the precomputed model ([Bru17] "Distance to the top/bottom atmosphere
boundary"), from the shared core :mod:`skydome.transport._geometry`, and the quadrature
nodes along a ray (the core's geometric rule on the two pieces of the ray). Lengths in
metres, angles as cosines.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from skydome.transport._geometry import clamp_cosine as clamp_cos  # noqa: F401
from skydome.transport._geometry import (distance_to_ground, distance_to_top,  # noqa: F401
                                        point_along)
from skydome.transport._geometry import ray_hits_ground as hits_ground  # noqa: F401
from skydome.transport._quadrature import geometric_node, geometric_step


# -- quadrature along a ray -------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _ray_piece(piece, r, mu, d):
    """(a, b): piece 0 or 1 of the ray [0, d], split at its lowest point; the nodes of piece
    0 are laid out from b backwards (dense at the lowest point), those of piece 1 from a."""
    t_low = min(max(-r * mu, 0.0), d)
    return (0.0, t_low) if piece == 0 else (t_low, d)


@njit(cache=True)
def ray_nodes(r, mu, d, n, ts, t_out, w_out):
    """Midpoint nodes in v = ln(1 + u / ts) on the two pieces of the ray [0, d] split at its
    lowest point (as in :mod:`skydome.transport._kernels`); returns the node count."""
    m = 0
    for piece in range(2):
        a, b = _ray_piece(piece, r, mu, d)
        if b - a <= 0.0:
            continue
        dv = geometric_step(b - a, n, ts)
        for k in range(n):
            u, w_out[m] = geometric_node(k, dv, ts)
            t_out[m] = b - u if piece == 0 else a + u
            m += 1
    return m


def gauss_rule(n):
    """(x, w): the n-point Gauss-Legendre rule on [0, 1] (nodes ascending, weights summing
    to 1; numpy's ``leggauss`` mapped from [-1, 1]), for :func:`ray_nodes_rule`."""
    x, w = np.polynomial.legendre.leggauss(int(n))
    return np.ascontiguousarray(0.5 * (x + 1.0)), np.ascontiguousarray(0.5 * w)


@njit(cache=True)
def ray_nodes_rule(r, mu, d, rx, rw, ts, t_out, w_out):
    """:func:`ray_nodes` with the rule (rx, rw) on [0, 1] (:func:`gauss_rule`) in place of
    the midpoint rule: on each piece of the ray, v = ln(1 + u / ts) runs over
    [0, V = ln(1 + length / ts)], node k at v = V rx[k], u = ts expm1(v), weight
    (u + ts) V rw[k] (du = (u + ts) dv). The midpoint rule in v integrates even a constant
    short, by V^2 / (24 n^2) per piece relatively (the Jacobian e^v is convex: 1.5 % for a
    200 km ray with 10 nodes); Gauss-Legendre integrates the Jacobian times a smooth
    integrand to order 2n. Returns the node count (at most 2 rx.size)."""
    m = 0
    for piece in range(2):
        a, b = _ray_piece(piece, r, mu, d)
        if b - a <= 0.0:
            continue
        V = math.log1p((b - a) / ts)
        for k in range(rx.shape[0]):
            u = ts * math.expm1(V * rx[k])
            t_out[m] = b - u if piece == 0 else a + u
            w_out[m] = (u + ts) * V * rw[k]
            m += 1
    return m
