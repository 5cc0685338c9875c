"""Outputs of the render and environment-map paths, saved for a bit-for-bit comparison of
two source trees (a change that should not move any value).

``dump OUT.npz`` (with one tree's ``src`` on ``PYTHONPATH``) saves, for ``hosek_wilkie2012``,
``preetham1999``, ``precomputed`` and ``cie1994_clear`` (sun 30 deg, azimuth 135 deg, 16
wavelengths): the environment maps of four conventions (lat-long 1024 x 512 and 512 x 256,
a 64 px cube map, a 256 px fisheye) and a 256 x 128 map with each ground (Lambertian,
black), and the XYZ renders of a fisheye, a lat-long map and an angular map (with the sun
disc, and with a black ground), their display sRGB and their PNG files' bytes.
``compare A.npz B.npz`` prints every array that differs (with its largest relative
difference) and the count.

Run each tree's dump twice and compare the second runs: a process that compiles numba's
kernels (an empty cache) can differ from one that loads them from the cache in the last bits.
"""

from __future__ import annotations

import os
import sys
import tempfile

import numpy as np


def dump(path: str) -> None:
    import skydome as sd
    from skydome.export.envmap import render_envmap
    from skydome.imaging import AngularMap, Equirect, Fisheye, render
    from skydome.spectra import wavelength_grid

    out = {}
    wl = wavelength_grid(380.0, 780.0, n=16)
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=135.0)
    png = os.path.join(tempfile.mkdtemp(), "x.png")
    for name in ("hosek_wilkie2012", "preetham1999", "precomputed", "cie1994_clear"):
        sky = sd.model(name, sun=sun)
        for conv, size in (("skydome", "1024x512"), ("blender", "512x256"), ("unity", "64"),
                           ("radiance", "256")):
            env = render_envmap(sky, conv, size, wavelengths_nm=wl)
            for k, im in env.images.items():
                out[f"env/{name}/{conv}/{k}"] = im
        for ground in ("lambertian", "black"):
            env = render_envmap(sky, "skydome", "256x128", wavelengths_nm=wl, ground=ground)
            out[f"envground/{name}/{ground}"] = env.images["map"]
        for proj in (Fisheye(256), Equirect(512), AngularMap(200)):
            img = render(sky, proj, wl, output="xyz")
            out[f"render/{name}/{proj!r}"] = img.data
            out[f"srgb/{name}/{proj!r}"] = img.to_srgb()
            img.save(png)
            with open(png, "rb") as f:
                out[f"png/{name}/{proj!r}"] = np.frombuffer(f.read(), np.uint8)
            out[f"renderblack/{name}/{proj!r}"] = render(sky, proj, wl, ground="black",
                                                         output="xyz").data
    np.savez(path, **out)
    print(f"{len(out)} arrays -> {path}")


def compare(a_path: str, b_path: str) -> None:
    a, b = np.load(a_path), np.load(b_path)
    n_bad = 0
    for k in a.files:
        x, y = a[k], b[k]
        if x.shape == y.shape and np.array_equal(x, y):
            continue
        n_bad += 1
        if x.shape == y.shape and x.dtype.kind == "f":
            nz = x != 0.0
            rel = np.max(np.abs(x - y)[nz] / np.abs(x[nz])) if nz.any() else np.max(np.abs(y))
            print(f"{k}: largest relative difference {rel:.3g}")
        else:
            print(f"{k}: differs ({x.shape} / {y.shape})")
    print(f"{len(a.files)} arrays compared, {n_bad} differ")


if __name__ == "__main__":
    if sys.argv[1:2] == ["dump"] and len(sys.argv) == 3:
        dump(sys.argv[2])
    elif sys.argv[1:2] == ["compare"] and len(sys.argv) == 4:
        compare(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)
