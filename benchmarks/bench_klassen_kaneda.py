"""Throughput and accuracy of klassen1987 and kaneda1991 (issue 4, parts 1-2).

Prints, for each model: the set-up ("precompute") time, rays per second for the directions
of a 256x128 equirectangular image (full sphere) at 16 wavelengths, and the relative error
in luminance and per wavelength against the single_scattering reference (same
Atmosphere.earth(turbidity=2.5), same sun) over the upper hemisphere of that image, for sun
elevations 5, 30 and 60 deg. For kaneda1991 the fog-free error measures the integrator;
for klassen1987 it measures the model (flat earth, homogeneous layers).

Run:  .venv/bin/python benchmarks/bench_klassen_kaneda.py
"""

from __future__ import annotations

import os
import time

import numpy as np


def main():
    import skydome as sd
    from skydome.spectra import spectrum_to_xyz

    wl = np.linspace(380.0, 780.0, 16)
    d_all = sd.Equirect(256, 128).directions()[0].reshape(-1, 3)
    up = d_all[d_all[:, 2] > 0.0]
    print(f"{os.cpu_count()} cores; 256x128 equirect = {d_all.shape[0]} rays, 16 wavelengths")

    # warm-up: numba kernels (cached on disk) and the shared column table
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=135.0)
    sd.model("kaneda1991", sun=sun).radiance(d_all[:8], wl)
    sd.model("single_scattering", sun=sun).radiance(d_all[:8], wl)

    for name, kw in (("klassen1987", {}), ("kaneda1991", {}),
                     ("kaneda1991", {"fog_density": 0.002})):
        t0 = time.perf_counter()
        sky = sd.model(name, sun=sun, **kw)
        sky.radiance(d_all[:1], wl)       # first call builds what the model precomputes
        setup = time.perf_counter() - t0
        best = np.inf
        for _ in range(3):
            t0 = time.perf_counter()
            sky.radiance(d_all, wl)
            best = min(best, time.perf_counter() - t0)
        print(f"{name} {kw or ''}: set-up {setup * 1e3:.1f} ms, "
              f"{d_all.shape[0] / best:,.0f} rays/s ({best:.3f} s per image)")

    # a fresh table build (the precompute of kaneda1991 and single_scattering)
    from skydome.transport.optical_depth import ColumnTable

    props = sd.Atmosphere.earth(turbidity=2.5).optical_properties(wl)
    t0 = time.perf_counter()
    ColumnTable(props)
    print(f"column table 256x512 build: {time.perf_counter() - t0:.3f} s")

    wl41 = np.linspace(380.0, 780.0, 41)
    for elev in (5.0, 30.0, 60.0):
        sun = sd.Sun(elevation_deg=elev, azimuth_deg=135.0)
        ref = sd.model("single_scattering", sun=sun)
        lr = ref.radiance(up, wl41)
        yr = spectrum_to_xyz(lr, wl41)[..., 1]
        for name in ("kaneda1991", "klassen1987"):
            sky = sd.model(name, sun=sun)
            ls = sky.radiance(up, wl41)
            ys = spectrum_to_xyz(ls, wl41)[..., 1]
            ey = np.abs(ys / yr - 1.0)
            el = np.abs(ls / lr - 1.0)
            print(f"sun {elev:4.0f} deg {name:12s}: luminance |rel err| median {np.median(ey):.2e} "
                  f"max {ey.max():.2e}; spectral median {np.median(el):.2e} max {el.max():.2e}")


if __name__ == "__main__":
    main()
