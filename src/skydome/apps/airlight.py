"""Aerial perspective over an image as files (``skydome airlight``): reading the image and
its depth map, writing the result or a before/after sheet, and the demo's mountain scene. The
physics is in :mod:`skydome.effects.airlight`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skydome._io import atomic_file, check_output_file
from skydome._validate import check_choice
from skydome.effects.airlight import WHITE_BALANCES, apply_airlight, methods

__all__ = ["airlight_cli", "demo_effects"]


def _read_image(path):
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
        from skydome.imaging.image import read_exr

        ch = read_exr(p)
        return np.stack([ch["R"], ch["G"], ch["B"]], axis=-1).astype(np.float64)
    if suf == ".npy":
        return np.load(p).astype(np.float64)
    raise ValueError(f"image = '{path}': expected .png, .exr or .npy")


def _read_depth(path):
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"depth = '{path}' does not exist")
    suf = p.suffix.lower()
    if suf == ".npy":
        return np.load(p).astype(np.float64)
    if suf == ".exr":
        from skydome.imaging.image import read_exr

        ch = read_exr(p)
        key = next((k for k in ("Z", "Y", "R", "depth") if k in ch), None)
        if key is None:
            raise ValueError(f"depth = '{path}' has no Z, Y or R channel")
        return np.asarray(ch[key], dtype=np.float64)
    raise ValueError(f"depth = '{path}': expected .exr or .npy (metres)")


def _write(path, img):
    """Linear image -> .png (sRGB encoded, clipped) or .exr/.npy (linear), atomically."""
    from skydome.spectra import srgb_encode

    p = Path(path)
    suf = p.suffix.lower()
    with atomic_file(p) as tmp:
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
            from skydome._io import write_exr

            write_exr(tmp, h, chans)


def _display_gain(x) -> float:
    """Display exposure of a linear image (a daylight-balanced camera with automatic
    exposure): the 99th percentile of its luminance (Rec. 709 weights) maps to 0.85."""
    y = np.asarray(x) @ np.array([0.2126, 0.7152, 0.0722])
    return 0.85 / max(float(np.percentile(y, 99.0)), 1e-12)


def _side_by_side(before, after, path, labels, cols: int = 1):
    from skydome.imaging.sheets import contact_sheet
    from skydome.spectra import srgb_encode

    imgs = [srgb_encode(np.clip(x, 0, 1)) for x in (before, *after)]
    h, w = imgs[0].shape[:2]
    contact_sheet(list(zip(imgs, labels)), path, cols=cols, tile=(w, h), labels_above=True, line_height=16, font_size=13,
                  background=(20, 20, 20), text_colours=((230, 230, 230),))


def airlight_cli(image, depth, out, sun, *, method, turbidity, fov_deg, view_azimuth_deg,
                 synthetic: bool = False, white_balance: str = "fixed", fill_sky: bool = False,
                 width: int = 320, height: int = 180):
    """The ``skydome airlight`` command: validates, applies, writes (atomically)."""
    o = check_output_file(out, (".png", ".exr", ".npy"))
    check_choice("method", method, methods())
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
    """Clear, moderate and hazy air over the synthetic mountains (precomputed tables), for
    the demo: four 368 x 164 panels in a 2 x 2 grid (about 2:1 like the gallery's cells)."""
    import skydome as sd
    from skydome.effects.dobashi2002 import synthetic_mountains

    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=120.0)
    img, dep, _ = synthetic_mountains(368, 164, sun=sun)
    # half-size tables (a few seconds each)
    small = dict(scattering_r_size=16, scattering_mu_size=64, scattering_mu_s_size=16, orders=3,
                 n_wavelengths=12)
    kw = dict(method="precomputed", model_params=small, fill_sky=True)
    clear = apply_airlight(img, dep, sun, turbidity=2.0, **kw)
    moderate = apply_airlight(img, dep, sun, turbidity=4.0, **kw)
    hazy = apply_airlight(img, dep, sun, turbidity=8.0, **kw)
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    path = Path(out_dir) / "airlight_mountains.png"

    g_clear = _display_gain(clear)
    _side_by_side(g_clear * img, [g_clear * clear, _display_gain(moderate) * moderate,
                                  _display_gain(hazy) * hazy], path,
                  ["no air (sky pixels black), exposure of the next", "clear air (turbidity 2), sky from the model",
                   "moderate haze (turbidity 4), sky from the model", "haze (turbidity 8), sky from the model"],
                  cols=2)
    return [path]
