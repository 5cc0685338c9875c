"""Named scalar guards and ray/shell geometry of the numerical core (numba, scalar).

Private: plain floats, no options, no units beyond metres and cosines. Every function
is a scalar ``@njit`` so that a shader or ``numba.cuda.jit(device=True)`` port can mirror
it one to one.

Geometry ([Bru17] = E. Bruneton, precomputed_atmospheric_scattering, 2017,
atmosphere/functions.glsl, sections "Distance to the top/bottom atmosphere boundary" and
"RayIntersectsGround"): the planet is a sphere of radius ``R`` centred on the origin, the
atmosphere ends at the sphere of radius ``Rt``. A point is given by its distance ``r``
from the centre, a ray by ``mu``, the cosine of the angle between the ray and the local
vertical at its origin. A point at distance ``t`` along the ray has the radius
``r_t = sqrt(t^2 + 2 r mu t + r^2)`` (law of cosines) and the local cosine
``mu_t = (r mu + t) / r_t``; a second direction with cosine ``mu_s`` at the origin and
cosine ``nu`` with the ray has ``mu_s_t = (r mu_s + t nu) / r_t`` there.
"""

from __future__ import annotations

import math

from skydome._kernel_cache import njit


# -- named guards ([Bru17] ClampCosine, SafeSqrt) -------------------------------------------------
@njit(cache=True)
def safe_sqrt(x):
    """sqrt(max(x, 0)): the square root of a quantity that is >= 0 except for rounding."""
    return math.sqrt(max(x, 0.0))


@njit(cache=True)
def clamp_cosine(x):
    """x clamped to [-1, 1] ([Bru17] ClampCosine)."""
    return min(max(x, -1.0), 1.0)


@njit(cache=True)
def clamp_radius(r, R, Rt):
    """r clamped to the shell [R, Rt] [m] ([Bru17] ClampRadius)."""
    return min(max(r, R), Rt)


# -- distances along a ray -------------------------------------------------------------------------
@njit(cache=True)
def distance_to_sphere_far(r, mu, radius):
    """Distance along the ray from (r, mu) to the far intersection with the sphere of the
    given radius [m] (r <= radius): -r mu + sqrt(r^2 (mu^2 - 1) + radius^2)."""
    return -r * mu + safe_sqrt(r * r * (mu * mu - 1.0) + radius * radius)


@njit(cache=True)
def distance_to_top(r, mu, Rt):
    """Distance from (r, mu) to the top of the atmosphere along the ray [m], >= 0
    ([Bru17] DistanceToTopAtmosphereBoundary; r <= Rt)."""
    return max(distance_to_sphere_far(r, mu, Rt), 0.0)


@njit(cache=True)
def distance_to_ground(r, mu, R):
    """Distance from (r, mu) to the ground along the ray [m], >= 0 ([Bru17]
    DistanceToBottomAtmosphereBoundary; meaningful where :func:`ray_hits_ground`)."""
    return max(-r * mu - safe_sqrt(r * r * (mu * mu - 1.0) + R * R), 0.0)


@njit(cache=True)
def ray_hits_ground(r, mu, R):
    """True where the ray from (r, mu) meets the ground sphere in front of it ([Bru17]
    RayIntersectsGround: mu < 0 and r^2 (mu^2 - 1) + R^2 >= 0)."""
    return mu < 0.0 and r * r * (mu * mu - 1.0) + R * R >= 0.0


@njit(cache=True)
def radius_along(r, mu, t):
    """Radius [m] of the point at distance t along the ray from (r, mu) (law of cosines)."""
    return safe_sqrt(t * t + 2.0 * r * mu * t + r * r)


@njit(cache=True)
def radius_along_above(r, mu, t, R):
    """Radius [m] of the point at distance t along the ray, at least R (a point that
    rounding puts just below the ground is taken on it): sqrt(max(r_t^2, R^2))."""
    return math.sqrt(max(r * r + 2.0 * r * mu * t + t * t, R * R))


@njit(cache=True)
def point_along(r, mu, t, R, Rt):
    """Radius of the point at distance t along the ray, clamped to the shell [R, Rt] [m]."""
    return clamp_radius(radius_along(r, mu, t), R, Rt)


@njit(cache=True)
def mu_along(r, mu, t, r_t):
    """Cosine of the ray's zenith angle at the point at distance t whose radius is r_t."""
    return clamp_cosine((r * mu + t) / r_t)


@njit(cache=True)
def mu_s_along(r, mu_s, nu, t, r_t):
    """Cosine of the sun's zenith angle at the point at distance t along the ray (radius
    r_t), for the sun at cosine mu_s at the origin and cosine nu with the ray."""
    return clamp_cosine((r * mu_s + t * nu) / r_t)


# -- the part of a ray inside the shell ------------------------------------------------------------
@njit(cache=True)
def ray_segment(r, mu, R, Rt, ground=True):
    """(t_start, t_end, hits_ground) [m] of the part of the ray from (r, mu) inside the
    atmosphere.

    t_start > 0 when the origin lies above the top of the atmosphere; t_end < 0 when the
    ray misses the atmosphere. With ``ground`` False the planet is transparent (used for
    the grazing rays of the column table). An observer on (or, by rounding, just below)
    the ground looking down sees the ground at its feet: t_ground = 0.
    """
    disc_t = r * r * (mu * mu - 1.0) + Rt * Rt
    if disc_t < 0.0:
        return 0.0, -1.0, False
    sq = math.sqrt(disc_t)
    t_near = -r * mu - sq
    t_far = -r * mu + sq
    if t_far <= 0.0:
        return 0.0, -1.0, False
    t0 = max(t_near, 0.0)
    disc_g = r * r * (mu * mu - 1.0) + R * R
    if ground and mu < 0.0 and disc_g >= 0.0:
        tg = max(-r * mu - math.sqrt(disc_g), 0.0)
        return t0, max(tg, t0), True
    return t0, t_far, False


@njit(cache=True)
def ray_segment_xyz(px, py, pz, dx, dy, dz, R, Rt):
    """:func:`ray_segment` for a ray from the point p [m] (any position, planet centre at
    the origin) along the unit vector d: (t_start, t_end, hits_ground)."""
    r = math.sqrt(px * px + py * py + pz * pz)
    if r == 0.0:
        return ray_segment(0.0, 1.0, R, Rt, True)
    return ray_segment(r, (px * dx + py * dy + pz * dz) / r, R, Rt, True)


@njit(cache=True)
def lowest_point(r, mu, t0, t1):
    """Distance [m] of the lowest point of the ray within [t0, t1] (where every density
    that decreases with altitude is largest): -r mu clamped to the segment."""
    return min(max(-r * mu, t0), t1)


@njit(cache=True)
def shadow_crossings(r0, mu, sz, nu, R):
    """Distances t along the ray from (0, 0, r0) with direction d (d_z = mu, d . s = nu)
    where it crosses the boundary of the planet's shadow (the cylinder of radius R about
    the axis through the centre along the sun direction s, on the night side: p . s < 0).

    With o_perp, d_perp the parts perpendicular to s: |o_perp + t d_perp|^2 = R^2, i.e.
    a t^2 + 2 b t + c = 0, a = 1 - nu^2, b = r0 (mu - sz nu), c = r0^2 (1 - sz^2) - R^2.
    Returns (count, t1, t2) of the valid crossings (t > 0, night side).
    """
    a = 1.0 - nu * nu
    if a <= 1e-14:
        return 0, 0.0, 0.0
    b = r0 * (mu - sz * nu)
    c = r0 * r0 * (1.0 - sz * sz) - R * R
    disc = b * b - a * c
    if disc <= 0.0:
        return 0, 0.0, 0.0
    sq = math.sqrt(disc)
    n = 0
    out1 = 0.0
    out2 = 0.0
    for sign in (-1.0, 1.0):
        t = (-b + sign * sq) / a
        if t > 0.0 and r0 * sz + t * nu < 0.0:
            if n == 0:
                out1 = t
            else:
                out2 = t
            n += 1
    return n, out1, out2
