"""Small, fixed workloads of every physically based model kernel, timed through the public
API (so the same script runs on any version of the code): the figures of the table
"Uniform kernel core: before and after" in docs/performance.md.

Each workload is run once to compile or load the numba kernels, then timed as the best
of ``--repeat`` runs. Sizes are kept small so that a before/after comparison on a shared
2-core machine takes a few minutes. Run it with each version of the code on the path,
alternately, in the same shell session:

    PYTHONPATH=<old>/src python benchmarks/bench_kernel_core.py
    PYTHONPATH=src python benchmarks/bench_kernel_core.py

Prints one line per workload: name, best time [ms], rays per second.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def _dirs(n: int, lower: bool = False) -> np.ndarray:
    """n directions on a fixed spiral over the upper (or whole) sphere."""
    k = np.arange(n) + 0.5
    z = 1.0 - k / n if not lower else 1.0 - 2.0 * k / n
    phi = k * np.pi * (3.0 - np.sqrt(5.0))
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


def _best(fn, repeat: int) -> float:
    fn()                                   # compile / load the kernels, fill the caches
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only", default="", help="comma-separated workload names")
    args = ap.parse_args()

    import skydome as sd

    wl = np.linspace(380.0, 780.0, 16)
    sun = sd.Sun(elevation_deg=25.0, azimuth_deg=150.0)
    d4k = _dirs(4096)
    d1k = _dirs(1024)
    d_all = _dirs(2048, lower=True)
    ash = sd.Atmosphere.volcanic_ash(0.5)

    def model(name, **kw):
        return sd.model(name, sun=sun, **kw)

    ss = model("single_scattering")
    n93 = model("nishita1993", camera_altitude_m=20e3)
    n96 = model("nishita1996", orders=1)
    n96m = model("nishita1996", orders=3, sky_directions=14, lattice_size=7)
    kan = model("kaneda1991")
    mc = model("montecarlo", samples=32)
    hil = model("hillaire2020")
    hil_m = model("hillaire2020", use_skyview=False)

    def hillaire_tables():
        m = model("hillaire2020")
        m.radiance(d1k[:1], wl)

    def n96_multiple():
        m = model("nishita1996", orders=3, sky_directions=14, lattice_size=7)
        m.radiance(d1k[:1], wl)

    work = [
        ("single_scattering 4096 rays", lambda: ss.radiance(d4k, wl), 4096),
        ("single_scattering volcanic ash 1024 rays",
         lambda: model("single_scattering", atmosphere=ash).radiance(d1k, wl), 1024),
        ("nishita1993 2048 rays (whole sphere)", lambda: n93.radiance(d_all, wl), 2048),
        ("nishita1996 orders=1 1024 rays", lambda: n96.radiance(d1k, wl), 1024),
        ("nishita1996 orders=3 precompute", n96_multiple, 0),
        ("nishita1996 orders=3 1024 rays", lambda: n96m.radiance(d1k, wl), 1024),
        ("kaneda1991 1024 rays", lambda: kan.radiance(d1k, wl), 1024),
        ("montecarlo 32 paths x 64 rays", lambda: mc.radiance(d1k[::16], wl), 64),
        ("hillaire2020 tables", hillaire_tables, 0),
        ("hillaire2020 sky view 4096 rays", lambda: hil.radiance(d4k, wl), 4096),
        ("hillaire2020 ray march 1024 rays", lambda: hil_m.radiance(d1k, wl), 1024),
    ]
    only = {w.strip() for w in args.only.split(",") if w.strip()}
    for name, fn, n in work:
        if only and not any(name.startswith(o) for o in only):
            continue
        t = _best(fn, args.repeat)
        rate = f"{n / t:12,.0f} rays/s" if n else ""
        print(f"{name:45s} {t * 1e3:10.1f} ms {rate}", flush=True)


if __name__ == "__main__":
    main()
