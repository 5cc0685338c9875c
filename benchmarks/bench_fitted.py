"""Throughput of the ``fitted`` model beside hosek_wilkie2012 and preetham1999, in one run.

Prints million directions per second for luminance and XYZ (every model), million
direction-wavelengths per second for spectral radiance (fitted and hosek_wilkie2012, 41
wavelengths 380-780 nm), the time to build a fitted model (its angular table for one
configuration; the first construction also loads the coefficient file), and the compute
time of a 4096 x 2048 lat-long environment map of each model
(``skydome.export.envmap.render_envmap``, what ``skydome export envmap`` computes before it
writes the file). Kernels are compiled (and numba's cache filled) before the clock starts.

Each call allocates its output, as a caller's plain call does; the first touch of that fresh
memory (page faults, 48 MB for XYZ of 2 M directions) is part of the figure. The fitted
model also takes ``out=`` (an output array reused from call to call, as a frame loop would);
its rates into a reused output are printed too, so that the kernel's speed and the page
faults' cost can be told apart.

Each rate is printed twice: per second of wall-clock time (what a caller sees; on a shared
machine it follows the load) and, in brackets, per second of this process's CPU time (all
its threads together: what the machine's load changes least; on an idle machine the wall
rate approaches it times the number of threads). The thread count is numba's
(NUMBA_NUM_THREADS=1 for single-thread figures).

Run:  [NUMBA_NUM_THREADS=1] python benchmarks/bench_fitted.py [--n 2000000] [--repeat 3]
      [--no-envmap]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def _best(f, repeat):
    """(wall, CPU) seconds of the fastest of ``repeat`` calls (each its own best)."""
    wall = cpu = np.inf
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        f()
        wall = min(wall, time.perf_counter() - t)
        cpu = min(cpu, time.process_time() - c)
    return wall, cpu


def _rate(n, times):
    wall, cpu = times
    return f"{n / wall / 1e6:.1f} ({n / max(cpu, 1e-9) / 1e6:.1f})"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=2_000_000, help="directions per call")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-envmap", action="store_true")
    a = ap.parse_args(argv)
    import skydome as sd
    from skydome.spectra import default_wavelengths

    import numba

    print(f"cores: {os.cpu_count()}, numba threads: {numba.get_num_threads()}, "
          f"load average at start: {os.getloadavg()[0]:.1f}")
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
                    a.repeat)[0]
    print(f"fitted: first model {first * 1e3:.0f} ms (coefficient file loaded, imports), "
          f"then {t_build * 1e3:.1f} ms per new configuration")
    models = {"fitted": sd.model("fitted", sun=sun, aerosol_optical_depth=0.1),
              "hosek_wilkie2012": sd.model("hosek_wilkie2012", sun=sun, turbidity=2.0),
              "preetham1999": sd.model("preetham1999", sun=sun, turbidity=2.0)}
    print("Rates per second of wall time, in brackets per second of CPU time:")
    print("| model | luminance, M directions/s | XYZ, M directions/s | luminance / XYZ into "
          "a reused out=, M directions/s | spectral 41 wl, M direction-wavelengths/s | "
          "envmap 4096x2048 compute, s |")
    print("|---|---|---|---|---|---|")
    for name, sky in models.items():
        sky.luminance(d[:1000]), sky.xyz(d[:1000])       # compile / warm
        t_y = _best(lambda: sky.luminance(d), a.repeat)
        t_xyz = _best(lambda: sky.xyz(d), a.repeat)
        reused = "-"
        if name == "fitted":
            out_y, out_xyz = np.zeros(a.n), np.zeros((a.n, 3))    # touched before the clock
            t_oy = _best(lambda: sky.luminance(d, out=out_y), a.repeat)
            t_oxyz = _best(lambda: sky.xyz(d, out=out_xyz), a.repeat)
            reused = f"{_rate(a.n, t_oy)} / {_rate(a.n, t_oxyz)}"
        spec = "-"
        if sky.native == "spectral":
            sky.radiance(d_spec[:100], wl)
            t_s = _best(lambda: sky.radiance(d_spec, wl), a.repeat)
            spec = _rate(d_spec.shape[0] * wl.size, t_s)
        env = "-"
        if not a.no_envmap:
            from skydome.export.envmap import render_envmap

            render_envmap(sky, "skydome", "256x128")
            t_e, c_e = _best(lambda: render_envmap(sky, "skydome", "4096x2048"), 1)
            env = f"{t_e:.2f} (CPU {c_e:.2f})"
        print(f"| {name} | {_rate(a.n, t_y)} | {_rate(a.n, t_xyz)} | {reused} | {spec} "
              f"| {env} |")
    print(f"load average at end: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
