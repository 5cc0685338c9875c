"""Before/after timing of the single-scattering kernel from two source trees, alternately.

On a loaded machine one timing after another measures the load as much as the code, so
this runs one worker process per source tree (each imports ``skydome`` from its own
``src``), warms both (numba compilation, column table), then asks them in turn for one
timing each (A, B, A, B, ...), ``--repeat`` rounds, and prints the best of each:
process CPU time of the kernel call alone (``time.process_time``), on one numba thread,
as rays per second. It also compares the two trees' radiances (largest relative
difference where the radiance exceeds 1e-12 of its maximum) and, with ``--models``, times
the other models that share the transport core the same way.

Run:  python benchmarks/bench_single_scattering_ab.py OLD_TREE NEW_TREE [--repeat 7]
      [--models hillaire2020_luts] [--no-gases]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

WORKER = r"""
import json, sys, time
import numpy as np
import numba
numba.set_num_threads(1)
import skydome as sd
from skydome.transport import _kernels as K

cfg = json.loads(sys.argv[1])
w, h = cfg["size"]
d = np.ascontiguousarray(sd.Equirect(w, h).directions()[0].reshape(-1, 3))
wl = np.linspace(380.0, 780.0, cfg["n_wl"])
sun = sd.Sun(elevation_deg=cfg["elevation"], azimuth_deg=135.0)
name = cfg["model"]
atm = (sd.Atmosphere.earth() if cfg.get("gases", True)
       else sd.Atmosphere.earth(precipitable_water_cm=0.0, mixed_gases=False))
if name == "single_scattering":
    sky = sd.model(name, sun=sun, atmosphere=atm)
    ss = sky._integrator(wl)
    e = np.ascontiguousarray(sky._solar(wl))
    s = np.ascontiguousarray(sun.direction, dtype=np.float64).reshape(3)
    out = np.empty((d.shape[0], wl.size))
    def call():
        K.single_scattering(d, ss.r0, s, ss.medium, e, ss.table.table, ss.view_samples,
                            ss.scale_m, ss.light_exact, ss.light_samples, out)
        return out
elif name == "hillaire2020_luts":
    # the per-sun cost of hillaire2020: its transmittance, multiple-scattering and sky-view
    # tables at the model's default sizes (the radiance of the directions then read from them)
    sky = sd.model("hillaire2020", sun=sun, atmosphere=atm)
    def call():
        sky._tables.clear()
        return sky.radiance(d, wl)
else:
    sky = sd.model(name, sun=sun, atmosphere=atm)
    def call():
        return sky.radiance(d, wl)
res = np.array(call())
np.save(cfg["save"], res)
print("ready", flush=True)
for line in sys.stdin:
    if line.strip() != "go":
        break
    t0 = time.process_time()
    call()
    print(time.process_time() - t0, flush=True)
"""


def start(tree: Path, cfg: dict) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(tree / "src"), NUMBA_NUM_THREADS="1")
    p = subprocess.Popen([sys.executable, "-c", WORKER, json.dumps(cfg)], stdin=subprocess.PIPE,
                         stdout=subprocess.PIPE, text=True, env=env, cwd=str(tree))
    line = p.stdout.readline().strip()
    if line != "ready":
        raise RuntimeError(f"worker in {tree} did not start: {line!r}")
    return p


def ab(trees, cfg, repeat):
    with tempfile.TemporaryDirectory() as tmp:
        procs = []
        for k, tree in enumerate(trees):
            c = dict(cfg, save=str(Path(tmp) / f"r{k}.npy"))
            procs.append(start(tree, c))
        best = [np.inf] * len(procs)
        for _ in range(repeat):
            for k, p in enumerate(procs):
                p.stdin.write("go\n")
                p.stdin.flush()
                best[k] = min(best[k], float(p.stdout.readline()))
        for p in procs:
            p.stdin.close()
            p.wait()
        r = [np.load(Path(tmp) / f"r{k}.npy") for k in range(len(procs))]
    big = np.abs(r[0]) > 1e-12 * np.abs(r[0]).max()
    rel = float(np.max(np.abs(r[1][big] / r[0][big] - 1.0))) if big.any() else 0.0
    return best, rel


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--size", type=int, nargs=2, default=(512, 256))
    ap.add_argument("--wavelengths", type=int, default=16)
    ap.add_argument("--elevations", type=float, nargs="+", default=(30.0, -4.0))
    ap.add_argument("--models", nargs="*", default=(),
                    help="other models to time by radiance(); hillaire2020_luts times the "
                         "build of hillaire2020's tables")
    ap.add_argument("--no-gases", action="store_true",
                    help="Atmosphere.earth() without water vapour and mixed gases")
    args = ap.parse_args(argv)
    n = args.size[0] * args.size[1]
    print(f"load average before: {os.getloadavg()[0]:.1f}")
    print("| model | sun elevation | old: rays/s | new: rays/s | speed-up | max rel. difference |")
    print("|---|---|---|---|---|---|")
    for model in ("single_scattering", *args.models):
        for elev in args.elevations:
            cfg = dict(model=model, size=list(args.size), n_wl=args.wavelengths, elevation=elev,
                       gases=not args.no_gases)
            (t_old, t_new), rel = ab([args.old, args.new], cfg, args.repeat)
            print(f"| {model} | {elev:g} deg | {n / t_old:,.0f} | {n / t_new:,.0f} | "
                  f"{t_old / t_new:.2f}x | {rel:.1e} |", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
