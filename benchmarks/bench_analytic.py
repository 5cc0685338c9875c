"""Directions per second of every analytic model on a 2048x1024 equirect grid (issue 3).

Luminance-only models are timed through ``luminance(directions)``, XYZ models through
``xyz(directions)`` and spectral ones through ``radiance(directions, 16 wavelengths)``.
Where a model keeps its numpy reference evaluation beside the numba kernel, that is timed
too. Target of issue 3: >= 20 million directions/s for the luminance-only models on 2 cores.
With --write the table goes into docs/performance.md.

Run:  .venv/bin/python benchmarks/bench_analytic.py [--write]
"""

from __future__ import annotations

import argparse
import os
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
    ("asrc_cie", {"epsilon": 3.0, "delta": 0.2}),
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
    _reference.d = d
    wl = np.linspace(380.0, 780.0, 16)
    sun = sd.Sun(elevation_deg=35.0, azimuth_deg=160.0)
    rows = ["| model | native | evaluated | time for 2048x1024 | million directions/s "
            "| numpy reference, million directions/s |", "|---|---|---|---|---|---|"]
    for name, params in CASES:
        sky = sd.model(name, sun=sun, **params)
        if sky.native == "luminance":
            f, what = (lambda: sky.luminance(d)), "luminance"
        elif sky.native == "xyz":
            f, what = (lambda: sky.xyz(d)), "xyz"
        else:
            f, what = (lambda: sky.radiance(d, wl)), "radiance, 16 wl"
        ref = _reference(sky)
        f()
        best = min(_time(f) for _ in range(args.repeat))
        ref_txt = "-"
        if ref is not None:
            ref_best = min(_time(ref) for _ in range(max(1, args.repeat - 1)))
            ref_txt = f"{d.shape[0] / ref_best / 1e6:.1f}"
        rows.append(f"| {name} | {sky.native} | {what} | {best:.3f} s | "
                    f"{d.shape[0] / best / 1e6:.1f} | {ref_txt} |")
    load = ""
    if hasattr(os, "getloadavg"):
        load = f" Load average during the run: {os.getloadavg()[0]:.1f}."
    rows += ["", f"Machine: {machine()}.{load}"]
    text = "\n".join(rows)
    print(text)
    if args.write:
        write_section(Path(__file__).resolve().parents[1] / "docs" / "performance.md", "analytic", text)


def _reference(sky):
    """The model's numpy reference evaluation (kept beside its numba kernel), or None."""
    from skydome._validate import as_directions

    d = _reference.d
    if hasattr(sky, "_relative") and sky.native == "luminance":
        return lambda: sky.zenith_luminance * sky._relative(as_directions(d))
    if hasattr(sky, "_luminance_reference"):
        return lambda: sky._luminance_reference(d)
    if hasattr(sky, "_xyz_reference"):
        return lambda: sky._xyz_reference(d)
    return None


def _time(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
