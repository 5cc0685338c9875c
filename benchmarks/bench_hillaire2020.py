"""Hillaire (2020) sky: LUT build times and render throughput.

Prints the time to build each table (transmittance 256 x 64, multiple scattering 32 x 32,
sky view 192 x 108, aerial perspective 32^3) at 16 wavelengths, and the throughput of
radiance() for a 2048 x 1024 equirectangular image at 16 wavelengths through the sky-view
LUT, plus a smaller per-pixel ray-march run. Run: python benchmarks/bench_hillaire2020.py
"""

from __future__ import annotations

import time

import numpy as np


def main() -> None:
    import skydome as sd
    from skydome.models.simulated import _kernels_hillaire2020  # noqa: F401  (compile once)

    wl = np.linspace(380.0, 780.0, 16)
    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=135.0)
    # warm-up: compile/load the numba kernels
    warm = sd.model("hillaire2020", sun=sun, ap_size=4)
    warm.radiance(np.array([[0.0, 0.0, 1.0]]), wl)
    warm.aerial_perspective(np.array([[1.0, 0.0, 0.0]]), 1e4, wl)
    sd.model("hillaire2020", sun=sun, use_skyview=False).radiance(np.array([[0.0, 0.0, 1.0]]), wl)

    sky = sd.model("hillaire2020", sun=sun)
    from skydome.models.simulated.hillaire2020 import _Tables
    from skydome.models.simulated import _kernels_hillaire2020 as K

    from skydome.transport._medium import medium_from_properties

    m = medium_from_properties(sky.atmosphere.optical_properties(wl))
    t = time.perf_counter()
    tlut = K.build_transmittance(m, 64, 256, 64, 500.0)
    t_trans = time.perf_counter() - t
    orders = np.zeros((2, 32, 32, wl.size))
    t = time.perf_counter()
    K.build_multiple_scattering(m, tlut, 32, 32, 8, 10, 500.0, orders)
    t_ms = time.perf_counter() - t
    tb = _Tables(sky, wl)
    t = time.perf_counter()
    tb.skyview
    t_sv = time.perf_counter() - t
    t = time.perf_counter()
    tb.aerial
    t_ap = time.perf_counter() - t
    sky._tables[tuple(np.round(wl, 9))] = tb
    print(f"transmittance LUT 256x64 x16 wl: {t_trans * 1e3:8.1f} ms")
    print(f"multiple-scattering LUT 32x32 (64 dirs, 20 steps) x16 wl: {t_ms * 1e3:8.1f} ms")
    print(f"sky-view LUT 192x108 x16 wl: {t_sv * 1e3:8.1f} ms")
    print(f"aerial-perspective volume 32^3 x16 wl: {t_ap * 1e3:8.1f} ms")

    w, h = 2048, 1024
    az = (np.arange(w) + 0.5) / w * 360.0
    el = 90.0 - (np.arange(h) + 0.5) / h * 180.0
    A, E = np.meshgrid(np.radians(az), np.radians(el))
    d = np.stack([np.cos(E) * np.sin(A), np.cos(E) * np.cos(A), np.sin(E)], axis=-1)
    t = time.perf_counter()
    L = sky.radiance(d, wl)
    dt = time.perf_counter() - t
    print(f"render 2048x1024 x16 wl via sky-view LUT: {dt:6.2f} s  "
          f"({w * h / dt / 1e6:6.2f} Mpixel/s), mean {L.mean():.4g} W m^-2 sr^-1 nm^-1")

    march = sd.model("hillaire2020", sun=sun, use_skyview=False)
    march._tables[tuple(np.round(wl, 9))] = tb
    sub = d[::4, ::4]
    t = time.perf_counter()
    march.radiance(sub, wl)
    dt = time.perf_counter() - t
    print(f"render 512x256 x16 wl by per-pixel ray march: {dt:6.2f} s  "
          f"({sub.shape[0] * sub.shape[1] / dt / 1e6:6.3f} Mpixel/s; 2048x1024 would take "
          f"{w * h / (sub.shape[0] * sub.shape[1] / dt):.1f} s)")


if __name__ == "__main__":
    main()
