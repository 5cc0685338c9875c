"""Environment-map conventions of renderers and engines: how a pixel of their map maps to a
direction of their world, and how their world's axes sit against skydome's East-North-Up.

Each :class:`Convention` has

* ``axes``: the 3 x 3 matrix taking an ENU vector (x east, y north, z up) to the tool's
  world axes (rows: the tool's x, y and z expressed in ENU);
* a pixel layout: ``uv_from_direction`` / ``direction_from_uv`` with u in [0, 1) left to
  right and v in [0, 1] from the TOP row down (the orientation in which the image file is
  stored and viewed), transcribed from the tool's own lookup code (cited per convention).

* ``units``: the name of the tool's own scale of RGB radiance (a :class:`Units` of
  :data:`UNITS`), the default in which maps and sun lights are written for it.

Which horizontal axis is north is not fixed by most tools (they have no geography); the
choice made here is stated per convention and the sun light exported with the map
(:mod:`skydome.export.sun`) uses the same axes, so map and sun always agree.

Units
-----
``photometric`` (every convention but ``mitsuba``): RGB radiance in W m^-2 sr^-1 with
luminance = 683 lm/W x Y(RGB), Y(RGB) = 0.2126 R + 0.7152 G + 0.0722 B; Blender's sun
strength and world strength, three.js, Unity, Unreal and pbrt read it so (a white
Lambertian plane's radiance x pi x 683 = its illuminance in lx).

``mitsuba``: Mitsuba 3's own scale, in which its spectral emitters (``sunsky``, a
``spectrum`` in W m^-2 sr^-1 nm^-1) and RGB maps meet. Its films turn spectral radiance L
into Y = integral of L y-bar d(lambda) [nm] x ``MI_CIE_Y_NORMALIZATION`` with
``MI_CIE_Y_NORMALIZATION = 1 / 106.7502593994140625`` ([Mitsuba3-spectrum]), and its
``sunsky`` multiplies the Hosek-Wilkie RGB dataset (whose Y is integral L y-bar
d(lambda)) by the same constant ([Mitsuba3-sunsky]). With luminance = 683 lm/W x
integral L y-bar d(lambda), Mitsuba's Y = luminance / (683 x 106.7503): skydome's
photometric values divided by :data:`MITSUBA_Y_NORMALIZATION_NM`. (The CIE 1931 y-bar,
1 nm table 360-830 nm, integrates to 106.857 nm; Mitsuba's constant is 0.1 % below it, so
in Mitsuba's spectral variants a spectrum of 1 W m^-2 sr^-1 nm^-1 renders Y = 1.001;
skydome follows Mitsuba's constant, which is what its renders divide by.)

References
----------
.. [Cycles] Blender Cycles, ``kernel/camera/projection.h``: ``direction_to_equirectangular``
   = ``direction_to_equirectangular_range(dir, (-2 pi, pi, -pi, pi))``, u = (atan2(y, x) - pi)
   / (-2 pi), v = (acos(z) - pi) / (-pi) with v up from the bottom row; Blender is Z-up
   and right-handed.
.. [Mitsuba3] Mitsuba 3, ``src/emitters/envmap.cpp``: uv = (atan2(x, -z) / (2 pi),
   acos(y) / pi) (v down from the top row); Y-up, right-handed.
.. [pbrt4] M. Pharr, W. Jakob, G. Humphreys, "Physically Based Rendering", 4th ed.,
   section 3.8.3 (equal-area octahedral mapping of Clarberg 2008) and ``ImageInfiniteLight``,
   which looks up ``EqualAreaSphereToSquare(w)`` in a square image; Z-up as the scenes of
   the book.
.. [UE] Unreal Engine, ``TextureCompressorModule.cpp``, ``FImageViewLongLat::LookupLongLat``:
   X = (1 + atan2(D.x, -D.y) / pi) / 2, Y = acos(D.z) / pi (after the face-to-world swap
   of y and z); Z-up, left-handed (X forward, Y right).
.. [Unity] Unity built-in ``Skybox/Panoramic`` shader, ``ToRadialCoords``: uv = (0.5, 1) -
   (atan2(z, x) / (2 pi), acos(y) / pi), v up from the bottom row; Y-up, left-handed
   (Z forward, X right).
.. [three] three.js ``common.glsl.js``, ``equirectUv``: u = atan(z, x) / (2 pi) + 0.5,
   v = asin(y) / pi + 0.5, v up from the bottom row; Y-up, right-handed (the default camera
   looks down -Z). Cube textures are looked up with ``vec3(flipEnvMap * d.x, d.yz)``,
   ``flipEnvMap = -1`` for cube textures made from images (``envmap_fragment.glsl.js``,
   ``WebGLBackground.js``): their faces follow the left-handed RenderMan table.
.. [GL46] The OpenGL 4.6 core profile specification, section 8.13, table 8.19 (cube-map
   face selection; the same table as Direct3D and RenderMan).
.. [Radiance] G. Ward, ``rpict`` manual: view type ``-vta`` (angular fisheye); Radiance
   scenes are Z-up with +Y north and +X east (``gensky``).
.. [Mitsuba3-spectrum] Mitsuba 3.9, ``include/mitsuba/core/spectrum.h``:
   ``MI_CIE_Y_NORMALIZATION (1.0 / 106.7502593994140625)``, applied in ``spectrum_to_xyz``
   and ``spectrum_to_srgb``.
.. [Mitsuba3-sunsky] Mitsuba 3.9, ``include/mitsuba/render/sunsky.h`` and
   ``src/emitters/sunsky.cpp``: the RGB sky ``res *= MI_CIE_Y_NORMALIZATION``; the spectral
   sky in W m^-2 sr^-1 nm^-1; the sky's frame is Z-up (``cos_theta`` of the emitter-local
   direction), turned into the scene by ``to_world``; ``sun_direction`` is given in world
   space.
.. [Clarberg08] P. Clarberg, "Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD",
   Journal of Graphics Tools 13(3), 2008.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Convention", "CONVENTIONS", "get_convention", "equal_area_square_to_sphere",
           "equal_area_sphere_to_square", "Units", "UNITS", "get_units", "resolve_units",
           "MITSUBA_Y_NORMALIZATION_NM"]

_TWO_PI = 2.0 * np.pi


def _sph(theta, phi_x, phi_y):
    """Unit vector with polar angle ``theta`` from the up axis and the horizontal unit
    components (cos-like, sin-like) ``phi_x``, ``phi_y``."""
    s = np.sin(theta)
    return s * phi_x, s * phi_y, np.cos(theta)


def _acos(x):
    return np.arccos(np.clip(x, -1.0, 1.0))


# -- per-tool lat-long layouts: direction in the TOOL's axes <-> (u, v from the top) ----------
def _uv_skydome(d):
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return (np.arctan2(x, y) / _TWO_PI) % 1.0, _acos(z) / np.pi


def _dir_skydome(u, v):
    a = _TWO_PI * u                                  # azimuth from north towards east
    x, y, z = _sph(np.pi * v, np.sin(a), np.cos(a))
    return np.stack([x, y, z], axis=-1)


def _uv_blender(d):                                  # [Cycles]
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return (0.5 - np.arctan2(y, x) / _TWO_PI) % 1.0, _acos(z) / np.pi


def _dir_blender(u, v):
    phi = np.pi - _TWO_PI * u
    x, y, z = _sph(np.pi * v, np.cos(phi), np.sin(phi))
    return np.stack([x, y, z], axis=-1)


def _uv_mitsuba(d):                                  # [Mitsuba3]
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return (np.arctan2(x, -z) / _TWO_PI) % 1.0, _acos(y) / np.pi


def _dir_mitsuba(u, v):
    a = _TWO_PI * u
    sx, m_z, y = _sph(np.pi * v, np.sin(a), np.cos(a))
    return np.stack([sx, y, -m_z], axis=-1)


def _uv_unreal(d):                                   # [UE]
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return (0.5 + np.arctan2(x, -y) / _TWO_PI) % 1.0, _acos(z) / np.pi


def _dir_unreal(u, v):
    a = _TWO_PI * (u - 0.5)
    x, m_y, z = _sph(np.pi * v, np.sin(a), np.cos(a))
    return np.stack([x, -m_y, z], axis=-1)


def _uv_unity(d):                                    # [Unity]
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return (0.5 - np.arctan2(z, x) / _TWO_PI) % 1.0, _acos(y) / np.pi


def _dir_unity(u, v):
    phi = _TWO_PI * (0.5 - u)
    x, z, y = _sph(np.pi * v, np.cos(phi), np.sin(phi))
    return np.stack([x, y, z], axis=-1)


def _uv_three(d):                                    # [three]
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    # v_three = asin(y) / pi + 0.5 counts up from the bottom row: 1 - v_three = acos(y) / pi
    return (np.arctan2(z, x) / _TWO_PI + 0.5) % 1.0, _acos(y) / np.pi


def _dir_three(u, v):
    phi = _TWO_PI * (u - 0.5)
    x, z, y = _sph(np.pi * v, np.cos(phi), np.sin(phi))
    return np.stack([x, y, z], axis=-1)


# -- pbrt-v4: equal-area octahedral square [pbrt4] section 3.8.3, [Clarberg08] ---------------
def equal_area_square_to_sphere(u, v):
    """Unit vectors (..., 3) of points (u, v) in [0, 1]^2 of the equal-area octahedral
    square (centre = +z, corners = -z) [Clarberg08]."""
    uu, vv = 2.0 * np.asarray(u, dtype=np.float64) - 1.0, 2.0 * np.asarray(v, dtype=np.float64) - 1.0
    up, vp = np.abs(uu), np.abs(vv)
    signed = 1.0 - (up + vp)                          # signed distance from the diagonal
    r = 1.0 - np.abs(signed)
    with np.errstate(invalid="ignore", divide="ignore"):
        phi = np.where(r == 0.0, 1.0, (vp - up) / np.where(r == 0.0, 1.0, r) + 1.0) * np.pi / 4
    z = np.copysign(1.0 - r * r, signed)
    cos_p = np.copysign(np.cos(phi), uu)
    sin_p = np.copysign(np.sin(phi), vv)
    s = r * np.sqrt(np.maximum(2.0 - r * r, 0.0))
    return np.stack([cos_p * s, sin_p * s, z], axis=-1)


def equal_area_sphere_to_square(d):
    """(u, v) in [0, 1]^2 of unit vectors ``d`` (..., 3); the inverse of
    :func:`equal_area_square_to_sphere`."""
    d = np.asarray(d, dtype=np.float64)
    x, y, z = np.abs(d[..., 0]), np.abs(d[..., 1]), np.abs(d[..., 2])
    r = np.sqrt(np.maximum(1.0 - z, 0.0))
    a = np.maximum(x, y)
    b = np.minimum(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        b_over_a = np.where(a == 0.0, 0.0, b / np.where(a == 0.0, 1.0, a))
    phi = np.arctan(b_over_a) * 2.0 / np.pi
    phi = np.where(x < y, 1.0 - phi, phi)
    v = phi * r
    u = r - v
    neg = d[..., 2] < 0.0
    u, v = np.where(neg, 1.0 - v, u), np.where(neg, 1.0 - u, v)
    u = np.copysign(u, d[..., 0])
    v = np.copysign(v, d[..., 1])
    return 0.5 * (u + 1.0), 0.5 * (v + 1.0)


def _uv_pbrt(d):
    return equal_area_sphere_to_square(d)


def _dir_pbrt(u, v):
    return equal_area_square_to_sphere(u, v)


def _uv_radiance(d):
    """Angular fisheye of the upper hemisphere, ``rpict -vta -vd 0 0 1 -vu 0 1 0 -vh 180
    -vv 180``: north at the top, east on the left; NaN below the horizon."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    theta = _acos(z)
    rho = np.hypot(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(rho > 0, theta / (0.5 * np.pi) / np.where(rho > 0, rho, 1.0), 0.0)
    u = 0.5 - 0.5 * k * x
    v = 0.5 - 0.5 * k * y
    below = theta > 0.5 * np.pi
    return np.where(below, np.nan, u), np.where(below, np.nan, v)


def _dir_radiance(u, v):
    px, py = (0.5 - u) * 2.0, (0.5 - v) * 2.0          # east left, north up
    r = np.hypot(px, py)
    theta = 0.5 * np.pi * r
    with np.errstate(invalid="ignore", divide="ignore"):
        cx = np.where(r > 0, px / np.where(r > 0, r, 1.0), 0.0)
        cy = np.where(r > 0, py / np.where(r > 0, r, 1.0), 0.0)
    x, y, z = _sph(theta, cx, cy)
    out = np.stack([x, y, z], axis=-1)
    out[r > 1.0] = np.nan
    return out


# -- units of RGB radiance ---------------------------------------------------------------------
#: Luminous efficacy of skydome's photometric scale [lm/W] (the SI definition of the candela).
_K_M = 683.0
#: Mitsuba 3's normalisation of the CIE y-bar [nm]: ``1 / MI_CIE_Y_NORMALIZATION``
#: ([Mitsuba3-spectrum]; 3.9.1 exposes it as ``mitsuba.MI_CIE_Y_NORMALIZATION``).
MITSUBA_Y_NORMALIZATION_NM = 106.7502593994140625


@dataclass(frozen=True)
class Units:
    """A scale of RGB radiance (see the module's Units section).

    ``luminance_per_unit`` [cd m^-2]: the luminance of RGB values with Y(RGB) = 1
    (Rec. 709 weights); the same number is the illuminance [lx] of an RGB irradiance with
    Y = 1. ``scale`` multiplies skydome's photometric values (W m^-2 sr^-1, 683 lm/W)
    into these units.
    """

    name: str
    luminance_per_unit: float
    description: str
    reference: str

    @property
    def scale(self) -> float:
        """Factor from skydome's photometric RGB (683 lm/W) to these units."""
        return _K_M / self.luminance_per_unit

    def describe(self) -> dict:
        return {"units": self.name, "luminance_per_unit_cd_m2": self.luminance_per_unit,
                "from_photometric": self.scale, "description": self.description,
                "reference": self.reference}


UNITS: dict[str, Units] = {u.name: u for u in (
    Units("photometric", _K_M,
          "RGB radiance [W m^-2 sr^-1], Rec. 709 primaries, luminance = 683 lm/W x Y(RGB)",
          "the SI candela: 683 lm/W at 540 THz"),
    Units("mitsuba", _K_M * MITSUBA_Y_NORMALIZATION_NM,
          "Mitsuba 3 units: RGB radiance, Rec. 709 primaries, Y(RGB) = integral of spectral "
          "radiance [W m^-2 sr^-1 nm^-1] x y-bar d(lambda) [nm] / 106.7503, i.e. luminance = "
          "683 lm/W x 106.7503 nm x Y(RGB)",
          "Mitsuba 3 include/mitsuba/core/spectrum.h MI_CIE_Y_NORMALIZATION "
          "= 1 / 106.7502593994140625"),
)}


def get_units(name) -> Units:
    """The :class:`Units` called ``name``; ValueError listing the names otherwise."""
    if isinstance(name, Units):
        return name
    if name not in UNITS:
        raise ValueError(f"units = {name!r} is not one of {', '.join(UNITS)}")
    return UNITS[name]


def resolve_units(convention, units=None) -> Units:
    """``units`` if given, else the convention's own (:attr:`Convention.units`)."""
    return get_units(get_convention(convention).units if units is None else units)


@dataclass(frozen=True)
class Convention:
    """One tool's environment-map convention (see the module docstring)."""

    name: str
    tool: str
    up: str                  # the tool's up axis, e.g. "+Z"
    handedness: str          # "right" or "left"
    axes: tuple              # rows: the tool's x, y, z in ENU
    layouts: tuple           # image layouts the tool reads
    centre: str              # what the image centre looks at
    north: str               # the tool axis that skydome puts north
    reference: str
    _uv: object = None
    _dir: object = None
    cube_flip_x: bool = False    # the tool looks cube maps up with its x negated
    units: str = "photometric"   # the tool's own scale of RGB radiance (a name of UNITS)

    @property
    def cube_matrix(self) -> np.ndarray:
        """3 x 3 matrix taking ENU vectors to the axes in which the tool looks up cube-map
        faces ([GL46] face table): its own axes, x negated where ``cube_flip_x``."""
        m = self.matrix
        if self.cube_flip_x:
            m = m * np.array([[-1.0], [1.0], [1.0]])
        return m

    @property
    def matrix(self) -> np.ndarray:
        """3 x 3 matrix taking ENU vectors to the tool's axes (``tool = M @ enu``)."""
        return np.array(self.axes, dtype=np.float64)

    @property
    def matrix4(self) -> list:
        """The 4 x 4 affine form of :attr:`matrix` as nested lists: a renderer's
        ``to_world`` that turns an emitter defined in ENU-like axes (Z up, e.g. Mitsuba's
        ``sunsky``) into the tool's world."""
        m = np.eye(4)
        m[:3, :3] = self.matrix
        return m.tolist()

    def to_tool(self, enu) -> np.ndarray:
        """ENU vector(s) (..., 3) in the tool's axes."""
        return np.asarray(enu, dtype=np.float64) @ self.matrix.T

    def to_enu(self, tool) -> np.ndarray:
        """Tool-axis vector(s) (..., 3) in ENU (the matrix is orthogonal)."""
        return np.asarray(tool, dtype=np.float64) @ self.matrix

    def uv_from_direction(self, enu) -> tuple[np.ndarray, np.ndarray]:
        """(u, v) of ENU unit directions; u left to right in [0, 1), v from the top."""
        return self._uv(self.to_tool(enu))

    def direction_from_uv(self, u, v) -> np.ndarray:
        """ENU unit directions (..., 3) of image positions (u, v); NaN where none."""
        u, v = np.broadcast_arrays(np.asarray(u, dtype=np.float64),
                                   np.asarray(v, dtype=np.float64))
        return self.to_enu(self._dir(u, v))

    def describe(self) -> dict:
        return {"convention": self.name, "tool": self.tool, "up": self.up,
                "handedness": self.handedness, "axes_in_enu": [list(r) for r in self.axes],
                "image_centre": self.centre, "north": self.north,
                "layouts": list(self.layouts), "reference": self.reference,
                "units": self.units}


_E, _N, _U = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
_S = (0.0, -1.0, 0.0)

CONVENTIONS: dict[str, Convention] = {c.name: c for c in (
    Convention("skydome", "skydome", "+Z", "right", (_E, _N, _U),
               ("latlong", "cubemap", "cross"), "south (azimuth 180 deg); north at the left edge",
               "+Y", "skydome.imaging.projections.Equirect", _uv_skydome, _dir_skydome),
    Convention("blender", "Blender (Cycles, EEVEE) Environment Texture, equirectangular",
               "+Z", "right", (_E, _N, _U), ("latlong",),
               "+X = east; north (+Y) a quarter from the left edge", "+Y",
               "[Cycles] kernel/camera/projection.h", _uv_blender, _dir_blender),
    Convention("mitsuba", "Mitsuba 3 envmap emitter", "+Y", "right", (_E, _U, _S),
               ("latlong",), "+Z = south; north (-Z) at the left edge, east (+X) a quarter in",
               "-Z", "[Mitsuba3] src/emitters/envmap.cpp", _uv_mitsuba, _dir_mitsuba,
               units="mitsuba"),
    Convention("pbrt", "pbrt-v4 imageinfinite light (equal-area octahedral square)", "+Z",
               "right", (_E, _N, _U), ("equiarea",),
               "the zenith (+Z); the four corners are the nadir", "+Y",
               "[pbrt4] section 3.8.3, ImageInfiniteLight", _uv_pbrt, _dir_pbrt),
    Convention("unreal", "Unreal Engine long-lat cube map / HDRI backdrop", "+Z", "left",
               (_N, _E, _U), ("latlong", "cubemap", "cross"),
               "-Y = west; north (+X) three quarters across, east (+Y) at the edges", "+X",
               "[UE] TextureCompressorModule.cpp FImageViewLongLat", _uv_unreal, _dir_unreal),
    Convention("unity", "Unity Skybox/Panoramic (latitude-longitude) and cube maps", "+Y",
               "left", (_E, _U, _N), ("latlong", "cubemap", "cross"),
               "+X = east; north (+Z) a quarter from the left edge", "+Z",
               "[Unity] Skybox-Panoramic.shader ToRadialCoords", _uv_unity, _dir_unity),
    Convention("three", "three.js equirectangular textures and cube maps", "+Y", "right",
               (_E, _U, _S), ("latlong", "cubemap", "cross"),
               "+X = east; north (-Z) a quarter from the left edge", "-Z",
               "[three] src/renderers/shaders/ShaderChunk/common.glsl.js equirectUv",
               _uv_three, _dir_three, cube_flip_x=True),
    Convention("radiance", "Radiance angular fisheye (rpict -vta), upper hemisphere", "+Z",
               "right", (_E, _N, _U), ("fisheye",),
               "the zenith; north at the top, east on the left", "+Y",
               "[Radiance] rpict -vta", _uv_radiance, _dir_radiance),
)}


def get_convention(name) -> Convention:
    """The :class:`Convention` called ``name``; ValueError listing the names otherwise."""
    if isinstance(name, Convention):
        return name
    if name not in CONVENTIONS:
        raise ValueError(f"convention = {name!r} is not one of {', '.join(CONVENTIONS)}")
    return CONVENTIONS[name]
