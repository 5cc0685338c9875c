"""Render path: sd.render() of an equirectangular map of the precomputed sky.

Prints, for one picture size, the time and the peak of numpy memory (tracemalloc) of

* ``native``: ``render(sky, Equirect(W), wl)`` (a spectral image at 16 wavelengths)
  followed by ``.xyz()``, what a writer needs;
* ``xyz``: ``render(sky, Equirect(W), wl, output="xyz")``, the fused path (the table ->
  wavelength resampling and the CMF integration folded into one matrix per render);
* ``radiance``: the model's own ``radiance_table()`` over the same directions (the floor).

Run it with the code to measure first on the path, e.g.
``PYTHONPATH=src python benchmarks/bench_render_path.py 2048``; code without
``output=`` (an older version) reports the native path only.
"""

from __future__ import annotations

import inspect
import sys
import time
import tracemalloc

import numpy as np

import skydome as sd
from skydome.imaging import Equirect, render
from skydome.spectra import wavelength_grid


def _measure(fn):
    t0 = time.perf_counter()
    fn()
    dt = time.perf_counter() - t0
    tracemalloc.start()
    fn()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return dt, peak / 2**20


def main() -> None:
    width = int(sys.argv[1]) if len(sys.argv) > 1 else 2048
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=135.0)
    t0 = time.perf_counter()
    sky = sd.model("precomputed", sun=sun)
    print(f"precomputed tables (defaults): {time.perf_counter() - t0:.1f} s")
    wl = wavelength_grid(380.0, 780.0, n=16)
    proj = Equirect(width)
    render(sky, Equirect(64), wl)  # compile / warm up
    rows = [("native + xyz()", lambda: render(sky, proj, wl).xyz())]
    if "output" in inspect.signature(render).parameters:
        render(sky, Equirect(64), wl, output="xyz")
        rows.append(("xyz (fused)", lambda: render(sky, proj, wl, output="xyz")))
    d, m = proj.directions()
    dm = d[m]
    rows.append(("radiance_table only", lambda: sky.radiance_table(dm)))
    print(f"{width}x{proj.height} equirect, 16 wavelengths, precomputed "
          f"({sky.n_wavelengths} table wavelengths)")
    for name, fn in rows:
        dt, mb = _measure(fn)
        print(f"  {name:22s} {dt:7.2f} s   peak numpy memory {mb:8.0f} MiB")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
