"""The sky of one ``precomputed`` table setting against another's, over the whole sky.

``run`` precomputes the tables once (cache off, ``Atmosphere.earth`` at one aerosol optical
depth, 20 table wavelengths) and writes to an ``.npz`` the luminance and the radiance at
the 20 table wavelengths of ~1800 directions (elevations -5..90 deg, 0.2-deg steps from the
horizon to 3 deg; azimuths 0..180 deg from the sun every 5 deg) at several sun elevations,
for a ground observer and one at 10 km, with the precomputation's wall and CPU time and the
process's peak resident memory. ``compare`` prints, per sky, the luminance RMS (solid-angle
weighted) and max relative difference of one file against another and the largest
per-wavelength RMS: the measure of a faster approximation against the exact tables (no
Monte Carlo noise). The script imports ``skydome`` from the path, so that two versions of
the code can be run on the same directions.

Run: python benchmarks/spectral_orders.py run --aod 0.2 --settings high_order_wavelengths=5
--out a.npz; python benchmarks/spectral_orders.py compare --ref main.npz --other a.npz
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cost_precomputed import _parse  # noqa: E402  (--settings key=value,...)

SUN_ELEVATIONS = (60.0, 10.0, 2.0, -4.0, -6.0)
OBSERVER_ALTITUDES_M = (0.0, 10_000.0)


def sky_directions():
    """(directions, solid-angle weights, elevation): 49 elevations x 37 azimuths from the
    sun (the sky is symmetric about the sun's vertical plane)."""
    el = np.concatenate([np.arange(-5.0, 0.0, 0.5), np.arange(0.0, 3.0, 0.2),
                         np.arange(3.0, 10.0, 1.0), np.arange(10.0, 90.1, 5.0)])
    d_el = np.gradient(el)
    az = np.arange(0.0, 180.1, 5.0)
    E, A = np.meshgrid(el, az, indexing="ij")
    w = (np.cos(np.radians(E)) * d_el[:, None] * np.where((A == 0) | (A == 180), 0.5, 1.0))
    e, a = np.radians(E.ravel()), np.radians(A.ravel() + 180.0)   # the sun at azimuth 180
    d = np.stack([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)], axis=-1)
    return d, w.ravel(), E.ravel()


def run(args):
    import skydome as sd
    from skydome.atmosphere import Atmosphere

    kw = _parse(args.settings)
    d, _, _ = sky_directions()
    load0 = os.getloadavg()[0]
    w0, c0 = time.perf_counter(), time.process_time()
    m = sd.model("precomputed", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=180.0),
                 atmosphere=Atmosphere.earth(aerosol_optical_depth=args.aod), cache=False, **kw)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    wl = m.table_wavelengths_nm
    out = dict(wall=wall, cpu=cpu, rss=rss, wl=wl)
    for h in OBSERVER_ALTITUDES_M:
        for e in SUN_ELEVATIONS:
            sky = m.with_sun(sd.Sun(elevation_deg=e, azimuth_deg=180.0), observer_altitude_m=h)
            out[f"L_{e:g}_{h:g}"] = sky.radiance(d, wl)
            out[f"Y_{e:g}_{h:g}"] = sky.luminance(d)
    np.savez(args.out, **out)
    print(f"settings {kw or 'default'}, aod {args.aod:g}: precompute {wall:.1f} s wall, "
          f"{cpu:.1f} s CPU, peak RSS {rss:.2f} GB, load average {load0:.1f} -> "
          f"{os.getloadavg()[0]:.1f} ({sd.__file__})", flush=True)


def _rel(a, b):
    """(b - a) / a where a > 0 (else 0, and a mask)."""
    ok = a > 1e-30 * max(float(np.max(a)), 1e-300)
    return np.where(ok, (b - a) / np.where(ok, a, 1.0), 0.0), ok


def compare(args):
    ref, oth = np.load(args.ref), np.load(args.other)
    _, w, _ = sky_directions()
    print(f"{args.other} against {args.ref}: precompute {float(oth['wall']):.1f} s wall / "
          f"{float(oth['cpu']):.1f} s CPU / {float(oth['rss']):.2f} GB against "
          f"{float(ref['wall']):.1f} / {float(ref['cpu']):.1f} s / {float(ref['rss']):.2f} GB")
    worst = [0.0, 0.0, 0.0]
    for h in OBSERVER_ALTITUDES_M:
        for e in SUN_ELEVATIONS:
            k = f"{e:g}_{h:g}"
            r, ok = _rel(ref["Y_" + k], oth["Y_" + k])
            ww = w * ok
            rms = np.sqrt(np.sum(ww * r * r) / ww.sum())
            mx = np.max(np.abs(r))
            mean = np.sum(ww * r) / ww.sum()
            rl, okl = _rel(ref["L_" + k], oth["L_" + k])
            wl_ = w[:, None] * okl
            rms_l = np.sqrt(np.sum(wl_ * rl * rl, axis=0) / np.maximum(wl_.sum(axis=0), 1e-300))
            lw = int(np.argmax(rms_l))
            worst = [max(worst[0], rms), max(worst[1], mx), max(worst[2], rms_l.max())]
            print(f"  sun {e:5.1f} observer {h / 1000:4.0f} km: luminance RMS {100 * rms:.3f} % "
                  f"max {100 * mx:.3f} % mean {100 * mean:+.3f} %; per wavelength RMS max "
                  f"{100 * rms_l[lw]:.3f} % ({float(ref['wl'][lw]):.0f} nm)")
    print(f"  worst: luminance RMS {100 * worst[0]:.3f} %, max {100 * worst[1]:.3f} %, "
          f"per-wavelength RMS {100 * worst[2]:.3f} % (bound 0.1 / 0.3 / 0.3 %)")


def main(argv=None):
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--aod", type=float, default=0.2)
    r.add_argument("--settings", default="")
    r.add_argument("--out", required=True)
    c = sub.add_parser("compare")
    c.add_argument("--ref", required=True)
    c.add_argument("--other", required=True)
    args = ap.parse_args(argv)
    (run if args.cmd == "run" else compare)(args)


if __name__ == "__main__":
    sys.exit(main())
