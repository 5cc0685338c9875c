"""The display-transform comparison of docs/sections/rendering.md: the demo skies under
each transform, one exposure per sky, and the noon zenith's colour through each.

    PYTHONPATH=src python docs/display_figures.py docs/figures [cache.npz]

The optional npz caches the rendered XYZ images (the precomputed tables are the slow part).
"""

import sys
from pathlib import Path

import numpy as np

SKIES = [  # (label, sun elevation, sun azimuth, model parameters)
    ("noon, sun 60 deg", 60.0, 180.0, {}),
    ("sun 30 deg", 30.0, 135.0, {}),
    ("sun 2 deg", 2.0, 270.0, {}),
    ("turbidity 8, sun 30 deg", 30.0, 180.0, {"turbidity": 8.0}),
    ("sun -4 deg, twilight", -4.0, 270.0, {}),
]
#: columns: (transform, Hunt-effect chroma gain on)
COLUMNS = [("hue-preserving", True), ("hue-preserving", False), ("agx", True), ("agx", False),
           ("aces-hill", False), ("filmic", False)]


def render_skies(size: int = 160, cache=None):
    """XYZ images (Y in cd m^-2) of the demo skies from the default model, fisheye."""
    import skydome as sd
    from skydome.render import SkyImage, make_projection
    from skydome.spectra import wavelength_grid

    proj = make_projection("fisheye", str(size))
    if cache is not None and Path(cache).exists():
        data = np.load(cache)
        return [SkyImage(data[f"s{i}"], "xyz", mask=data[f"m{i}"], projection=proj)
                for i in range(len(SKIES))]
    wl = wavelength_grid(380.0, 780.0, n=16)
    images = []
    for label, el, az, params in SKIES:
        sky = sd.model("precomputed", sun=sd.Sun(elevation_deg=el, azimuth_deg=az), **params)
        images.append(sd.render(sky, proj, wl, output="xyz"))
    if cache is not None:
        np.savez_compressed(cache, **{f"s{i}": im.xyz() for i, im in enumerate(images)},
                            **{f"m{i}": im.mask for i, im in enumerate(images)})
    return images


def _lch(srgb_code):
    """CIELAB L*, C*, h [deg] (D65) of sRGB code values in [0, 1] (our own conversion)."""
    from skydome.render.display import _lab_f
    from skydome.spectra import SRGB_WHITE_XY, _xy_to_white_xyz, linear_srgb_to_xyz, srgb_decode

    n = linear_srgb_to_xyz(srgb_decode(np.asarray(srgb_code, float))) / _xy_to_white_xyz(SRGB_WHITE_XY)
    f = _lab_f(n)
    L, a, b = 116.0 * f[..., 1] - 16.0, 500.0 * (f[..., 0] - f[..., 1]), 200.0 * (f[..., 1] - f[..., 2])
    return L, np.hypot(a, b), np.degrees(np.arctan2(b, a)) % 360.0


def doc_figures(directory, cache=None) -> dict:
    from skydome.render.sheets import contact_sheet

    images = render_skies(cache=cache)
    tiles, res = [], {}
    for (label, *_), im in zip(SKIES, images):
        k = im.auto_exposure()
        for tm, hunt in COLUMNS:
            tiles.append((im.to_srgb(k, tm, hunt=hunt), ()))
    # the noon zenith (centre pixel) through each column
    im = images[0]
    c = im.shape[0] // 2
    k = im.auto_exposure()
    res["noon_zenith_linear_rgb_cd_m2"] = im.linear_srgb()[c, c].round(1).tolist()
    res["noon_auto_ev100"] = float(np.log2(1.0 / (1.2 * k)))
    res["noon_chroma_gain"] = im.chroma_gain()
    for tm, hunt in COLUMNS:
        code = im.to_srgb(k, tm, hunt=hunt)[c, c]
        L, C, h = _lch(code)
        res[f"{tm}{'+hunt' if hunt else ''}"] = {"srgb8": np.round(code * 255).astype(int).tolist(),
                                                 "L": round(float(L), 1), "C": round(float(C), 1),
                                                 "h": round(float(h), 1)}
    cols = [f"{tm}{' + Hunt gain' if hunt else ''}" for tm, hunt in COLUMNS]
    contact_sheet(tiles, Path(directory) / "display_transforms.png", cols=len(COLUMNS), tile=160,
                  line_height=14, column_labels=cols, row_labels=[s[0] for s in SKIES],
                  row_label_width=170)
    return res


if __name__ == "__main__":
    import json

    print(json.dumps(doc_figures(sys.argv[1] if len(sys.argv) > 1 else "docs/figures",
                                 sys.argv[2] if len(sys.argv) > 2 else None), indent=1))
