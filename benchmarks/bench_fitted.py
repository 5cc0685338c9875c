"""Throughput of the ``fitted`` model beside hosek_wilkie2012 and preetham1999, in one run.

Prints million directions per second for luminance and XYZ (every model), million
direction-wavelengths per second for spectral radiance (fitted and hosek_wilkie2012, 41
wavelengths 380-780 nm), the time to build a fitted model (its angular table for one
configuration; the first construction also loads the coefficient file), and the compute
time of a 4096 x 2048 lat-long environment map of each model
(``skydome.export.envmap.render_envmap``, what ``skydome export envmap`` computes before it
writes the file). Kernels are compiled (and numba's cache filled) before the clock starts.

Run:  python benchmarks/bench_fitted.py [--n 2000000] [--repeat 3] [--no-envmap]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def _best(f, repeat):
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t)
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=2_000_000, help="directions per call")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-envmap", action="store_true")
    a = ap.parse_args(argv)
    import skydome as sd
    from skydome.spectra import default_wavelengths

    print(f"cores: {os.cpu_count()}, load average at start: {os.getloadavg()[0]:.1f}")
    rng = np.random.default_rng(1)
    d = rng.normal(size=(a.n, 3))
    d[:, 2] = np.abs(d[:, 2])
    d /= np.linalg.norm(d, axis=1)[:, None]
    d_spec = np.ascontiguousarray(d[: a.n // 10])
    wl = default_wavelengths()
    sun = sd.Sun(elevation_deg=35.0, azimuth_deg=160.0)
    t = time.perf_counter()
    sd.model("fitted", sun=sun)
    first = time.perf_counter() - t
    t_build = _best(lambda: sd.model("fitted", sun=sun, aerosol_optical_depth=0.05,
                                     ground_albedo=0.3, observer_altitude_m=1234.0),
                    a.repeat)
    print(f"fitted: first model {first * 1e3:.0f} ms (coefficient file loaded, imports), "
          f"then {t_build * 1e3:.1f} ms per new configuration")
    models = {"fitted": sd.model("fitted", sun=sun, aerosol_optical_depth=0.1),
              "hosek_wilkie2012": sd.model("hosek_wilkie2012", sun=sun, turbidity=2.0),
              "preetham1999": sd.model("preetham1999", sun=sun, turbidity=2.0)}
    print("| model | luminance, M directions/s | XYZ, M directions/s | spectral 41 wl, "
          "M direction-wavelengths/s | envmap 4096x2048 compute |")
    print("|---|---|---|---|---|")
    for name, sky in models.items():
        sky.luminance(d[:1000]), sky.xyz(d[:1000])       # compile / warm
        t_y = _best(lambda: sky.luminance(d), a.repeat)
        t_xyz = _best(lambda: sky.xyz(d), a.repeat)
        spec = "-"
        if sky.native == "spectral":
            sky.radiance(d_spec[:100], wl)
            t_s = _best(lambda: sky.radiance(d_spec, wl), a.repeat)
            spec = f"{d_spec.shape[0] * wl.size / t_s / 1e6:.1f}"
        env = "-"
        if not a.no_envmap:
            from skydome.export.envmap import render_envmap

            render_envmap(sky, "skydome", "256x128")
            t_e = _best(lambda: render_envmap(sky, "skydome", "4096x2048"), 1)
            env = f"{t_e:.2f} s"
        print(f"| {name} | {a.n / t_y / 1e6:.1f} | {a.n / t_xyz / 1e6:.1f} | {spec} | {env} |")
    print(f"load average at end: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
