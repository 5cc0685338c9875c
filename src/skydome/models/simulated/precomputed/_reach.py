"""The mu_s rows of the scattering density J that an observer's own rays reach.

The observer's sky map of orders 2..N (:func:`._multiple.multiple_scattering_slice`)
reads J [k, theta, phi, r, mu_s, wavelength] at the quadrature nodes of the rays from the
observer, at the sun cosine of each node, mu_s_t = (r0 mu_s + t nu) / r_t: the cosine of
the angle between the sun and the node's own zenith. A node at distance t along a ray from
radius r0 has its zenith turned from the observer's by the central angle gamma between the
two radii, so that (the triangle inequality on the sphere of directions) its sun zenith
angle lies within [theta_s - gamma, theta_s + gamma]. A ray inside the atmosphere turns by
at most

    gamma_max = acos(R / r0) + acos(R / Rt),

the central angle of the longest ray: down from r0 to grazing the ground (acos(R / r0)),
then up to the top (acos(R / Rt)); a ray that meets the ground ends there (at most
acos(R / r0)), one that does not dip below r0 turns by at most acos(r0 / Rt). For the
default 100 km atmosphere: 10.1 deg at the ground, 14.1 deg at 15 km.

:func:`density_mu_s_rows` maps that band of sun zenith angles, widened by
:data:`ANGLE_MARGIN` for the rounding of the nodes' geometry, onto J's mu_s axis (the
mapping of :func:`._mapping.mu_s_unit`, recomputed here in plain Python so that the cache
can be read before numba is imported; :func:`._mapping.mu_s_unit` clamps to [0, 1] the same
way) and takes the interpolation's two nodes of each end (:func:`._mapping._split`,
clamped as it clamps). The angle margin also covers the difference between this mapping
and the kernel's (fast-math) one, a few units in the last place of the unit coordinate
(1e-6 rad moves it by at least 5e-6 of a row on a 48-node axis), so no row is added
(:data:`ROW_MARGIN`). The kernel reports the rows it read and reads none outside the rows
it is given (``reach`` of :func:`._multiple.multiple_scattering_slice`), so that a bound
that was wrong would be found, not served (930 suns, altitudes and axis sizes checked:
none outside, the bound tight to the row in some).

Plain Python (math only): no numba, no NumPy.
"""

from __future__ import annotations

import math

# the mu_s mapping of _mapping (MU_S_CENTRE, MU_S_WIDTH: the same values)
_CENTRE = math.radians(92.0)
_WIDTH = math.radians(6.0)

#: widening of the band of sun zenith angles [rad] for the rounding of the nodes' radii
#: and cosines (float64: about 1e-8 rad where acos is steepest, at a cosine of 1)
ANGLE_MARGIN = 1e-6
#: rows added on each side of the band's interpolation nodes: none needed (the angle
#: margin covers the rounding of the mapping too: 1e-6 rad is at least 5e-6 of a row at
#: 48 nodes, the mappings differ by a few units in the last place); the kernel's ``reach``
#: remains the check
ROW_MARGIN = 0


def max_central_angle(r0: float, R: float, Rt: float) -> float:
    """The largest central angle [rad] between the observer at radius ``r0`` (R <= r0 <=
    Rt) and any point of a ray from it inside the shell [R, Rt]: acos(R / r0) + acos(R /
    Rt)."""
    r0 = min(max(float(r0), R), Rt)
    return math.acos(min(R / r0, 1.0)) + math.acos(min(R / Rt, 1.0))


def _unit(theta: float, mu_s_min: float) -> float:
    """:func:`._mapping.mu_s_unit` of the sun zenith angle ``theta`` [rad]."""
    th_max = math.acos(min(max(mu_s_min, -1.0), 1.0))
    top = math.asinh((th_max - _CENTRE) / _WIDTH)
    inv = 1.0 / (top - math.asinh((0.0 - _CENTRE) / _WIDTH))
    x = (top - math.asinh((min(theta, th_max) - _CENTRE) / _WIDTH)) * inv
    return min(max(x, 0.0), 1.0)


def _node(theta: float, mu_s_min: float, n: int) -> int:
    """The lower interpolation node of the sun zenith angle ``theta`` on an mu_s axis of
    n nodes (:func:`._mapping.density_mu_s_index`, :func:`._mapping._split`)."""
    f = min(max(_unit(theta, mu_s_min) * (n - 1), 0.0), n - 1.0)
    return min(int(f), n - 2)


def density_mu_s_rows(r0: float, mu_s: float, R: float, Rt: float, mu_s_min: float,
                      n: int) -> tuple[int, int]:
    """(first, end): the rows first..end-1 of J's mu_s axis of ``n`` nodes that contain
    every row :func:`._multiple.multiple_scattering_slice` reads for the observer at radius
    ``r0`` [m] with the sun at zenith cosine ``mu_s`` (planet radius R, top radius Rt,
    the tables' ``mu_s_min``); see the module's text for the bound."""
    n = int(n)
    if n < 2:
        return 0, n
    theta_s = math.acos(min(max(float(mu_s), -1.0), 1.0))
    gamma = max_central_angle(r0, R, Rt) + ANGLE_MARGIN
    # the mapping decreases with the angle: the largest angle gives the first row
    first = _node(min(theta_s + gamma, math.pi), mu_s_min, n)
    last = _node(max(theta_s - gamma, 0.0), mu_s_min, n) + 1     # the upper node read
    return max(0, first - ROW_MARGIN), min(n, last + 1 + ROW_MARGIN)
