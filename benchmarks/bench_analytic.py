"""Directions per second of every analytic model on a 2048x1024 equirect grid (issue 3).

Luminance-only models are timed through ``luminance(directions)``, XYZ models through
``xyz(directions)`` and spectral ones through ``radiance(directions, 16 wavelengths)``.
With --write the table goes into docs/performance.md.

Run:  .venv/bin/python benchmarks/bench_analytic.py [--write]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_single_scattering import machine, write_section  # noqa: E402

CASES = [
    ("cie1994_overcast", {}),
    ("cie1994_clear", {}),
    ("cie1994_intermediate", {}),
    ("cie2003", {"sky_type": 12}),
    ("asrc_cie", {"sky_clearness": 3.0, "sky_brightness": 0.2}),
    ("perez1993", {"dni": 650.0, "dhi": 120.0}),
    ("preetham1999", {"turbidity": 3.0}),
    ("hoffman_preetham2002", {"turbidity": 3.0}),
]


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--write", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    import skydome as sd

    d = sd.Equirect(2048, 1024).directions()[0].reshape(-1, 3)
    wl = np.linspace(380.0, 780.0, 16)
    sun = sd.Sun(elevation_deg=35.0, azimuth_deg=160.0)
    rows = ["| model | native | evaluated | time for 2048x1024 | million directions/s |", "|---|---|---|---|---|"]
    for name, params in CASES:
        sky = sd.model(name, sun=sun, **params)
        if sky.native == "luminance":
            f, what = (lambda: sky.luminance(d)), "luminance"
        elif sky.native == "xyz":
            f, what = (lambda: sky.xyz(d)), "xyz"
        else:
            f, what = (lambda: sky.radiance(d, wl)), "radiance, 16 wl"
        f()
        best = min(_time(f) for _ in range(args.repeat))
        rows.append(f"| {name} | {sky.native} | {what} | {best:.3f} s | {d.shape[0] / best / 1e6:.1f} |")
    rows += ["", f"Machine: {machine()}."]
    text = "\n".join(rows)
    print(text)
    if args.write:
        write_section(Path(__file__).resolve().parents[1] / "docs" / "performance.md", "analytic", text)


def _time(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
