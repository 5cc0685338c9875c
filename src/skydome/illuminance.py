"""Illuminance and irradiance of any sky model on horizontal, vertical and tilted planes.

A plane is given by its tilt from the horizontal ``tilt_deg`` in [0, 180] (0: facing the
zenith, 90: a vertical wall, 180: facing the ground) and the azimuth its normal points to
``azimuth_deg`` (from north towards east, as the sun's: 180 is a south-facing wall), the
names and conventions of pvlib's ``surface_tilt`` / ``surface_azimuth``. Its unit normal
in the East-North-Up frame is::

    n = (sin(tilt) sin(azimuth), sin(tilt) cos(azimuth), cos(tilt))

Three parts of the light reach the plane and are returned separately:

* **sky**: ``E_sky = integral L(d) max(d . n, 0) d(omega)`` over the sky hemisphere
  (``d_z > 0``), the sun's disc excluded (models return the sky without the sun);
* **sun**: ``E_sun = E_n max(s . n, 0)`` for the sun above the horizon, ``E_n`` the model's
  direct normal illuminance (:meth:`SkyModel.direct_normal_illuminance`) or spectral
  irradiance (``sun_radiance x solid angle``); 0 for models without a sun;
* **ground** (optional, ``ground_albedo`` given): a Lambertian ground of reflectance rho lit
  by the global horizontal light is seen by the plane through its view factor
  ``(1 - cos tilt) / 2``: ``E_ground = rho (E_sky,h + E_sun,h) (1 - cos tilt) / 2``
  (the isotropic ground of Liu & Jordan 1963, as pvlib's ``get_ground_diffuse``).

Illuminance [lx] is computed from the model's luminance [cd m^-2], so it works for every
model, spectral or luminance-only; spectral irradiance [W m^-2 nm^-1] needs a model with
``radiance()`` (spectral or XYZ native).

Quadrature
----------
Gauss-Legendre in the zenith angle on [0, pi/2] (weight sin(theta)); on each ring the azimuths where the
plane sees the sky (``d . n > 0``) form one arc found in closed form, integrated with the
periodic midpoint rule where the arc is the whole circle and with Gauss-Legendre nodes on
the arc otherwise. The kink of ``max(d . n, 0)`` therefore never falls inside a cell, and
a uniform sky is integrated to round-off on every plane. With the defaults (``n_mu=64``,
``n_phi=128``) the error for the sharpest CIE sky (type 15, tests) is below 1e-4.

References
----------
.. [LJ63] Liu, B. Y. H., Jordan, R. C. (1963). The long-term average performance of
   flat-plate solar-energy collectors. Solar Energy 7(2), 53-74.
.. [CIE03] CIE S 011/E:2003, Spatial distribution of daylight - CIE standard general sky.

Examples
--------
>>> import skydome as sd
>>> from skydome import illuminance as il
>>> sky = sd.model("cie2003", sun=sd.Sun(elevation_deg=40, azimuth_deg=180), sky_type=12)
>>> e = il.illuminance(sky, tilt_deg=90, azimuth_deg=180, ground_albedo=0.2)
>>> e.sky, e.sun, e.ground, e.total                                    # doctest: +SKIP
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from skydome._validate import check_int, check_number

__all__ = ["PlaneLight", "plane_normal", "sky_quadrature", "sky_illuminance",
           "sun_illuminance", "ground_illuminance", "illuminance", "horizontal_illuminance",
           "vertical_illuminance", "sky_irradiance", "sun_irradiance", "irradiance"]

N_MU_DEFAULT = 64
N_PHI_DEFAULT = 128


@dataclass(frozen=True)
class PlaneLight:
    """The light on one plane, by part.

    Attributes
    ----------
    sky, sun, ground : float or numpy.ndarray
        Illuminance [lx] (from :func:`illuminance`) or spectral irradiance
        [W m^-2 nm^-1], shape (n_wavelengths,) (from :func:`irradiance`); ``ground`` is 0
        when no ``ground_albedo`` was given.
    unit : str
        "lx" or "W m^-2 nm^-1".
    """

    sky: float | np.ndarray
    sun: float | np.ndarray
    ground: float | np.ndarray
    unit: str

    @property
    def total(self):
        """sky + sun + ground."""
        return self.sky + self.sun + self.ground

    @property
    def diffuse(self):
        """sky + ground (everything but the direct sun)."""
        return self.sky + self.ground


# -- planes and nodes -------------------------------------------------------------------------
def _check_plane(tilt_deg, azimuth_deg) -> tuple[float, float]:
    t = check_number("tilt_deg", tilt_deg, 0.0, 180.0, "deg")
    a = check_number("azimuth_deg", azimuth_deg, unit="deg") % 360.0
    return t, a


def plane_normal(tilt_deg: float = 0.0, azimuth_deg: float = 180.0) -> np.ndarray:
    """Unit normal (3,) East-North-Up of a plane tilted ``tilt_deg`` [deg] in [0, 180] from
    the horizontal, facing ``azimuth_deg`` [deg] (from north towards east)."""
    t, a = _check_plane(tilt_deg, azimuth_deg)
    tr, ar = math.radians(t), math.radians(a)
    return np.array([math.sin(tr) * math.sin(ar), math.sin(tr) * math.cos(ar), math.cos(tr)])


@lru_cache(maxsize=16)
def _gauss_01(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [0, 1].

    numpy's ``leggauss`` finds the nodes as the eigenvalues of an n x n matrix (LAPACK,
    through the BLAS library's threads): run with one BLAS thread, for the same bits (tested)
    without the threads' start and hand-offs, which took 2.6-2.8 s of CPU for n = 512 on a
    2-core machine with other jobs against 0.02 s on one thread (docs/performance.md)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def sky_quadrature(normal=(0.0, 0.0, 1.0), n_mu: int = N_MU_DEFAULT,
                   n_phi: int = N_PHI_DEFAULT) -> tuple[np.ndarray, np.ndarray]:
    """Directions and weights for ``integral_sky f(d) max(d . n, 0) d(omega)``.

    Parameters
    ----------
    normal : array_like
        Plane normal (3,), East-North-Up (normalised here).
    n_mu, n_phi : int
        Nodes in the zenith angle (Gauss-Legendre on [0, pi/2]) and along each azimuth arc.

    Returns
    -------
    directions : numpy.ndarray
        (k, 3) unit vectors of the upper hemisphere seen by the plane.
    weights : numpy.ndarray
        (k,) solid angle times ``d . n`` [sr], so that ``sum(weights * f(directions))``
        is the integral; ``sum(weights)`` is the plane's view of a unit uniform sky.
    """
    n_mu = check_int("n_mu", n_mu, 2, 4096)
    n_phi = check_int("n_phi", n_phi, 4, 8192)
    nv = np.asarray(normal, dtype=np.float64)
    if nv.shape != (3,) or not np.all(np.isfinite(nv)) or not np.any(nv):
        raise ValueError(f"normal must be a finite non-zero 3-vector, got {normal!r}")
    nv = nv / np.linalg.norm(nv)
    nx, ny, nz = nv
    a_h = math.hypot(nx, ny)            # horizontal part of the normal
    phi_n = math.atan2(nx, ny)          # its azimuth (from north towards east)
    # Nodes in the zenith angle theta with weight sin(theta) d(theta), so that sin and cos
    # of theta are smooth in the variable. Rings with theta < theta_c = |pi/2 - tilt| are
    # seen whole (tilt < 90) or not at all (tilt > 90); beyond theta_c the seen arc grows
    # like sqrt(theta - theta_c), which the substitution theta = theta_c + (pi/2 -
    # theta_c) u^2 makes smooth in u. Each part gets its own Gauss-Legendre rule.
    theta_c = abs(0.5 * math.pi - math.acos(max(-1.0, min(1.0, nz))))
    n_a = 0 if theta_c <= 0.0 else max(2, int(round(n_mu * theta_c / (0.5 * math.pi))))
    n_b = 0 if theta_c >= 0.5 * math.pi - 1e-12 else max(2, n_mu - n_a)
    theta_parts, w_parts = [], []
    if n_a:
        tq, wq = _gauss_01(n_a)
        theta_parts.append(theta_c * tq)
        w_parts.append(theta_c * wq)
    if n_b:
        uq, wq = _gauss_01(n_b)
        span = 0.5 * math.pi - theta_c
        theta_parts.append(theta_c + span * uq * uq)
        w_parts.append(2.0 * span * uq * wq)
    theta = np.concatenate(theta_parts)
    wmu = np.concatenate(w_parts) * np.sin(theta)
    gx, gw = _gauss_01(n_phi)
    dirs, wts = [], []
    for th, wm in zip(theta, wmu):
        m, s = math.cos(th), math.sin(th)
        # d . n = m nz + s a_h cos(phi - phi_n) > 0  <=>  cos(phi - phi_n) > c
        if a_h * s <= 1e-300:
            c = -math.inf if m * nz > 0.0 else math.inf
        else:
            c = -m * nz / (a_h * s)
        if c >= 1.0:
            continue                     # this ring is behind the plane
        if c <= -1.0:                    # the whole ring: periodic midpoint rule
            phi = phi_n + (np.arange(n_phi) + 0.5) * (2.0 * math.pi / n_phi)
            wphi = np.full(n_phi, 2.0 * math.pi / n_phi)
        else:                            # one arc |phi - phi_n| < acos(c): Gauss-Legendre
            half = math.acos(c)
            phi = phi_n - half + 2.0 * half * gx
            wphi = 2.0 * half * gw
        d = np.stack([s * np.sin(phi), s * np.cos(phi),
                      np.full(phi.size, m)], axis=-1)
        cos_i = np.maximum(d @ nv, 0.0)
        dirs.append(d)
        wts.append(wm * wphi * cos_i)
    if not dirs:
        return np.zeros((0, 3)), np.zeros(0)
    return np.concatenate(dirs), np.concatenate(wts)


def _planes(tilt_deg, azimuth_deg):
    """Broadcast plane angles; returns (shape, list of (tilt, azimuth))."""
    if np.ndim(tilt_deg) == 0 and np.ndim(azimuth_deg) == 0:
        return None, [_check_plane(tilt_deg, azimuth_deg)]
    t, a = np.broadcast_arrays(np.asarray(tilt_deg, dtype=np.float64),
                               np.asarray(azimuth_deg, dtype=np.float64))
    return t.shape, [_check_plane(float(x), float(y)) for x, y in zip(t.ravel(), a.ravel())]


def _shape_out(shape, values):
    if shape is None:
        return values[0]
    arr = np.asarray(values, dtype=np.float64)
    return arr.reshape(shape + arr.shape[1:])


def _check_model(sky) -> None:
    if not (callable(getattr(sky, "luminance", None)) and hasattr(sky, "sun")):
        raise TypeError(f"sky must be a skydome sky model, not {type(sky).__name__}")


# -- illuminance [lx] ------------------------------------------------------------------------
def sky_illuminance(sky, tilt_deg=0.0, azimuth_deg=180.0, *, n_mu: int = N_MU_DEFAULT,
                    n_phi: int = N_PHI_DEFAULT):
    """Illuminance from the sky alone (no sun, no ground) on a plane [lx].

    Parameters
    ----------
    sky : SkyModel
        Any model (its :meth:`luminance` is integrated).
    tilt_deg, azimuth_deg : float or array_like
        Plane tilt [deg] in [0, 180] and facing azimuth [deg]; broadcast together.
    n_mu, n_phi : int
        Quadrature nodes (see :func:`sky_quadrature`).

    Returns
    -------
    float or numpy.ndarray
        [lx], the shape of the broadcast plane angles.
    """
    _check_model(sky)
    shape, planes = _planes(tilt_deg, azimuth_deg)
    out = []
    for t, a in planes:
        d, w = sky_quadrature(plane_normal(t, a), n_mu, n_phi)
        out.append(float(w @ np.asarray(sky.luminance(d), dtype=np.float64)) if w.size else 0.0)
    return _shape_out(shape, out)


def _sun_cosine(sky, t: float, a: float) -> float:
    sun = sky.sun
    if sun is None or sun.elevation_deg <= 0.0:
        return 0.0
    return max(float(plane_normal(t, a) @ sun.direction), 0.0)


def sun_illuminance(sky, tilt_deg=0.0, azimuth_deg=180.0):
    """Direct illuminance of the sun on a plane [lx]: ``E_n max(s . n, 0)``, 0 with the sun
    at or below the horizon or for a model without a sun."""
    _check_model(sky)
    return _direct(sky, tilt_deg, azimuth_deg, lambda: float(sky.direct_normal_illuminance()),
                   0.0)


def _direct(sky, tilt_deg, azimuth_deg, normal_value, zero):
    """``normal_value() x max(s . n, 0)`` on each plane (``zero`` where the sun does not
    reach it); ``normal_value`` is called at most once."""
    shape, planes = _planes(tilt_deg, azimuth_deg)
    e_n = None
    out = []
    for t, a in planes:
        c = _sun_cosine(sky, t, a)
        if c > 0.0 and e_n is None:
            e_n = normal_value()
        out.append(e_n * c if c > 0.0 else zero)
    return _shape_out(shape, out)


def _view_factor_ground(t: float) -> float:
    return 0.5 * (1.0 - math.cos(math.radians(t)))   # [LJ63]


def ground_illuminance(sky, tilt_deg=0.0, azimuth_deg=180.0, *, ground_albedo: float,
                       n_mu: int = N_MU_DEFAULT, n_phi: int = N_PHI_DEFAULT):
    """Illuminance reflected by a Lambertian ground of reflectance ``ground_albedo`` in
    [0, 1] onto a plane [lx]: ``rho E_global,h (1 - cos tilt) / 2`` [LJ63]."""
    _check_model(sky)
    rho = check_number("ground_albedo", ground_albedo, 0.0, 1.0)
    shape, planes = _planes(tilt_deg, azimuth_deg)
    e_h = None
    out = []
    for t, a in planes:
        f = _view_factor_ground(t)
        if f > 0.0 and rho > 0.0 and e_h is None:
            e_h = sky_illuminance(sky, 0.0, 0.0, n_mu=n_mu, n_phi=n_phi) + sun_illuminance(sky)
        out.append(rho * e_h * f if (f > 0.0 and rho > 0.0) else 0.0)
    return _shape_out(shape, out)


def illuminance(sky, tilt_deg=0.0, azimuth_deg=180.0, *, ground_albedo: float | None = None,
                n_mu: int = N_MU_DEFAULT, n_phi: int = N_PHI_DEFAULT) -> PlaneLight:
    """Sky, sun and (with ``ground_albedo``) ground-reflected illuminance on a plane [lx].

    Parameters
    ----------
    sky : SkyModel
        Any registered model.
    tilt_deg, azimuth_deg : float or array_like
        Tilt from the horizontal [deg] in [0, 180] and the azimuth the plane faces [deg]
        (north 0, east 90); broadcast together.
    ground_albedo : float, optional
        Reflectance of a Lambertian ground in [0, 1]; None: no ground-reflected part.
    n_mu, n_phi : int
        Quadrature nodes for the sky integral.

    Returns
    -------
    PlaneLight
        ``sky``, ``sun``, ``ground`` [lx] (floats, or arrays shaped like the plane
        angles), ``total`` and ``diffuse``.
    """
    _check_model(sky)
    if ground_albedo is not None:
        check_number("ground_albedo", ground_albedo, 0.0, 1.0)
    e_sky = sky_illuminance(sky, tilt_deg, azimuth_deg, n_mu=n_mu, n_phi=n_phi)
    e_sun = sun_illuminance(sky, tilt_deg, azimuth_deg)
    if ground_albedo is None:
        e_gnd = 0.0 * np.asarray(e_sky) if np.ndim(e_sky) else 0.0
    else:
        e_gnd = ground_illuminance(sky, tilt_deg, azimuth_deg, ground_albedo=ground_albedo,
                                   n_mu=n_mu, n_phi=n_phi)
    return PlaneLight(e_sky, e_sun, e_gnd, "lx")


def horizontal_illuminance(sky, *, ground_albedo: float | None = None,
                           n_mu: int = N_MU_DEFAULT, n_phi: int = N_PHI_DEFAULT) -> PlaneLight:
    """:func:`illuminance` on the horizontal plane (tilt 0)."""
    return illuminance(sky, 0.0, 180.0, ground_albedo=ground_albedo, n_mu=n_mu, n_phi=n_phi)


def vertical_illuminance(sky, azimuth_deg=180.0, *, ground_albedo: float | None = None,
                         n_mu: int = N_MU_DEFAULT, n_phi: int = N_PHI_DEFAULT) -> PlaneLight:
    """:func:`illuminance` on a vertical plane (tilt 90) facing ``azimuth_deg``."""
    return illuminance(sky, 90.0, azimuth_deg, ground_albedo=ground_albedo, n_mu=n_mu,
                       n_phi=n_phi)


# -- spectral irradiance [W m^-2 nm^-1] ------------------------------------------------------
def _check_spectral(sky, wavelengths_nm) -> np.ndarray:
    from skydome._validate import as_wavelengths

    _check_model(sky)
    if getattr(sky, "native", "spectral") == "luminance":
        raise TypeError(f"model {getattr(sky, 'name', sky)!r} is luminance-only: use "
                        "illuminance() for lx")
    return as_wavelengths(wavelengths_nm)


def sky_irradiance(sky, wavelengths_nm, tilt_deg=0.0, azimuth_deg=180.0, *,
                   n_mu: int = N_MU_DEFAULT, n_phi: int = N_PHI_DEFAULT):
    """Spectral irradiance from the sky alone on a plane [W m^-2 nm^-1], shape
    plane-shape + (n_wavelengths,)."""
    wl = _check_spectral(sky, wavelengths_nm)
    shape, planes = _planes(tilt_deg, azimuth_deg)
    out = []
    for t, a in planes:
        d, w = sky_quadrature(plane_normal(t, a), n_mu, n_phi)
        out.append(w @ np.asarray(sky.radiance(d, wl), dtype=np.float64) if w.size
                   else np.zeros(wl.size))
    return _shape_out(shape, out)


def sun_irradiance(sky, wavelengths_nm, tilt_deg=0.0, azimuth_deg=180.0):
    """Direct spectral irradiance of the sun on a plane [W m^-2 nm^-1]:
    ``sun_radiance x solid angle x max(s . n, 0)``; zeros without a sun above the horizon."""
    wl = _check_spectral(sky, wavelengths_nm)

    def normal_value():
        ls = sky.sun_radiance(wl)
        return (np.zeros(wl.size) if ls is None
                else np.asarray(ls, dtype=np.float64).reshape(-1) * sky.sun.solid_angle_sr)

    return _direct(sky, tilt_deg, azimuth_deg, normal_value, np.zeros(wl.size))


def irradiance(sky, wavelengths_nm, tilt_deg=0.0, azimuth_deg=180.0, *,
               ground_albedo: float | None = None, n_mu: int = N_MU_DEFAULT,
               n_phi: int = N_PHI_DEFAULT) -> PlaneLight:
    """Sky, sun and (with ``ground_albedo``, grey Lambertian) ground-reflected spectral
    irradiance on a plane [W m^-2 nm^-1], each of shape plane-shape + (n_wavelengths,).
    Arguments as :func:`illuminance`."""
    wl = _check_spectral(sky, wavelengths_nm)
    rho = None if ground_albedo is None else check_number("ground_albedo", ground_albedo, 0.0, 1.0)
    e_sky = sky_irradiance(sky, wl, tilt_deg, azimuth_deg, n_mu=n_mu, n_phi=n_phi)
    e_sun = sun_irradiance(sky, wl, tilt_deg, azimuth_deg)
    if rho is None or rho == 0.0:
        e_gnd = np.zeros_like(np.asarray(e_sky))
    else:
        e_h = sky_irradiance(sky, wl, n_mu=n_mu, n_phi=n_phi) + sun_irradiance(sky, wl)
        shape, planes = _planes(tilt_deg, azimuth_deg)
        e_gnd = _shape_out(shape, [rho * e_h * _view_factor_ground(t) for t, _ in planes])
    return PlaneLight(e_sky, e_sun, e_gnd, "W m^-2 nm^-1")
