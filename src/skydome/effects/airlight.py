"""Aerial perspective / airlight over an image with a depth map (survey section 5.3).

L_eye = L_object T(s) + L_in(s): the light of a distant object is attenuated by the air
between it and the eye (extinction) and the air adds the sunlight it scatters towards the
eye (airlight). Distant mountains therefore turn bluer and brighter in clear air (Rayleigh
airlight) and grey-white in haze (aerosol airlight, almost independent of wavelength).

:func:`apply_airlight` applies it with a choice of method, each model's own
``aerial_perspective`` along every pixel's ray:

* ``precomputed`` (Bruneton 2017 tables, multiple scattering), ``hillaire2020``,
  ``preetham1999`` (its section 5), ``hoffman_preetham2002`` (F_ex, L_in);
* ``dobashi2002`` (the table-based formulation, with light shafts in
  :mod:`skydome.effects.dobashi2002`).

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

__all__ = ["METHODS", "WHITE_BALANCES", "apply_airlight", "airlight_cli", "demo_effects"]

METHODS = ("precomputed", "hillaire2020", "preetham1999", "hoffman_preetham2002", "dobashi2002")


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
    method : {"precomputed", "hillaire2020", "preetham1999", "hoffman_preetham2002", "dobashi2002"}
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
    from skydome.spectra import solar_irradiance, spectrum_to_xyz, wavelength_grid, xyz_to_linear_srgb

    check_choice("method", method, METHODS)
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
                             "(choose one of precomputed, hillaire2020, preetham1999, hoffman_preetham2002)")
        atm = sd.Atmosphere.earth(turbidity=turbidity)
        out = apply_aerial_perspective(img, depth, cam, sun, atmosphere=atm, return_parts=return_parts)
        return out
    if sun.elevation_deg < 0 and method in ("preetham1999", "hoffman_preetham2002"):
        raise ValueError(f"sun elevation_deg = {sun.elevation_deg:g} deg is out of range [0, 90] deg "
                         f"for method {method!r}")
    wl = wavelength_grid(380.0, 780.0, n=n_wavelengths)
    sky = sd.model(method, sun=sun, turbidity=turbidity, **(model_params or {}))
    h, w = depth.shape
    dirs = cam.ray_directions(w, h)
    obj = np.isfinite(depth) & (depth > 0)
    T = np.ones(depth.shape + (wl.size,))
    Lin = np.zeros(depth.shape + (wl.size,))
    if obj.any():
        # hillaire2020: march each ray; its froxel volume (4 km slices) halves the
        # extinction over the first kilometres and clamps distances beyond ~30 km
        kw = {"use_volume": False} if method == "hillaire2020" else {}
        t, l_in = sky.aerial_perspective(dirs[obj], depth[obj], wl, **kw)
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


def _read_image(path):
    from pathlib import Path

    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"image = '{path}' does not exist")
    suf = p.suffix.lower()
    if suf == ".png":
        from PIL import Image

        from skydome.spectra import srgb_decode

        a = np.asarray(Image.open(p).convert("RGB"), dtype=np.float64) / 255.0
        return srgb_decode(a)
    if suf == ".exr":
        from skydome.render.image import read_exr

        ch = read_exr(p)
        return np.stack([ch["R"], ch["G"], ch["B"]], axis=-1).astype(np.float64)
    if suf == ".npy":
        return np.load(p).astype(np.float64)
    raise ValueError(f"image = '{path}': expected .png, .exr or .npy")


def _read_depth(path):
    from pathlib import Path

    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"depth = '{path}' does not exist")
    suf = p.suffix.lower()
    if suf == ".npy":
        return np.load(p).astype(np.float64)
    if suf == ".exr":
        from skydome.render.image import read_exr

        ch = read_exr(p)
        key = next((k for k in ("Z", "Y", "R", "depth") if k in ch), None)
        if key is None:
            raise ValueError(f"depth = '{path}' has no Z, Y or R channel")
        return np.asarray(ch[key], dtype=np.float64)
    raise ValueError(f"depth = '{path}': expected .exr or .npy (metres)")


def _write(path, img):
    """Linear image -> .png (sRGB encoded, clipped) or .exr/.npy (linear), atomically."""
    import os
    import tempfile
    from pathlib import Path

    from skydome.spectra import srgb_encode

    p = Path(path)
    suf = p.suffix.lower()
    fd, tmp = tempfile.mkstemp(prefix=".skydome-", suffix=suf, dir=p.parent)
    os.close(fd)
    try:
        if suf == ".png":
            from PIL import Image

            enc = (np.clip(srgb_encode(np.clip(img, 0, 1)), 0, 1) * 255 + 0.5).astype(np.uint8)
            Image.fromarray(enc).save(tmp, format="PNG")
        elif suf == ".npy":
            with open(tmp, "wb") as fh:
                np.save(fh, img)
        else:
            import OpenEXR

            h = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
            chans = {"RGB": np.ascontiguousarray(img.astype(np.float32))}
            OpenEXR.File(h, chans).write(tmp)
        os.replace(tmp, p)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def _display_gain(x) -> float:
    """Display exposure of a linear image (a daylight-balanced camera with automatic
    exposure): the 99th percentile of its luminance (Rec. 709 weights) maps to 0.85."""
    y = np.asarray(x) @ np.array([0.2126, 0.7152, 0.0722])
    return 0.85 / max(float(np.percentile(y, 99.0)), 1e-12)


def _side_by_side(before, after, path, labels):
    from PIL import Image, ImageDraw

    from skydome.spectra import srgb_encode

    tiles = [(np.clip(srgb_encode(np.clip(x, 0, 1)), 0, 1) * 255 + 0.5).astype(np.uint8) for x in (before, *after)]
    h, w = tiles[0].shape[:2]
    sheet = Image.new("RGB", (w, (h + 16) * len(tiles)), (20, 20, 20))
    d = ImageDraw.Draw(sheet)
    for i, (t, lab) in enumerate(zip(tiles, labels)):
        sheet.paste(Image.fromarray(t), (0, i * (h + 16) + 16))
        d.text((4, i * (h + 16) + 2), lab, fill=(230, 230, 230))
    sheet.save(path)


def airlight_cli(image, depth, out, sun, *, method, turbidity, fov_deg, view_azimuth_deg,
                 synthetic: bool = False, white_balance: str = "fixed", fill_sky: bool = False,
                 width: int = 320, height: int = 180):
    """The ``skydome airlight`` command: validates, applies, writes (atomically)."""
    from pathlib import Path

    o = Path(out)
    if o.suffix.lower() not in (".png", ".exr", ".npy"):
        raise ValueError(f"out = '{out}': expected .png, .exr or .npy")
    if not o.parent.is_dir():
        raise ValueError(f"out = '{out}': folder '{o.parent}' does not exist")
    check_choice("method", method, METHODS)
    check_choice("white_balance", white_balance, WHITE_BALANCES)
    if synthetic:
        from skydome.effects.dobashi2002 import Camera, synthetic_mountains

        cam = Camera(fov_deg=fov_deg, azimuth_deg=view_azimuth_deg, elevation_deg=2.0, altitude_m=300.0)
        img, dep, _ = synthetic_mountains(width, height, camera=cam, sun=sun)
        res = apply_airlight(img, dep, sun, method=method, turbidity=turbidity, fov_deg=fov_deg,
                             view_azimuth_deg=view_azimuth_deg, view_elevation_deg=2.0,
                             white_balance=white_balance, fill_sky=fill_sky)
        # PNG: each panel at a display exposure (99th luminance percentile at 0.85), as a
        # camera with automatic exposure; the linear result is written unscaled otherwise
        _side_by_side(_display_gain(img) * img, [_display_gain(res) * res], o,
                      ["scene without air (own exposure)", f"{method}, turbidity {turbidity:g} (own exposure)"]) \
            if o.suffix.lower() == ".png" else _write(o, res)
        return res
    if image is None or depth is None:
        raise ValueError("--image and --depth are required (or --synthetic)")
    img = _read_image(image)
    dep = _read_depth(depth)
    res = apply_airlight(img, dep, sun, method=method, turbidity=turbidity, fov_deg=fov_deg,
                         view_azimuth_deg=view_azimuth_deg, white_balance=white_balance,
                         fill_sky=fill_sky)
    _write(o, res)
    return res


def demo_effects(out_dir):
    """Clear and hazy air over the synthetic mountains (precomputed tables), for the demo."""
    from pathlib import Path

    import skydome as sd
    from skydome.effects.dobashi2002 import synthetic_mountains

    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=120.0)
    img, dep, _ = synthetic_mountains(320, 180, sun=sun)
    # half-size tables (a few seconds each)
    small = dict(scattering_r_size=16, scattering_mu_size=64, scattering_mu_s_size=16, orders=3,
                 n_wavelengths=12)
    kw = dict(method="precomputed", model_params=small, fill_sky=True)
    clear = apply_airlight(img, dep, sun, turbidity=2.0, **kw)
    hazy = apply_airlight(img, dep, sun, turbidity=8.0, **kw)
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    path = Path(out_dir) / "airlight_mountains.png"

    g_clear = _display_gain(clear)
    _side_by_side(g_clear * img, [g_clear * clear, _display_gain(hazy) * hazy], path,
                  ["no air (sky pixels black), exposure of the next", "clear air (turbidity 2), sky from the model",
                   "haze (turbidity 8), sky from the model"])
    return [path]
