"""Benchmark of the ``precomputed`` model.

Prints, on this machine:

1. the table precomputation (cache off) at the earlier default (Bruneton's 2017 sizes:
   transmittance 256 x 64, scattering 32 x 128 x 32 x 8, irradiance 64 x 16, 4 orders), at
   the earlier validated settings and at this version's default, 20 wavelengths, with the
   time of each stage (transmittance columns, single scattering, and per further order:
   incident radiance, scattering density, indirect irradiance, multiple scattering), and
   the start-up from the on-disk cache at the default (where the version has one);
2. the precomputation at Radiance ``genssky``'s own table sizes (its source, gen/atmos.c:
   transmittance 256 x 64, scattering 16 x 64 x 16 x 4, irradiance 64 x 16, 20 wavelengths
   380-780 nm, 4 orders), and ``genssky`` itself (shipped in pyradiance's ``bin/`` folder)
   on the same machine with as many threads as there are cores, and the speed ratio
   (issue target: at least 20x);
3. the render throughput of a 2048 x 1024 equirectangular spectral image (20 wavelengths)
   from the tables (issue target: at least 2 Mpixel/s on 2 cores).

The machine's load average is printed with each figure (on a shared machine the wall
times vary with the other jobs).

Run: python benchmarks/bench_precomputed.py [--quick] [--no-genssky] [--only=LABEL]
(LABEL old_default, old_validated or default: only that precomputation is timed, for
/usr/bin/time -v peak-memory runs)
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

OLD_DEFAULT = dict(orders=4, remaining_orders="none", sphere_samples=16, scattering_nu_size=8,
                   scattering_mu_s_size=32, integration_samples=20)
OLD_VALIDATED = dict(orders=6, remaining_orders="geometric", sphere_samples=32,
                     scattering_nu_size=16, scattering_mu_s_size=64, density_mu_s_size=64,
                     integration_samples=20)
GENSSKY_SIZES = dict(transmittance_mu_size=256, transmittance_r_size=64, scattering_r_size=16,
                     scattering_mu_size=64, scattering_mu_s_size=16, scattering_nu_size=4,
                     irradiance_mu_s_size=64, irradiance_r_size=16)
STAGES = {"build_column_table": "transmittance columns",
          "single_scattering_table": "single scattering",
          "incident_radiance": "incident radiance (per order)",
          "indirect_irradiance": "indirect irradiance (per order)",
          "multiple_scattering_table": "multiple scattering (per order)"}


def _load():
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


@contextlib.contextmanager
def _stage_timer(times):
    """Time the numba kernels called by the precomputation (module attributes wrapped)."""
    from skydome.transport import _kernels as K

    try:   # the package layout (skydome.models.simulated.precomputed._single, ...)
        from skydome.models.simulated.precomputed import _density, _irradiance, _multiple, _single
        mods = (_single, _density, _irradiance, _multiple, K)
    except ImportError:   # the single kernel module of earlier versions
        from skydome.models.simulated import _kernels_precomputed as KP
        mods = (KP, K)
    saved = []
    for mod in mods:
        for name in STAGES:
            if hasattr(mod, name):
                f = getattr(mod, name)
                saved.append((mod, name, f))

                def g(*a, _f=f, _n=name):
                    t0 = time.perf_counter()
                    r = _f(*a)
                    times.setdefault(_n, []).append(time.perf_counter() - t0)
                    return r

                setattr(mod, name, g)
    try:
        yield times
    finally:
        for mod, name, f in saved:
            setattr(mod, name, f)


def _has_cache(sd) -> bool:
    return any(p.name == "cache" for p in sd.models.get_model_class("precomputed").parameters)


def _precompute(sd, sun, repeats, **kw):
    """Best wall time [s] of ``repeats`` precomputations (cache off), and the stage times of
    the best."""
    best, best_stages = np.inf, {}
    if _has_cache(sd):
        kw["cache"] = False
    for _ in range(repeats):
        stages = {}
        with _stage_timer(stages):
            t0 = time.perf_counter()
            sd.model("precomputed", sun=sun, n_wavelengths=20, **kw)
            dt = time.perf_counter() - t0
        if dt < best:
            best, best_stages = dt, stages
    return best, best_stages


def _genssky_seconds(threads: int):
    """Wall time of one genssky run in a fresh folder (it precomputes its tables into
    ./atmos_data); None when unavailable."""
    try:
        import pyradiance
    except ImportError:
        return None, "pyradiance not installed"
    root = os.path.dirname(pyradiance.__file__)
    exe = os.path.join(root, "bin", "genssky")
    if not os.path.exists(exe):
        return None, "genssky not shipped"
    env = dict(os.environ, RAYPATH=os.path.join(root, "lib"))
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        proc = subprocess.run([exe, "6", "21", "12", "-a", "37.7", "-o", "122.2", "-m", "120",
                               "-n", str(threads), "-f", os.path.join(tmp, "sky")],
                              cwd=tmp, env=env, capture_output=True, timeout=900)
        dt = time.perf_counter() - t0
        data = os.path.join(tmp, "atmos_data")
        files = sorted(os.listdir(data)) if os.path.isdir(data) else []
        if not any(f.startswith("scat_") for f in files):
            return None, f"genssky wrote no tables (exit {proc.returncode})"
        note = "" if proc.returncode == 0 else (f" (exit status {proc.returncode} after writing "
                                                "its tables; the time is its precomputation)")
        return dt, f"tables {', '.join(files)}{note}"


def main(quick: bool = False, genssky: bool = True, only=()) -> None:
    import skydome as sd
    from skydome.transport.geometry import direction_from_angles

    cores = os.cpu_count() or 1
    print(f"cpu cores: {cores}; load average at start: {_load():.1f}")
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    # warm-up: compile/load the numba kernels on a tiny table set
    small = dict(scattering_r_size=4, scattering_mu_size=8, scattering_mu_s_size=4,
                 scattering_nu_size=2, irradiance_mu_s_size=4, irradiance_r_size=4,
                 transmittance_mu_size=8, transmittance_r_size=4)
    t0 = time.perf_counter()
    sd.model("precomputed", sun=sun, n_wavelengths=2, orders=2, **small)
    print(f"kernel compile/load (first use): {time.perf_counter() - t0:.1f} s")

    repeats = 1 if quick else 2
    for key, label, kw in (("old_default", "old default (Bruneton sizes 32 x 128 x 32 x 8, 4 orders)",
                             OLD_DEFAULT), ("old_validated", "old validated settings", OLD_VALIDATED),
                            ("default", "this version's default", {})):
        if only and key not in only:
            continue
        t_bru, stages = _precompute(sd, sun, repeats, **kw)
        print(f"precompute, {label}, 20 wavelengths: {t_bru:.2f} s (best of {repeats}; "
              f"load {_load():.1f})")
        for name, text in STAGES.items():
            if name in stages:
                v = stages[name]
                print(f"    {text:34s} {sum(v):6.2f} s  [{', '.join(f'{x:.2f}' for x in v)}]")
        acc = sum(sum(v) for v in stages.values())
        print(f"    {'other (numpy: scattering density J, ...)':34s} {t_bru - acc:6.2f} s")
    if _has_cache(sd):
        with tempfile.TemporaryDirectory() as tmp:
            os.environ["SKYDOME_CACHE_DIR"] = tmp
            sd.model("precomputed", sun=sun)
            t0 = time.perf_counter()
            m = sd.model("precomputed", sun=sun)
            print(f"cached start-up at the default settings: {time.perf_counter() - t0:.2f} s "
                  f"(from cache: {m.from_cache}; load {_load():.1f})")
            del os.environ["SKYDOME_CACHE_DIR"]
    if only:
        return

    t_gen, _ = _precompute(sd, sun, repeats, orders=4, **GENSSKY_SIZES)
    print(f"precompute, genssky sizes (16 x 64 x 16 x 4), 20 wavelengths, 4 orders: "
          f"{t_gen:.2f} s (best of {repeats}; load {_load():.1f})")

    w, h = (512, 256) if quick else (2048, 1024)
    lon = (np.arange(w) + 0.5) / w * 360.0
    lat = 90.0 - (np.arange(h) + 0.5) / h * 180.0
    LA, LO = np.meshgrid(lat, lon, indexing="ij")
    dirs = direction_from_angles(LA, LO).reshape(-1, 3)
    m = sd.model("precomputed", sun=sun, n_wavelengths=20, **({"cache": False} if _has_cache(sd) else {}))
    wl = m.table_wavelengths_nm
    m.radiance(dirs[:1000], wl)
    best = np.inf
    for i in range(3):
        # a new sun position each time: includes the per-sun work (table slices)
        mi = m.with_sun(sd.Sun(elevation_deg=30.0 + 0.5 * (i + 1), azimuth_deg=180.0))
        t0 = time.perf_counter()
        L = mi.radiance(dirs, wl)
        best = min(best, time.perf_counter() - t0)
    print(f"render {w}x{h} equirect x 20 wavelengths (radiance, W m^-2 sr^-1 nm^-1): "
          f"{best:.3f} s = {dirs.shape[0] / best / 1e6:.2f} Mpixel/s (best of 3 sun positions; "
          f"target >= 2; "
          f"load {_load():.1f}); finite={np.isfinite(L).all()}, min={L.min():.3g}")
    del L

    if quick or not genssky:
        return
    g, note = _genssky_seconds(cores)
    if g is None:
        print(f"genssky: not timed ({note})")
        return
    print(f"genssky precomputation (its own sizes, -n {cores}): {g:.2f} s (load {_load():.1f}); "
          f"{note}")
    print(f"speed ratio at genssky's sizes, genssky / precomputed: {g / t_gen:.1f}x "
          f"(target >= 20x)")


if __name__ == "__main__":
    only = [a.split("=", 1)[1] for a in sys.argv if a.startswith("--only=")]
    main(quick="--quick" in sys.argv, genssky="--no-genssky" not in sys.argv, only=only)
