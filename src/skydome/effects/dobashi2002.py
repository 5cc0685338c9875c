"""Aerial perspective and light shafts after Dobashi, Yamamoto & Nishita (2002).

Dobashi et al. render the light scattered by the air between the eye and the scene by
placing *sampling planes* in the view volume and accumulating, plane by plane, the light
scattered in the slab between consecutive planes; the scattering integrals are not
evaluated per pixel but read from precomputed two-dimensional tables bound as textures,
and a shadow test at the sampling planes leaves out the air that the sun does not reach,
which draws light shafts ([DYN02] secs. 3-5; survey sec. 7.7).

For sunlight (a parallel source) in a spherical atmosphere with exponential density, the
single-scattered light reaching the eye along a view ray of length s is (survey eqs. 15-16)

    L(s) = L_0 T(s) + E_sun sum_c beta_c p_c(theta) J_c(s, mu),                  (1)
    J_c(s, mu) = int_0^s rho_c(h(t)) T_sun(h(t)) V(t) exp(-tau(t, mu)) dt,          (2)
    tau(t, mu) = sum_c beta_ext,c D_c(t, mu),  D_c(t, mu) = int_0^t rho_c(h(t')) dt',  (3)

with mu the cosine of the ray's zenith angle, h(t) the altitude along the ray, T_sun the
transmittance to the sun, V the visibility of the sun (1 without shadows) and theta the
angle between the ray and the sun (constant along a ray, so the phase function sits outside
the integral). Without shadows J_c and D_c depend only on (distance, angle): they are the
2D tables of [DYN02] (here per constituent and wavelength), computed once per frame by
cumulative quadrature and interpolated per pixel. With shadows the ray is cut by the
sampling planes z = z_k (perpendicular to the view axis) and

    J_c(s) ~ sum_k V(t_k-1/2) [J_c(t_k, mu) - J_c(t_k-1, mu)],                    (4)

the table difference over each slab weighted by the sun's visibility at the slab's middle;
rays that never enter a shadow telescope back to J_c(s, mu). The shadow test uses a
heightmap: a point is in shadow when it lies below the top of the terrain's shadow volume,
precomputed on the heightmap grid by marching towards the sun (a shadow map in the
heightmap's frame).

Deviations from [DYN02]: the paper's constant ambient term for multiple scattering is left
out (single scattering only); the paper tabulates with graphics hardware precision, we use
float64; the sun's zenith angle is taken as at the camera for every point of the scene
(the local vertical turns by t / R: 0.45 deg at 50 km), which keeps the tables 2D.

References
----------
[DYN02] Dobashi, Y., Yamamoto, T., Nishita, T. 2002. Interactive Rendering of Atmospheric
    Scattering Effects Using Graphics Hardware. Graphics Hardware 2002, 99-108.
    doi:10.2312/EGGH/EGGH02/099-108.
[KRZ06] Kment, Rauter & Zotti, Modelling of Daylight for Computer Graphics, eqs. 12, 15-16,
    sec. 7.7.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from skydome._validate import as_wavelengths, check_choice, check_int, check_number
from skydome.camera import Camera

__all__ = ["Camera", "Heightmap", "ScatteringTables", "apply_aerial_perspective",
           "synthetic_mountains", "build_tables", "reference_sunlight", "terrain_lambert", "inscatter_direct", "shadow_volume_top",
           "DEFAULT_CAMERA"]


# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Heightmap:
    """Terrain heights on a regular grid: heights_m[j, i] at (x_m[i] east, y_m[j] north)."""

    heights_m: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray

    def __post_init__(self):
        h = np.asarray(self.heights_m, dtype=np.float64)
        x = np.asarray(self.x_m, dtype=np.float64)
        y = np.asarray(self.y_m, dtype=np.float64)
        if h.ndim != 2 or h.shape != (y.size, x.size) or x.size < 2 or y.size < 2:
            raise ValueError(f"heightmap: heights_m shape {h.shape} must be (len(y_m), len(x_m)) >= (2, 2)")
        if not np.all(np.isfinite(h)):
            raise ValueError("heightmap: heights_m must be finite")
        for name, v in (("x_m", x), ("y_m", y)):
            dv = np.diff(v)
            if not np.all(dv > 0) or not np.allclose(dv, dv[0], rtol=1e-6):
                raise ValueError(f"heightmap: {name} must be increasing and evenly spaced")
        object.__setattr__(self, "heights_m", h)
        object.__setattr__(self, "x_m", x)
        object.__setattr__(self, "y_m", y)

    def sample(self, field: np.ndarray, x, y, outside: float = 0.0) -> np.ndarray:
        """Bilinear sample of a grid field (same grid as heights) at points (x, y) [m];
        ``outside`` beyond the grid."""
        fx = (np.asarray(x) - self.x_m[0]) / (self.x_m[1] - self.x_m[0])
        fy = (np.asarray(y) - self.y_m[0]) / (self.y_m[1] - self.y_m[0])
        nx, ny = self.x_m.size, self.y_m.size
        inside = (fx >= 0) & (fx <= nx - 1) & (fy >= 0) & (fy <= ny - 1)
        fx = np.clip(fx, 0, nx - 1)
        fy = np.clip(fy, 0, ny - 1)
        i = np.minimum(fx.astype(np.int64), nx - 2)
        j = np.minimum(fy.astype(np.int64), ny - 2)
        wx, wy = fx - i, fy - j
        v = ((1 - wy) * ((1 - wx) * field[j, i] + wx * field[j, i + 1])
             + wy * ((1 - wx) * field[j + 1, i] + wx * field[j + 1, i + 1]))
        return np.where(inside, v, outside)

    def height(self, x, y) -> np.ndarray:
        """Terrain height [m] at (x, y); 0 outside the grid."""
        return self.sample(self.heights_m, x, y)


def shadow_volume_top(heightmap: Heightmap, sun_direction) -> np.ndarray:
    """Top of the terrain's shadow volume on the heightmap grid [m].

    S(x, y) = max over d >= 0 of [H(x + d s_h) - d tan(a)], with s_h the horizontal unit
    vector towards the sun and a its elevation: a point above (x, y) at altitude z sees the
    sun iff z >= S(x, y). Marched in steps of the grid spacing until d tan(a) exceeds the
    highest terrain. A sun below the horizon shadows everything (S = +inf).
    """
    s = np.asarray(sun_direction, dtype=np.float64)
    H = heightmap.heights_m
    if s[2] <= 0.0:
        return np.full(H.shape, np.inf)
    sh = np.hypot(s[0], s[1])
    if sh < 1e-9:
        return H.copy()
    ux, uy = s[0] / sh, s[1] / sh
    tan_a = s[2] / sh
    step = min(heightmap.x_m[1] - heightmap.x_m[0], heightmap.y_m[1] - heightmap.y_m[0])
    X, Y = np.meshgrid(heightmap.x_m, heightmap.y_m)
    top = H.copy()
    rise = max(float(H.max() - min(H.min(), 0.0)), 0.0)
    n = int(np.ceil(rise / (tan_a * step))) + 1
    for k in range(1, n + 1):
        d = k * step
        top = np.maximum(top, heightmap.height(X + d * ux, Y + d * uy) - d * tan_a)
    return top


# ---------------------------------------------------------------------------------------------
def _phases(atmosphere, wl, cos_theta):
    """Phase function of every constituent at wavelengths wl [sr^-1], shape
    (..., nc, nl), from the kernels' core (:mod:`skydome.transport._phase`; tabulated
    phase functions such as Lorenz-Mie included)."""
    from skydome.transport._medium import medium_from_properties
    from skydome.transport._phase import phase_values_many

    m = medium_from_properties(atmosphere.optical_properties(wl))
    c = np.ascontiguousarray(np.asarray(cos_theta, dtype=np.float64).reshape(-1))
    out = np.empty((c.size, m.phase_code.size, wl.size))
    phase_values_many(m, c, out)
    return out.reshape(np.shape(cos_theta) + out.shape[1:])


def _ray_altitude(t, mu, r0, R):
    """Altitude [m] at distance t along a ray leaving radius r0 with zenith cosine mu."""
    return np.sqrt(np.maximum(r0 * r0 + t * t + 2.0 * r0 * t * mu, 0.0)) - R


def _sun_transmittance(atmosphere, altitude_m, mu_sun, wl):
    """exp(-optical depth to the sun) at altitudes (...) -> (..., nl); 0 in the planet's
    shadow. Exponential profiles by the Chapman approximation, others by quadrature."""
    from skydome.transport.optical_depth import chapman_column, column_density

    h = np.maximum(np.asarray(altitude_m, dtype=np.float64), 0.0)
    h = np.minimum(h, atmosphere.top_altitude_m)
    tau = np.zeros(h.shape + (wl.size,))
    mu = np.full(h.shape, float(mu_sun))
    for c in atmosphere.constituents:
        ext = c.scattering(wl) + c.absorption(wl)
        if not np.any(ext > 0):
            continue
        code, p0, _ = c.profile.kernel_params()
        if code == 0:
            col = chapman_column(p0, h, mu, atmosphere.planet_radius_m)
        else:
            col = column_density(c.profile, h, mu, atmosphere.planet_radius_m,
                                 atmosphere.top_radius_m, samples=64)
            hits = (mu < 0) & ((atmosphere.planet_radius_m + h) ** 2 * (1 - mu * mu)
                               <= atmosphere.planet_radius_m ** 2)
            col = np.where(hits, np.inf, col)
        with np.errstate(invalid="ignore"):
            tau = tau + np.where(np.isinf(col)[..., None], np.inf, col[..., None] * ext)
    return np.exp(-tau)


class ScatteringTables(NamedTuple):
    """The per-frame 2D tables of [DYN02] on a (distance, view zenith cosine) grid.

    t_m (nd,): distance nodes [m] (quadratic spacing); mu (na,): cosine nodes (uniform);
    J (nd, na, nc, nl): in-scattering integrals J_c [m] (eq. 2 with V = 1);
    D (nd, na, nc): column densities D_c [m] (eq. 3); wl (nl,); scattering, extinction
    (nc, nl) [m^-1]; e_sun (nl,) [W m^-2 nm^-1]; mu_sun; camera altitude [m].
    """

    t_m: np.ndarray
    mu: np.ndarray
    J: np.ndarray
    D: np.ndarray
    wl: np.ndarray
    scattering: np.ndarray
    extinction: np.ndarray
    e_sun: np.ndarray
    mu_sun: float
    altitude_m: float

    def _coords(self, t, mu):
        nd, na = self.t_m.size, self.mu.size
        tmax = self.t_m[-1]
        u = np.sqrt(np.clip(t, 0.0, tmax) / tmax) * (nd - 1)
        i = np.minimum(u.astype(np.int64), nd - 2)
        ti, ti1 = self.t_m[i], self.t_m[i + 1]
        wt = np.clip((np.clip(t, 0.0, tmax) - ti) / (ti1 - ti), 0.0, 1.0)     # linear in t
        if na == 1:
            return i, wt, np.zeros_like(i), np.zeros_like(wt)
        fa = (np.clip(mu, self.mu[0], self.mu[-1]) - self.mu[0]) / (self.mu[1] - self.mu[0])
        j = np.minimum(fa.astype(np.int64), na - 2)
        return i, wt, j, fa - j

    def _lookup(self, table, t, mu):
        i, wt, j, wa = self._coords(t, mu)
        return _lerp2(table, i, wt, j, wa, single=self.mu.size == 1)

    def inscatter_integrals(self, t, mu) -> np.ndarray:
        """J_c at (t, mu) (...), shape (..., nc, nl) [m]."""
        return self._lookup(self.J, t, mu)

    def columns(self, t, mu) -> np.ndarray:
        """D_c at (t, mu) (...), shape (..., nc) [m]."""
        return self._lookup(self.D, t, mu)


def _lerp2(table, i, wt, j, wa, single=False):
    ex = (Ellipsis,) + (None,) * (table.ndim - 2)
    wt, wa = wt[ex], wa[ex]
    if single:
        return (1 - wt) * table[i, 0] + wt * table[i + 1, 0]
    return ((1 - wt) * ((1 - wa) * table[i, j] + wa * table[i, j + 1])
            + wt * ((1 - wa) * table[i + 1, j] + wa * table[i + 1, j + 1]))


def _integrand_parts(atmosphere, t, mu, alt0, mu_sun, wl):
    """rho_c(h(t)) (..., nc) and T_sun(h(t)) (..., nl) along rays."""
    R = atmosphere.planet_radius_m
    h = _ray_altitude(t, mu, R + alt0, R)
    rho = np.stack([c.profile.density(h) for c in atmosphere.constituents], axis=-1)
    return rho, _sun_transmittance(atmosphere, h, mu_sun, wl)


def build_tables(atmosphere, wavelengths_nm, sun, altitude_m: float, max_distance_m: float,
                 mu_range=(-1.0, 1.0), n_distance: int = 64, n_angle: int = 64,
                 substeps: int = 8) -> ScatteringTables:
    """Tabulate eqs. (2)-(3) (V = 1) on a (distance, view cosine) grid [DYN02].

    Distances 0..max_distance_m on nodes t_k = max (k / (n-1))^2; each interval is split in
    ``substeps`` and integrated by the trapezoidal rule, cumulatively.
    """
    wl = as_wavelengths(wavelengths_nm)
    n_distance = check_int("n_distance", n_distance, 2, 4096)
    n_angle = check_int("n_angle", n_angle, 1, 4096)
    substeps = check_int("substeps", substeps, 1, 256)
    tmax = check_number("max_distance_m", max_distance_m, 0.0, 1e7, "m", low_open=True)
    lo, hi = float(mu_range[0]), float(mu_range[1])
    mu = np.linspace(lo, hi, n_angle) if n_angle > 1 else np.array([lo])
    nf = (n_distance - 1) * substeps + 1
    tf = tmax * np.linspace(0.0, 1.0, nf) ** 2
    mu_sun = float(sun.direction[2])
    props = atmosphere.optical_properties(wl)
    rho, tsun = _integrand_parts(atmosphere, tf[:, None], mu[None, :], altitude_m, mu_sun, wl)
    dt = np.diff(tf)[:, None, None]
    # eq. (3): D_c by cumulative trapezoid
    D = np.concatenate([np.zeros((1,) + rho.shape[1:]),
                        np.cumsum(0.5 * (rho[1:] + rho[:-1]) * dt, axis=0)], axis=0)
    tau = np.einsum("tac,cl->tal", D, props.extinction)
    g = rho[..., :, None] * (tsun * np.exp(-tau))[..., None, :]          # (nf, na, nc, nl)
    J = np.concatenate([np.zeros((1,) + g.shape[1:]),
                        np.cumsum(0.5 * (g[1:] + g[:-1]) * dt[..., None], axis=0)], axis=0)
    from skydome.spectra import solar_irradiance

    return ScatteringTables(tf[::substeps], mu, J[::substeps], D[::substeps], wl, props.scattering,
                            props.extinction, solar_irradiance(wl) * sun.irradiance_scale,
                            mu_sun, float(altitude_m))


def inscatter_direct(atmosphere, wavelengths_nm, sun, altitude_m: float, distance_m: float,
                     mu: float, samples: int = 4000):
    """J_c(s, mu) (nc, nl) and D_c(s, mu) (nc,) by direct quadrature of eqs. (2)-(3) along one
    ray (composite trapezoid on ``samples`` uniform nodes), for checking the tables."""
    wl = as_wavelengths(wavelengths_nm)
    t = np.linspace(0.0, float(distance_m), int(samples))
    rho, tsun = _integrand_parts(atmosphere, t, np.full(t.shape, float(mu)), altitude_m,
                                 float(sun.direction[2]), wl)
    props = atmosphere.optical_properties(wl)
    dt = np.diff(t)[:, None]
    D = np.concatenate([np.zeros((1, rho.shape[1])), np.cumsum(0.5 * (rho[1:] + rho[:-1]) * dt, axis=0)])
    g = rho[:, :, None] * (tsun * np.exp(-(D @ props.extinction)))[:, None, :]
    J = np.sum(0.5 * (g[1:] + g[:-1]) * dt[..., None], axis=0)
    return J, D[-1]


# ---------------------------------------------------------------------------------------------
def apply_aerial_perspective(image, depth_m, camera, sun, atmosphere=None, method: str = "dobashi2002",
                             shafts: bool = False, heightmap: Heightmap | None = None,
                             wavelengths_nm=None, white_luminance_cd_m2: float | None = None,
                             n_planes: int = 48, n_distance: int = 64, n_angle: int = 64,
                             extent_m: float | None = None, mu_range=None,
                             return_parts: bool = False):
    """Add aerial perspective (and optionally light shafts) to an image with depth [DYN02].

    Parameters
    ----------
    image : array_like (H, W, 3) or (H, W, n_wavelengths)
        Linear RGB (sRGB primaries) white-balanced to the direct sunlight at the camera:
        (1, 1, 1) is a white Lambertian surface facing the sun (below the horizon: facing
        the unattenuated sun); or, with ``white_luminance_cd_m2``, absolute linear sRGB
        with Y = 1 at that luminance. Or spectral radiance [W m^-2 sr^-1 nm^-1] when
        ``wavelengths_nm`` is given.
    depth_m : array_like (H, W)
        Distance from the eye to the surface along each pixel's ray [m]; +inf for the sky
        (those pixels are returned unchanged).
    camera : Camera or (fov_deg, view_direction[, altitude_m])
    sun : skydome.Sun
    atmosphere : skydome.Atmosphere, optional
        Default ``Atmosphere.earth(turbidity=2.5)``.
    method : {"dobashi2002"}
    shafts : bool
        Test the sun's visibility at the sampling planes against ``heightmap`` (light shafts).
    heightmap : Heightmap
        Terrain for the shadow test (required with ``shafts``).
    wavelengths_nm : array_like, optional
        Wavelengths of a spectral ``image``; RGB images are processed on 21 wavelengths
        380-780 nm and converted with the CIE 1931 observer.
    white_luminance_cd_m2 : float, optional
        Luminance [cd m^-2] of image value Y = 1 for absolute (not white-balanced) linear
        sRGB images (RGB only).
    n_planes : int
        Sampling planes for the shadow test.
    n_distance, n_angle : int
        Table size.
    extent_m : float, optional
        Distance [m] that the tables cover and depth of the last sampling plane (default:
        the farthest surface of the image); every finite depth must be within it. A fixed
        extent makes the tables independent of the image (the viewer's shader uses that).
    mu_range : (float, float), optional
        Range of view zenith cosines of the tables (default: that of the surface pixels).
    return_parts : bool
        Also return (transmittance, in-scattered light) in the output's units.

    Returns
    -------
    numpy.ndarray
        The image with the air in front of each surface added, same shape and units.
    """
    from skydome.atmosphere import Atmosphere
    from skydome.sun import Sun

    check_choice("method", method, ("dobashi2002",))
    if not isinstance(sun, Sun):
        raise TypeError(f"sun must be a skydome.Sun, not {type(sun).__name__}")
    cam = Camera.make(camera)
    img = np.asarray(image, dtype=np.float64)
    if img.ndim != 3 or img.shape[0] < 1 or img.shape[1] < 1:
        raise ValueError(f"image must have shape (H, W, channels), got {img.shape}")
    H, W = img.shape[:2]
    depth = np.asarray(depth_m, dtype=np.float64)
    if depth.shape != (H, W):
        raise ValueError(f"depth_m shape {depth.shape} does not match the image's (H, W) = {(H, W)}")
    if np.any(np.isnan(depth)) or np.any(depth < 0):
        raise ValueError("depth_m must be >= 0 m (inf for the sky), without NaN")
    if not np.all(np.isfinite(img)):
        raise ValueError("image must be finite")
    spectral = wavelengths_nm is not None
    if spectral:
        wl = as_wavelengths(wavelengths_nm)
        if img.shape[2] != wl.size:
            raise ValueError(f"image has {img.shape[2]} channels but {wl.size} wavelengths were given")
    else:
        if img.shape[2] != 3:
            raise ValueError(f"an RGB image must have 3 channels, got {img.shape[2]} "
                             "(give wavelengths_nm for a spectral image)")
        wl = np.linspace(380.0, 780.0, 21)
    if atmosphere is None:
        atmosphere = Atmosphere.earth(turbidity=2.5)
    elif not isinstance(atmosphere, Atmosphere):
        raise TypeError(f"atmosphere must be a skydome.Atmosphere, not {type(atmosphere).__name__}")
    if cam.altitude_m >= atmosphere.top_altitude_m:
        raise ValueError(f"camera altitude_m = {cam.altitude_m:g} m is out of range "
                         f"[0, {atmosphere.top_altitude_m:g}) m")
    if shafts and not isinstance(heightmap, Heightmap):
        raise ValueError("shafts=True needs a heightmap (skydome.effects.dobashi2002.Heightmap)")
    n_planes = check_int("n_planes", n_planes, 1, 4096)
    if extent_m is not None:
        extent_m = check_number("extent_m", extent_m, 0.0, 1e7, "m", low_open=True)
        far = float(depth[np.isfinite(depth)].max(initial=0.0))
        if far > extent_m:
            raise ValueError(f"depth_m reaches {far:g} m, beyond extent_m = {extent_m:g} m")
    if mu_range is not None:
        lo, hi = (check_number("mu_range", float(v), -1.0, 1.0) for v in mu_range)
        if not lo < hi:
            raise ValueError(f"mu_range = {tuple(mu_range)} must be increasing within [-1, 1]")

    dirs = cam.ray_directions(W, H)
    mu = dirs[..., 2]
    finite = np.isfinite(depth)
    out_T = np.ones((H, W, wl.size))
    out_L = np.zeros((H, W, wl.size))
    if np.any(finite & (depth > 0)):
        tmax = float(depth[finite].max()) if extent_m is None else extent_m
        mus = mu[finite]
        if mu_range is None:
            tables = build_tables(atmosphere, wl, sun, cam.altitude_m, tmax, (mus.min(), mus.max()),
                                  n_distance, n_angle if mus.max() > mus.min() else 1)
        else:
            tables = build_tables(atmosphere, wl, sun, cam.altitude_m, tmax, mu_range, n_distance,
                                  n_angle)
        t_pix = np.where(finite, depth, 0.0)
        cos_theta = dirs @ sun.direction
        phase = _phases(atmosphere, wl, cos_theta)                                        # (H,W,nc,nl)
        weight = phase * tables.scattering[None, None]                                     # (H,W,nc,nl)
        D = tables.columns(t_pix, mu)
        out_T = np.exp(-np.einsum("hwc,cl->hwl", D, tables.extinction))                    # eq. (3)
        if not shafts:
            J = tables.inscatter_integrals(t_pix, mu)                                     # eq. (2)
        else:
            J = _shadowed_integrals(tables, heightmap, cam, sun, dirs, t_pix, n_planes,
                                    atmosphere.planet_radius_m, extent_m)                     # eq. (4)
        out_L = tables.e_sun * np.einsum("hwcl,hwcl->hwl", weight, J)                    # eq. (1)
        out_T = np.where(finite[..., None], out_T, 1.0)
        out_L = np.where(finite[..., None], out_L, 0.0)
    if spectral:
        out = img * out_T + out_L
        return (out, out_T, out_L) if return_parts else out
    # RGB: in-scattered light to linear sRGB; transmittance per channel for sunlit surfaces
    from skydome.spectra import spectrum_to_xyz, xyz_to_linear_srgb

    ref = reference_sunlight(atmosphere, sun, cam.altitude_m, wl)
    ref_rgb = np.maximum(xyz_to_linear_srgb(spectrum_to_xyz(ref / np.pi, wl)), 1e-30)
    if white_luminance_cd_m2 is None:
        # white-balanced to the sunlight: (1, 1, 1) = a white Lambertian surface facing the sun
        scale = ref_rgb
    else:
        white = check_number("white_luminance_cd_m2", white_luminance_cd_m2, 0.0, None, "cd/m^2",
                             low_open=True)
        scale = np.full(3, white)
    T_rgb = np.clip(xyz_to_linear_srgb(spectrum_to_xyz(out_T * ref, wl)) / (ref_rgb * np.pi), 0.0, 1.0)
    L_rgb = np.maximum(xyz_to_linear_srgb(spectrum_to_xyz(out_L, wl)) / scale, 0.0)
    untouched = (~finite | (depth == 0.0))[..., None]     # exactly unchanged (no round-off)
    T_rgb = np.where(untouched, 1.0, T_rgb)
    L_rgb = np.where(untouched, 0.0, L_rgb)
    out = np.where(untouched, img, img * T_rgb + L_rgb)
    return (out, T_rgb, L_rgb) if return_parts else out


def reference_sunlight(atmosphere, sun, altitude_m: float, wl) -> np.ndarray:
    """Spectral irradiance [W m^-2 nm^-1] of the direct sunlight at the camera, the white of
    the white-balanced RGB images (the unattenuated sun when it is (nearly) set)."""
    from skydome.spectra import solar_irradiance, spectrum_to_xyz

    e_sun = solar_irradiance(wl) * sun.irradiance_scale
    direct = e_sun * _sun_transmittance(atmosphere, np.array(float(altitude_m)), float(sun.direction[2]), wl)
    return direct if spectrum_to_xyz(direct, wl)[1] > 1e-9 * spectrum_to_xyz(e_sun, wl)[1] else e_sun


def _shadowed_integrals(tables, heightmap, cam, sun, dirs, t_pix, n_planes, planet_radius_m,
                        extent_m=None):
    """Eq. (4): slab-by-slab table differences weighted by the sun's visibility at the
    middle of each slab; slabs are cut by planes perpendicular to the view axis at
    z_k = z_max (k / n)^2 (denser near the eye, where a shadow covers more pixels), z_max
    the farthest surface's depth along the view axis, or ``extent_m``."""
    forward, _, _ = cam.basis()
    mu = dirs[..., 2]
    cosf = np.maximum(dirs @ forward, 1e-6)
    z_pix = t_pix * cosf
    zmax = float(z_pix.max()) if extent_m is None else float(extent_m)
    top = shadow_volume_top(heightmap, sun.direction)
    J_prev = np.zeros(t_pix.shape + tables.J.shape[2:])
    total = np.zeros_like(J_prev)
    t_prev = np.zeros_like(t_pix)
    for k in range(1, n_planes + 1):
        z_k = zmax * (k / n_planes) ** 2           # planes denser near the eye
        t_k = np.minimum(z_k / cosf, t_pix)
        active = t_k > t_prev
        if not np.any(active):
            break
        J_k = tables.inscatter_integrals(t_k, mu)
        t_mid = 0.5 * (t_k + t_prev)
        x = cam.east_m + t_mid * dirs[..., 0]
        y = cam.north_m + t_mid * dirs[..., 1]
        alt = _ray_altitude(t_mid, mu, planet_radius_m + cam.altitude_m, planet_radius_m)
        visible = alt >= heightmap.sample(top, x, y, outside=-np.inf)
        total += np.where((active & visible)[..., None, None], J_k - J_prev, 0.0)
        J_prev = J_k
        t_prev = t_k
    return total


def _altitude_flat_consistent(t, mu, alt0):
    """Altitude above a spherical ground of the Earth's radius (the heightmap's datum) [m]."""
    from skydome.constants import EARTH_RADIUS

    return _ray_altitude(t, mu, EARTH_RADIUS + alt0, EARTH_RADIUS)


# ---------------------------------------------------------------------------------------------
def _ridge_noise(rng, x, octaves=6, base_wavelength_m=8000.0):
    """1D fractal noise in [-1, 1] (sum of random-phase sines, amplitude halving per octave)."""
    v = np.zeros_like(x)
    amp, total = 1.0, 0.0
    for o in range(octaves):
        k = 2 * np.pi / (base_wavelength_m / 2 ** o)
        v += amp * np.sin(k * x * rng.uniform(0.8, 1.25) + rng.uniform(0, 2 * np.pi))
        total += amp
        amp *= 0.5
    return v / total


#: Mean grey-green albedo of the synthetic terrain (linear sRGB) and its constant sky fill
TERRAIN_ALBEDO = np.array([0.16, 0.19, 0.12])
TERRAIN_FILL = 0.15
#: How far the synthetic scene's rays are marched (x its farthest ridge) and in how many steps
MARCH_RANGE, MARCH_STEPS = 1.3, 1500


def terrain_lambert(heightmap: Heightmap, sun_direction) -> np.ndarray:
    """cos(incidence) of the sun on the heightmap grid (>= 0): normals from the height
    gradient (central differences)."""
    H = heightmap.heights_m
    gy, gx = np.gradient(H, heightmap.y_m[1] - heightmap.y_m[0], heightmap.x_m[1] - heightmap.x_m[0])
    n = np.stack([-gx, -gy, np.ones_like(H)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.clip(n @ np.asarray(sun_direction, dtype=np.float64), 0.0, None)


DEFAULT_CAMERA = Camera(fov_deg=60.0, azimuth_deg=0.0, elevation_deg=2.0, altitude_m=300.0)


def synthetic_mountains(width: int = 320, height: int = 180, seed: int = 0, camera: Camera | None = None,
                        sun=None, ranges_km=(3.0, 7.0, 13.0, 22.0, 35.0)):
    """A synthetic scene of mountain ridges at increasing distance, for aerial perspective.

    The terrain is a heightmap of ridges (fractal crest lines) running across the view at
    ``ranges_km`` from the camera; the image is rendered by marching each pixel's ray over
    the heightmap (earth curvature included, datum radius 6360 km), with Lambertian shading
    by the sun and a grey-green albedo (no air: that is what the effect adds).

    Parameters
    ----------
    width, height : int
        Image size [pixels], 8..4096.
    seed : int
        Random seed of the ridge shapes.
    camera : Camera, optional
        Default ``DEFAULT_CAMERA`` (60 deg wide, looking north 2 deg up from 300 m).
    sun : skydome.Sun, optional
        For the shading (default elevation 25 deg, azimuth 120 deg).
    ranges_km : sequence of float
        Distances of the ridges from the camera along the view's azimuth [km].

    Returns
    -------
    image : (height, width, 3) linear sRGB, 1 = white surface facing the sun; sky pixels 0
    depth_m : (height, width) ray distance to the terrain [m]; inf for the sky
    heightmap : Heightmap of the terrain (grid 200 m)
    """
    from skydome.sun import Sun

    width = check_int("width", width, 8, 4096)
    height = check_int("height", height, 8, 4096)
    seed = check_int("seed", seed, 0, 2 ** 32 - 1)
    cam = DEFAULT_CAMERA if camera is None else Camera.make(camera)
    sun = sun if sun is not None else Sun(elevation_deg=25.0, azimuth_deg=120.0)
    rng = np.random.default_rng(seed)
    f, right, _ = cam.basis()
    fh = np.array([f[0], f[1], 0.0]) / np.hypot(f[0], f[1])
    rh = np.array([right[0], right[1], 0.0])
    far = 1000.0 * max(ranges_km) * MARCH_RANGE
    half = far * np.tan(np.radians(min(cam.fov_deg, 150.0)) / 2.0) * 1.3 + 2000.0
    step = 200.0
    # grid covering the view's footprint
    corners = np.array([[cam.east_m, cam.north_m]] * 1) + np.array(
        [a * fh[:2] * far + b * rh[:2] * half for a in (-0.1, 1.0) for b in (-1.0, 1.0)])
    x = np.arange(corners[:, 0].min() - step, corners[:, 0].max() + 2 * step, step)
    y = np.arange(corners[:, 1].min() - step, corners[:, 1].max() + 2 * step, step)
    X, Y = np.meshgrid(x, y)
    along = (X - cam.east_m) * fh[0] + (Y - cam.north_m) * fh[1]
    across = (X - cam.east_m) * rh[0] + (Y - cam.north_m) * rh[1]
    Hm = np.zeros_like(X)
    for i, r_km in enumerate(ranges_km):
        r = 1000.0 * r_km
        peak = (350.0 + 120.0 * r_km ** 0.8) * rng.uniform(0.8, 1.2)   # farther ridges are higher
        crest = peak * (0.65 + 0.35 * _ridge_noise(rng, across, base_wavelength_m=6000.0 + 400.0 * r_km))
        crest_pos = r + 0.08 * r * _ridge_noise(rng, across, octaves=3, base_wavelength_m=20000.0)
        w = 0.35 * r ** 0.85 + 600.0
        Hm = np.maximum(Hm, crest * np.exp(-((along - crest_pos) / w) ** 2))
    hm = Heightmap(Hm, x, y)

    # render: march each ray over the heightmap
    dirs = cam.ray_directions(width, height)
    mu = dirs[..., 2]
    n_steps = MARCH_STEPS
    ts = far * (np.arange(1, n_steps + 1) / n_steps) ** 1.5
    depth = np.full((height, width), np.inf)
    hit_prev = np.zeros((height, width), dtype=bool)
    t_prev = np.zeros((height, width))
    for t in ts:
        alive = ~hit_prev
        if not np.any(alive):
            break
        alt = _altitude_flat_consistent(t, mu, cam.altitude_m)
        hx = cam.east_m + t * dirs[..., 0]
        hy = cam.north_m + t * dirs[..., 1]
        ground = hm.height(hx, hy)
        hit = alive & (alt <= ground)
        # refine by linear interpolation of the height difference within the step
        if np.any(hit):
            ap = _altitude_flat_consistent(t_prev, mu, cam.altitude_m)
            gp = hm.height(cam.east_m + t_prev * dirs[..., 0], cam.north_m + t_prev * dirs[..., 1])
            d0, d1 = ap - gp, alt - ground
            frac = np.clip(d0 / np.maximum(d0 - d1, 1e-9), 0.0, 1.0)
            depth = np.where(hit, t_prev + frac * (t - t_prev), depth)
            hit_prev |= hit
        t_prev = np.where(hit_prev, t_prev, t)
    # shading: normals from the heightmap gradient, Lambert with the sun, a little sky fill
    lambert = terrain_lambert(hm, sun.direction)
    top = shadow_volume_top(hm, sun.direction)
    finite = np.isfinite(depth)
    t_hit = np.where(finite, depth, 0.0)
    px = cam.east_m + t_hit * dirs[..., 0]
    py = cam.north_m + t_hit * dirs[..., 1]
    shade = hm.sample(lambert, px, py)
    lit = hm.height(px, py) + 1.0 >= hm.sample(top, px, py, outside=-np.inf)
    albedo = TERRAIN_ALBEDO * (0.85 + 0.3 * rng.random((height, width, 1)))
    img = albedo * (np.where(lit, shade, 0.0)[..., None] + TERRAIN_FILL)
    img = np.where(finite[..., None], img, 0.0)
    return img, depth, hm
