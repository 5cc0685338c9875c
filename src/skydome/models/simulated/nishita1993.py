"""``nishita1993``: the earth and its atmosphere seen from anywhere, in space or in the air.

Nishita, Sirai, Tadamura & Nakamae, "Display of the Earth Taking into Account Atmospheric
Scattering", SIGGRAPH 93, 175-182 ([NSTN93]; survey section 7.3). Single scattering of
parallel sunlight by air molecules and aerosols in a spherical atmosphere, with the
optical depth to the sun read from the paper's spheres x cylinders lookup table, the
earth's shadow, and the light of the surface below (a uniform albedo, a sea coloured by
Fresnel reflection and scattering by the water with the sun's glint on its waves after
Cox & Munk 1954 [CM54], an albedo texture, or the earth's land from a Blue Marble map with
that sea around it) attenuated on its way to the camera. See ``docs/sections/nishita1993.md`` for the equations, the tables and
every departure from the paper.
"""

from __future__ import annotations

import math
import re

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_int, check_number
from skydome.models import ATMOSPHERE, TURBIDITY, Parameter, SkyModel, register

__all__ = ["Nishita1993", "parse_length"]

_SURFACES = ("ocean", "albedo", "texture", "earth")
_LENGTH_RE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(km|m)?\s*$")
_MAX_ALTITUDE_M = 1e9
#: relative refractive index of sea water in the visible
N_WATER = 1.34
#: the shipped map of the earth's land (RGB) and land fraction (alpha), see its .txt
EARTH_MAP = "earth_albedo_512x256.png"


def cox_munk_mean_square_slope(wind_speed_m_s: float) -> float:
    """Mean square slope of the sea surface for wind speed W [m/s] at 12.5 m above the sea:
    sigma^2 = 0.003 + 5.12e-3 W (Cox & Munk 1954, clean surface, both slope components)."""
    return 0.003 + 5.12e-3 * float(wind_speed_m_s)       # [CM54] eq. for sigma_c^2 + sigma_u^2


def parse_length(name: str, value) -> float:
    """A length [m] from a number of metres or a string ``"36000km"``, ``"400 km"``,
    ``"8e5 m"`` or ``"8e5"`` (metres); ValueError naming ``name`` otherwise."""
    if isinstance(value, str):
        m = _LENGTH_RE.match(value)
        if not m:
            raise ValueError(f"{name} = {value!r} is not a length: give metres or a number "
                             f"with the unit m or km, e.g. '36000km'")
        v = float(m.group(1)) * (1e3 if m.group(2) == "km" else 1.0)
        return check_number(name, v, 0.0, _MAX_ALTITUDE_M, "m")
    return check_number(name, value, 0.0, _MAX_ALTITUDE_M, "m")


def _load_texture(texture) -> np.ndarray:
    """(H, W, 4) linear RGB albedo in [0, 1] from an image path or an array, and a land
    fraction of 1 (the whole texture is Lambertian)."""
    if isinstance(texture, (str, bytes)) or hasattr(texture, "__fspath__"):
        import os

        path = os.fspath(texture)
        if not os.path.isfile(path):
            raise FileNotFoundError(f"texture = {path!r}: no such file")
        from PIL import Image

        with Image.open(path) as im:
            rgb = np.asarray(im.convert("RGB"), dtype=np.float64) / 255.0
        from skydome.spectra import srgb_decode

        return _with_land(srgb_decode(rgb))      # IEC 61966-2-1, to linear reflectance
    a = np.asarray(texture, dtype=np.float64)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=-1)
    if a.ndim != 3 or a.shape[-1] not in (3, 4) or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"texture must be an image path or an array (H, W) or (H, W, 3) of "
                         f"albedo in [0, 1], got shape {a.shape}")
    a = a[..., :3]
    if not np.all(np.isfinite(a)) or a.min() < 0.0 or a.max() > 1.0:
        raise ValueError("texture values are out of range [0, 1] (albedo)")
    return _with_land(a)


def _with_land(rgb: np.ndarray, land: np.ndarray | None = None) -> np.ndarray:
    """(H, W, 4): linear RGB albedo and the land fraction (1 where not given)."""
    out = np.ones(rgb.shape[:2] + (4,))
    out[..., :3] = rgb
    if land is not None:
        out[..., 3] = land
    return np.ascontiguousarray(out)


def _load_earth_map() -> np.ndarray:
    """(256, 512, 4) the shipped earth map: linear RGB albedo of the land and land fraction."""
    from PIL import Image

    from skydome.data import DATA_DIR

    with Image.open(DATA_DIR / EARTH_MAP) as im:
        a = np.asarray(im.convert("RGBA"), dtype=np.float64) / 255.0
    from skydome.spectra import srgb_decode

    return _with_land(srgb_decode(a[..., :3]), a[..., 3])   # IEC 61966-2-1


def _texture_basis(wl: np.ndarray) -> np.ndarray:
    """(3, n_lambda) weights turning linear (R, G, B) albedo into a spectral albedo: linear
    interpolation through B at 465 nm, G at 550 nm and R at 610 nm, constant beyond."""
    nodes = np.array([465.0, 550.0, 610.0])
    out = np.empty((3, wl.size))
    for k, col in enumerate((2, 1, 0)):   # R row uses the 610 nm node, ...
        e = np.zeros(3)
        e[col] = 1.0
        out[k] = np.interp(wl, nodes, e)
    return out


@register
class Nishita1993(SkyModel):
    """The earth and its atmosphere seen by a camera anywhere above the surface.

    Parameters
    ----------
    sun : skydome.Sun
        The sun's elevation and azimuth AT THE SUB-CAMERA POINT (the point of the surface
        below the camera), any elevation in [-90, 90] deg.
    atmosphere : skydome.Atmosphere, optional
        The medium. Default ``Atmosphere.earth(turbidity=turbidity)``.
    turbidity : float
        Preetham turbidity [1, 32] used when no atmosphere is given (default 2.5).
    camera_altitude_m : float
        Camera altitude above the sub-camera point [m], [0, 1e9] (default 36e6 m, about
        geostationary).
    camera_altitude : str or float, optional
        The same as a length with unit: ``"36000km"``, ``"400 km"``, or metres. Overrides
        ``camera_altitude_m`` (give one of them).
    camera_latitude_deg, camera_longitude_deg : float
        Geographic position of the sub-camera point [deg]; orients the albedo texture
        (default 0, 0).
    surface : {"ocean", "albedo", "texture", "earth"}
        What covers the planet: the paper's sea with the sun's glint on a wind-roughened
        surface (default), a uniform Lambertian ``albedo``, a Lambertian albedo ``texture``,
        or ``earth``: the land of the shipped Blue Marble map (Lambertian, its colour as
        albedo) and the sea elsewhere.
    wind_speed_m_s : float
        Wind speed over the sea [m/s] at 12.5 m, [0, 30] (default 5): the mean square
        slope of the waves, sigma^2 = 0.003 + 5.12e-3 W (Cox & Munk 1954), sets the size
        of the sun's glint.
    albedo : float, optional
        Uniform albedo [0, 1] for ``surface="albedo"`` (default: the atmosphere's ground
        albedo).
    texture : str, path or array, optional
        Equirectangular (latitude-longitude) albedo map: an image file (sRGB) or an array
        (H, W) / (H, W, 3) of linear albedo in [0, 1]; row 0 at latitude +90 deg, column 0
        at longitude -180 deg.
    spheres : int
        Number of spheres of the optical-depth table and of the view-ray samples (default 64).
    substeps : int
        Trapezoid pieces per interval between sphere crossings on the view ray (default 2).
    light_samples : int
        Quadrature nodes per table entry (default 128).
    light_exact : bool
        Integrate every light path directly instead of reading the table (slow; checks it).
    sun_disc : bool
        Give the sun's disc a radiance (default True).

    Notes
    -----
    The camera looks from ``(0, 0, R + camera_altitude)`` in the East-North-Up frame of the
    sub-camera point; ``radiance`` takes directions from the camera in that frame. Rays
    that miss the atmosphere see black space (0); rays that hit the planet see its lit or
    dark surface through the air in front of it. Night side: zero (no moon, no city lights).
    """

    name = "nishita1993"
    reference = ("Nishita, Sirai, Tadamura & Nakamae, Display of the Earth Taking into Account "
                 "Atmospheric Scattering, SIGGRAPH 93, 175-182 (eqs. 1-3, sec. 4-5)")
    native = "spectral"
    own_ground = "own"                    # measured against rho E_h / pi: docs/models.md
    summary = ("The earth seen from space or the air: single scattering, sea colour and glint, "
               "land map, shadow.")
    parameters = (
        ATMOSPHERE,
        TURBIDITY,
        Parameter("camera_altitude_m", "m", 36e6, 0.0, _MAX_ALTITUDE_M,
                  "camera altitude above the sub-camera point"),
        Parameter("camera_altitude", "", None, doc="camera altitude with unit, e.g. 36000km or 400km "
                  "(overrides camera_altitude_m)", kind="length"),
        Parameter("camera_latitude_deg", "deg", 0.0, -90.0, 90.0, "latitude of the sub-camera point"),
        Parameter("camera_longitude_deg", "deg", 0.0, -180.0, 180.0,
                  "longitude of the sub-camera point"),
        Parameter("surface", "", "ocean", doc="ocean, albedo, texture or earth (land map + ocean)",
                  kind="choice", choices=_SURFACES),
        Parameter("wind_speed_m_s", "m/s", 5.0, 0.0, 30.0,
                  "wind speed over the sea (Cox-Munk wave slopes: size of the sun's glint)"),
        Parameter("albedo", "", None, 0.0, 1.0, "uniform surface albedo (default: the atmosphere's)"),
        Parameter("texture", "", None, doc="equirectangular albedo image path or array", kind="object"),
        Parameter("spheres", "", 64, 8, 1024, "spheres of the optical-depth table", kind="int"),
        Parameter("cylinders", "", 64, 4, 1024, "cylinders per sphere and side of the table",
                  kind="int"),
        Parameter("substeps", "", 2, 1, 64, "view-ray pieces between sphere crossings", kind="int"),
        Parameter("light_samples", "", 128, 2, 4096, "quadrature nodes per table entry", kind="int"),
        Parameter("light_exact", "", False, doc="integrate light paths directly (slow)", kind="bool"),
        Parameter("sun_disc", "", True, doc="give the sun's disc a radiance", kind="bool"),
    )

    #: table layout: cylinders inside the planet (uniform in radius), scale of the sphere
    #: spacing [m] and weight of the linear part of the spacing
    _N_INNER = 16
    _SPACING_SCALE_M = 8000.0
    _SPACING_LINEAR = 0.5
    _QUAD_SCALE_M = 500.0

    def _setup(self, p, params):
        sun = self.sun
        atm = p["atmosphere"]
        if p["camera_altitude"] is not None:
            if "camera_altitude_m" in params:
                raise ValueError("give either camera_altitude or camera_altitude_m, not both")
            p["camera_altitude_m"] = parse_length("camera_altitude", p["camera_altitude"])
        if p["surface"] == "texture":
            if p["texture"] is None:
                raise ValueError("surface = 'texture' needs texture (an image path or an array)")
            self._texture = _load_texture(p["texture"])
        else:
            if p["texture"] is not None:
                raise ValueError(f"texture given but surface = {p['surface']!r}: use surface='texture'")
            self._texture = _load_earth_map() if p["surface"] == "earth" else np.zeros((1, 1, 4))
        if p["albedo"] is not None and p["surface"] != "albedo":
            raise ValueError(f"albedo given but surface = {p['surface']!r}: use surface='albedo'")

        self.sun = sun
        self.atmosphere = atm
        self.turbidity = p["turbidity"]
        self.camera_altitude_m = float(p["camera_altitude_m"])
        self.camera_altitude = p["camera_altitude"]
        self.camera_latitude_deg = p["camera_latitude_deg"]
        self.camera_longitude_deg = p["camera_longitude_deg"]
        self.surface = p["surface"]
        self.wind_speed_m_s = float(p["wind_speed_m_s"])
        self._sigma2 = cox_munk_mean_square_slope(self.wind_speed_m_s)
        self.albedo = p["albedo"]
        self.texture = p["texture"] if isinstance(p["texture"], str) else (
            None if p["texture"] is None else "array")
        self.spheres = p["spheres"]
        self.cylinders = p["cylinders"]
        self.substeps = p["substeps"]
        self.light_samples = p["light_samples"]
        self.light_exact = p["light_exact"]
        self.sun_disc = p["sun_disc"]

        R = atm.planet_radius_m
        top = atm.top_altitude_m
        self._R = float(R)
        self._Rt = float(atm.top_radius_m)
        self._r0 = self._R + self.camera_altitude_m
        # the sphere radii: u(h_i) = i / (n_s - 1) ([NSTN93] sec. 4.1: spheres placed so that
        # the density differences between neighbours are about equal; see the kernel)
        self._sph_r = R + self._sphere_altitudes(self.spheres, top)
        lat, lon = np.radians(self.camera_latitude_deg), np.radians(self.camera_longitude_deg)
        east = [-math.sin(lon), math.cos(lon), 0.0]
        north = [-math.sin(lat) * math.cos(lon), -math.sin(lat) * math.sin(lon), math.cos(lat)]
        up = [math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)]
        self._rot = np.ascontiguousarray(np.array([east, north, up]).T)
        self._table = None            # columns (n_c, 2, n_s, n_cyl), built on first use
        self._props: dict = {}
        self.table_build_s = None

    # -- construction helpers -------------------------------------------------------------
    def _sphere_altitudes(self, n: int, top: float) -> np.ndarray:
        """Altitudes [m] with u(h) = i / (n - 1), u the kernel's sphere map (bisection)."""
        H, w = self._SPACING_SCALE_M, self._SPACING_LINEAR
        target = np.arange(n) / (n - 1.0)

        def u(h):
            return (1.0 - w) * -np.expm1(-h / H) / -np.expm1(-top / H) + w * h / top

        lo = np.zeros(n)
        hi = np.full(n, top)
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            below = u(mid) < target
            lo = np.where(below, mid, lo)
            hi = np.where(below, hi, mid)
        h = 0.5 * (lo + hi)
        h[0], h[-1] = 0.0, top
        return h

    def _optics(self, wl):
        """Optical properties, solar irradiance and the surface tables for wavelengths wl."""
        key = tuple(np.round(wl, 9))
        if key in self._props:
            return self._props[key]
        if len(self._props) > 4:
            self._props.clear()
        from skydome.data import load_table
        from skydome.spectra import solar_irradiance

        props = self.atmosphere.optical_properties(wl, fold=True)
        self._build_table(props)
        e_sun = np.ascontiguousarray(solar_irradiance(wl) * self.sun.irradiance_scale)
        if self.surface == "albedo":
            albedo = (np.full(wl.size, self.albedo) if self.albedo is not None
                      else np.ascontiguousarray(props.ground_albedo, dtype=np.float64))
        else:
            albedo = np.zeros(wl.size)
        _, sea = load_table("seawater_optical_properties")
        from skydome.spectra import resample

        a_w, b_w = resample(wl, sea[:, 0], sea[:, 1:3], "hold").T
        entry = {"props": props, "e_sun": e_sun, "albedo": np.ascontiguousarray(albedo),
                 "water_c": np.ascontiguousarray(a_w + b_w), "water_b": np.ascontiguousarray(b_w),
                 "basis": np.ascontiguousarray(_texture_basis(wl))}
        entry["mu_grid"], entry["e_sky"] = self._sky_irradiance_table(entry)
        self._props[key] = entry
        return entry

    def _build_table(self, props) -> None:
        """The optical-depth table ([NSTN93] sec. 4.1), once per model (it holds columns of
        relative density, the same for every wavelength)."""
        if self._table is not None:
            return
        import time

        from skydome.models.simulated import _kernels_nishita1993 as K

        t0 = time.perf_counter()
        self._codes = np.ascontiguousarray(props.profile_code)
        self._p0 = np.ascontiguousarray(props.profile_p0, dtype=np.float64)
        self._p1 = np.ascontiguousarray(props.profile_p1, dtype=np.float64)
        self._table = K.build_table(self._medium(props), self._sph_r, self.cylinders,
                                    self.light_samples, self._QUAD_SCALE_M)
        self.table_build_s = time.perf_counter() - t0

    def _medium(self, props):
        """The kernels' medium record of these optical properties on this model's shell."""
        from skydome.transport._medium import medium_from_properties

        return medium_from_properties(props)._replace(R=float(self._R), Rt=float(self._Rt))

    def _trace(self, dirs, entry, r0, sun, surface_code, mu_grid, e_sky) -> np.ndarray:
        from skydome.models.simulated import _kernels_nishita1993 as K

        p = entry["props"]
        flat = np.ascontiguousarray(dirs.reshape(-1, 3), dtype=np.float64)
        out = np.empty((flat.shape[0], p.wavelengths_nm.size))
        lt = K.LightTable(self._sph_r, self._table, float(self._SPACING_SCALE_M),
                          float(self._Rt - self._R), float(self._SPACING_LINEAR), int(self._N_INNER),
                          bool(self.light_exact), int(self.light_samples), float(self._QUAD_SCALE_M),
                          int(self.substeps))
        sf = K.Surface(int(surface_code), np.ascontiguousarray(entry["albedo"], dtype=np.float64),
                       np.ascontiguousarray(mu_grid, dtype=np.float64),
                       np.ascontiguousarray(e_sky, dtype=np.float64),
                       np.ascontiguousarray(entry["water_c"], dtype=np.float64),
                       np.ascontiguousarray(entry["water_b"], dtype=np.float64), float(N_WATER),
                       float(self._sigma2), self._texture, entry["basis"], self._rot)
        K.render_rays(flat, float(r0), np.ascontiguousarray(sun, dtype=np.float64),
                      self._medium(p), entry["e_sun"], lt, sf, out)
        return out

    def _sky_irradiance_table(self, entry):
        """Diffuse sky irradiance on a horizontal surface [W m^-2 nm^-1] against the cosine
        of the sun's zenith angle there ([NSTN93] sec. 5: the skylight lookup table),
        integrated over the single-scattering sky seen from the ground (midpoint rule,
        12 x 24 directions over the hemisphere)."""
        mu_grid = np.linspace(-0.3, 1.0, 27)
        nz, naz = 12, 24
        mu = (np.arange(nz) + 0.5) / nz
        phi = (np.arange(naz) + 0.5) / naz * 2.0 * np.pi
        M, P = np.meshgrid(mu, phi, indexing="ij")
        s = np.sqrt(1.0 - M * M)
        dirs = np.stack([s * np.sin(P), s * np.cos(P), M], axis=-1).reshape(-1, 3)
        w = (M * (1.0 / nz) * (2.0 * np.pi / naz)).reshape(-1)
        nl = entry["e_sun"].size
        e_sky = np.zeros((mu_grid.size, nl))
        dummy_mu = np.array([-1.0, 1.0])
        dummy_e = np.zeros((2, nl))
        for i, ms in enumerate(mu_grid):
            sun = np.array([0.0, math.sqrt(max(1.0 - ms * ms, 0.0)), ms])
            L = self._trace(dirs, entry, self._R, sun, 0, dummy_mu, dummy_e)
            e_sky[i] = w @ L
        return np.ascontiguousarray(mu_grid), np.ascontiguousarray(e_sky)

    # -- public -----------------------------------------------------------------------------
    @property
    def observer(self) -> np.ndarray:
        """Camera position [m] in the ENU frame of the sub-camera point (origin on the
        surface)."""
        return np.array([0.0, 0.0, self.camera_altitude_m])

    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] reaching the camera from ``directions``
        (..., 3) (unit vectors from the camera, ENU frame of the sub-camera point), shape
        (..., n_wavelengths). Space is black (0); the sun's disc is not included here (see
        :meth:`sun_radiance`)."""
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        entry = self._optics(wl)
        code = {"albedo": 0, "ocean": 1, "texture": 2, "earth": 3}[self.surface]
        out = self._trace(d, entry, self._r0, self.sun.direction, code, entry["mu_grid"],
                          entry["e_sky"])
        np.maximum(out, 0.0, out=out)
        return out.reshape(d.shape[:-1] + (wl.size,))

    def sun_radiance(self, wavelengths_nm):
        """Radiance of the sun's disc seen from the camera [W m^-2 sr^-1 nm^-1]:
        E_sun / Omega_sun x T(camera -> sun); 0 when the planet hides the sun; None when
        ``sun_disc`` is False."""
        if not self.sun_disc:
            return None
        from skydome.transport._kernels import column_quadrature, ray_hits_ground

        wl = as_wavelengths(wavelengths_nm)
        entry = self._optics(wl)
        p = entry["props"]
        mu = float(self.sun.direction[2])
        if ray_hits_ground(self._r0, mu, self._R):
            return np.zeros(wl.size)
        cols = np.array([column_quadrature(int(self._codes[c]), float(self._p0[c]),
                                           float(self._p1[c]), self._r0, mu, self._R, self._Rt,
                                           256, self._QUAD_SCALE_M, True)
                         for c in range(self._codes.size)])
        t = np.exp(-(cols @ p.extinction))
        return entry["e_sun"] / self.sun.solid_angle_sr * t

    def table_columns(self, r_m, mu_s) -> np.ndarray:
        """Columns of relative density to the sun [m] read from the optical-depth table at
        radii ``r_m`` [m] and sun cosines ``mu_s``, shape (n, n_constituents) (for tests)."""
        from skydome.models.simulated import _kernels_nishita1993 as K
        from skydome.spectra import default_wavelengths

        self._optics(default_wavelengths())
        r = np.ascontiguousarray(np.atleast_1d(r_m), dtype=np.float64)
        m = np.ascontiguousarray(np.atleast_1d(mu_s), dtype=np.float64)
        out = np.zeros((r.size, self._codes.size))
        K.lookup_columns(self._table, r, m, self._R, self._SPACING_SCALE_M, self._Rt - self._R,
                         self._SPACING_LINEAR, self._N_INNER, out)
        return out

    def default_projection(self, size):
        """A :class:`skydome.camera.Camera` at the model's camera looking at the
        planet's centre with north up, its field of view framing the whole disc with the
        atmosphere (at most 160 deg).

        Parameters
        ----------
        size : int or str
            ``N`` or ``"WxH"`` [pixels].
        """
        from skydome.camera import Camera
        from skydome.camera import _parse_size

        w, h = _parse_size(size)
        h = w if h is None else h
        if self._r0 > self._Rt:
            half = math.degrees(math.asin(self._Rt / self._r0))
            fov = min(2.0 * half * 1.08 * max(1.0, w / h), 160.0)
        else:
            fov = 160.0
        return Camera(w, h, fov, position=(0.0, 0.0, self.camera_altitude_m),
                      look_at=(0.0, 0.0, -self._R), up=(0.0, 1.0, 0.0))
