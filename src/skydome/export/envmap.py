"""Environment maps for renderers and engines: lat-long, pbrt-v4 equal-area, Radiance
fisheye and cube maps in each tool's own convention (:mod:`skydome.export.conventions`),
float32 or half EXR and Radiance .hdr, order-2 irradiance spherical harmonics.

Units of the maps: linear RGB with Rec. 709 / sRGB primaries (D65 white) in
W m^-2 sr^-1 on the photometric scale luminance = 683 lm/W x (0.2126 R + 0.7152 G +
0.0722 B), so that a renderer's white Lambertian plane lit by the map has radiance x pi x 683
= illuminance in lx, and a sun lamp of "strength" E in W m^-2 (Blender) or irradiance E
(Mitsuba) matches the map when E = illuminance / 683 (:mod:`skydome.export.sun`). The
``radiance`` convention's .hdr files use Radiance's own scale instead (179 lm/W). These are
the ``photometric`` units; a convention may name its tool's own units instead
(:data:`skydome.export.conventions.UNITS`): the ``mitsuba`` convention writes Mitsuba 3's
(luminance = 683 lm/W x 106.7503 nm x Y(RGB)), in which its spectral emitters and
``sunsky`` meet the map; ``units=`` chooses either for any convention.

The sky and the ground come from :func:`skydome.imaging.render` through a
:class:`MapProjection` (the convention's pixel layout as a skydome projection), without
the sun (a lat-long map in bands of rows, the same pixels as one render of the whole map
with less memory: :func:`_render_latlong_bands`); the sun is the render's own sun light
(``SkyImage.sun_light``), either left out (exported as a light,
``EnvironmentMap.sun_light``) or added energy-true into the pixel that holds its centre
(``sun="map"``). Below the horizon the map holds, by default, the
render's Lambertian ground (:mod:`skydome.imaging.ground`: ``L = albedo E_h / pi`` with
E_h the model's sky and sun on a horizontal plane, and the model's albedo,
:func:`skydome.imaging.ground.model_albedo`, or the one given); ``ground="black"`` leaves
zero, ``ground="model"`` keeps what the render's ``ground="model"`` gives there (the
model's own ground, else that Lambertian one).

References
----------
.. [RH01] R. Ramamoorthi, P. Hanrahan, "An Efficient Representation for Irradiance
   Environment Maps", SIGGRAPH 2001: eqs. 3 (the real SH basis to order 2, constants
   0.282095, 0.488603, 1.092548, 0.315392, 0.546274), 7-8 (A_0 = pi, A_1 = 2 pi / 3,
   A_2 = pi / 4) and 10.
.. [GL46] The OpenGL 4.6 core profile specification, section 8.13 "Cube Map Texture
   Selection", table 8.19 (major axis and s_c, t_c per face); the same face table as
   Direct3D and RenderMan.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from skydome.export.conventions import Convention, Units, get_convention, resolve_units
from skydome.imaging.projections import Projection
from skydome.imaging import _one_blas_thread

__all__ = ["MapProjection", "CubeFaceProjection", "EnvironmentMap", "render_envmap",
           "FACES", "LAYOUTS", "cube_face_direction", "cube_face_from_direction",
           "sh_basis", "irradiance_sh", "sh_irradiance", "K_M", "HALF_MAX",
           "check_envmap_options", "check_map_path"]

#: Luminous efficacy of the maps' photometric scale [lm/W].
K_M = 683.0
#: Radiance's white efficacy [lm/W] (its .hdr files).
from skydome.constants import RADIANCE_WHITE_EFFICACY as RADIANCE_EFFICACY  # noqa: E402
#: Largest finite half float.
HALF_MAX = 65504.0
#: Cube faces in file order.
FACES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")
#: Layouts: one image (latlong, equiarea, fisheye), six faces stacked (cubemap), six files
#: (faces) or a horizontal cross.
LAYOUTS = ("latlong", "equiarea", "fisheye", "cubemap", "faces", "cross")
_CUBE_LAYOUTS = ("cubemap", "faces", "cross")
_NATIVE = {"latlong": "latlong", "equiarea": "equiarea", "fisheye": "fisheye"}
# the cross: (face, row, column) in a 3 x 4 grid of faces [GL46] table orientation
_CROSS = (("+Y", 0, 1), ("-X", 1, 0), ("+Z", 1, 1), ("+X", 1, 2), ("-Z", 1, 3), ("-Y", 2, 1))


def _jacobian_numeric(proj: Projection, row, col, h: float = 1e-3) -> np.ndarray:
    """Solid angle per pixel^2 [sr] from central differences of direction_from_pixel."""
    dr = (proj.direction_from_pixel(row + h, col) - proj.direction_from_pixel(row - h, col))
    dc = (proj.direction_from_pixel(row, col + h) - proj.direction_from_pixel(row, col - h))
    return np.linalg.norm(np.cross(dr, dc), axis=-1) / (4.0 * h * h)


class _Cached:
    """Directions and solid angles computed once per projection (read-only arrays)."""

    def directions(self):
        if getattr(self, "_dirs", None) is None:
            d, m = self._pixel_directions()
            d.setflags(write=False)
            m.setflags(write=False)
            self._dirs = (d, m)
        return self._dirs

    def _pixel_directions(self):
        return Projection.directions(self)

    def solid_angles(self):
        if getattr(self, "_omega", None) is None:
            _, m = self.directions()
            w = np.where(m, self._exact_solid_angles(), 0.0)
            w.setflags(write=False)
            self._omega = w
        return self._omega


class MapProjection(_Cached, Projection):
    """A convention's single-image layout (lat-long, equal-area square or fisheye) as a
    skydome :class:`~skydome.imaging.projections.Projection` (directions in ENU)."""

    def __init__(self, convention, width: int, height: int):
        from skydome.imaging.projections import _check_size

        self.convention = get_convention(convention)
        self.layout = self.convention.layouts[0] if self.convention.layouts[0] in _NATIVE else "latlong"
        self.width = _check_size("width", width)
        self.height = _check_size("height", height)
        self.name = f"{self.convention.name}-{self.layout}"
        self._convention = f"{self.convention.name}: {self.convention.centre}"

    def direction_from_pixel(self, row, col) -> np.ndarray:
        row, col = np.broadcast_arrays(np.asarray(row, dtype=np.float64),
                                       np.asarray(col, dtype=np.float64))
        d = self.convention.direction_from_uv(col / self.width, row / self.height)
        bad = (row < 0) | (row > self.height) | (col < 0) | (col > self.width)
        d[bad] = np.nan
        return d

    def pixel_from_direction(self, directions) -> tuple[np.ndarray, np.ndarray]:
        from skydome.imaging.projections import _as_dirs

        u, v = self.convention.uv_from_direction(_as_dirs(directions))
        return v * self.height, u * self.width

    def _pixel_directions(self):
        """The pixel centres' directions; a lat-long map's are separable: every lat-long
        layout has v = zenith angle / pi, so d(u, v) = sin(pi v) h(u) + cos(pi v) up, with
        h(u) the horizontal unit vector of column u. Computed as that outer product (one
        sin and cos per row and per column instead of per pixel), the same values, bit for
        bit, as direction_from_pixel at every centre (the tool -> ENU matrices are signed
        permutations: exact)."""
        if self._latlong_axes() is None:
            return Projection.directions(self)
        return self._latlong_rows(0, self.height), np.ones(self.shape, dtype=bool)

    def _latlong_axes(self):
        """(sin, cos) of the rows' zenith angles and (h_x, h_y) of the columns' horizontal
        unit vectors of a lat-long map with +z up (cached), else None."""
        if self.layout != "latlong":
            return None
        if getattr(self, "_axes", None) is None:
            conv = self.convention
            if not np.array_equal(conv.direction_from_uv(0.0, 0.0), (0.0, 0.0, 1.0)):
                self._axes = ()
                return None
            v = (np.arange(self.height, dtype=np.float64) + 0.5) / self.height
            u = (np.arange(self.width, dtype=np.float64) + 0.5) / self.width
            h = conv.direction_from_uv(u, np.full_like(u, 0.5))   # sin(pi / 2) = 1 exactly
            # z = cos(pi v) (h's own z, cos(pi / 2), is 6e-17 and unused)
            self._axes = (np.sin(np.pi * v), np.cos(np.pi * v), np.ascontiguousarray(h[:, 0]),
                          np.ascontiguousarray(h[:, 1]))
        return self._axes or None

    def _latlong_rows(self, r0: int, r1: int) -> np.ndarray:
        """Directions (r1 - r0, W, 3) of rows r0:r1 of a separable lat-long map: (s h_x,
        s h_y, c) in one parallel pass."""
        from skydome.export._kernels_envmap import latlong_directions

        s, c, hx, hy = self._latlong_axes()
        d = np.empty((r1 - r0, self.width, 3))
        latlong_directions(s[r0:r1], c[r0:r1], hx, hy, d)
        return d

    def _jacobian(self, row, col) -> np.ndarray:
        if self.layout == "latlong":
            # every lat-long layout has v = zenith angle / pi: dOmega = sin(theta) dtheta dphi
            return (np.sin(np.pi * row / self.height) * (np.pi / self.height)
                    * (2.0 * np.pi / self.width))
        if self.layout == "equiarea":
            return np.full(np.shape(row), 4.0 * np.pi / (self.width * self.height))
        return _jacobian_numeric(self, row, col)

    def _exact_solid_angles(self) -> np.ndarray:
        if self.layout == "latlong":
            # a pixel spans 2 pi / W in azimuth and zenith angles pi i / H .. pi (i + 1) / H
            edges = np.cos(np.pi * np.arange(self.height + 1) / self.height)
            band = (edges[:-1] - edges[1:]) * (2.0 * np.pi / self.width)
            return np.repeat(band[:, None], self.width, axis=1)
        if self.layout == "equiarea":
            return np.full(self.shape, 4.0 * np.pi / (self.width * self.height))
        return Projection.solid_angles(self)


class _LatLongBand(Projection):
    """Rows r0:r1 of a separable lat-long :class:`MapProjection` as a projection of their
    own (a map rendered in bands of rows: each band's directions, pixels and the model's
    values are those rows' of the whole map's)."""

    def __init__(self, parent: MapProjection, r0: int, r1: int):
        self.parent = parent
        self.r0 = r0
        self.width = parent.width
        self.height = r1 - r0
        self.name = parent.name
        self._convention = parent._convention

    def directions(self):
        return (self.parent._latlong_rows(self.r0, self.r0 + self.height),
                np.ones(self.shape, dtype=bool))

    def direction_from_pixel(self, row, col) -> np.ndarray:
        return self.parent.direction_from_pixel(np.asarray(row, dtype=np.float64) + self.r0,
                                                col)

    def pixel_from_direction(self, directions) -> tuple[np.ndarray, np.ndarray]:
        r, c = self.parent.pixel_from_direction(directions)
        return r - self.r0, c

    def _jacobian(self, row, col) -> np.ndarray:
        return self.parent._jacobian(np.asarray(row, dtype=np.float64) + self.r0, col)

    def describe(self) -> dict[str, Any]:
        return dict(self.parent.describe(), rows=[self.r0, self.r0 + self.height])


def _sky_rows(proj: MapProjection) -> int | None:
    """The number of rows with z = cos(zenith) >= 0 (the model's, above the horizon) of a
    separable lat-long map when they are its first rows, else None."""
    axes = proj._latlong_axes()
    if axes is None:
        return None
    c = axes[1]
    n = int(np.count_nonzero(c >= 0.0))
    return n if bool(np.all(c[:n] >= 0.0)) else None


def _render_latlong_bands(sky, proj: MapProjection, wl, ground, progress, chunk: int = 262144):
    """(the map's RGB (H, W, 3), the render's sun light) of a separable lat-long map
    rendered in bands of rows, each band's XYZ turned into the map's RGB while it is in
    the cache (:func:`_xyz_to_map_rgb`); ``ground`` a render ground other than "model".

    The same values as one :func:`skydome.imaging.render` of the whole map: every pixel's
    direction and every model value are the same (a band is a whole number of the render's
    chunks where the width divides ``chunk``, as the whole map's sky is), and the rows
    below the horizon (z = cos(zenith) < 0 along a whole row) hold the render's ground,
    the same value in every pixel (a black or Lambertian ground): rendered for one row
    and copied. What it saves is memory: the whole map's directions (24 bytes a pixel)
    are never held, and on the 2-core virtual machine of docs/performance.md the first
    touch of fresh memory costs about 1 ms per MB."""
    from skydome.imaging import render

    render_ = getattr(render, "__wrapped__", render)     # render_envmap holds BLAS's limit
    H, W = proj.height, proj.width
    n_sky = _sky_rows(proj)
    rgb = np.empty((H, W, 3))
    rows = max(1, chunk // W)
    light = None

    def band(r0, r1):
        img = render_(sky, _LatLongBand(proj, r0, r1), wl, draw_sun=False, output="xyz",
                      ground=ground, chunk=chunk)
        rgb[r0:r1] = _xyz_to_map_rgb(img.data, img.mask)
        if progress is not None:
            progress(r1 * W, H * W)
        return img.sun_light

    for r0 in range(0, n_sky, rows):
        light = band(r0, min(r0 + rows, n_sky))
    if n_sky < H:
        ground_light = band(n_sky, n_sky + 1)
        light = ground_light if light is None else light
        first = rgb[n_sky]
        if n_sky + 1 < H:
            if np.all(first == first[0]):
                rgb[n_sky + 1:] = first
                if progress is not None:
                    progress(H * W, H * W)
            else:                                        # not a uniform ground: every row
                for r0 in range(n_sky + 1, H, rows):
                    band(r0, min(r0 + rows, H))
    return rgb, light


# -- cube faces [GL46] table 8.19 ------------------------------------------------------------
def cube_face_direction(face: str, sc, tc) -> np.ndarray:
    """Direction (..., 3), in the cube's axes, of face coordinates s_c, t_c in [-1, 1]
    (t_c down from the top row), unnormalised."""
    sc, tc = np.broadcast_arrays(np.asarray(sc, dtype=np.float64), np.asarray(tc, dtype=np.float64))
    one = np.ones_like(sc)
    table = {"+X": (one, -tc, -sc), "-X": (-one, -tc, sc), "+Y": (sc, one, tc),
             "-Y": (sc, -one, -tc), "+Z": (sc, -tc, one), "-Z": (-sc, -tc, -one)}
    return np.stack(table[face], axis=-1)


def cube_face_from_direction(d) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(face index into FACES, s, t) in [0, 1] of directions (..., 3) in the cube's axes:
    the major axis picks the face ([GL46] table 8.19)."""
    d = np.asarray(d, dtype=np.float64)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
    major = np.where((ax >= ay) & (ax >= az), 0, np.where(ay >= az, 1, 2))
    face = np.where(major == 0, np.where(x >= 0, 0, 1),
                    np.where(major == 1, np.where(y >= 0, 2, 3), np.where(z >= 0, 4, 5)))
    ma = np.choose(major, [ax, ay, az])
    sc = np.choose(face, [-z, z, x, x, x, -x])
    tc = np.choose(face, [-y, -y, z, -z, -y, -y])
    return face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0)


class CubeFaceProjection(_Cached, Projection):
    """One N x N face of a cube map in the convention's cube axes (directions in ENU): the
    tool's axes, except for three.js, which looks cube textures up with x negated."""

    def __init__(self, convention, face: str, size: int):
        from skydome.imaging.projections import _check_size

        if face not in FACES:
            raise ValueError(f"face = {face!r} is not one of {', '.join(FACES)}")
        self.convention = get_convention(convention)
        self.face = face
        self.width = self.height = _check_size("size", size)
        self.name = f"{self.convention.name}-cube{face}"
        self._convention = f"{self.convention.name} axes, face {face} [GL46]"

    def direction_from_pixel(self, row, col) -> np.ndarray:
        row, col = np.broadcast_arrays(np.asarray(row, dtype=np.float64),
                                       np.asarray(col, dtype=np.float64))
        d = cube_face_direction(self.face, 2.0 * col / self.width - 1.0,
                                2.0 * row / self.height - 1.0)
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        d = d @ self.convention.cube_matrix             # cube axes -> ENU
        bad = (row < 0) | (row > self.height) | (col < 0) | (col > self.width)
        d[bad] = np.nan
        return d

    def pixel_from_direction(self, directions) -> tuple[np.ndarray, np.ndarray]:
        from skydome.imaging.projections import _as_dirs

        face, s, t = cube_face_from_direction(_as_dirs(directions) @ self.convention.cube_matrix.T)
        mine = face == FACES.index(self.face)
        return (np.where(mine, t * self.height, np.nan), np.where(mine, s * self.width, np.nan))

    def _jacobian(self, row, col) -> np.ndarray:
        # dOmega = dA / (1 + sc^2 + tc^2)^(3/2) on the unit cube face (side 2)
        sc = 2.0 * col / self.width - 1.0
        tc = 2.0 * row / self.height - 1.0
        return (2.0 / self.width) * (2.0 / self.height) / (1.0 + sc * sc + tc * tc) ** 1.5

    def _exact_solid_angles(self) -> np.ndarray:
        # solid angle of the face rectangle [0, x] x [0, y] at distance 1: atan(x y /
        # sqrt(1 + x^2 + y^2)); a pixel is the difference of its four corners
        e = 2.0 * np.arange(self.width + 1) / self.width - 1.0
        X, Y = np.meshgrid(e, e, indexing="xy")
        F = np.arctan2(X * Y, np.sqrt(1.0 + X * X + Y * Y))
        return F[1:, 1:] - F[1:, :-1] - F[:-1, 1:] + F[:-1, :-1]


# -- spherical harmonics [RH01] -----------------------------------------------------------------
def sh_basis(d) -> np.ndarray:
    """Real SH basis Y_00, Y_1-1, Y_10, Y_11, Y_2-2, Y_2-1, Y_20, Y_21, Y_22 at unit vectors
    (..., 3) given in any frame's (x, y, z) ([RH01] eq. 3), shape (..., 9)."""
    d = np.asarray(d, dtype=np.float64)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    c = _SH_C
    return np.stack([np.full_like(x, c[0]), c[1] * y, c[1] * z, c[1] * x,
                     c[2] * x * y, c[2] * y * z, c[3] * (3.0 * z * z - 1.0),
                     c[2] * x * z, c[4] * (x * x - y * y)], axis=-1)


# [RH01] eq. 3 constants in full precision (printed there as 0.282095, 0.488603, 1.092548,
# 0.315392, 0.546274)
_SH_C = (0.5 / np.sqrt(np.pi), np.sqrt(3.0 / (4.0 * np.pi)), 0.5 * np.sqrt(15.0 / np.pi),
         0.25 * np.sqrt(5.0 / np.pi), 0.25 * np.sqrt(15.0 / np.pi))
_SH_BAND = np.array([0, 1, 1, 1, 2, 2, 2, 2, 2])
_A_HAT = np.array([np.pi, 2.0 * np.pi / 3.0, np.pi / 4.0])         # [RH01] eqs. 7-8


def irradiance_sh(radiance_rgb, directions_tool, solid_angles) -> np.ndarray:
    """Order-2 SH coefficients L_lm (9, 3) of a radiance map: sum of L Y_lm dOmega over the
    pixels ([RH01] eq. 10 as a quadrature)."""
    L = np.asarray(radiance_rgb, dtype=np.float64).reshape(-1, 3)
    Y = sh_basis(np.asarray(directions_tool).reshape(-1, 3))
    w = np.asarray(solid_angles, dtype=np.float64).reshape(-1)
    return Y.T @ (L * w[:, None])


def sh_irradiance(coefficients, normals_tool) -> np.ndarray:
    """Irradiance E(n) = sum_lm A_l L_lm Y_lm(n) (..., 3) [W m^-2] at unit normals in the
    coefficients' frame ([RH01] eq. 8)."""
    c = np.asarray(coefficients, dtype=np.float64) * _A_HAT[_SH_BAND][:, None]
    return sh_basis(normals_tool) @ c


# -- the map ----------------------------------------------------------------------------------
@dataclass
class EnvironmentMap:
    """A rendered environment map.

    Attributes
    ----------
    images : dict
        Image name -> (H, W, 3) float64 RGB radiance [W m^-2 sr^-1] (see module units):
        ``{"map": ...}`` for single-image layouts, ``{"+X": ..., ..., "-Z": ...}`` for cube
        layouts.
    projections : dict
        Image name -> the :class:`~skydome.imaging.projections.Projection` of its pixels.
    convention : Convention
    layout : str
    metadata : dict
    units : Units
        The scale of the RGB values (default: the convention's own).
    sun_light : dict or None
        The map's sun as a light in the convention (:func:`skydome.export.sun.sun_light_from`
        of the render's own sun light, at the map's wavelengths): the light that lit its
        Lambertian ground and that ``sun="map"`` put into it; None without a sun above the
        horizon.
    """

    images: dict
    projections: dict
    convention: Convention
    layout: str
    metadata: dict = field(default_factory=dict)
    units: Units | None = None

    def __post_init__(self):
        self.units = resolve_units(self.convention, self.units)
    sun_light: dict | None = None

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """ENU directions (n, 3) and solid angles (n,) of every pixel of every image."""
        ds, ws = [], []
        for name in self.images:
            p = self.projections[name]
            d, m = p.directions()
            ds.append(d.reshape(-1, 3))
            ws.append(np.where(m, p.solid_angles(), 0.0).reshape(-1))
        return np.concatenate(ds), np.concatenate(ws)

    def pixels(self) -> np.ndarray:
        """Every pixel's RGB (n, 3), in the order of :meth:`directions`."""
        return np.concatenate([im.reshape(-1, 3) for im in self.images.values()])

    def irradiance_sh(self) -> np.ndarray:
        """Order-2 irradiance SH (9, 3) of the map, in the convention's axes [RH01]."""
        d, w = self.directions()
        return irradiance_sh(self.pixels(), self.convention.to_tool(d), w)

    def assembled(self) -> np.ndarray:
        """The image as written for single-file layouts: the map, the six faces stacked
        top to bottom in FACES order (cubemap) or the horizontal cross (zeros off the cross)."""
        if self.layout in _NATIVE:
            return self.images["map"]
        n = self.images["+X"].shape[0]
        if self.layout == "cubemap":
            return np.concatenate([self.images[f] for f in FACES], axis=0)
        out = np.zeros((3 * n, 4 * n, 3))
        for f, r, c in _CROSS:
            out[r * n:(r + 1) * n, c * n:(c + 1) * n] = self.images[f]
        return out

    # -- writing ----------------------------------------------------------------------------
    def write(self, path, half: bool = False, also=()) -> list[Path]:
        """Write the map (.exr float32 or ``half``, or .hdr) atomically; ``layout="faces"``
        writes six files ``<stem>_px``, ``_nx``, ``_py``, ``_ny``, ``_pz``, ``_nz``.
        ``also``: (path, write) pairs of files that belong with the map, e.g. its sun light
        (``(sun_path, skydome.export.sun.sun_json_writer(light))``); ``write(tmp)`` writes
        one to a temporary file. The map's files and these are one unit
        (:func:`skydome._io.atomic_files`): every one is written to a temporary first, then
        all are renamed; on a failure (a full disk) none is left. Returns the paths
        written."""
        p = check_map_path(path, half)
        if self.layout == "faces":
            names = {"+X": "px", "-X": "nx", "+Y": "py", "-Y": "ny", "+Z": "pz", "-Z": "nz"}
            targets = [(p.with_name(f"{p.stem}_{names[f]}{p.suffix}"), self.images[f]) for f in FACES]
        else:
            targets = [(p, self.assembled())]
        largest = max(float(np.max(im)) for _, im in targets) if half else None
        if half and largest > HALF_MAX:
            raise ValueError(f"the map's largest value {largest:.4g} "
                             f"exceeds the half-float range ({HALF_MAX:g}): the sun in the map "
                             "needs float32 (drop half) or export the sun as a light")
        import os

        from skydome._io import atomic_files

        writers = [(target, (lambda tmp, im=im: self._write_exr(tmp, im, half))
                    if target.suffix.lower() == ".exr" else
                    (lambda tmp, im=im: self._write_hdr(tmp, im))) for target, im in targets]
        writers += [(Path(q), w) for q, w in also]
        # all faces and the files that go with the map, or none
        with atomic_files([q for q, _ in writers]) as tmps:
            for (q, write), tmp in zip(writers, tmps):
                try:
                    write(tmp)
                except OSError as exc:   # name the file asked for, not its temporary
                    if exc.errno is None or exc.filename not in (None, tmp):
                        raise
                    raise OSError(exc.errno, exc.strerror or os.strerror(exc.errno),
                                  str(q)) from exc
        return [q for q, _ in writers]

    def _header(self) -> dict[str, str]:
        import json

        meta = dict(self.metadata)
        meta["convention"] = self.convention.describe()
        meta["layout"] = self.layout
        return {f"skydome:{k}": v if isinstance(v, str) else json.dumps(v, default=str)
                for k, v in meta.items()}

    def _write_exr(self, tmp: str, im: np.ndarray, half: bool) -> None:
        import OpenEXR

        from skydome.imaging.image import _SRGB_CHROMATICITIES

        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
                  "chromaticities": _SRGB_CHROMATICITIES,
                  # RGB (1, 1, 1) is 683 cd m^-2 on the photometric scale of the module
                  # docs, 683 x 106.7503 cd m^-2 in Mitsuba's units
                  "whiteLuminance": self.units.luminance_per_unit}
        header.update(self._header())
        header["units"] = self.units.description
        ch = dict(zip("RGB", _channel_planes(im, half)))
        from skydome._io import write_exr

        write_exr(tmp, header, ch)       # a full disk: OSError ENOSPC (OpenEXR: RuntimeError)

    def _write_hdr(self, tmp: str, im: np.ndarray) -> None:
        from skydome.imaging.image import rgbe_encode

        H, W = im.shape[:2]
        scale = K_M / RADIANCE_EFFICACY if self.convention.name == "radiance" else 1.0
        lines = [b"#?RADIANCE",
                 b"PRIMARIES= 0.6400 0.3300 0.3000 0.6000 0.1500 0.0600 0.3127 0.3290"]
        for k, v in self._header().items():
            text = " ".join(str(v).split())[:996]
            lines.append(f"{k.replace('skydome:', 'SKYDOME_').upper()}= {text}".encode("ascii", "replace"))
        if self.convention.name == "radiance":
            lines.append(b"VIEW= -vta -vp 0 0 0 -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 180")
        lines.append(b"FORMAT=32-bit_rle_rgbe")
        head = b"\n".join(lines) + b"\n\n" + f"-Y {H} +X {W}\n".encode()
        with open(tmp, "wb") as f:
            f.write(head)
            f.write(rgbe_encode(np.maximum(im, 0.0) * scale).tobytes())


def _channel_planes(im: np.ndarray, half: bool) -> tuple[np.ndarray, ...]:
    """The R, G and B planes (H, W) of an (H, W, 3) image as half or float32, each
    contiguous: ``im[..., i].astype(float16 or float32)`` bit for bit, in one parallel pass
    (:mod:`skydome.export._kernels_envmap`)."""
    from skydome._threads import run_ranges
    from skydome.export._kernels_envmap import (MIN_PIXELS_PER_THREAD, float32_planes,
                                                half_planes)

    im = np.ascontiguousarray(im, dtype=np.float64)
    H, W = im.shape[:2]
    flat = im.reshape(-1, 3)
    # three planes, not one (3, n) block: each small enough to come from memory the
    # process has already touched (fresh pages cost more than the conversion)
    if half:
        out = [np.empty(H * W, dtype=np.uint16) for _ in range(3)]
        run_ranges(half_planes, H * W, (flat.view(np.uint64), *out), MIN_PIXELS_PER_THREAD)
        out = [o.view(np.float16) for o in out]
    else:
        out = [np.empty(H * W, dtype=np.float32) for _ in range(3)]
        run_ranges(float32_planes, H * W, (flat, *out), MIN_PIXELS_PER_THREAD)
    return tuple(o.reshape(H, W) for o in out)


def check_map_path(path, half: bool = False) -> Path:
    """ValueError unless ``path`` ends in .exr or .hdr in a writable folder (and .exr if
    ``half``)."""
    from skydome.imaging.image import check_output_path

    p = Path(path)
    if p.suffix.lower() not in (".exr", ".hdr"):
        raise ValueError(f"output file {str(p)!r} has suffix {p.suffix!r}: an environment map "
                         "must be .exr or .hdr")
    if half and p.suffix.lower() != ".exr":
        raise ValueError(f"half floats need an .exr file, not {str(p)!r}")
    return check_output_path(p)


def _parse_size(layout: str, size) -> tuple[int, int]:
    """(width, height) of a single image or (N, N) of a cube face from an int or 'WxH'."""
    if isinstance(size, str):
        parts = size.lower().split("x")
        try:
            vals = [int(s) for s in parts]
        except ValueError:
            raise ValueError(f"size = {size!r} must be N or WxH in pixels") from None
    elif isinstance(size, (tuple, list)):
        vals = [int(s) for s in size]
    else:
        vals = [int(size)]
    if len(vals) not in (1, 2) or min(vals) < 2 or max(vals) > 32768:
        raise ValueError(f"size = {size!r} is out of range: N or WxH, each in [2, 32768] pixels")
    if layout in _CUBE_LAYOUTS:
        if len(vals) == 2 and vals[0] != vals[1]:
            raise ValueError(f"size = {size!r}: cube faces are square (give N)")
        return vals[0], vals[0]
    if len(vals) == 1:
        w = vals[0]
        return w, (w if layout in ("equiarea", "fisheye") else max(2, w // 2))
    if layout in ("equiarea", "fisheye") and vals[0] != vals[1]:
        raise ValueError(f"size = {size!r}: the {layout} layout is square (give N)")
    return vals[0], vals[1]


def _sun_rgb(light: dict | None) -> np.ndarray:
    """RGB irradiance [W m^-2] (module scale) of a sun light of :mod:`skydome.export.sun`,
    or zeros without one."""
    if light is None:
        return np.zeros(3)
    return np.array(light["rgb_irradiance_W_m2"])


def check_envmap_options(convention, layout, size, sun="separate", ground="lambertian",
                         units=None):
    """Validate the options of :func:`render_envmap` before any work; returns
    (Convention, layout, (width, height))."""
    from skydome._validate import check_choice

    conv = get_convention(convention)
    resolve_units(conv, units)                          # ValueError naming units
    layout = conv.layouts[0] if layout is None else layout
    check_choice("layout", layout, LAYOUTS)
    allowed = set(conv.layouts) | (set(_CUBE_LAYOUTS) if "cubemap" in conv.layouts else set())
    if layout not in allowed:
        raise ValueError(f"layout = {layout!r} is not available for convention {conv.name!r} "
                         f"(valid: {', '.join(sorted(allowed))})")
    check_choice("sun", sun, ("separate", "map"))
    check_choice("ground", ground, ("lambertian", "black", "model"))
    return conv, layout, _parse_size(layout, size)


def _xyz_to_map_rgb(xyz: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The map's linear sRGB / 683 (H, W, 3) of an XYZ image, out-of-gamut negatives
    clipped, 0 where masked; computed in place in ``xyz`` (returned) by one parallel numba
    pass (:func:`skydome.export._kernels_envmap.xyz_to_map_rgb`: the values of
    ``np.maximum(xyz_to_linear_srgb(xyz) / 683, 0)``, no full-size temporaries)."""
    from skydome.export._kernels_envmap import xyz_to_map_rgb
    from skydome.spectra import _M_XYZ_TO_SRGB

    if not mask.all():
        xyz[~mask] = 0.0
    if not (xyz.flags.c_contiguous and xyz.dtype == np.float64):
        xyz = np.ascontiguousarray(xyz, dtype=np.float64)
    if xyz_to_map_rgb(xyz.reshape(-1, 3), _M_XYZ_TO_SRGB, K_M):
        raise ValueError("xyz contains NaN or infinite values")
    return xyz


@_one_blas_thread
def render_envmap(sky, convention: str = "skydome", size: Any = "1024x512",
                  layout: str | None = None, sun: str = "separate", ground: str = "lambertian",
                  ground_albedo: float | None = None, wavelengths_nm=None,
                  progress: Callable[[int, int], None] | None = None,
                  units: str | None = None) -> EnvironmentMap:
    """Render ``sky`` into an environment map in a tool's convention.

    Parameters
    ----------
    sky : SkyModel
    convention : str
        One of :data:`skydome.export.conventions.CONVENTIONS`.
    size : int, str or tuple
        ``N`` or ``"WxH"`` [pixels] for single images (lat-long default height W / 2;
        equal-area and fisheye square), ``N`` per face for cube layouts.
    layout : str, optional
        ``latlong``, ``equiarea``, ``fisheye``, ``cubemap`` (six faces stacked), ``faces``
        (six files) or ``cross``; default the convention's first layout. It must be one the
        convention lists (cube layouts: those with ``cubemap``).
    sun : str
        ``separate`` (not in the map; see :func:`skydome.export.sun.sun_light`) or ``map``
        (its irradiance added into the pixel holding its centre, energy-true).
    ground : str
        ``lambertian`` (albedo x E_h / pi below the horizon, for every model), ``black``
        or ``model`` (the render's ``ground="model"``).
    ground_albedo : float, optional
        In [0, 1]; default the model's albedo
        (:func:`skydome.imaging.ground.model_albedo`: its ``albedo`` parameter, else its
        atmosphere's ground albedo, else 0.2).
    wavelengths_nm : array_like, optional
        For spectral models, the sky's and the sun's (default
        :func:`skydome.spectra.default_wavelengths`, 41 samples 380-780 nm, those of
        :func:`skydome.export.sun.sun_light`).
    progress : callable, optional
        ``progress(done, total)`` over all pixels.
    units : str, optional
        Scale of the RGB values, a name of :data:`skydome.export.conventions.UNITS`:
        ``photometric`` (W m^-2 sr^-1, 683 lm/W) or ``mitsuba`` (Mitsuba 3's own); default
        the convention's (``mitsuba`` for the mitsuba convention, else photometric).
    """
    from skydome._validate import check_number
    from skydome.export.sun import sun_light_from
    from skydome.imaging import render
    from skydome.imaging.ground import horizontal_irradiance, model_albedo
    from skydome.spectra import default_wavelengths, spectrum_to_xyz, xyz_to_linear_srgb

    conv, layout, (W, H) = check_envmap_options(convention, layout, size, sun, ground,
                                                  units)
    if ground_albedo is not None:
        ground_albedo = check_number("ground_albedo", ground_albedo, 0.0, 1.0)
    wl = default_wavelengths() if wavelengths_nm is None else wavelengths_nm
    # the ground as imaging.render makes it (skydome.imaging.ground: one Lambertian ground,
    # one albedo rule): the model's albedo, a given one, black, or the model's own ground
    if ground == "lambertian":
        render_ground = "lambertian" if ground_albedo is None else ground_albedo
    else:
        render_ground = ground

    if layout in _CUBE_LAYOUTS:
        projections = {f: CubeFaceProjection(conv, f, W) for f in FACES}
    else:
        projections = {"map": MapProjection(conv, W, H)}
    total = sum(p.width * p.height for p in projections.values())
    done = [0]

    images = {}
    sun_light = None
    for name, proj in projections.items():
        base = done[0]

        def prog(k, n, base=base, size=proj.width * proj.height):
            # render reports the pixels it samples (not those the ground replaces)
            if progress is not None:
                progress(base + (size if k >= n else k * size // max(n, 1)), total)
        if (isinstance(proj, MapProjection) and render_ground != "model"
                and _sky_rows(proj) is not None):
            images[name], sun_light = _render_latlong_bands(sky, proj, wl, render_ground,
                                                            prog)
        else:
            img = render(sky, proj, wl, draw_sun=False, progress=prog, output="xyz",
                         ground=render_ground)
            images[name] = _xyz_to_map_rgb(img.data, img.mask)   # (the image's own array)
            sun_light = img.sun_light                  # the same for every image
        done[0] += proj.width * proj.height

    # the image's own sun light, in the convention (None: no sun above the horizon)
    light = None if sun_light is None else sun_light_from(sun_light, sky.sun, conv,
                                                                  units)
    env = EnvironmentMap(images, projections, conv, layout, units=units,
                         sun_light=light)
    E_sun = _sun_rgb(light)
    # the irradiance on a horizontal plane that lights the Lambertian ground (its sky and
    # sun), in the map's RGB
    spectral = getattr(sky, "native", "spectral") == "spectral"
    wl_h = np.asarray(wl, dtype=np.float64) if spectral else None
    E_h_xyz = horizontal_irradiance(sky, wl_h)
    if spectral:
        E_h_xyz = spectrum_to_xyz(E_h_xyz, wl_h)
    E_h = xyz_to_linear_srgb(E_h_xyz) / K_M
    if ground_albedo is None:
        ground_albedo = model_albedo(sky)
    if sun == "map" and light is not None:
        s = np.asarray(sky.sun.direction)
        best = None
        for name, proj in projections.items():
            r, c = proj.pixel_from_direction(s)
            if np.isfinite(r) and np.isfinite(c):
                best = (name, min(int(r), proj.height - 1), min(int(c), proj.width - 1))
                break
        name, r, c = best
        omega = projections[name].solid_angles()[r, c]
        images[name][r, c] += E_sun / omega
    env.metadata = {"model": getattr(sky, "name", type(sky).__name__),
                    "parameters": sky.describe().get("parameters", {}) if hasattr(sky, "describe") else {},
                    "sun": "in the map" if sun == "map" else "separate light",
                    "ground": ground, "ground_albedo": ground_albedo,
                    "horizontal_irradiance_rgb_W_m2": [float(x) for x in E_h],
                    "units": env.units.description, "units_name": env.units.name}
    # everything above is on the photometric scale; the map leaves in its units
    if env.units.scale != 1.0:
        for name in images:
            images[name] *= env.units.scale
    if sky.sun is not None:
        env.metadata["sun_position"] = {"elevation_deg": sky.sun.elevation_deg,
                                        "azimuth_deg": sky.sun.azimuth_deg}
    return env
