"""Ray/shell geometry of the precomputed model ([Bru17] "Distance to the top/bottom atmosphere
boundary"), from the shared core :mod:`skydome.transport._geometry`, and the quadrature
nodes along a ray (:func:`skydome.transport._quadrature.ray_nodes` and ``ray_nodes_rule``,
the core's rules on the two pieces of the ray). Lengths in metres, angles as cosines.
"""

from __future__ import annotations

from skydome.transport._geometry import clamp_cosine as clamp_cos  # noqa: F401
from skydome.transport._geometry import (distance_to_ground, distance_to_top,  # noqa: F401
                                        point_along)
from skydome.transport._geometry import ray_hits_ground as hits_ground  # noqa: F401
from skydome.transport._quadrature import ray_nodes, ray_nodes_rule  # noqa: F401
