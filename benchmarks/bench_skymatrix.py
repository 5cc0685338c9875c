"""Annual sky matrices: skydome's perez1993 path against Radiance's gendaymtx, same run.

Input: the TMY3 file pvlib ships (Greensboro, NC; 8760 hours), written as a .wea for
gendaymtx. Each case is timed end to end: gendaymtx -m MF -of (binary float) into a file;
skydome from the parsed weather to the same float file (sky matrix in one kernel call +
write). skydome is run twice per case: ``order 0`` (gendaymtx's definition: one point per
patch, Radiance's sun positions) and its default ``order 4`` (16 Gauss-Legendre nodes per
patch, SPA suns), storing float32 as the file does. The numba kernels are compiled before timing. With --write the table goes
into docs/performance.md.

Run:  .venv/bin/python benchmarks/bench_skymatrix.py [--write] [--repeat N]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_single_scattering import machine, write_section  # noqa: E402


def _radiance():
    import pyradiance

    root = Path(pyradiance.__file__).resolve().parent
    env = dict(os.environ, RAYPATH=os.pathsep.join([".", str(root / "lib")]))
    return root / "bin" / "gendaymtx", env


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--write", action="store_true")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--threads", type=int, default=0, help="numba threads (0: all)")
    args = ap.parse_args(argv)
    if args.threads:
        import numba

        numba.set_num_threads(args.threads)

    from skydome.daylighting.radiance_io import write_matrix
    from skydome.daylighting.skymatrix import perez_sky_matrix_from_weather
    from skydome.daylighting.weather import read_weather, sample_weather_path, write_wea

    t0 = time.perf_counter()
    w = read_weather(sample_weather_path())
    t_read = time.perf_counter() - t0
    gendaymtx, env = _radiance()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        write_wea(w, tmp / "y.wea")
        small = w.select(slice(0, 48))
        for o in (0, 4):  # compile the kernels
            perez_sky_matrix_from_weather(small, order=o)
        for mf in (1, 4):
            spec = "tregenza" if mf == 1 else f"reinhart:{mf}"
            best = {}
            for _ in range(args.repeat):
                t = time.perf_counter()
                with open(tmp / "g.mtx", "wb") as f:
                    subprocess.run([str(gendaymtx), "-m", str(mf), "-of", str(tmp / "y.wea")],
                                   stdout=f, stderr=subprocess.DEVNULL, env=env, check=True)
                best["gendaymtx"] = min(best.get("gendaymtx", 1e9), time.perf_counter() - t)
                for o, sp in ((0, "radiance"), (4, "spa")):
                    out = tmp / f"s{o}.mtx"
                    out.unlink(missing_ok=True)
                    t = time.perf_counter()
                    m = perez_sky_matrix_from_weather(w, patches=spec, order=o, sun_position=sp,
                                                      dew_point_c=11.0, dtype=np.float32)
                    tc = time.perf_counter() - t
                    write_matrix(out, m.sky, fmt="float", transpose=True)
                    key = f"order {o}"
                    best[key] = min(best.get(key, 1e9), time.perf_counter() - t)
                    best[key + ", matrix only"] = min(best.get(key + ", matrix only", 1e9), tc)
                    del m
            g = best["gendaymtx"]
            for key in ("gendaymtx", "order 0", "order 0, matrix only", "order 4",
                        "order 4, matrix only"):
                rows.append((spec, key, best[key], g / best[key]))
                print(f"{spec:11s} {key:22s} {best[key]:7.2f} s   x{g / best[key]:5.1f} vs "
                      f"gendaymtx", flush=True)
    load = os.getloadavg()[0]
    print(f"weather read + SPA sun positions: {t_read:.2f} s; load average {load:.1f}")
    if args.write:
        lines = [f"Annual sky matrices, 8760 h of the Greensboro TMY3 (benchmarks/bench_skymatrix.py; "
                 f"{machine()}; 1-min load average {load:.1f} during the run: the machine was "
                 "shared, figures are wall-clock times of one run each, peer and skydome "
                 f"interleaved; numba threads: {args.threads or 'all'}). 'matrix only' leaves "
                 "out writing the 242 MB float file (MF:4), which gendaymtx's figure includes.",
                 "",
                 "| patches | program | wall time [s] | speed vs gendaymtx |", "|---|---|---|---|"]
        for spec, key, t, r in rows:
            name = "gendaymtx -of" if key == "gendaymtx" else f"skydome, {key}"
            lines.append(f"| {spec} | {name} | {t:.2f} | {r:.1f}x |")
        lines += ["", f"Reading the TMY3 file and computing 8760 SPA sun positions: {t_read:.2f} s "
                  "(not included above)."]
        write_section(Path(__file__).resolve().parents[1] / "docs" / "performance.md",
                      "skymatrix", "\n".join(lines))


if __name__ == "__main__":
    main()
