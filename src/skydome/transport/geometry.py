"""Frames and ray geometry in the East-North-Up frame (x east, y north, z up).

Zenith angle is measured from +z; azimuth from north (+y) towards east (+x), so east is
90 deg, as in daylighting practice and pvlib. Pure NumPy; the numba twins of the
ray/sphere routines live in ``_kernels.py``.
"""

from __future__ import annotations

import numpy as np


def _real_degrees(name: str, value) -> np.ndarray:
    raw = np.asarray(value)
    if np.iscomplexobj(raw) or raw.dtype.kind not in "biuf":
        raise TypeError(f"{name} must be a real number or array of real numbers, "
                        f"got dtype {raw.dtype}")
    a = raw.astype(np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return a


def direction_from_angles(elevation_deg, azimuth_deg) -> np.ndarray:
    """Unit vector(s) (..., 3) for elevation above the horizon [deg] in [-90, 90] and
    azimuth from north towards east [deg] (any finite value), broadcast together.

    Raises TypeError for complex or non-numeric input and ValueError naming the argument
    for NaN, infinite or out-of-range values."""
    el_deg = _real_degrees("elevation_deg", elevation_deg)
    az_deg = _real_degrees("azimuth_deg", azimuth_deg)
    if np.any(np.abs(el_deg) > 90.0):
        bad = el_deg[np.abs(el_deg) > 90.0].flat[0]
        raise ValueError(f"elevation_deg = {bad:g} deg is out of range [-90, 90] deg")
    el = np.radians(el_deg)
    az = np.radians(az_deg)
    el, az = np.broadcast_arrays(el, az)
    c = np.cos(el)
    return np.stack([c * np.sin(az), c * np.cos(az), np.sin(el)], axis=-1)


def angles_from_direction(directions) -> tuple[np.ndarray, np.ndarray]:
    """(elevation_deg, azimuth_deg in [0, 360)) of unit vectors (..., 3)."""
    d = np.asarray(directions, dtype=np.float64)
    el = np.degrees(np.arcsin(np.clip(d[..., 2], -1.0, 1.0)))
    az = np.degrees(np.arctan2(d[..., 0], d[..., 1])) % 360.0
    return el, az


def zenith_azimuth_from_direction(directions) -> tuple[np.ndarray, np.ndarray]:
    """(zenith angle [rad], azimuth [rad], from north towards east) of unit vectors."""
    d = np.asarray(directions, dtype=np.float64)
    zen = np.arccos(np.clip(d[..., 2], -1.0, 1.0))
    az = np.arctan2(d[..., 0], d[..., 1]) % (2.0 * np.pi)
    return zen, az


def angle_between(a, b) -> np.ndarray:
    """Angle [rad] between unit vectors a (..., 3) and b (..., 3), robust near 0 and pi."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    # atan2(|a x b|, a . b) keeps precision for tiny angles, unlike acos.
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = np.sum(a * b, axis=-1)
    return np.arctan2(cross, dot)


def ray_sphere_intersections(r, mu, radius):
    """Distances along a ray from a point at distance r from the planet centre, with
    cosine mu between the ray and the local vertical, to a sphere of given radius.

    Returns (near, far); entries are NaN where the ray misses the sphere. From
    |p + t d|^2 = R^2 with |p| = r, p.d = r mu:  t = -r mu +- sqrt(r^2 (mu^2 - 1) + R^2).
    """
    r = np.asarray(r, dtype=np.float64)
    mu = np.asarray(mu, dtype=np.float64)
    disc = r * r * (mu * mu - 1.0) + radius * radius
    with np.errstate(invalid="ignore"):
        s = np.where(disc >= 0.0, np.sqrt(np.maximum(disc, 0.0)), np.nan)
    return -r * mu - s, -r * mu + s
