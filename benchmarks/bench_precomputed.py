"""Benchmark of the ``precomputed`` model: table precomputation at Bruneton's (2017) default
sizes (transmittance 256 x 64, scattering 32 x 128 x 32 x 8, irradiance 64 x 16) with 20
wavelengths and 4 orders, render throughput for a 2048 x 1024 equirectangular set of
directions x 20 wavelengths, and the ratio to Radiance's ``genssky`` precomputation (its
default sizes: 20 wavelengths, scattering 16 x 64 x 16 x 4, 4 orders) when pyradiance ships it.

Run: python benchmarks/bench_precomputed.py [--quick]
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

import numpy as np


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


def main(quick: bool = False) -> None:
    import skydome as sd
    from skydome.transport.geometry import direction_from_angles

    print(f"cpu cores: {os.cpu_count()}")
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    # warm-up: compile/load the numba kernels on a tiny table set
    small = dict(scattering_r_size=4, scattering_mu_size=8, scattering_mu_s_size=4,
                 scattering_nu_size=2, irradiance_mu_s_size=4, irradiance_r_size=4,
                 transmittance_mu_size=8, transmittance_r_size=4)
    t0 = time.perf_counter()
    sd.model("precomputed", sun=sun, n_wavelengths=2, orders=2, **small)
    print(f"kernel compile/load (first use): {time.perf_counter() - t0:.1f} s")

    t0 = time.perf_counter()
    m = sd.model("precomputed", sun=sun, n_wavelengths=20, orders=4)
    t_pre = time.perf_counter() - t0
    print(f"precompute, Bruneton default sizes, 20 wavelengths, 4 orders: {t_pre:.2f} s")

    w, h = (512, 256) if quick else (2048, 1024)
    lon = (np.arange(w) + 0.5) / w * 360.0
    lat = 90.0 - (np.arange(h) + 0.5) / h * 180.0
    LA, LO = np.meshgrid(lat, lon, indexing="ij")
    dirs = direction_from_angles(LA, LO).reshape(-1, 3)
    m.radiance_table(dirs[:1000])
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        L = m.radiance_table(dirs)
        best = min(best, time.perf_counter() - t0)
    print(f"render {w}x{h} directions x 20 wavelengths (radiance_table): {best:.3f} s = "
          f"{dirs.shape[0] / best / 1e6:.2f} Mpixel/s")
    wl = m.table_wavelengths_nm
    t0 = time.perf_counter()
    L = m.radiance(dirs, wl)
    dt = time.perf_counter() - t0
    print(f"render {w}x{h} x 20 wavelengths (radiance, W m^-2 sr^-1 nm^-1): {dt:.3f} s = "
          f"{dirs.shape[0] / dt / 1e6:.2f} Mpixel/s; finite={np.isfinite(L).all()}, "
          f"min={L.min():.3g}")
    del L

    if quick:
        return
    g, note = _genssky_seconds(os.cpu_count() or 1)
    if g is None:
        print(f"genssky: not timed ({note})")
    else:
        print(f"genssky precomputation (default sizes, -n {os.cpu_count()}): {g:.2f} s; {note}")
        print(f"ratio precomputed / genssky: {t_pre / g:.2f}")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
