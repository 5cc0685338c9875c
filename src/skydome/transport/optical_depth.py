"""Optical depth along rays in a spherical-shell atmosphere (survey eq. 12).

t(s, lambda) = integral over the path of beta(lambda) rho(h(s)) ds      [KRZ06] eq. 12

Three ways to get it:

* :func:`column_density` -- numerical quadrature of the density along the ray (any profile);
* :func:`chapman_column` -- the Chapman-function approximation for exponential profiles
  (asymptotic erfcx form), good to 0.13 % on Earth (see ``docs/models.md``);
* :class:`ColumnTable` -- a table of quadrature columns on Bruneton's (2017) transmittance
  parametrisation, interpolated bilinearly (what the single-scattering kernel uses for
  the light paths).

A column density is the integral of the *relative* density [m]; multiplying it by a
constituent's reference extinction coefficient [m^-1] gives that constituent's optical
depth. Rays start at altitude ``altitude_m`` with cosine ``cos_zenith`` between the ray and
the local vertical and end at the top of the atmosphere or where they hit the ground.

References
----------
[KRZ06] Kment, Rauter & Zotti, "Modelling of Daylight for Computer Graphics", TU Wien
    (the survey), eq. 12.
[Bru17] Bruneton, E. 2017. Precomputed Atmospheric Scattering: a New Implementation.
[Cha31] Chapman, S. 1931. The absorption and ionising effect of monochromatic radiation in
    an atmosphere on a rotating earth. Proc. Phys. Soc. 43, 483.
"""

from __future__ import annotations

import numpy as np

from skydome._validate import check_int, check_number
from skydome.constants import EARTH_RADIUS

__all__ = ["column_density", "optical_depth", "chapman_column", "chapman", "ColumnTable",
           "DEFAULT_QUADRATURE_SCALE_M"]

# Scale of the geometric node spacing of the quadrature [m] (see transport/_kernels.py).
DEFAULT_QUADRATURE_SCALE_M = 500.0


def _rays(altitude_m, cos_zenith, planet_radius_m, top_radius_m):
    h = np.asarray(altitude_m, dtype=np.float64)
    mu = np.asarray(cos_zenith, dtype=np.float64)
    if np.any(~np.isfinite(h)) or np.any(h < 0.0):
        raise ValueError(f"altitude_m = {h.min():g} m is out of range [0, inf) m")
    if np.any(~np.isfinite(mu)) or np.any(np.abs(mu) > 1.0):
        bad = mu[~(np.abs(mu) <= 1.0)].ravel()[0]
        raise ValueError(f"cos_zenith = {bad:g} is out of range [-1, 1]")
    if np.any(planet_radius_m + h > top_radius_m):
        raise ValueError(f"altitude_m = {h.max():g} m is out of range [0, "
                         f"{top_radius_m - planet_radius_m:g}] m (inside the atmosphere)")
    h, mu = np.broadcast_arrays(h, mu)
    return h, mu


def column_density(profile, altitude_m, cos_zenith, planet_radius_m=EARTH_RADIUS,
                   top_radius_m=EARTH_RADIUS + 100e3,
                   samples: int = 256, scale_m: float = DEFAULT_QUADRATURE_SCALE_M) -> np.ndarray:
    """Column density of a density profile along rays, by quadrature [m].

    Parameters
    ----------
    profile : skydome.atmosphere.profiles.DensityProfile
        Relative density as a function of altitude.
    altitude_m : array_like
        Altitude of the ray origin above the ground [m], inside the atmosphere.
    cos_zenith : array_like
        Cosine of the angle between the ray and the local vertical, in [-1, 1].
    planet_radius_m, top_radius_m : float
        Radii of the ground and of the top of the atmosphere [m].
    samples : int
        Midpoint nodes per piece of the ray (the ray is split at its lowest point), >= 2.
    scale_m : float
        Scale of the geometric node spacing [m].

    Returns
    -------
    numpy.ndarray
        Integral of the relative density from the origin to the top of the atmosphere or
        to the ground [m], broadcast shape of the inputs.
    """
    from skydome.transport import _kernels as K

    samples = check_int("samples", samples, 2, 1_000_000)
    scale_m = check_number("scale_m", scale_m, 0.0, 1e7, "m", low_open=True)
    h, mu = _rays(altitude_m, cos_zenith, planet_radius_m, top_radius_m)
    code, p0, p1 = profile.kernel_params()
    out = np.zeros((h.size, 1))
    K.columns_quadrature(np.array([code], dtype=np.int64), np.array([p0]), np.array([p1]),
                         (planet_radius_m + h).ravel(), mu.ravel(), float(planet_radius_m),
                         float(top_radius_m), samples, scale_m, out)
    return out[:, 0].reshape(h.shape)


def optical_depth(atmosphere, altitude_m, cos_zenith, wavelengths_nm, method: str = "quadrature",
                  samples: int = 256) -> np.ndarray:
    """Optical depth of the whole atmosphere along rays (survey eq. 12), shape (..., n_lambda).

    ``method`` is "quadrature" (any profile) or "chapman" (exponential profiles by the
    Chapman approximation; other profiles by quadrature).
    """
    from skydome._validate import as_wavelengths, check_choice

    check_choice("method", method, ("quadrature", "chapman"))
    wl = as_wavelengths(wavelengths_nm)
    h, mu = _rays(altitude_m, cos_zenith, atmosphere.planet_radius_m, atmosphere.top_radius_m)
    total = np.zeros(h.shape + (wl.size,))
    for c in atmosphere.constituents:
        ext = c.scattering(wl) + c.absorption(wl)
        code, p0, _ = c.profile.kernel_params()
        if method == "chapman" and code == 0:
            col = chapman_column(p0, h, mu, atmosphere.planet_radius_m)
        else:
            col = column_density(c.profile, h, mu, atmosphere.planet_radius_m,
                                 atmosphere.top_radius_m, samples)
        total += col[..., None] * ext
    return total


def chapman(x, cos_chi) -> np.ndarray:
    """Chapman grazing-incidence function Ch(x, chi), asymptotic approximation.

    Ch(x, chi) is the column of an exponential atmosphere along a ray at zenith angle chi
    from radius r, divided by the vertical column, with x = r / H. For cos chi >= 0 the
    first term of its asymptotic expansion for large x ([Cha31]; e.g. Huestis 2001, eq. 8):

        Ch(x, chi) ~ sqrt(pi x / 2) erfcx(sqrt(x / 2) cos chi),   erfcx(y) = exp(y^2) erfc(y),

    which is exact in the flat limit (1 / cos chi for x -> inf) and errs by -1/x relative at
    the zenith (-0.13 % for the 8 km Rayleigh profile on Earth, -0.05 % at the horizon).
    For cos chi < 0 the ray passes a lowest point at x0 = x sin chi and climbs again:

        Ch(x, chi) = 2 exp(x - x0) Ch(x0, 90 deg) - Ch(x, 180 deg - chi).

    The top of the atmosphere is taken at infinity.

    References: Huestis, D. L. 2001. Accurate evaluation of the Chapman function for
    atmospheric attenuation. J. Quant. Spectrosc. Radiat. Transfer 69, 709-721.
    """
    from scipy.special import erfcx

    x = np.asarray(x, dtype=np.float64)
    mu = np.asarray(cos_chi, dtype=np.float64)
    up = np.sqrt(0.5 * np.pi * x) * erfcx(np.sqrt(0.5 * x) * np.abs(mu))
    sin_chi = np.sqrt(np.maximum(1.0 - mu * mu, 0.0))
    x0 = x * sin_chi
    with np.errstate(over="ignore", invalid="ignore"):
        down = 2.0 * np.sqrt(0.5 * np.pi * x0) * np.exp(x - x0) - up
    return np.where(mu >= 0.0, up, down)


def chapman_column(scale_height_m, altitude_m, cos_zenith, planet_radius_m=EARTH_RADIUS) -> np.ndarray:
    """Column of an exponential profile exp(-h/H) along rays, by the Chapman approximation [m]:
    H exp(-h/H) Ch((R + h)/H, chi); infinite where the ray hits the ground."""
    H = float(scale_height_m)
    h = np.asarray(altitude_m, dtype=np.float64)
    mu = np.asarray(cos_zenith, dtype=np.float64)
    r = planet_radius_m + h
    col = H * np.exp(-h / H) * chapman(r / H, mu)
    hits = (mu < 0.0) & (r * r * (mu * mu - 1.0) + planet_radius_m ** 2 >= 0.0)
    return np.where(hits, np.inf, col)


class ColumnTable:
    """Column densities of every constituent to the top of the atmosphere, tabulated on
    Bruneton's (2017) transmittance parametrisation and interpolated bilinearly.

    x_r = rho / H with rho = sqrt(r^2 - R^2), H = sqrt(Rt^2 - R^2); x_mu = (d - d_min) /
    (d_max - d_min) with d the distance to the top, d_min = Rt - r, d_max = rho + H
    ([Bru17], GetTransmittanceTextureUvFromRMu). Rays that hit the ground are not in the
    table: they are in the planet's shadow.

    Parameters
    ----------
    props : skydome.atmosphere.OpticalProperties
    n_r, n_mu : int
        Table size (default 256 x 512).
    samples : int
        Quadrature nodes per ray piece for each entry (default 128).
    """

    def __init__(self, props, n_r: int = 256, n_mu: int = 512, samples: int = 128,
                 scale_m: float = DEFAULT_QUADRATURE_SCALE_M):
        from skydome.transport import _kernels as K

        self.n_r = check_int("n_r", n_r, 4, 4096)
        self.n_mu = check_int("n_mu", n_mu, 4, 16384)
        self.samples = check_int("samples", samples, 2, 100_000)
        self.props = props
        self.table = K.build_column_table(props.profile_code, props.profile_p0, props.profile_p1,
                                          float(props.planet_radius_m), float(props.top_radius_m),
                                          self.n_r, self.n_mu, self.samples, float(scale_m))

    _cache: dict = {}

    @classmethod
    def cached(cls, props, n_r: int = 256, n_mu: int = 512, samples: int = 128,
               scale_m: float = DEFAULT_QUADRATURE_SCALE_M) -> "ColumnTable":
        """A table shared by every caller with the same geometry and profiles (the columns
        do not depend on wavelength)."""
        key = (tuple(props.profile_code), tuple(props.profile_p0), tuple(props.profile_p1),
               float(props.planet_radius_m), float(props.top_radius_m), n_r, n_mu, samples,
               float(scale_m))
        if key not in cls._cache:
            if len(cls._cache) >= 8:
                cls._cache.pop(next(iter(cls._cache)))
            cls._cache[key] = cls(props, n_r, n_mu, samples, scale_m)
        return cls._cache[key]

    def lookup(self, altitude_m, cos_zenith) -> np.ndarray:
        """Interpolated columns (..., n_constituents) [m]; inf where the ray hits the ground."""
        from skydome.transport import _kernels as K

        p = self.props
        h, mu = _rays(altitude_m, cos_zenith, p.planet_radius_m, p.top_radius_m)
        r = (p.planet_radius_m + h).ravel()
        m = mu.ravel()
        nc = self.table.shape[0]
        out = np.empty((r.size, nc))
        for i in range(r.size):
            if K.ray_hits_ground(r[i], m[i], p.planet_radius_m):
                out[i] = np.inf
            else:
                for c in range(nc):
                    out[i, c] = K.table_lookup(self.table, c, r[i], m[i], p.planet_radius_m,
                                               p.top_radius_m)
        return out.reshape(h.shape + (nc,))
