"""Throughput and accuracy of the single-scattering reference (issue 2 benchmark).

Renders the directions of a 1024x512 equirectangular image (full sphere) at 16 wavelengths
with the default sample counts, prints rays per second, and measures the error of the
default counts against a converged run (view_samples=128, light_samples=512) on a
256x128 grid for several sun elevations. With --write, the figures go into
docs/performance.md between the markers of this benchmark.

Run:  .venv/bin/python benchmarks/bench_single_scattering.py [--write]
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import numba

    return f"{cpu}, {os.cpu_count()} cores, numba {numba.__version__} ({numba.get_num_threads()} threads), {platform.python_version()}"


def equirect_dirs(w, h):
    import skydome as sd

    return sd.Equirect(w, h).directions()[0]


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--write", action="store_true", help="write the figures into docs/performance.md")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)

    import skydome as sd
    from skydome.spectra import spectrum_to_xyz

    wl = np.linspace(380.0, 780.0, 16)
    lines = []

    # -- throughput ---------------------------------------------------------------------
    d = equirect_dirs(1024, 512).reshape(-1, 3)
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=135.0)
    sky = sd.model("single_scattering", sun=sun)
    sky.radiance(d[:64], wl)  # compile / load the cached kernels, build the column table
    best = np.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        sky.radiance(d, wl)
        best = min(best, time.perf_counter() - t0)
    rate = d.shape[0] / best
    t0 = time.perf_counter()
    sd.model("single_scattering", sun=sun, turbidity=3.0).radiance(d[:1], wl)
    setup = time.perf_counter() - t0
    lines.append(f"- 1024x512 equirect, 16 wavelengths, default counts (view_samples=16, "
                 f"light_samples=128): **{best:.2f} s, {rate / 1e6:.2f} million rays/s** "
                 f"(best of {args.repeat}); model set-up incl. column table: {setup:.2f} s")

    # -- accuracy of the defaults against a converged run ---------------------------------
    dd = equirect_dirs(256, 128)
    up = dd[..., 2] > 0
    lines.append("")
    lines.append("| sun elevation | max error, any wavelength (upper hemisphere) | RMS error | luminance max error |")
    lines.append("|---|---|---|---|")
    for elev in (2.0, 10.0, 30.0, 60.0, 90.0):
        s = sd.Sun(elevation_deg=elev, azimuth_deg=135.0)
        ref = sd.model("single_scattering", sun=s, view_samples=128, light_samples=512).radiance(dd, wl)
        got = sd.model("single_scattering", sun=s).radiance(dd, wl)
        m = up[..., None] & (ref > 1e-8)
        rel = np.abs(got / np.where(ref > 0, ref, 1) - 1)[m]
        Yr = spectrum_to_xyz(ref, wl)[..., 1][up]
        Yg = spectrum_to_xyz(got, wl)[..., 1][up]
        ly = np.abs(Yg / Yr - 1)
        lines.append(f"| {elev:g} deg | {rel.max() * 100:.3f} % | {np.sqrt(np.mean(rel ** 2)) * 100:.3f} % | "
                     f"{ly.max() * 100:.3f} % |")

    lines.append("")
    lines.append(f"Machine: {machine()}.")
    text = "\n".join(lines)
    print(text)
    if args.write:
        write_section(Path(__file__).resolve().parents[1] / "docs" / "performance.md",
                      "single_scattering", text)


def write_section(path: Path, key: str, text: str) -> None:
    """Replace the block between <!-- bench:key --> markers (append it if missing)."""
    start, end = f"<!-- bench:{key} -->", f"<!-- /bench:{key} -->"
    old = path.read_text() if path.exists() else "# Performance\n"
    block = f"{start}\n{text}\n{end}"
    if start in old and end in old:
        new = old[: old.index(start)] + block + old[old.index(end) + len(end):]
    else:
        new = old.rstrip("\n") + "\n\n" + block + "\n"
    tmp = path.with_suffix(".tmp")
    tmp.write_text(new)
    tmp.replace(path)


if __name__ == "__main__":
    main()
