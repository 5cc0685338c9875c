"""Rendering: sample any sky model through a projection into a :class:`SkyImage`.

>>> import skydome as sd
>>> sky = sd.model("single_scattering", sun=sd.Sun(elevation_deg=30, azimuth_deg=135))
>>> image = sd.render(sky, sd.Fisheye(256))
>>> image.save("sky.exr")

Nothing heavy is imported here (OpenEXR, Pillow and matplotlib load when used).
"""

from __future__ import annotations

import sys as _sys
from typing import Callable

import numpy as np

from skydome.render.image import SkyImage
from skydome.render.projections import AngularMap, Equirect, Fisheye, Projection, make_projection

__all__ = ["render", "Equirect", "Fisheye", "AngularMap", "make_projection", "SkyImage",
           "Projection"]


def _visible_disc_fraction(elevation_deg: float, radius_deg: float) -> float:
    """Fraction of the sun's disc above the horizon (flat circular-segment geometry)."""
    d = np.clip(-elevation_deg / radius_deg, -1.0, 1.0)  # horizon offset in disc radii
    # area above the chord at signed distance d: r^2 (acos d - d sqrt(1 - d^2))
    return float((np.arccos(d) - d * np.sqrt(1.0 - d * d)) / np.pi)


def render(sky, projection: Projection, wavelengths_nm=None, *,
           progress: Callable[[int, int], None] | None = None, draw_sun: bool = True,
           chunk: int = 32768) -> SkyImage:
    """Render a sky model into an image.

    Parameters
    ----------
    sky : SkyModel
        Any model. Spectral models (``native == "spectral"``) are sampled with
        ``sky.radiance(directions, wavelengths_nm)`` and give a spectral image; XYZ and
        luminance models with ``sky.xyz(directions)`` and give an XYZ image.
    projection : Projection
        Pixel layout (:class:`Fisheye`, :class:`Equirect`, :class:`AngularMap`).
    wavelengths_nm : array_like, optional
        Wavelengths [nm] for spectral models; default 16 samples 380-780 nm. Ignored for
        XYZ and luminance models.
    progress : callable, optional
        ``progress(done_pixels, total_pixels)``, called after every chunk.
    draw_sun : bool
        Draw the solar disc where the model has a sun with a radiance (see Notes).
    chunk : int
        Directions per model call (>= 1), bounding memory use.

    Returns
    -------
    SkyImage
        Spectral radiance [W m^-2 sr^-1 nm^-1] or XYZ (Y in cd m^-2); masked pixels 0.

    Notes
    -----
    The sun: if ``draw_sun``, ``sky.sun`` is set, ``sky.sun_radiance(wl)`` is not None and
    the sun's elevation exceeds minus its angular radius, every unmasked pixel whose centre
    lies within the sun's angular radius and at or above the horizon (the ground hides the
    rest of a setting sun) takes the sun's radiance. If no pixel centre falls inside the
    disc (a disc smaller than a pixel), the pixel containing the sun's direction becomes
    ``L_pix + (L_sun - L_pix) * Omega_sun / Omega_pix``, which preserves the pixel's flux;
    ``Omega_sun`` is the visible part of the disc's solid angle. For XYZ images the sun's
    spectrum is converted to XYZ.
    """
    from skydome._validate import as_wavelengths, check_int

    if isinstance(sky, str):
        raise TypeError(f"sky must be a sky model, got the string {sky!r}: build the model first, "
                        f"e.g. skydome.model({sky!r}, sun=skydome.Sun(elevation_deg=30, azimuth_deg=180))")
    if not (callable(getattr(sky, "radiance", None)) or callable(getattr(sky, "xyz", None))):
        raise TypeError(f"sky must be a sky model (with radiance() or xyz()), got {type(sky).__name__}")
    if not isinstance(projection, Projection):
        raise TypeError(f"projection must be a skydome Projection, got {type(projection).__name__}")
    chunk = check_int("chunk", chunk, 1, None)
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be callable or None, got {progress!r}")
    native = getattr(sky, "native", "spectral")
    spectral = native == "spectral"
    if spectral:
        if wavelengths_nm is None:
            from skydome.spectra import wavelength_grid

            wl = wavelength_grid(380.0, 780.0, n=16)
        else:
            wl = as_wavelengths(wavelengths_nm)
        n_ch = wl.size
    else:
        wl = None
        n_ch = 3

    dirs, mask = projection.directions()
    H, W = projection.shape
    sel = dirs[mask]
    total = sel.shape[0]
    values = np.empty((total, n_ch), dtype=np.float64)
    for start in range(0, total, chunk):
        d = sel[start:start + chunk]
        v = sky.radiance(d, wl) if spectral else sky.xyz(d)
        v = np.asarray(v, dtype=np.float64)
        if v.shape != (d.shape[0], n_ch):
            raise ValueError(f"model {getattr(sky, 'name', sky)!r} returned shape {v.shape}, "
                             f"expected {(d.shape[0], n_ch)}")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"model {getattr(sky, 'name', sky)!r} returned NaN or infinite values")
        values[start:start + d.shape[0]] = v
        if progress is not None:
            progress(min(start + chunk, total), total)
    data = np.zeros((H, W, n_ch), dtype=np.float64)
    data[mask] = values

    sun = getattr(sky, "sun", None)
    sun_info = None
    if sun is not None:
        sun_info = {"elevation_deg": sun.elevation_deg, "azimuth_deg": sun.azimuth_deg,
                    "angular_radius_deg": sun.angular_radius_deg}
    if draw_sun and sun is not None and sun.elevation_deg > -sun.angular_radius_deg:
        _draw_sun(sky, sun, projection, dirs, mask, data, wl, spectral)

    meta = {}
    describe = getattr(sky, "describe", None)
    if callable(describe):
        desc = describe()
        meta["model"] = desc.get("model", getattr(sky, "name", ""))
        meta["reference"] = desc.get("reference", "")
        meta["parameters"] = desc.get("parameters", {})
    else:
        meta["model"] = getattr(sky, "name", type(sky).__name__)
    if sun_info is not None:
        meta["sun"] = sun_info
    meta["projection"] = projection.describe()
    meta["quantity"] = ("spectral radiance [W m^-2 sr^-1 nm^-1]" if spectral
                        else "CIE 1931 XYZ, Y = luminance [cd m^-2]")
    return SkyImage(data, "spectral" if spectral else "xyz", wl, mask, projection, meta)


def _draw_sun(sky, sun, projection, dirs, mask, data, wl, spectral) -> None:
    """Paint the solar disc into ``data`` in place (see :func:`render` Notes)."""
    if spectral:
        L_sun = sky.sun_radiance(wl)
        if L_sun is None:
            return
        L_sun = np.asarray(L_sun, dtype=np.float64).reshape(-1)
    else:
        from skydome.spectra import default_wavelengths, spectrum_to_xyz

        w = default_wavelengths()
        L = sky.sun_radiance(w)
        if L is None:
            return
        L_sun = spectrum_to_xyz(np.asarray(L, dtype=np.float64).reshape(-1), w)
    if L_sun.shape[0] != data.shape[-1] or not np.all(np.isfinite(L_sun)):
        raise ValueError(f"sun_radiance of model {getattr(sky, 'name', sky)!r} has shape "
                         f"{L_sun.shape} or non-finite values")
    s = np.asarray(sun.direction, dtype=np.float64)
    r = np.radians(sun.angular_radius_deg)
    cos_r = np.cos(r)
    inside = mask & (dirs @ s >= cos_r) & (dirs[..., 2] >= 0.0)
    if np.any(inside):
        data[inside] = L_sun
        return
    row, col = projection.pixel_from_direction(s)
    row, col = float(row), float(col)
    if not (np.isfinite(row) and np.isfinite(col)):
        return
    H, W = projection.shape
    i = min(max(int(np.floor(row)), 0), H - 1)
    j = min(max(int(np.floor(col)), 0), W - 1)
    if not mask[i, j]:
        return
    omega_pix = float(projection.solid_angles()[i, j])
    if omega_pix <= 0.0:
        return
    omega_sun = sun.solid_angle_sr * _visible_disc_fraction(sun.elevation_deg, sun.angular_radius_deg)
    f = min(omega_sun / omega_pix, 1.0)
    data[i, j] = data[i, j] + (L_sun - data[i, j]) * f


# ``skydome.render`` names both this subpackage and the function above. Once the subpackage
# has been imported (``from skydome.render import ...``) Python binds the attribute
# ``skydome.render`` to the module, so the module itself is made callable: calling it calls
# :func:`render`, and ``sd.render(sky, projection)`` works either way.
class _CallableModule(type(_sys.modules[__name__])):
    def __call__(self, *args, **kwargs):
        return render(*args, **kwargs)


_sys.modules[__name__].__class__ = _CallableModule
