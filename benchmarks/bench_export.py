"""Export throughput: a 4096 x 2048 half-float lat-long map and a 6 x 1024^2 cube map from
the ``precomputed`` model (tables built, or read from the cache, before the clock starts),
written to a temporary folder; then a GGX-prefiltered mip chain (6 levels) of a
``--mips-width`` lat-long map and of a 6 x ``--mips-face``^2 cube map, and the LUT bakes of
precomputed and hillaire2020 (``write_luts``, npy + bin + float32 EXR). Prints wall times,
pixels per second and the load average.

Run:  .venv/bin/python benchmarks/bench_export.py [--width 4096] [--face 1024]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import skydome as sd
from skydome.export.envmap import render_envmap


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=4096)
    ap.add_argument("--face", type=int, default=1024)
    ap.add_argument("--model", default="precomputed")
    ap.add_argument("--mips-width", type=int, default=1024)
    ap.add_argument("--mips-face", type=int, default=256)
    ap.add_argument("--skip-maps", action="store_true", help="no 4096 / 1024^2 maps")
    ap.add_argument("--skip-bakes", action="store_true", help="no LUT bakes")
    args = ap.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.1f}")
    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=135.0)
    t0 = time.perf_counter()
    sky = sd.model(args.model, sun=sun)
    sky.radiance([[0.0, 0.0, 1.0]], [550.0]) if sky.native == "spectral" else sky.xyz([[0, 0, 1.0]])
    print(f"model {args.model}: built in {time.perf_counter() - t0:.1f} s "
          f"(cores: {os.cpu_count()})")
    with tempfile.TemporaryDirectory() as tmp:
        for label, kw, fname, half in () if args.skip_maps else (
                (f"lat-long {args.width}x{args.width // 2} half EXR",
                 dict(convention="blender", size=f"{args.width}x{args.width // 2}"), "map.exr", True),
                (f"cube map 6x{args.face}^2 float32 EXR",
                 dict(convention="unity", size=args.face, layout="cubemap"), "cube.exr", False)):
            t0 = time.perf_counter()
            env = render_envmap(sky, **kw)
            t1 = time.perf_counter()
            (path,) = env.write(Path(tmp) / fname, half=half)
            t2 = time.perf_counter()
            n = sum(im.shape[0] * im.shape[1] for im in env.images.values())
            print(f"{label}: render {t1 - t0:.1f} s, write {t2 - t1:.1f} s, total "
                  f"{t2 - t0:.1f} s ({n / (t2 - t0) / 1e6:.2f} Mpixel/s), "
                  f"{path.stat().st_size / 2**20:.1f} MiB")
        from skydome.export.luts import write_luts
        from skydome.export.prefilter import prefiltered_mips

        for label, kw in ((f"mips of lat-long {args.mips_width}x{args.mips_width // 2}",
                           dict(convention="blender", size=f"{args.mips_width}x{args.mips_width // 2}")),
                          (f"mips of cube map 6x{args.mips_face}^2",
                           dict(convention="unity", size=args.mips_face, layout="cubemap"))):
            env = render_envmap(sky, **kw)
            t0 = time.perf_counter()
            mips = prefiltered_mips(env, 6)
            print(f"{label}: 6 levels (5 filtered) in {time.perf_counter() - t0:.1f} s")
            del mips
        for name in () if args.skip_bakes else ("precomputed", "hillaire2020"):
            m = sky if name == args.model else sd.model(name, sun=sun)
            t0 = time.perf_counter()
            files = write_luts(m, Path(tmp) / f"luts_{name}", ("npy", "bin", "exr"))
            print(f"LUT bake {name}: {len(files)} files in {time.perf_counter() - t0:.1f} s "
                  f"(hillaire2020: its tables built inside)")
    print(f"load average at end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
