"""Benchmark: the demo's earth-from-space tile (``nishita1993``, 384 x 384 px, 16 wavelengths).

Prints, for each surface, the model's set-up (optical-depth table and sky-light table) and
the render of the tile through ``skydome.render()`` (camera projection, XYZ output), best of
3 after a warm-up run (numba compiled and cached). Run: python benchmarks/bench_earth_tile.py
"""

import os
import time

import skydome as sd
from skydome.spectra import wavelength_grid

WL = wavelength_grid(380.0, 780.0, n=16)
SUN = sd.Sun(elevation_deg=50.0, azimuth_deg=240.0)
SIZE = 384


def once(surface):
    t0 = time.perf_counter()
    sky = sd.model("nishita1993", sun=SUN, camera_altitude_m=36e6, surface=surface)
    sky.radiance([[0.0, 0.0, -1.0]], WL)            # builds the tables
    t1 = time.perf_counter()
    img = sd.render(sky, sky.default_projection(SIZE), WL, output="xyz")
    t2 = time.perf_counter()
    return t1 - t0, t2 - t1, int(img.mask.sum())


def main():
    print(f"machine: {os.cpu_count()} cores; tile {SIZE} x {SIZE}, {WL.size} wavelengths")
    print("| surface | set-up [s] | render [s] | rays/s |")
    print("| --- | --- | --- | --- |")
    for surface in ("ocean", "earth"):
        once(surface)
        runs = [once(surface) for _ in range(3)]
        setup = min(r[0] for r in runs)
        render = min(r[1] for r in runs)
        n = runs[0][2]
        print(f"| {surface} | {setup:.2f} | {render:.2f} | {n / render:,.0f} |")


if __name__ == "__main__":
    main()
