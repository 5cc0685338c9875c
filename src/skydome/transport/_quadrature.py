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
the 100 km-scale horizon path with the same few nodes.

Over the sphere: the product midpoint rule in (cos theta, phi), n_mu x n_phi cells of
equal solid angle 4 pi / (n_mu n_phi).
"""

from __future__ import annotations

import math

from numba import njit

from skydome.transport._geometry import lowest_point, radius_along, ray_segment, safe_sqrt
from skydome.transport._medium import profile_density


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
    total = 0.0
    for piece in range(2):
        if piece == 0:
            a, b = t0, tmin            # dense end at b
        else:
            a, b = tmin, t1            # dense end at a
        length = b - a
        if length <= 0.0:
            continue
        dv = geometric_step(length, n, ts)
        for k in range(n):
            u, w = geometric_node(k, dv, ts)
            t = b - u if piece == 0 else a + u
            total += w * profile_density(code, p0, p1, radius_along(r, mu, t) - R)
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
