"""The ground below the horizon of an environment map.

A Lambertian ground of albedo rho, lit by the model's sky and sun, has the radiance

    L_ground = rho E_h / pi,   E_h = int_(upper hemisphere) L_sky cos(theta) dOmega
                                     + E_n,sun x sin(sun elevation) x (visible part of the disc)

for an observer standing on it (no air between the eye and the ground). E_h is computed
by Gauss-Legendre quadrature in cos(theta) (32 nodes) times the midpoint rule in azimuth
(64 nodes) over the model's own sky.

``ground="model"`` (the default of :func:`skydome.imaging.render`): models that trace
ground-hit rays themselves (the physically based ones: their radiance below the horizon
is the ground seen through the air in front of it; ``own_ground`` on the model's class,
:mod:`skydome.models`) keep their values. Two of them light their ground with the
transmitted sun only (``own_ground = "sun"``: measured, the nadir
of a ground-level observer at sun 40 deg is rho E_sun sin(el) / pi to 1e-6, while
``precomputed``, ``nishita1996`` and ``montecarlo`` give rho E_h / pi within 2 %); for a
ground-level observer of those, the skylight term rho E_sky / pi is added. For the other
models (the analytic ones give nothing below the horizon) the ground is the Lambertian
one above. ``ground="black"``: nothing below the horizon.
``ground="lambertian"``: the Lambertian ground of the model's albedo for every model.
``ground=<albedo in [0, 1]>``: the Lambertian ground of that albedo for every model.

The model's albedo (:func:`model_albedo`, the one rule of skydome's renders and
environment maps): the model's own ground albedo parameter ``albedo`` where it has one
that is set (``hosek_wilkie2012``, ``nishita1993``), else its ``atmosphere.ground_albedo``
(spectral where the atmosphere's is), else 0.2, the default ground reflectance of
Radiance's ``gensky`` (``-g 0.2``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["DEFAULT_ALBEDO", "GROUNDS", "check_ground", "horizontal_irradiance", "apply_ground",
           "model_albedo", "sun_only_ground"]

#: Ground albedo for models without one (Radiance gensky's default ground reflectance).
DEFAULT_ALBEDO = 0.2
#: The named values of ``ground`` (besides an albedo in [0, 1]).
GROUNDS = ("model", "black", "lambertian")


def sun_only_ground() -> tuple[str, ...]:
    """The registered models whose own ground is lit by the transmitted sun only (no
    skylight on the ground): those declaring ``own_ground = "sun"``."""
    from skydome.models import available

    return tuple(n for n, cls in available().items() if cls.own_ground == "sun")


def __getattr__(name):
    # SUN_ONLY_GROUND, read from the models' capabilities when asked for
    if name == "SUN_ONLY_GROUND":
        return sun_only_ground()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def check_ground(ground):
    """Validate ``ground``: "model", "black", "lambertian" or an albedo in [0, 1]."""
    if isinstance(ground, str):
        if ground not in GROUNDS:
            raise ValueError(f"ground = {ground!r} must be 'model', 'black', 'lambertian' or "
                             "an albedo in [0, 1]")
        return ground
    if isinstance(ground, bool) or not isinstance(ground, (int, float, np.floating, np.integer)):
        raise TypeError(f"ground must be 'model', 'black', 'lambertian' or an albedo in [0, 1], "
                        f"got {ground!r}")
    g = float(ground)
    if not 0.0 <= g <= 1.0:
        raise ValueError(f"ground = {g} is out of range [0, 1] (an albedo)")
    return g


def _sky_values(sky, dirs, wl):
    if wl is not None:
        return np.asarray(sky.radiance(dirs, wl), dtype=np.float64)
    return np.asarray(sky.xyz(dirs), dtype=np.float64)


def horizontal_irradiance(sky, wavelengths_nm=None, n_mu: int = 32, n_phi: int = 64,
                          include_sun: bool = True) -> np.ndarray:
    """Irradiance on a horizontal plane from the model's sky and (``include_sun``) sun:
    spectral [W m^-2 nm^-1] at ``wavelengths_nm``, or XYZ (Y = illuminance [lx]) if None."""
    from skydome.imaging.sun_disc import XYZ_CHANNEL_WAVELENGTHS_NM, _visible_fraction, sun_disc_radiance

    from skydome.illuminance import sky_quadrature

    # the horizontal plane's directions and weights (cos(theta) included) of the library's
    # one hemisphere quadrature
    d, w = sky_quadrature((0.0, 0.0, 1.0), n_mu, n_phi)
    E = w @ _sky_values(sky, d, wavelengths_nm)
    sun = getattr(sky, "sun", None)
    if include_sun and sun is not None and sun.elevation_deg > -sun.angular_radius_deg:
        Ls = sun_disc_radiance(sky, wavelengths_nm)
        if Ls is not None:
            ch = XYZ_CHANNEL_WAVELENGTHS_NM if wavelengths_nm is None else wavelengths_nm
            vis = _visible_fraction(sun.elevation_deg, sun.angular_radius_deg, ch)
            E = E + Ls * sun.solid_angle_sr * vis * max(np.sin(np.radians(sun.elevation_deg)), 0.0)
    return E


def model_albedo(sky, wavelengths_nm=None) -> np.ndarray | float:
    """The albedo of the model's ground (module docstring): per wavelength at
    ``wavelengths_nm`` (an array, or a float where it is grey), or the value at 555 nm
    when ``wavelengths_nm`` is None (XYZ images)."""
    own = getattr(sky, "albedo", None)
    if isinstance(own, (int, float, np.floating, np.integer)) and not isinstance(own, bool):
        return float(own)
    a = getattr(getattr(sky, "atmosphere", None), "ground_albedo", None)
    if a is None:
        return DEFAULT_ALBEDO
    w = np.asarray(wavelengths_nm if wavelengths_nm is not None else (555.0,), dtype=np.float64)
    v = np.asarray(a(w) if callable(a) else a, dtype=np.float64)
    return v if wavelengths_nm is not None else float(np.ravel(v)[0])


def _albedo(sky, wl, ground) -> np.ndarray | float:
    if ground not in ("model", "lambertian"):
        return float(ground)
    return model_albedo(sky, wl)


def apply_ground(sky, data: np.ndarray, dirs: np.ndarray, mask: np.ndarray, wl, ground,
                 to_xyz=None) -> str | None:
    """Fill the pixels below the horizon of ``data`` in place; returns a description for
    the image metadata (None if no pixel lies below the horizon). ``wl``: the spectral
    channels (None: XYZ); ``to_xyz``: an (n_wl x 3) matrix when ``data`` holds XYZ of
    spectra sampled at ``wl`` (the fused render path)."""
    conv = (lambda v: v) if to_xyz is None else (lambda v: np.asarray(v) @ to_xyz)
    below = mask & (dirs[..., 2] < 0.0)
    if not np.any(below):
        return None
    if ground == "black":
        _fill(data, below, 0.0)
        return "black"
    if ground == "model" and np.any(data[below] > 0.0):
        if (getattr(sky, "own_ground", None) == "sun"
                and float(getattr(sky, "observer_altitude_m", 0.0) or 0.0) == 0.0):
            rho = _albedo(sky, wl, ground)
            data[below] += np.maximum(conv(np.asarray(rho) * horizontal_irradiance(
                sky, wl, include_sun=False) / np.pi), 0.0)
            return "the model's own ground (lit by its sun) plus its skylight, rho E_sky / pi"
        return "the model's own ground-hit rays"
    rho = _albedo(sky, wl, ground)
    L = conv(np.asarray(rho) * horizontal_irradiance(sky, wl) / np.pi)
    _fill(data, below, np.maximum(L, 0.0))
    return (f"Lambertian, albedo {np.round(np.ravel(rho), 4).tolist()}, lit by the model's "
            "sky and sun (observer on the ground)")


def _fill(data: np.ndarray, where: np.ndarray, value) -> None:
    """``data[where] = value`` in place (``data`` (H, W, C), ``where`` (H, W) bool): one
    slice assignment where the pixels are one run in memory (a lat-long map's lower half),
    else ``np.copyto`` through the mask (no gather through a boolean index)."""
    flat = where.reshape(-1)
    n = int(np.count_nonzero(flat))
    first = int(np.argmax(flat)) if n else 0
    if data.flags.c_contiguous and bool(flat[first:first + n].all()):
        data.reshape(-1, data.shape[-1])[first:first + n] = value
    else:
        np.copyto(data, value, where=where[..., None])
