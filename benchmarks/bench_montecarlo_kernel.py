"""CPU time of the ``montecarlo`` path tracer's kernel alone (``trace``), one thread.

The model's call of its kernel is wrapped so that only ``trace`` is timed (process CPU time,
best of ``--repeat`` calls after a warm-up), on a fixed workload: 64 directions over the
upper hemisphere x 16 wavelengths x 128 paths, sun at 30 deg, fixed seed. With ``--save``
the radiance and the Stokes vectors are written to an .npz file, so that two versions of the
kernel can be compared for equality.

Run:  python benchmarks/bench_montecarlo_kernel.py [--repeat 11] [--polarised] [--save F]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=11)
    ap.add_argument("--samples", type=int, default=128)
    ap.add_argument("--polarised", action="store_true")
    ap.add_argument("--save", default=None)
    args = ap.parse_args()

    import numba
    import skydome as sd
    from skydome.models.simulated import _kernels_montecarlo as K

    numba.set_num_threads(1)
    times = []
    kernel = K.trace

    def timed(*a):
        t0 = time.process_time()
        kernel(*a)
        times.append(time.process_time() - t0)

    K.trace = timed
    n_az, n_el = 16, 4
    az = np.radians(np.repeat(np.arange(n_az) * 360.0 / n_az, n_el))
    el = np.radians(np.tile(10.0 + 20.0 * np.arange(n_el), n_az))
    d = np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], axis=-1)
    wl = np.linspace(400.0, 700.0, 16)
    m = sd.model("montecarlo", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=180.0),
                 samples=args.samples, seed=1, polarised=args.polarised)
    out = None
    for _ in range(args.repeat + 1):
        m._last = None                      # the model keeps its last result
        out = m.radiance(d, wl)
    best = min(times[1:])
    print(f"montecarlo kernel alone: 64 directions x 16 wavelengths x {args.samples} paths"
          f"{' polarised' if args.polarised else ''}, 1 thread: best {best * 1e3:.1f} ms CPU"
          f" (median {np.median(times[1:]) * 1e3:.1f} ms, {args.repeat} calls)")
    if args.save:
        np.savez(args.save, radiance=np.asarray(out), stokes=m._last[1][0])


if __name__ == "__main__":
    main()
