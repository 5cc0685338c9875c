"""Export throughput: a 4096 x 2048 half-float lat-long map and a 6 x 1024^2 cube map from
the ``precomputed`` model (tables built, or read from the cache, before the clock starts),
written to a temporary folder. Prints wall times and pixels per second.

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
    args = ap.parse_args()
    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=135.0)
    t0 = time.perf_counter()
    sky = sd.model(args.model, sun=sun)
    sky.radiance([[0.0, 0.0, 1.0]], [550.0]) if sky.native == "spectral" else sky.xyz([[0, 0, 1.0]])
    print(f"model {args.model}: built in {time.perf_counter() - t0:.1f} s "
          f"(cores: {os.cpu_count()})")
    with tempfile.TemporaryDirectory() as tmp:
        for label, kw, fname, half in (
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


if __name__ == "__main__":
    main()
