"""A pinhole (perspective) camera placed anywhere, as a :class:`Projection`.

The sky projections of :mod:`skydome.render.projections` look at the whole sky from the
observer; a :class:`Camera` looks in one direction with a limited field of view, which is
what a picture of the earth from space needs. It implements the same protocol (``shape``,
``directions()``, ``solid_angles()``, ``pixel_from_direction``, ``direction_from_pixel``,
``name``, ``describe()``), so :func:`skydome.render.render` renders it unchanged.

Frame: East-North-Up of the sub-camera point with its origin on the planet's surface
(x east, y north, z up; the planet's centre at (0, 0, -R)). ``position`` and ``look_at``
are points in that frame [m]; the camera's directions are unit vectors in the same frame.
The picture's right-hand edge is along ``forward x up`` and its top along ``up``
(projected normal to the view direction), as in Radiance's ``-vtv`` perspective view.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from skydome._validate import check_number
from skydome.render.projections import Projection, _as_dirs, _check_size

__all__ = ["Camera"]


def _as_point(name: str, value) -> np.ndarray:
    p = np.asarray(value, dtype=np.float64)
    if p.shape != (3,):
        raise ValueError(f"{name} must be a point (x, y, z) [m], got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} = {tuple(p)} is not finite")
    return p


class Camera(Projection):
    """Perspective (pinhole) camera.

    Parameters
    ----------
    width, height : int
        Image size [pixels], 2..32768 each.
    fov_deg : float
        Full field of view across the image width [deg], in (0, 179]. Square pixels: the
        vertical field of view follows from the aspect ratio.
    position : array_like (3,)
        Camera position [m] in the East-North-Up frame of the sub-camera point, origin on
        the surface (default: 36 000 km above the origin).
    look_at : array_like (3,)
        Point the camera looks at [m] (default: the planet's centre, (0, 0, -6 371 km)).
    up : array_like (3,)
        Direction that appears upwards in the picture (default north, (0, 1, 0)); must not
        be parallel to the view direction.

    Notes
    -----
    A pixel at continuous coordinates (row, col) looks along
    ``forward * f + right * (col - W/2) + up' * (H/2 - row)`` with the focal length
    ``f = (W/2) / tan(fov/2)`` [pixels]; its solid angle per unit pixel area is
    ``f / (x^2 + y^2 + f^2)^(3/2)``. No pixel is masked.
    """

    name = "camera"

    def __init__(self, width: int, height: int | None = None, fov_deg: float = 20.0,
                 position=(0.0, 0.0, 36e6), look_at=(0.0, 0.0, -6_371_000.0), up=(0.0, 1.0, 0.0)):
        self.width = _check_size("width", width)
        self.height = self.width if height is None else _check_size("height", height)
        self.fov_deg = check_number("fov_deg", fov_deg, 0.0, 179.0, "deg", low_open=True)
        self.position = _as_point("position", position)
        self.look_at = _as_point("look_at", look_at)
        up = _as_point("up", up)
        fwd = self.look_at - self.position
        n = np.linalg.norm(fwd)
        if not n > 0.0:
            raise ValueError("look_at must differ from position")
        fwd = fwd / n
        right = np.cross(fwd, up)
        rn = np.linalg.norm(right)
        if not rn > 1e-9 * max(np.linalg.norm(up), 1e-300):
            raise ValueError(f"up = {tuple(up)} is parallel to the view direction {tuple(fwd)}")
        right = right / rn
        self.forward = fwd
        self.right = right
        self.up = np.cross(right, fwd)
        self.focal_px = 0.5 * self.width / math.tan(math.radians(0.5 * self.fov_deg))
        self._convention = ("perspective pinhole: image right along forward x up, image top "
                            "along up; focal length (W/2)/tan(fov/2) pixels; ENU frame of the "
                            "sub-camera point, origin on the surface")

    def direction_from_pixel(self, row, col) -> np.ndarray:
        row, col = np.broadcast_arrays(np.asarray(row, dtype=np.float64),
                                       np.asarray(col, dtype=np.float64))
        x = col - 0.5 * self.width
        y = 0.5 * self.height - row
        d = (self.forward * self.focal_px + self.right * x[..., None] + self.up * y[..., None])
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        bad = ((row < 0) | (row > self.height) | (col < 0) | (col > self.width)
               | ~np.isfinite(row + col))
        d[bad] = np.nan
        return d

    def pixel_from_direction(self, directions) -> tuple[np.ndarray, np.ndarray]:
        d = _as_dirs(directions)
        z = d @ self.forward
        with np.errstate(invalid="ignore", divide="ignore"):
            x = self.focal_px * (d @ self.right) / z
            y = self.focal_px * (d @ self.up) / z
        col = x + 0.5 * self.width
        row = 0.5 * self.height - y
        bad = (~(z > 0.0) | ~np.isfinite(row) | ~np.isfinite(col) | (row < 0) | (row > self.height)
               | (col < 0) | (col > self.width))
        return np.where(bad, np.nan, row), np.where(bad, np.nan, col)

    def _jacobian(self, row, col) -> np.ndarray:
        x = col - 0.5 * self.width
        y = 0.5 * self.height - row
        f = self.focal_px
        return f / (x * x + y * y + f * f) ** 1.5

    def describe(self) -> dict[str, Any]:
        out = super().describe()
        out.update({"fov_deg": self.fov_deg, "position_m": self.position.tolist(),
                    "look_at_m": self.look_at.tolist(), "up": self.up.tolist()})
        return out

    def __repr__(self) -> str:
        return (f"Camera(width={self.width}, height={self.height}, fov_deg={self.fov_deg:g}, "
                f"position={self.position.tolist()}, look_at={self.look_at.tolist()})")

    def __hash__(self) -> int:
        return hash((type(self).__name__, self.width, self.height, self.fov_deg))
