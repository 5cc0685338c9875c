"""Image geometry below every layer that uses it: the :class:`Projection` protocol (how the
pixels of an image map to directions and back) and the pinhole :class:`Camera`.

Models that own a view (``nishita1993``'s earth from space) and effects that work on a
photograph (``dobashi2002``'s aerial perspective, the airlight driver) build a Camera here,
and :func:`skydome.imaging.render` renders any Projection; so neither models nor effects
import :mod:`skydome.imaging`. The sky projections (fisheye, equirect, angular map) are in
:mod:`skydome.imaging.projections`.

Pixel convention: continuous coordinates ``(row, col)``, row down from the top edge, column
right from the left edge; pixel ``(i, j)`` covers ``[i, i+1) x [j, j+1)``, its centre is at
``(i + 0.5, j + 0.5)``. Directions are unit vectors in the East-North-Up frame.
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from skydome._validate import check_number

__all__ = ["Projection", "Camera"]

_MAX_SIZE = 32768
_MIN_SIZE = 2


def _check_size(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer number of pixels, got {value!r}")
    v = int(value)
    if not _MIN_SIZE <= v <= _MAX_SIZE:
        raise ValueError(f"{name} = {v} is out of range [{_MIN_SIZE}, {_MAX_SIZE}] pixels")
    return v


class Projection:
    """Base class: a mapping between pixels of an (H, W) image and sky directions.

    Subclasses implement :meth:`direction_from_pixel`, :meth:`pixel_from_direction` and
    :meth:`_jacobian` (solid angle per unit pixel area [sr/pixel^2] at a pixel position)
    and set ``name``, ``width`` and ``height``.
    """

    name: str = ""
    width: int = 0
    height: int = 0
    #: Radiance view options giving the same pixel -> direction mapping (None: none does)
    radiance_view: str | None = None

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W): image height and width [pixels]."""
        return (self.height, self.width)

    def _centres(self) -> tuple[np.ndarray, np.ndarray]:
        rows = np.arange(self.height, dtype=np.float64) + 0.5
        cols = np.arange(self.width, dtype=np.float64) + 0.5
        return np.meshgrid(rows, cols, indexing="ij")

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Directions of the pixel centres.

        Returns
        -------
        dirs : numpy.ndarray
            Shape (H, W, 3), float64 unit vectors (East-North-Up) of the pixel centres.
            Masked pixels hold the placeholder (0, 0, -1) (nadir); they are never sampled.
        mask : numpy.ndarray
            Shape (H, W), bool: True where the pixel centre maps to a direction.
        """
        r, c = self._centres()
        d = self.direction_from_pixel(r, c)
        mask = np.all(np.isfinite(d), axis=-1)
        d[~mask] = (0.0, 0.0, -1.0)
        return d, mask

    def solid_angles(self) -> np.ndarray:
        """Solid angle of every pixel [sr], shape (H, W); 0 where masked.

        Each unmasked pixel's solid angle is the projection's Jacobian (solid angle per
        unit pixel area) integrated over the whole pixel with a 4 x 4 midpoint rule
        (exactly, for ``Equirect``); pixels on the edge of a disc count whole when their
        centre is inside and not at all otherwise. Their sum approximates 4 pi (full
        sphere) or 2 pi (hemisphere).
        """
        _, mask = self.directions()
        r0, c0 = np.meshgrid(np.arange(self.height, dtype=np.float64),
                             np.arange(self.width, dtype=np.float64), indexing="ij")
        return np.where(mask, self._pixel_jacobian_mean(r0, c0), 0.0)

    def _pixel_jacobian_mean(self, r0, c0) -> np.ndarray:
        """The Jacobian's 4 x 4 midpoint mean over the pixels with corners (r0, c0). On a
        disc's rim the sub-samples outside the disc (no direction, a NaN Jacobian) are left
        out, so that a rim pixel counts whole with the mean of its inside samples (the rule
        of :meth:`solid_angles`); inside, the same sums in the same order as ever."""
        n = 4
        offs = (np.arange(n) + 0.5) / n
        acc = np.zeros(np.shape(r0))
        count = np.zeros(np.shape(r0))
        for dr in offs:
            for dc in offs:
                j = self._jacobian(r0 + dr, c0 + dc)
                ok = np.isfinite(j)
                acc += np.where(ok, j, 0.0)
                count += ok
        return np.where(count == n * n, acc / (n * n), acc / np.maximum(count, 1.0))

    def solid_angles_at(self, flat_index) -> np.ndarray:
        """Solid angles [sr] of the pixels ``flat_index`` (indices into the flattened (H, W)
        image, row-major): ``solid_angles().reshape(-1)[flat_index]``, computed for those
        pixels alone where the projection uses the generic rule of :meth:`solid_angles`
        (the same 4 x 4 midpoint sums in the same order, so the same bits), else taken
        from the whole image's."""
        flat_index = np.asarray(flat_index, dtype=np.int64)
        if type(self).solid_angles is not Projection.solid_angles:
            return self.solid_angles().reshape(-1)[flat_index]
        r0 = (flat_index // self.width).astype(np.float64)
        c0 = (flat_index % self.width).astype(np.float64)
        inside = np.all(np.isfinite(self.direction_from_pixel(r0 + 0.5, c0 + 0.5)), axis=-1)
        return np.where(inside, self._pixel_jacobian_mean(r0, c0), 0.0)

    def direction_from_pixel(self, row, col) -> np.ndarray:
        """Unit direction(s) (..., 3) at continuous pixel coordinates; NaN where the
        position maps to no direction (outside the image or the projection's disc)."""
        raise NotImplementedError

    def pixel_from_direction(self, directions) -> tuple[np.ndarray, np.ndarray]:
        """Continuous pixel coordinates (row, col) of unit direction(s) (..., 3); pixel
        centres lie at i + 0.5. NaN where the direction is not in the image."""
        raise NotImplementedError

    def _jacobian(self, row, col) -> np.ndarray:
        raise NotImplementedError

    def sun_pixel(self, sun) -> tuple[float, float] | None:
        """Continuous pixel coordinates (row, col) of the centre of ``sun`` (a
        :class:`skydome.Sun`); None when the sun is below the horizon (elevation < 0), NaN
        when it is above the horizon but outside the image."""
        if sun.elevation_deg < 0:
            return None
        r, c = self.pixel_from_direction(np.asarray(sun.direction, dtype=np.float64))
        return float(r), float(c)

    def describe(self) -> dict[str, Any]:
        """Name, size and orientation convention of the projection."""
        return {"projection": self.name, "width": self.width, "height": self.height,
                "convention": self._convention}

    _convention = ""

    def __repr__(self) -> str:
        return f"{type(self).__name__}(width={self.width}, height={self.height})"

    def __eq__(self, other) -> bool:
        return type(self) is type(other) and self.describe() == other.describe()

    def __hash__(self) -> int:
        return hash((type(self).__name__, self.width, self.height))


def _as_dirs(directions) -> np.ndarray:
    d = np.asarray(directions, dtype=np.float64)
    if d.ndim == 0 or d.shape[-1] != 3:
        raise ValueError(f"directions must have shape (..., 3), got {d.shape}")
    n = np.linalg.norm(d, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return d / n




_SIZE_RE = re.compile(r"^\s*(\d+)\s*(?:[xX]\s*(\d+)\s*)?$")


def _parse_size(size: Any) -> tuple[int, int | None]:
    if isinstance(size, (int, np.integer)) and not isinstance(size, bool):
        w, h = int(size), None
    elif isinstance(size, str) and _SIZE_RE.match(size):
        m = _SIZE_RE.match(size)
        w = int(m.group(1))
        h = None if m.group(2) is None else int(m.group(2))
    else:
        raise ValueError(f"size = {size!r} is not an image size: give N or WxH "
                         f"with whole numbers in [{_MIN_SIZE}, {_MAX_SIZE}] pixels")
    for v in (w, h):
        if v is not None and not _MIN_SIZE <= v <= _MAX_SIZE:
            raise ValueError(f"size = {str(size)!r} is out of range: every side must be in "
                             f"[{_MIN_SIZE}, {_MAX_SIZE}] pixels")
    return w, h


def _as_point(name: str, value) -> np.ndarray:
    p = np.asarray(value, dtype=np.float64)
    if p.shape != (3,):
        raise ValueError(f"{name} must be a point (x, y, z) [m], got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} = {tuple(p)} is not finite")
    return p


def _direction(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit vector (East-North-Up) of an elevation and an azimuth from north towards east."""
    el, az = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)])


class Camera(Projection):
    """A perspective (pinhole) camera, placed in one of two ways.

    * **By a view direction** (a photograph from the ground, as for aerial perspective):
      ``Camera(fov_deg=60, azimuth_deg=0, elevation_deg=2, altitude_m=300)``; the camera
      stands at ``(east_m, north_m, altitude_m)`` and looks towards the azimuth (from north
      towards east) and elevation, with the image's top towards the zenith.
    * **By points** (any view, e.g. the earth from space):
      ``Camera(640, 480, 30, position=(0, 0, 36e6), look_at=(0, 0, -6.371e6), up=(0, 1, 0))``.

    With ``width`` (and ``height``) it is a :class:`Projection` that
    :func:`skydome.imaging.render` renders; without, :meth:`ray_directions` gives the rays of
    an image of any size.

    Parameters
    ----------
    width, height : int, optional
        Image size [pixels], 2..32768 each (``height`` defaults to ``width``).
    fov_deg : float
        Full field of view across the image width [deg], in (0, 179] (default 60). Square
        pixels: the vertical field of view follows from the aspect ratio.
    position, look_at : array_like (3,), optional
        Camera position and the point it looks at [m], East-North-Up frame of the
        sub-camera point with its origin on the surface (the planet's centre at (0, 0, -R)).
        Give both or neither.
    up : array_like (3,)
        With ``position``: the direction that appears upwards (default north, (0, 1, 0));
        it must not be parallel to the view direction. Otherwise the zenith.
    azimuth_deg, elevation_deg : float
        Without ``position``: the view direction [deg]; elevation in [-89, 89] (default 0, 0).
    altitude_m, east_m, north_m : float
        Without ``position``: the eye's height above the ground [m], >= 0 (default 300),
        and its horizontal position [m] (default 0, 0).

    Attributes
    ----------
    forward, right, up : ndarray (3,)
        The camera's unit axes (view direction; image right = forward x up; image top).
    fov_deg, azimuth_deg, elevation_deg, altitude_m, east_m, north_m : float
        The view in either placement (for a camera placed by points, the angles of its view
        direction and its position's coordinates).

    Notes
    -----
    A pixel at continuous coordinates (row, col) looks along
    ``forward * f + right * (col - W/2) + up * (H/2 - row)`` with the focal length
    ``f = (W/2) / tan(fov/2)`` [pixels], as Radiance's ``-vtv`` perspective view; its solid
    angle per unit pixel area is ``f / (x^2 + y^2 + f^2)^(3/2)``. No pixel is masked.
    """

    name = "camera"

    def __init__(self, width: int | None = None, height: int | None = None, fov_deg: float = 60.0,
                 position=None, look_at=None, up=None, *, azimuth_deg: float | None = None,
                 elevation_deg: float | None = None, altitude_m: float | None = None,
                 east_m: float = 0.0, north_m: float = 0.0):
        self.width = None if width is None else _check_size("width", width)
        if height is not None and width is None:
            raise ValueError("height needs a width")
        self.height = self.width if height is None else _check_size("height", height)
        self.fov_deg = check_number("fov_deg", fov_deg, 0.0, 179.0, "deg", low_open=True)
        if (position is None) != (look_at is None):
            raise ValueError("give both position and look_at, or neither (then azimuth_deg, "
                             "elevation_deg and altitude_m place the camera)")
        if position is not None:
            if azimuth_deg is not None or elevation_deg is not None or altitude_m is not None:
                raise ValueError("give either position/look_at or azimuth_deg/elevation_deg/"
                                 "altitude_m, not both")
            self.position = _as_point("position", position)
            self.look_at = _as_point("look_at", look_at)
            up = _as_point("up", (0.0, 1.0, 0.0) if up is None else up)
            fwd = self.look_at - self.position
            n = np.linalg.norm(fwd)
            if not n > 0.0:
                raise ValueError("look_at must differ from position")
            fwd = fwd / n
        else:
            az = check_number("azimuth_deg", 0.0 if azimuth_deg is None else azimuth_deg,
                              -360.0, 720.0, "deg")
            el = check_number("elevation_deg", 0.0 if elevation_deg is None else elevation_deg,
                              -89.0, 89.0, "deg")
            alt = check_number("altitude_m", 300.0 if altitude_m is None else altitude_m, 0.0, 1e9, "m")
            self.position = np.array([check_number("east_m", east_m, unit="m"),
                                      check_number("north_m", north_m, unit="m"), alt])
            fwd = _direction(el, az)
            self.look_at = self.position + fwd
            up = np.array([0.0, 0.0, 1.0]) if up is None else _as_point("up", up)
        right = np.cross(fwd, up)
        rn = np.linalg.norm(right)
        if not rn > 1e-9 * max(np.linalg.norm(up), 1e-300):
            raise ValueError(f"up = {tuple(up)} is parallel to the view direction {tuple(fwd)}")
        self.forward = fwd
        self.right = right / rn
        self.up = np.cross(self.right, fwd)
        self.east_m, self.north_m, self.altitude_m = (float(v) for v in self.position)
        self.elevation_deg = math.degrees(math.asin(max(-1.0, min(1.0, float(fwd[2])))))
        self.azimuth_deg = (math.degrees(math.atan2(float(fwd[0]), float(fwd[1]))) % 360.0
                            if azimuth_deg is None else float(azimuth_deg))
        self._convention = ("perspective pinhole: image right along forward x up, image top "
                            "along up; focal length (W/2)/tan(fov/2) pixels; ENU frame of the "
                            "sub-camera point, origin on the surface")

    @classmethod
    def make(cls, camera: Any) -> "Camera":
        """A Camera, or ``(fov_deg, view_direction[, altitude_m])`` with ``view_direction`` a
        vector (3,) in East-North-Up."""
        if isinstance(camera, Camera):
            return camera
        if isinstance(camera, (tuple, list)) and len(camera) in (2, 3):
            d = np.asarray(camera[1], dtype=np.float64)
            if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) == 0:
                raise ValueError(f"camera view direction must be a non-zero vector (3,), got {camera[1]!r}")
            d = d / np.linalg.norm(d)
            el = math.degrees(math.asin(max(-1.0, min(1.0, float(d[2])))))
            az = math.degrees(math.atan2(float(d[0]), float(d[1]))) % 360.0
            kw = {} if len(camera) == 2 else {"altitude_m": float(camera[2])}
            return cls(fov_deg=float(camera[0]), azimuth_deg=az, elevation_deg=el, **kw)
        raise TypeError(f"camera must be a Camera or (fov_deg, view_direction), got {type(camera).__name__}")

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(forward, right, up) unit vectors of the camera in East-North-Up."""
        return self.forward, self.right, self.up

    def _focal(self, width: int) -> float:
        return 0.5 * width / math.tan(math.radians(0.5 * self.fov_deg))

    @property
    def focal_px(self) -> float:
        """Focal length [pixels] of the camera's own image width."""
        return self._focal(self._size()[1])

    def _size(self) -> tuple[int, int]:
        if self.width is None:
            raise ValueError("this camera has no image size: give width (and height) to use it "
                             "as a projection, or call ray_directions(width, height)")
        return self.height, self.width

    def _centres(self) -> tuple[np.ndarray, np.ndarray]:
        self._size()
        return super()._centres()

    def _rays(self, row, col, width: int, height: int) -> np.ndarray:
        f = self._focal(width)
        x = col - 0.5 * width
        y = 0.5 * height - row
        d = self.forward * f + self.right * x[..., None] + self.up * y[..., None]
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def ray_directions(self, width: int, height: int) -> np.ndarray:
        """Unit ray directions through the pixel centres of a ``width`` x ``height`` image,
        shape (height, width, 3); row 0 is the top of the image."""
        from skydome._validate import check_int

        w, h = check_int("width", width, 1, _MAX_SIZE), check_int("height", height, 1, _MAX_SIZE)
        r, c = np.meshgrid(np.arange(h) + 0.5, np.arange(w) + 0.5, indexing="ij")
        return self._rays(r, c, w, h)

    def direction_from_pixel(self, row, col) -> np.ndarray:
        H, W = self._size()
        row, col = np.broadcast_arrays(np.asarray(row, dtype=np.float64),
                                       np.asarray(col, dtype=np.float64))
        d = self._rays(row, col, W, H)
        bad = (row < 0) | (row > H) | (col < 0) | (col > W) | ~np.isfinite(row + col)
        d[bad] = np.nan
        return d

    def pixel_from_direction(self, directions) -> tuple[np.ndarray, np.ndarray]:
        H, W = self._size()
        d = _as_dirs(directions)
        f = self._focal(W)
        z = d @ self.forward
        with np.errstate(invalid="ignore", divide="ignore"):
            x = f * (d @ self.right) / z
            y = f * (d @ self.up) / z
        col = x + 0.5 * W
        row = 0.5 * H - y
        bad = (~(z > 0.0) | ~np.isfinite(row) | ~np.isfinite(col) | (row < 0) | (row > H)
               | (col < 0) | (col > W))
        return np.where(bad, np.nan, row), np.where(bad, np.nan, col)

    def _jacobian(self, row, col) -> np.ndarray:
        H, W = self._size()
        x = col - 0.5 * W
        y = 0.5 * H - row
        f = self._focal(W)
        return f / (x * x + y * y + f * f) ** 1.5

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W): image height and width [pixels]."""
        return self._size()

    def describe(self) -> dict[str, Any]:
        self._size()
        out = super().describe()
        out.update({"fov_deg": self.fov_deg, "position_m": self.position.tolist(),
                    "look_at_m": self.look_at.tolist(), "up": self.up.tolist()})
        return out

    def __repr__(self) -> str:
        return (f"Camera(width={self.width}, height={self.height}, fov_deg={self.fov_deg:g}, "
                f"position={self.position.tolist()}, look_at={self.look_at.tolist()})")

    def __eq__(self, other) -> bool:
        return (type(self) is type(other) and (self.width, self.height, self.fov_deg)
                == (other.width, other.height, other.fov_deg)
                and np.array_equal(self.position, other.position)
                and np.array_equal(self.forward, other.forward) and np.array_equal(self.up, other.up))

    def __hash__(self) -> int:
        return hash((type(self).__name__, self.width, self.height, self.fov_deg))
