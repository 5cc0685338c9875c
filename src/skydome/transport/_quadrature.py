"""Node sets of the numerical core: along rays and over the sphere (numba, scalar).

Along a ray every integral uses the same rule. The ray is split at the point of lowest
altitude (where the density of every profile that decreases with altitude is largest);
each piece of length L is integrated by the midpoint rule in the variable
``v = ln(1 + u / ts)``, where ``u`` is the distance from the dense end, so that the nodes
are spaced geometrically away from the dense end: node k of n has
``u_k = ts (exp((k + 1/2) dv) - 1)`` and weight ``w_k = (u_k + ts) dv`` with
``dv = ln(1 + L / ts) / n`` (the Jacobian du/dv = u + ts). The rule is second order in dv:
a constant density over a path of length L has the relative error
(ln(1 + L/ts) / n)^2 / 24. This resolves the 1.2 km aerosol scale height looking up and
the 100 km-scale horizon path with the same few nodes. :func:`piece_nodes` lays out the
nodes of one piece for every kernel that walks a ray (:func:`ray_nodes` the two pieces of
a ray split at its lowest point).

The better rule for smooth integrands (:func:`ray_nodes_rule`, :func:`piece_nodes_rule`):
Gauss-Legendre in the same v per piece, node k at v = V x_k, V = ln(1 + L / ts), with
(x_k, w_k) the Gauss-Legendre rule on [0, 1] (:func:`gauss_legendre_unit`). The midpoint
rule in v integrates even a constant short, by V^2 / (24 n^2) per piece relatively (the
Jacobian e^v is convex: 1.5 % for a 200 km ray with 10 nodes); Gauss-Legendre integrates
the Jacobian times a smooth integrand to order 2n.

Over the sphere: the product midpoint rule in (cos theta, phi), n_mu x n_phi cells of
equal solid angle 4 pi / (n_mu n_phi).
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit

from skydome.transport._geometry import lowest_point, radius_along, ray_segment, safe_sqrt
from skydome.transport._medium import profile_density
from skydome.transport._vexp import expm1_many


@njit(cache=True)
def geometric_step(length, n, ts):
    """dv = ln(1 + length / ts) / n of the geometric rule (n nodes over ``length`` [m])."""
    return math.log1p(length / ts) / n


@njit(cache=True)
def geometric_node(k, dv, ts):
    """(u, w) of node k of the geometric midpoint rule: distance from the dense end [m] and
    weight [m], u = ts expm1((k + 1/2) dv), w = (u + ts) dv."""
    u = ts * math.expm1((k + 0.5) * dv)
    return u, (u + ts) * dv


@njit(cache=True)
def geometric_edge(k, dv, ts):
    """Distance from the dense end [m] of the k-th cell edge of the geometric rule,
    ts expm1(k dv) (k = 0..n; edges bracket the nodes of :func:`geometric_node`)."""
    return ts * math.expm1(k * dv)


@njit(cache=True, inline="always")
def piece_nodes(a, b, dense_at_b, n, ts, ascending, t_out, w_out, m, vector, xbits, xbits_f):
    """The n nodes of the geometric midpoint rule on the piece [a, b] of a ray (dense at b
    where ``dense_at_b``, else at a): distances into t_out[m:m + n] [m], weights into
    w_out[m:m + n] [m] (node k at u_k = ts expm1((k + 1/2) dv) from the dense end, weight
    (u_k + ts) dv, dv = :func:`geometric_step`); in increasing distance where
    ``ascending``, else from the dense end. Returns m + n.

    ``vector``: the n expm1 in one vectorised pass (:func:`skydome.transport._vexp.
    expm1_many`, scratch xbits (int64) and its float64 view xbits_f, at least n long; m
    must be 0), else one :func:`geometric_node` per node. Inlined, so that each kernel
    keeps its own floating-point flags."""
    dv = geometric_step(b - a, n, ts)
    flip = ascending and dense_at_b
    if vector:
        for kk in range(n):
            k = n - 1 - kk if flip else kk
            t_out[kk] = (k + 0.5) * dv
        expm1_many(t_out, n, w_out, xbits, xbits_f)
        for kk in range(n):
            u = ts * w_out[kk]
            w_out[kk] = (u + ts) * dv
            t_out[kk] = b - u if dense_at_b else a + u
        return n
    for kk in range(n):
        k = n - 1 - kk if flip else kk
        u, w = geometric_node(k, dv, ts)
        t_out[m + kk] = b - u if dense_at_b else a + u
        w_out[m + kk] = w
    return m + n


@njit(cache=True, inline="always")
def piece_nodes_rule(a, b, dense_at_b, rx, rw, ts, t_out, w_out, m):
    """:func:`piece_nodes` with the rule (rx, rw) on [0, 1] (:func:`gauss_legendre_unit`)
    in place of the midpoint rule: v = ln(1 + u / ts) runs over [0, V = ln(1 + (b - a) /
    ts)], node k at v = V rx[k], u = ts expm1(v) from the dense end, weight
    (u + ts) V rw[k] (du = (u + ts) dv); in the order of rx from the dense end. Returns
    m + rx.size."""
    V = math.log1p((b - a) / ts)
    for k in range(rx.shape[0]):
        u = ts * math.expm1(V * rx[k])
        t_out[m] = b - u if dense_at_b else a + u
        w_out[m] = (u + ts) * V * rw[k]
        m += 1
    return m


def gauss_legendre_unit(n):
    """(x, w): the n-point Gauss-Legendre rule on [0, 1] (nodes ascending, weights summing
    to 1; numpy's ``leggauss`` mapped from [-1, 1]), for :func:`ray_nodes_rule`."""
    x, w = np.polynomial.legendre.leggauss(int(n))
    return np.ascontiguousarray(0.5 * (x + 1.0)), np.ascontiguousarray(0.5 * w)


@njit(cache=True)
def ray_nodes(r, mu, d, n, ts, t_out, w_out):
    """The geometric midpoint rule on the ray [0, d] from radius r, zenith cosine mu, split
    at its lowest point: n nodes per piece (:func:`piece_nodes`, each piece from its dense
    end), the piece from the start to the lowest point as two (for n >= 4): start to its
    midpoint dense at the start, midpoint to the lowest point dense there, n nodes each;
    distances t_out and weights w_out [m] (room for 3 n); returns the node count."""
    t_low = lowest_point(r, mu, 0.0, d)
    no_bits = np.empty(0, dtype=np.int64)     # the scalar form's unused scratch
    m = 0
    for piece in range(2):
        a, b, dense_at_b = piece_bounds(piece, 0.0, t_low, d)
        if b - a <= 0.0:
            continue
        # n nodes on each half of a descending piece (at most 3 n nodes a ray; n // 2 on
        # the first half left the midpoint rule's low bias, (ln(1 + L / ts) / n)^2 / 24,
        # at 0.7 % there)
        split = dense_at_b and n >= 4
        for half in range(2 if split else 1):
            ha, hb, hd = piece_half(a, b, dense_at_b, split, half)
            m = piece_nodes(ha, hb, hd, n, ts, False, t_out, w_out, m, False, no_bits,
                            no_bits.view(np.float64))
    return m


@njit(cache=True, inline="always")
def piece_half(a, b, dense_at_b, split, half):
    """(a, b, dense_at_b) of part ``half`` of the piece [a, b] of a ray: the piece itself
    unless ``split``; split (a piece from the ray's start down to its lowest point, dense
    at b): half 0 is [a, midpoint] dense at a, half 1 [midpoint, b] dense at b.

    A descending ray's integrands are large at both ends of that piece: at the start (the
    transmittance from the start, near 1 only within the first optical depths: an
    observer inside haze) and at the lowest point (the density). Nodes dense at the lowest
    point alone left the first kilometres of a 100 km horizon piece without a node: single
    scattering 0.005 deg above the horizon from 350-1100 m in AOD 1 haze came out 94-98 %
    low (docs/models.md, "Descending rays and observers inside haze")."""
    if not split:
        return a, b, dense_at_b
    h = a + 0.5 * (b - a)
    if half == 0:
        return a, h, False
    return h, b, True


@njit(cache=True)
def ray_nodes_rule(r, mu, d, rx, rw, ts, t_out, w_out):
    """:func:`ray_nodes` with the rule (rx, rw) on [0, 1] per piece
    (:func:`piece_nodes_rule`; module docstring); returns the node count (at most
    2 rx.size)."""
    t_low = lowest_point(r, mu, 0.0, d)
    m = 0
    for piece in range(2):
        a, b, dense_at_b = piece_bounds(piece, 0.0, t_low, d)
        if b - a <= 0.0:
            continue
        m = piece_nodes_rule(a, b, dense_at_b, rx, rw, ts, t_out, w_out, m)
    return m


@njit(cache=True)
def piece_bounds(piece, t0, tmin, t1):
    """(a, b, dense_at_b) of piece 0 (from the start t0 to the lowest point tmin, densest at
    its end b) or piece 1 (from tmin to the end t1, densest at its start a) of a ray."""
    if piece == 0:
        return t0, tmin, True
    return tmin, t1, False


@njit(cache=True)
def column_quadrature(code, p0, p1, r, mu, R, Rt, n, ts, ground=True):
    """Column density of one profile from (r, mu) to the end of the ray [m]: the integral
    of the relative density along the ray ([KRZ06] eq. 12 without beta).

    The ray ends at the top of the atmosphere or at the ground (where it hits it and
    ``ground`` is set). ``n`` midpoint nodes per piece (module docstring), scale ``ts`` [m].
    """
    t0, t1, _ = ray_segment(r, mu, R, Rt, ground)
    if t1 <= t0:
        return 0.0
    tmin = lowest_point(r, mu, t0, t1)
    tq = np.empty(n)
    wq = np.empty(n)
    no_bits = np.empty(0, dtype=np.int64)     # the scalar form's unused scratch
    total = 0.0
    for piece in range(2):
        a, b, dense_at_b = piece_bounds(piece, t0, tmin, t1)
        if b - a <= 0.0:
            continue
        piece_nodes(a, b, dense_at_b, n, ts, False, tq, wq, 0, False, no_bits,
                    no_bits.view(np.float64))
        for k in range(n):
            total += wq[k] * profile_density(code, p0, p1, radius_along(r, mu, tq[k]) - R)
    return total


@njit(cache=True)
def medium_columns(m, r, mu, n, ts, ground, out):
    """out[c] = column density of every constituent of the medium m from (r, mu) to the
    end of the ray [m] (:func:`column_quadrature`)."""
    for c in range(m.profile_code.shape[0]):
        out[c] = column_quadrature(m.profile_code[c], m.profile_p0[c], m.profile_p1[c], r, mu,
                                   m.R, m.Rt, n, ts, ground)


@njit(cache=True)
def simpson(f0, fm, f1, h):
    """Simpson's rule over an interval of length h from the values at its ends and middle."""
    return h / 6.0 * (f0 + 4.0 * fm + f1)


@njit(cache=True)
def sphere_node(k, n_mu, n_phi):
    """(x, y, z, w) of cell k of the product midpoint rule over the sphere: n_mu bands of
    equal width in cos(theta) times n_phi sectors in azimuth; w = 4 pi / (n_mu n_phi) [sr].
    k = i n_phi + j, band i from the zenith down, sector j from +x towards +y."""
    i = k // n_phi
    j = k % n_phi
    z = 1.0 - (i + 0.5) * 2.0 / n_mu
    s = safe_sqrt(1.0 - z * z)
    phi = (j + 0.5) * 2.0 * math.pi / n_phi
    return s * math.cos(phi), s * math.sin(phi), z, 4.0 * math.pi / (n_mu * n_phi)
