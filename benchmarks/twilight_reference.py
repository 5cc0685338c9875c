"""Twilight Monte Carlo references and the ``precomputed`` sky's error against them.

The twilight sky (sun below the horizon) is the hardest case for the ``montecarlo``
reference: most paths never reach sunlit air, so its noise at sun -6 deg is ten times that
of the day sky for the same paths. This script spends the paths on few directions, a half
sky mirrored about the sun's vertical plane (the sky is symmetric about it): the ring
centres of ``validate_multiple_scattering.directions(20)`` (elevations 10, 30, 50, 70 deg)
at azimuths 0, 45, 90, 135, 180 deg from the sun, plus the zenith, 21 directions with the
solid angle each stands for in the whole sky; 6 wavelengths 400-700 nm;
``Atmosphere.earth(aerosol_optical_depth=0.2)``.

``reference``: runs ``montecarlo`` (``--samples`` paths per direction and wavelength per
sun elevation, ``--seed``) and writes the radiance, its standard error and the provenance
(directions, weights, wavelengths, samples, seed, atmosphere, run time) to ``--out``;
a second run with another seed is merged into the file by ``--merge`` (sample-weighted mean,
combined standard error).

``compare``: for each sun elevation in the file, ``precomputed`` at the named settings
(``--settings``, keys of SETTINGS) against the reference: luminance RMS / max relative error
(solid-angle weighted as in ``validate_multiple_scattering.compare``), xy mean / max and the
reference's noise; with ``--against NAME`` also each setting against that setting's tables
(table against table, no Monte Carlo noise: the discretisation error).

Run:
  python benchmarks/twilight_reference.py reference --elevations -4 --samples 600000 --out refs.npz
  python benchmarks/twilight_reference.py compare --refs refs.npz --settings default,fine --against fine
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from validate_multiple_scattering import compare as compare_lum  # noqa: E402
from validate_multiple_scattering import luminance_xy  # noqa: E402

RING_EDGES_DEG = (0.0, 20.0, 40.0, 60.0, 80.0)
AZIMUTHS_FROM_SUN_DEG = (0.0, 45.0, 90.0, 135.0, 180.0)
SUN_AZIMUTH_DEG = 180.0
WAVELENGTHS_NM = np.linspace(400.0, 700.0, 6)
AOD = 0.2

# precomputed settings compared: the default (20 table wavelengths over 380-780 nm), the
# default on the 6 compared wavelengths (no interpolation in wavelength), and on those one
# discretisation at a time made finer, then several together
WL6 = dict(table_wavelengths_nm=WAVELENGTHS_NM)
SETTINGS = {
    "default": {},
    # the orders >= 3 at every table wavelength (the default computes them at a subset)
    "all_wavelengths": dict(high_order_wavelengths=None),
    "wl6": WL6,
    "orders10": dict(WL6, orders=10),
    "mu_s64": dict(WL6, scattering_mu_s_size=64),
    "mu_s96": dict(WL6, scattering_mu_s_size=96),
    "mu_s128": dict(WL6, scattering_mu_s_size=128),
    # the 4-D tables' mu_s axis alone (the scattering density's stays at 48 nodes), and the
    # density's alone
    "table_mu_s96": dict(WL6, scattering_mu_s_size=96, density_mu_s_size=48),
    "density_mu_s96": dict(WL6, density_mu_s_size=96),
    "nu32": dict(WL6, scattering_nu_size=32),
    "mu256": dict(WL6, scattering_mu_size=256),
    "r64": dict(WL6, scattering_r_size=64),
    "sphere64": dict(WL6, sphere_samples=64, high_order_sphere_samples=32),
    "int60": dict(WL6, integration_samples=60),
    "irr128": dict(WL6, irradiance_mu_s_size=128, irradiance_r_size=32),
    "trans": dict(WL6, transmittance_mu_size=1024, transmittance_r_size=256),
    # the discretisations that move the twilight sky, finer together
    "fine": dict(WL6, scattering_mu_s_size=128, integration_samples=60, orders=10,
                 scattering_nu_size=32),
    # candidates on the default's 20 table wavelengths
    "default_mu_s64": dict(scattering_mu_s_size=64),
    "default_mu_s96": dict(scattering_mu_s_size=96),
}


def twilight_directions():
    """The 21 directions (unit vectors, sun at azimuth 180 deg) and the solid angle [sr]
    each stands for in the whole sky (mirror image included); the weights sum to 2 pi."""
    from skydome.transport.geometry import direction_from_angles

    dirs, w = [], []
    edges = list(RING_EDGES_DEG) + [90.0]
    for lo, hi in zip(edges[:-1], edges[1:]):
        band = 2 * np.pi * (np.sin(np.radians(hi)) - np.sin(np.radians(lo)))
        if hi == 90.0:
            dirs.append(np.array([0.0, 0.0, 1.0]))
            w.append(band)
            continue
        e = 0.5 * (lo + hi)
        for a in AZIMUTHS_FROM_SUN_DEG:
            share = 22.5 if a in (0.0, 180.0) else 45.0   # of 180 deg: the mirror half too
            dirs.append(direction_from_angles(e, (SUN_AZIMUTH_DEG + a) % 360.0))
            w.append(band * share / 180.0)
    return np.array(dirs), np.array(w)


# the few directions of tests/test_precomputed_twilight.py: (elevation, azimuth from the sun)
# [deg]: the twilight arch low towards the sun, the earth's shadow low opposite it, the side
# 30 deg up, 50 deg up opposite the sun, the zenith
TEST_DIRECTIONS_DEG = ((10.0, 0.0), (10.0, 180.0), (30.0, 90.0), (50.0, 180.0), (90.0, 0.0))


def test_directions():
    """The test's directions (unit vectors, sun at azimuth 180 deg); weights 1 sr each (a
    placeholder: the test compares direction by direction)."""
    from skydome.transport.geometry import direction_from_angles

    d = np.array([direction_from_angles(e, (SUN_AZIMUTH_DEG + a) % 360.0)
                  for e, a in TEST_DIRECTIONS_DEG])
    return d, np.ones(len(d))


def key(elev):
    return f"{elev:g}"


def run_reference(args):
    import skydome as sd
    from skydome.atmosphere import Atmosphere

    dirs, w = test_directions() if args.test_set else twilight_directions()
    wl = np.array([float(x) for x in args.wavelengths.split(",")]) if args.wavelengths \
        else WAVELENGTHS_NM
    out = {}
    if os.path.exists(args.out):
        out = dict(np.load(args.out, allow_pickle=False))
    for elev in [float(x) for x in args.elevations.split(",")]:
        mc = sd.model("montecarlo", sun=sd.Sun(elevation_deg=elev, azimuth_deg=SUN_AZIMUTH_DEG),
                      atmosphere=Atmosphere.earth(aerosol_optical_depth=AOD),
                      samples=args.samples, seed=args.seed, max_order=args.max_order,
                      next_event=args.next_event)
        t0 = time.perf_counter()
        c0 = time.process_time()
        L, E = mc.radiance_with_error(dirs, wl)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        rate = args.samples * dirs.shape[0] * wl.size / max(cpu, 1e-9)
        k = key(elev)
        run = {k: L, k + "_err": E, k + "_samples": np.float64(args.samples),
               k + "_seeds": np.str_(str(args.seed)), k + "_cpu_s": np.float64(cpu)}
        if args.merge and k in out:
            run = pool(out, run, k)
        out.update(run)
        samples, seeds = float(out[k + "_samples"]), str(out[k + "_seeds"])
        noise = np.sqrt(np.mean((out[k + "_err"] / out[k]) ** 2)) if wl.size < 3 else \
            compare_lum(out[k], out[k + "_err"], out[k], wl, w)["noise"]
        print(f"sun {elev:g}: {args.samples} paths per direction and wavelength, {wall:.0f} s wall, "
              f"{cpu:.0f} s CPU, {rate:.0f} paths per CPU second; luminance noise "
              f"{100 * noise:.2f} % (RMS relative standard error) "
              f"(file total {samples:.0f} paths, seeds {seeds})", flush=True)
        out.update(directions=dirs, weights_sr=w, wavelengths_nm=wl,
                   provenance=np.str_(
                       "skydome montecarlo (backward path tracing, all orders, next-event "
                       f"estimation towards the sun: next_event={args.next_event!r}), "
                       "benchmarks/twilight_reference.py reference; "
                       f"Atmosphere.earth(aerosol_optical_depth={AOD}); sun azimuth "
                       f"{SUN_AZIMUTH_DEG:g} deg; max_order {args.max_order}; keys '<elev>' "
                       "radiance [W m^-2 sr^-1 nm^-1] (directions, wavelengths), '<elev>_err' its standard error, "
                       "'<elev>_samples' paths per direction and wavelength, '<elev>_seeds'"),
                   command=np.str_(" ".join(["python benchmarks/twilight_reference.py",
                                             *sys.argv[1:]])))
        save_npz(args.out, out)


def save_npz(path, arrays: dict) -> None:
    """``arrays`` written to the .npz ``path`` whole or not at all (skydome._io.atomic_write;
    the temporary ends in .npz, so numpy adds no suffix to it)."""
    from skydome._io import atomic_write

    atomic_write(path, lambda tmp: np.savez(tmp, **arrays), suffix=".npz")


def pool(a, b, k):
    """The sky k of two runs with independent paths pooled: the sample-weighted mean and the
    standard error of the mean of all n_a + n_b paths (per-path variance e^2 n from each
    run's standard error e)."""
    n0, n1 = float(a[k + "_samples"]), float(b[k + "_samples"])
    m0, e0, m1, e1 = a[k], a[k + "_err"], b[k], b[k + "_err"]
    mean = (n0 * m0 + n1 * m1) / (n0 + n1)
    second = (n0 * (n0 * e0 ** 2 + m0 ** 2) + n1 * (n1 * e1 ** 2 + m1 ** 2)) / (n0 + n1)
    err = np.sqrt(np.maximum(second - mean ** 2, 0.0) / (n0 + n1))
    return {k: mean, k + "_err": err, k + "_samples": np.float64(n0 + n1),
            k + "_seeds": np.str_(f"{a[k + '_seeds']},{b[k + '_seeds']}"),
            k + "_cpu_s": np.float64(float(a[k + "_cpu_s"]) + float(b[k + "_cpu_s"]))}


def run_merge(args):
    """Pool the skies of --other into --out (same directions and wavelengths required)."""
    out = dict(np.load(args.out, allow_pickle=False))
    other = dict(np.load(args.other, allow_pickle=False))
    for name in ("directions", "wavelengths_nm"):
        if not np.array_equal(out[name], other[name]):
            raise ValueError(f"--other: its {name} differ from those of --out")
    for k in [k for k in other if k + "_err" in other]:
        if k in out:
            out.update(pool(out, other, k))
        else:
            out.update({kk: other[kk] for kk in other if kk == k or kk.startswith(k + "_")})
        print(f"sun {k}: {float(out[k + '_samples']):.0f} paths, seeds {out[k + '_seeds']}")
    save_npz(args.out, out)


def _commit(path):
    import subprocess

    try:
        return subprocess.run(["git", "-C", str(path), "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, timeout=10).stdout.strip()
    except OSError:
        return "?"


def run_compare(args):
    import skydome as sd
    from skydome.atmosphere import Atmosphere

    dirs, w = twilight_directions()
    wl = WAVELENGTHS_NM
    refs = dict(np.load(args.refs, allow_pickle=False)) if args.refs else {}
    elevs = [float(x) for x in args.elevations.split(",")]
    src = Path(sd.__file__).parent
    print(f"load average {os.getloadavg()[0]:.1f}; skydome from {src} (commit {_commit(src)})")
    got = {}
    for f in [f for f in args.load.split(",") if f]:
        got.update({tuple(k.split("|")): v for k, v in np.load(f).items()})
    names = [n for n in args.settings.split(",") if n]
    for name in names:
        if all((name, key(e)) in got for e in elevs):
            continue
        kw = SETTINGS[name]
        t0 = time.perf_counter()
        c0 = time.process_time()
        m = sd.model("precomputed", sun=sd.Sun(elevation_deg=-4.0, azimuth_deg=SUN_AZIMUTH_DEG),
                     atmosphere=Atmosphere.earth(aerosol_optical_depth=AOD), cache=False, **kw)
        print(f"{name} {kw}: precompute {time.perf_counter() - t0:.0f} s wall, "
              f"{time.process_time() - c0:.0f} s CPU", flush=True)
        for elev in elevs:
            got[name, key(elev)] = m.with_sun(
                sd.Sun(elevation_deg=elev, azimuth_deg=SUN_AZIMUTH_DEG)).radiance(dirs, wl)
        del m
        if args.save:
            save_npz(args.save, {f"{n}|{k}": v for (n, k), v in got.items()})
    for name in names:
        print(f"{name} {SETTINGS[name]}")
        for elev in elevs:
            k = key(elev)
            L = got[name, k]
            line = f"  sun {elev:5.1f}:"
            if k in refs:
                c = compare_lum(refs[k], refs[k + "_err"], L, wl, w)
                line += (f" against MC lum RMS {100 * c['rms']:5.2f} % max {100 * c['max']:5.2f} %"
                         f" mean {100 * np.sum(w * c['rel']) / w.sum():+5.2f} %, xy mean "
                         f"{c['xy_mean']:.4f} max {c['xy_max']:.4f} (MC noise {100 * c['noise']:.2f} %,"
                         f" {float(refs[k + '_samples']):.0f} paths)")
            if args.against and name != args.against:
                a = compare_lum(got[args.against, k], np.zeros_like(L), L, wl, w)
                line += (f"; against {args.against}: RMS {100 * a['rms']:.2f} % max "
                         f"{100 * a['max']:.2f} % mean {100 * np.sum(w * a['rel']) / w.sum():+.2f} %")
            print(line, flush=True)
            if args.verbose and k in refs:
                el = np.degrees(np.arcsin(np.clip(dirs[:, 2], -1, 1)))
                az = (np.degrees(np.arctan2(dirs[:, 0], dirs[:, 1])) - SUN_AZIMUTH_DEG) % 360
                Yr = luminance_xy(refs[k], wl)[0]
                Ye = luminance_xy(refs[k + "_err"], wl)[0]
                for i in range(dirs.shape[0]):
                    print(f"    el {el[i]:4.0f} az-from-sun {az[i]:5.0f}: {100 * c['rel'][i]:+6.2f} %"
                          f" (MC {Yr[i]:.4g} cd/m2 +- {100 * Ye[i] / Yr[i]:.1f} %)")


def main(argv=None):
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("reference")
    r.add_argument("--elevations", default="-2,-4,-6")
    r.add_argument("--samples", type=int, default=100_000)
    r.add_argument("--seed", type=int, default=1)
    r.add_argument("--merge", action="store_true", help="pool with the file's paths of the same sky")
    r.add_argument("--max-order", type=int, default=None,
                   help="highest scattering order (a diagnostic: where the noise comes from)")
    r.add_argument("--next-event", default="vertex", choices=("vertex", "segment"),
                   help="montecarlo's next_event (segment: for deep twilight)")
    r.add_argument("--out", required=True)
    r.add_argument("--test-set", action="store_true", help="the test's 5 directions")
    r.add_argument("--wavelengths", default="", help="e.g. 550 (default: 6 over 400-700 nm)")
    c = sub.add_parser("compare")
    c.add_argument("--refs", default="", help="the reference file (none: tables only)")
    c.add_argument("--elevations", default="-2,-4,-6")
    c.add_argument("--settings", default="default")
    c.add_argument("--against", default="", help="also compare every setting with this one")
    c.add_argument("--verbose", action="store_true", help="every direction's error")
    c.add_argument("--save", default="", help="write every setting's radiance to this .npz")
    c.add_argument("--load", default="", help="radiances saved by --save (comma-separated)")
    g = sub.add_parser("merge")
    g.add_argument("--out", required=True)
    g.add_argument("--other", required=True)
    args = ap.parse_args(argv)
    {"reference": run_reference, "compare": run_compare, "merge": run_merge}[args.cmd](args)


if __name__ == "__main__":
    main()
