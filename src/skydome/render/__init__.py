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


def render(sky, projection: Projection, wavelengths_nm=None, *,
           progress: Callable[[int, int], None] | None = None, draw_sun: bool = True,
           chunk: int = 32768, limb_darkening: bool = True, ground="model") -> SkyImage:
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
        Draw the solar disc where the model has a sun with a radiance (see Notes). If
        False the image has no disc and ``image.sun_light`` holds the sun as a separate
        :class:`~skydome.render.sun_disc.SunLight` (direction, angular radius, spectral
        normal irradiance) for renderers that take it that way.
    chunk : int
        Directions per model call (>= 1), bounding memory use.
    limb_darkening : bool
        Give the disc the sun's centre-to-limb darkening (Neckel 2005; default) or, if
        False, a uniform radiance. Either way its flux is the model's.
    ground : {"model", "black"} or float
        What the pixels below the horizon show (:mod:`skydome.render.ground`): "model"
        (default) the model's own ground where it traces ground-hit rays, else a
        Lambertian ground of the model's albedo (0.2 without one) lit by its sky and sun;
        "black"; or an albedo in [0, 1] for a Lambertian ground on every model.

    Returns
    -------
    SkyImage
        Spectral radiance [W m^-2 sr^-1 nm^-1] or XYZ (Y in cd m^-2); masked pixels 0.

    Notes
    -----
    The sun: if ``draw_sun``, ``sky.sun`` is set, the model gives a sun radiance
    (:func:`~skydome.render.sun_disc.sun_disc_radiance`) and the sun's elevation exceeds
    minus its angular radius, the disc is drawn by
    :func:`~skydome.render.sun_disc.draw_sun_disc`: its limb-darkened radiance is
    distributed over the pixels it covers in proportion to the flux falling into each, so
    that the drawn flux sum (L - L_sky) Omega_pix equals the model's direct normal
    irradiance L_sun Omega_sun (times the part of the disc above the horizon) in any
    projection and for a disc of any size, smaller than a pixel included. The disc
    replaces the sky it covers. For XYZ images the sun's spectrum is converted to XYZ.
    """
    from skydome._validate import as_wavelengths, check_int

    if not isinstance(projection, Projection):
        raise TypeError(f"projection must be a skydome Projection, got {type(projection).__name__}")
    chunk = check_int("chunk", chunk, 1, None)
    from skydome.render.ground import apply_ground, check_ground

    ground = check_ground(ground)
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
    ground_info = apply_ground(sky, data, dirs, mask, wl, ground)

    sun = getattr(sky, "sun", None)
    sun_info = None
    if sun is not None:
        sun_info = {"elevation_deg": sun.elevation_deg, "azimuth_deg": sun.azimuth_deg,
                    "angular_radius_deg": sun.angular_radius_deg}
    sun_light = None
    if sun is not None and sun.elevation_deg > -sun.angular_radius_deg:
        from skydome.render import sun_disc

        if draw_sun:
            L_sun = sun_disc.sun_disc_radiance(sky, wl)
            if L_sun is not None:
                if L_sun.shape[0] != n_ch:
                    raise ValueError(f"sun radiance of model {getattr(sky, 'name', sky)!r} has "
                                     f"shape {L_sun.shape}, expected ({n_ch},)")
                ch_wl = wl if spectral else sun_disc.XYZ_CHANNEL_WAVELENGTHS_NM
                sun_disc.draw_sun_disc(data, projection, mask, sun, L_sun, ch_wl,
                                       limb_darkening=limb_darkening)
                sun_info["drawn"] = "limb-darkened disc" if limb_darkening else "uniform disc"
        else:
            sun_light = sun_disc.sun_light(sky, wl)
            if sun_light is not None:
                sun_info["drawn"] = "left out (see the sun light)"

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
    if ground_info is not None:
        meta["ground"] = ground_info
    meta["projection"] = projection.describe()
    meta["quantity"] = ("spectral radiance [W m^-2 sr^-1 nm^-1]" if spectral
                        else "CIE 1931 XYZ, Y = luminance [cd m^-2]")
    image = SkyImage(data, "spectral" if spectral else "xyz", wl, mask, projection, meta)
    image.sun_light = sun_light
    return image


# ``skydome.render`` names both this subpackage and the function above. Once the subpackage
# has been imported (``from skydome.render import ...``) Python binds the attribute
# ``skydome.render`` to the module, so the module itself is made callable: calling it calls
# :func:`render`, and ``sd.render(sky, projection)`` works either way.
class _CallableModule(type(_sys.modules[__name__])):
    def __call__(self, *args, **kwargs):
        return render(*args, **kwargs)


_sys.modules[__name__].__class__ = _CallableModule
