"""Projections: how the pixels of a sky image map to directions in the sky.

Every projection maps continuous pixel coordinates ``(row, col)`` (row down from the top
edge, column right from the left edge, pixel ``(i, j)`` covering ``[i, i+1) x [j, j+1)``
so that its centre is at ``(i + 0.5, j + 0.5)``) to unit direction vectors in the
East-North-Up frame (x east, y north, z up; azimuth from north towards east), and back.

Conventions
-----------
``Equirect`` (latitude-longitude environment map)
    Column coordinate ``col`` runs with azimuth: ``azimuth = 360 deg * col / W``, so the
    left edge is north (azimuth 0), a quarter of the way across is east, the image centre
    is south (azimuth 180) and three quarters across is west; azimuth increases from left
    to right. Row coordinate runs down from the zenith: ``elevation = 90 deg - 180 deg *
    row / H`` (full sphere, bottom edge = nadir) or ``90 deg - 90 deg * row / H``
    (``hemisphere=True``, bottom edge = horizon). This is the layout of the common HDR
    latitude-longitude environment maps (zenith at the top, horizon across the middle).
``Fisheye``
    Hemispherical equidistant ("angular") fisheye identical to Radiance's
    ``rpict -vta -vp 0 0 0 -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 180`` (a camera looking up with
    north at the top of the picture): zenith at the image centre, distance from the centre
    proportional to the zenith angle, the horizon on the inscribed circle. Looking up at
    the sky, north is at the top and east on the LEFT (west on the right). Pixels whose
    centre lies outside the circle are masked.
``AngularMap``
    Debevec's angular map (light probe) layout [Deb98] applied to the whole sphere looking
    up: zenith at the centre, radius proportional to the angle from the zenith, the horizon
    on the circle of half the radius and the nadir on the edge circle; north up and east
    left as for the fisheye. Pixels whose centre lies outside the edge circle are masked.
    This is also Radiance's ``-vta`` view with ``-vh 360 -vv 360``.

References
----------
.. [Ward98] G. Ward, "rpict" manual page and ``image.c:viewray`` of the Radiance
   synthetic imaging system (view type ``-vta``, angular fisheye).
.. [Deb98] P. Debevec, "Rendering synthetic objects into real scenes", SIGGRAPH 1998,
   and the "Light Probe Image Gallery" angular map format (radius proportional to angle,
   r = 1 at 180 deg from the view direction).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from skydome._validate import check_choice
from skydome.camera import _MIN_SIZE, Projection, _as_dirs, _check_size, _parse_size  # noqa: F401 (re-exported)

__all__ = ["Projection", "Equirect", "Fisheye", "AngularMap", "make_projection", "PROJECTION_NAMES"]

PROJECTION_NAMES = ("fisheye", "equirect", "equirect-hemisphere", "angular")
class Equirect(Projection):
    """Equirectangular (latitude-longitude) map of the full sphere or the upper hemisphere.

    Parameters
    ----------
    width : int
        Image width [pixels], 2..32768; the columns span azimuth 0..360 deg.
    height : int, optional
        Image height [pixels]; default ``width // 2`` (full sphere, square pixels in
        angle) or ``width // 4`` (``hemisphere=True``).
    hemisphere : bool
        If True the rows span elevation 90..0 deg (zenith to horizon) only.

    Notes
    -----
    ``azimuth = 360 deg * col / W`` (left edge north, then east, centre south, west) and
    ``elevation = 90 deg - E * row / H`` with E = 180 deg (full) or 90 deg (hemisphere).
    """

    def __init__(self, width: int, height: int | None = None, hemisphere: bool = False):
        self.width = _check_size("width", width)
        self.hemisphere = bool(hemisphere)
        if height is None:
            height = max(_MIN_SIZE, self.width // (4 if self.hemisphere else 2))
        self.height = _check_size("height", height)
        self.name = "equirect-hemisphere" if self.hemisphere else "equirect"
        self._span = 0.5 * np.pi if self.hemisphere else np.pi  # elevation span [rad]
        self._convention = (
            "row 0 at the zenith, elevation = 90 deg - %g deg * row / H; azimuth = 360 deg * "
            "col / W from north (left edge) through east, south at the centre, west"
            % np.degrees(self._span))

    def direction_from_pixel(self, row, col) -> np.ndarray:
        row, col = np.broadcast_arrays(np.asarray(row, dtype=np.float64),
                                       np.asarray(col, dtype=np.float64))
        el = 0.5 * np.pi - self._span * row / self.height
        az = 2.0 * np.pi * col / self.width
        ce = np.cos(el)
        d = np.stack([ce * np.sin(az), ce * np.cos(az), np.sin(el)], axis=-1)
        bad = (row < 0) | (row > self.height) | (col < 0) | (col > self.width) | ~np.isfinite(row + col)
        d[bad] = np.nan
        return d

    def pixel_from_direction(self, directions) -> tuple[np.ndarray, np.ndarray]:
        d = _as_dirs(directions)
        x, y, z = d[..., 0], d[..., 1], d[..., 2]
        el = np.arctan2(z, np.hypot(x, y))
        az = np.arctan2(x, y) % (2.0 * np.pi)
        row = (0.5 * np.pi - el) / self._span * self.height
        col = az / (2.0 * np.pi) * self.width
        bad = ~np.isfinite(row) | ~np.isfinite(col) | (row > self.height)
        row = np.where(bad, np.nan, row)
        col = np.where(bad, np.nan, col)
        return row, col

    def _jacobian(self, row, col) -> np.ndarray:
        el = 0.5 * np.pi - self._span * row / self.height
        return np.cos(el) * (self._span / self.height) * (2.0 * np.pi / self.width)

    def solid_angles(self) -> np.ndarray:
        """Exact solid angle of each pixel [sr]: ``dphi * (sin(el_top) - sin(el_bottom))``."""
        edges = 0.5 * np.pi - self._span * np.arange(self.height + 1) / self.height
        band = np.sin(edges[:-1]) - np.sin(edges[1:])
        return np.repeat((band * 2.0 * np.pi / self.width)[:, None], self.width, axis=1)

    def solid_angles_at(self, flat_index) -> np.ndarray:
        """Exact solid angles [sr] of the pixels ``flat_index`` (row-major flat indices), as
        :meth:`solid_angles` gives them."""
        row = np.asarray(flat_index, dtype=np.int64) // self.width
        top = 0.5 * np.pi - self._span * row / self.height
        bottom = 0.5 * np.pi - self._span * (row + 1) / self.height
        return (np.sin(top) - np.sin(bottom)) * 2.0 * np.pi / self.width


class _Polar(Projection):
    """Square image, zenith at the centre, angle from the zenith = ``scale * rho`` where
    ``rho`` is the distance from the centre in units of the image width; looking up with
    north at the top and east on the left (Radiance -vd 0 0 1 -vu 0 1 0)."""

    _scale = np.pi  # zenith angle [rad] per image width

    def __init__(self, size: int):
        self.width = self.height = _check_size("size", size)

    def _max_angle(self) -> float:
        return 0.5 * self._scale

    def direction_from_pixel(self, row, col) -> np.ndarray:
        row, col = np.broadcast_arrays(np.asarray(row, dtype=np.float64),
                                       np.asarray(col, dtype=np.float64))
        # Radiance image.c viewray(), VT_ANG: x, y in [-1/2, 1/2] of the view size,
        # angle from the view direction = |(x vh, y vv)| with vh = vv = 180 deg.
        x = col / self.width - 0.5        # towards image right = hvec = vdir x vup = west
        y = 0.5 - row / self.height       # towards image top = vup = north
        rho = np.hypot(x, y)
        theta = self._scale * rho
        with np.errstate(invalid="ignore", divide="ignore"):
            s = np.where(rho > 0.0, np.sin(theta) / np.where(rho > 0, rho, 1.0), self._scale)
        d = np.stack([-x * s, y * s, np.cos(theta)], axis=-1)
        bad = ~(theta <= self._max_angle() + 1e-12)  # round-off on the edge circle
        d[bad] = np.nan
        return d

    def pixel_from_direction(self, directions) -> tuple[np.ndarray, np.ndarray]:
        d = _as_dirs(directions)
        e, n, z = d[..., 0], d[..., 1], d[..., 2]
        h = np.hypot(e, n)
        theta = np.arctan2(h, z)
        rho = theta / self._scale
        with np.errstate(invalid="ignore", divide="ignore"):
            f = np.where(h > 0.0, rho / np.where(h > 0, h, 1.0), 0.0)
        x = -e * f
        y = n * f
        col = (x + 0.5) * self.width
        row = (0.5 - y) * self.height
        bad = ~(theta <= self._max_angle()) | ~np.isfinite(row) | ~np.isfinite(col)
        return np.where(bad, np.nan, row), np.where(bad, np.nan, col)

    def _jacobian(self, row, col) -> np.ndarray:
        # dOmega = sin(theta) dtheta dphi, theta = k rho, pixel area = W^2 rho drho dphi:
        # dOmega / dA = k sin(k rho) / (W^2 rho)  (-> k^2 / W^2 at the centre)
        x = col / self.width - 0.5
        y = 0.5 - row / self.height
        rho = np.hypot(x, y)
        k = self._scale
        with np.errstate(invalid="ignore", divide="ignore"):
            j = np.where(rho > 0.0, k * np.sin(k * rho) / np.where(rho > 0, rho, 1.0), k * k)
        # Not cut at the disc's edge: a pixel whose centre is inside counts whole, one
        # whose centre is outside not at all, so the edge errors cancel on average.
        return np.maximum(j, 0.0) / (self.width * self.height)


class Fisheye(_Polar):
    """Hemispherical angular fisheye looking up, as Radiance's ``rpict -vta -vd 0 0 1
    -vu 0 1 0 -vh 180 -vv 180``.

    Parameters
    ----------
    size : int
        Width = height [pixels], 2..32768.

    Notes
    -----
    Zenith at the centre; the distance from the centre is proportional to the zenith angle
    (equidistant), with the horizon on the inscribed circle (radius ``size / 2``). North
    is at the top and east on the left, as seen looking up at the sky. Pixels whose centre
    lies outside the circle are masked.
    """

    name = "fisheye"
    _scale = np.pi          # 180 deg across the image width
    radiance_view = "-vta -vp 0 0 0 -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 180"
    _convention = ("Radiance rpict -vta -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 180: zenith at the "
                   "centre, radius proportional to zenith angle, horizon on the inscribed "
                   "circle, north up, east left (looking up)")


class AngularMap(_Polar):
    """Debevec angular map of the whole sphere, looking up.

    Parameters
    ----------
    size : int
        Width = height [pixels], 2..32768.

    Notes
    -----
    Zenith at the centre; radius proportional to the angle from the zenith; the horizon
    on the circle of half the image radius, the nadir on the edge circle. North up, east
    left (as the fisheye). Pixels whose centre lies outside the edge circle are masked.
    """

    name = "angular"
    _scale = 2.0 * np.pi    # 360 deg across the image width
    radiance_view = "-vta -vp 0 0 0 -vd 0 0 1 -vu 0 1 0 -vh 360 -vv 360"
    _convention = ("Debevec angular map looking up: zenith at the centre, radius "
                   "proportional to angle from the zenith, horizon at half radius, nadir on "
                   "the edge circle, north up, east left")


def make_projection(name: str, size: Any) -> Projection:
    """Build a projection from its name and a size.

    Parameters
    ----------
    name : {"fisheye", "equirect", "equirect-hemisphere", "angular"}
    size : int or str
        ``N`` (fisheye/angular: N x N; equirect: width N, default height) or ``"WxH"``
        (fisheye and angular need W == H).

    Raises
    ------
    ValueError
        Unknown name, or a size that is not ``N``/``WxH`` with sides in [2, 32768].
    """
    check_choice("projection", name, PROJECTION_NAMES)
    w, h = _parse_size(size)
    if name in ("fisheye", "angular"):
        if h is not None and h != w:
            raise ValueError(f"size = {str(size)!r} is not square: the {name} projection "
                             f"needs N or NxN")
        return Fisheye(w) if name == "fisheye" else AngularMap(w)
    return Equirect(w, h, hemisphere=(name == "equirect-hemisphere"))
