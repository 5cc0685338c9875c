"""Aerial perspective / airlight over an image with a depth map (survey section 5.3).

L_eye = L_object T(s) + L_in(s): the light of a distant object is attenuated by the air
between it and the eye (extinction) and the air adds the sunlight it scatters towards the
eye (airlight). Distant mountains therefore turn bluer and brighter in clear air (Rayleigh
airlight) and grey-white in haze (aerosol airlight, almost independent of wavelength).

:func:`apply_airlight` applies it with a choice of method, each model's own
``aerial_perspective`` along every pixel's ray:

* every registered model that declares ``airlight = True`` (:mod:`skydome.models`,
  capabilities; with the keywords of its ``airlight_options``): ``precomputed`` (Bruneton
  2017 tables, multiple scattering), ``hillaire2020``, ``preetham1999`` (its section 5),
  ``hoffman_preetham2002`` (F_ex, L_in);
* ``dobashi2002`` (the table-based formulation, with light shafts in
  :mod:`skydome.effects.dobashi2002`).

:func:`methods` lists them (``METHODS`` is the same tuple, read when asked for).

Image convention: input linear sRGB white-balanced to the direct sunlight at the camera
((1, 1, 1) = a white Lambertian surface facing the sun, as :mod:`skydome.effects.dobashi2002`
and its synthetic scene use). With the sun's transmitted spectral irradiance E_t(lambda),
such a surface has radiance E_t / pi; the object is attenuated by the transmittance weighted
with E_t and the airlight added. ``white_balance="fixed"`` (default) divides the result by
the luminance of a white surface under the unattenuated sun (E_0 / pi): true colour on a
fixed scale, so that clear and hazy air (whose sunlight differs) can be compared;
``white_balance="sun"`` expresses it in the input's units instead (each channel divided by
that of the white surface: a camera balanced on a white card facing the sun). (The ``dobashi2002`` method
keeps that module's output, white-balanced on the sun.) PNG input is decoded from sRGB;
output is encoded to sRGB (clipped) for PNG, linear for EXR/NPY. Sky pixels (depth inf, nan
or <= 0) are left unchanged.
"""

from __future__ import annotations

import numpy as np

from skydome._validate import check_choice, check_number

__all__ = ["METHODS", "WHITE_BALANCES", "apply_airlight", "methods"]

#: The methods that are not a sky model's aerial perspective.
EFFECT_METHODS = ("dobashi2002",)


def methods() -> tuple[str, ...]:
    """The methods of :func:`apply_airlight`: the models that declare ``airlight = True``
    (``precomputed`` first, the default, then by name) and :data:`EFFECT_METHODS`."""
    from skydome.models import available

    names = sorted((n for n, cls in available().items() if cls.airlight),
                   key=lambda n: (n != "precomputed", n))
    return tuple(names) + EFFECT_METHODS


def __getattr__(name):
    # METHODS, read from the models' capabilities when asked for
    if name == "METHODS":
        return methods()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _white_rgb(spectrum, wl):
    from skydome.spectra import spectrum_to_xyz, xyz_to_linear_srgb

    return xyz_to_linear_srgb(spectrum_to_xyz(spectrum, wl))


WHITE_BALANCES = ("fixed", "sun")


def apply_airlight(image, depth_m, sun, *, method: str = "precomputed", turbidity: float = 2.5,
                   fov_deg: float = 60.0, view_azimuth_deg: float = 0.0,
                   view_elevation_deg: float = 0.0, n_wavelengths: int = 16,
                   white_balance: str = "fixed", model_params: dict | None = None, fill_sky: bool = False,
                   return_parts=False):
    """Aerial perspective on a white-balanced linear sRGB image (H, W, 3) with depth [m].

    Parameters
    ----------
    image : array_like (H, W, 3)
        Linear sRGB, (1, 1, 1) = a white Lambertian surface facing the sun (radiance
        E_t / pi with E_t the sun's transmitted spectral irradiance at the camera).
    depth_m : array_like (H, W)
        Distance along each pixel's ray [m]; inf, nan or <= 0: sky (left unchanged).
    sun : skydome.Sun
    method : str
        One of :func:`methods` ("precomputed", "hillaire2020", "hoffman_preetham2002",
        "preetham1999", "dobashi2002").
    turbidity : float
        Turbidity of the air (2..10 for the Preetham methods).
    fov_deg, view_azimuth_deg, view_elevation_deg : float
        Pinhole camera: horizontal field of view, azimuth (from north towards east) and
        elevation of the optical axis [deg]; image top towards the zenith.
    white_balance : {"fixed", "sun"}
        ``"fixed"`` (default): the output is true colour relative to a white surface under
        the unattenuated (extraterrestrial) sun, so that clear and hazy air, whose sunlight
        differs, compare on one scale (the sun's own colour at the camera is applied to the
        objects). ``"sun"``: the output has the input's units (white-balanced to the
        transmitted direct sunlight, as a camera balanced on a white card facing the sun);
        a distance of 0 leaves the image unchanged. Needs the sun above the horizon. In
        haze with a low sun the direct sunlight is strongly reddened while the airlight is
        lit also by the bluer diffuse skylight, so with ``"sun"`` hazy airlight comes out
        blue.
    model_params : dict, optional
        Further keyword parameters for the model (e.g. smaller tables for ``precomputed``).
    fill_sky : bool
        Replace the sky pixels (depth inf, nan or <= 0) by the model's sky radiance along
        their rays, in the output's units (default False: sky pixels are left unchanged).
        Not available for ``dobashi2002``, which keeps its own sky handling.
    return_parts : bool
        Also return the per-pixel transmittance (weighted with the reflected sunlight) and
        the airlight in the output's units, each (H, W, 3).

    Returns
    -------
    ndarray (H, W, 3)
    """
    import skydome as sd
    from skydome.effects.dobashi2002 import Camera, apply_aerial_perspective
    from skydome.models import get_model_class
    from skydome.spectra import solar_irradiance, spectrum_to_xyz, wavelength_grid, xyz_to_linear_srgb

    check_choice("method", method, methods())
    check_choice("white_balance", white_balance, WHITE_BALANCES)
    if white_balance == "sun" and sun.elevation_deg <= 0.0:
        raise ValueError(f"sun elevation_deg = {sun.elevation_deg:g} deg is out of range (0, 90] deg "
                         "for white_balance 'sun' (use white_balance='fixed')")
    img = np.asarray(image, dtype=np.float64)
    depth = np.asarray(depth_m, dtype=np.float64)
    if img.ndim != 3 or img.shape[-1] != 3:
        raise ValueError(f"image has shape {img.shape}; expected (height, width, 3)")
    if depth.shape != img.shape[:2]:
        raise ValueError(f"depth has shape {depth.shape}; expected {img.shape[:2]} (the image's)")
    cam = Camera(fov_deg=check_number("fov", fov_deg, 1.0, 170.0, "deg"),
                 azimuth_deg=check_number("view_azimuth", view_azimuth_deg, -360.0, 360.0, "deg"),
                 elevation_deg=check_number("view_elevation", view_elevation_deg, -89.0, 89.0, "deg"))
    if method == "dobashi2002":
        if fill_sky:
            raise ValueError("fill_sky = True is not available for method 'dobashi2002' "
                             f"(choose one of {', '.join(methods()[:-len(EFFECT_METHODS)])})")
        atm = sd.Atmosphere.earth(turbidity=turbidity)
        out = apply_aerial_perspective(img, depth, cam, sun, atmosphere=atm, return_parts=return_parts)
        return out
    cls = get_model_class(method)
    if not cls.sun_in_range(sun.elevation_deg):
        lo, hi = cls.sun_elevation_range_deg
        raise ValueError(f"sun elevation_deg = {sun.elevation_deg:g} deg is out of range "
                         f"[{lo:g}, {hi:g}] deg for method {method!r}")
    wl = wavelength_grid(380.0, 780.0, n=n_wavelengths)
    sky = cls(sun=sun, turbidity=turbidity, **(model_params or {}))
    h, w = depth.shape
    dirs = cam.ray_directions(w, h)
    obj = np.isfinite(depth) & (depth > 0)
    T = np.ones(depth.shape + (wl.size,))
    Lin = np.zeros(depth.shape + (wl.size,))
    if obj.any():
        # the model's own keywords (hillaire2020: march each ray, not its froxel volume)
        t, l_in = sky.aerial_perspective(dirs[obj], depth[obj], wl, **cls.airlight_options)
        T[obj], Lin[obj] = t, l_in
    # the object: image (1, 1, 1) = a white Lambertian surface facing the transmitted sun,
    # radiance E_trans / pi; the result is divided by the luminance of a white surface under
    # the unattenuated sun (a fixed scale, so that clear and hazy air compare in true colour)
    e_sun = solar_irradiance(wl) * sun.irradiance_scale
    sun_t = sd.model("single_scattering", sun=sun, turbidity=min(max(turbidity, 1.0), 32.0))
    e_trans = sun_t.sun_radiance(wl) * sun.solid_angle_sr if sun.elevation_deg > -0.5 else 0 * e_sun
    white_trans = np.maximum(e_trans, 1e-12 * e_sun) / np.pi
    y_ref = float(spectrum_to_xyz(e_sun / np.pi, wl)[1])
    rgb_white_trans = _white_rgb(white_trans, wl)
    # transmittance of each channel, weighted with the light the object reflects (E_t / pi);
    # small negative values from out-of-gamut spectra are clipped
    t_rgb = np.maximum(xyz_to_linear_srgb(spectrum_to_xyz(T * white_trans, wl)) / rgb_white_trans, 0.0)
    l_abs = xyz_to_linear_srgb(spectrum_to_xyz(Lin, wl))
    if white_balance == "sun":
        l_rgb = l_abs / rgb_white_trans                    # units of the input image
        out = img * t_rgb + l_rgb
    else:
        l_rgb = l_abs / y_ref
        out = img * (rgb_white_trans / y_ref) * t_rgb + l_rgb   # the sun's colour applied
    out[~obj] = img[~obj]
    if fill_sky and (~obj).any():
        sky_abs = xyz_to_linear_srgb(spectrum_to_xyz(sky.radiance(dirs[~obj], wl), wl))
        out[~obj] = sky_abs / (rgb_white_trans if white_balance == "sun" else y_ref)
    out = np.maximum(out, 0.0)
    if return_parts:
        return out, t_rgb, l_rgb
    return out
