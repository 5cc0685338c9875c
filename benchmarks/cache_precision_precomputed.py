"""What the table cache's storage precision costs the ``precomputed`` sky.

``grid OUT.npz``: the default model's radiance on its table wavelengths at 1,717 directions
(1,500 random over the sphere, 216 near the horizon, the zenith) x sun elevations -10..90
deg x observer altitudes 0-15 km, and its aerial perspective (in-scattered light at 1, 10,
50 km, sun 2, 30, 60 deg), with the tables from the cache (``$SKYDOME_CACHE_DIR``; the
first run fills it). Run it once with each code version (each its own cache folder).

``compare A.npz B.npz``: the largest and RMS relative change of B against A, in all, per
sun elevation and observer altitude, summed over the wavelengths, and of the aerial
perspective per case.

Figures: docs/performance.md, "A light table cache (cache format 12)".
"""

from __future__ import annotations

import resource
import sys
import time

import numpy as np

ELEVATIONS = [-10, -8, -6, -4, -2, 0, 2, 5, 10, 20, 30, 45, 60, 90]
ALTITUDES = [0.0, 1000.0, 5000.0, 10000.0, 15000.0]
AP_SUNS = (2, 30, 60)
AP_DISTANCES = (1e3, 1e4, 5e4)


def directions():
    rng = np.random.default_rng(3)
    v = rng.normal(size=(1500, 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    az = np.radians(np.arange(0, 360, 10))
    el = np.radians([-5, -1, 0.2, 1, 3, 6])
    hb = np.array([[np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)]
                   for e in el for a in az])
    return np.vstack([v, hb, [[0.0, 0.0, 1.0]]])


def grid(out):
    import skydome as sd

    t0 = time.perf_counter()
    sky0 = sd.model("precomputed", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=180.0))
    print(f"model {time.perf_counter() - t0:.1f} s, from_cache {sky0.from_cache}", flush=True)
    dirs = directions()
    rad = np.zeros((len(ELEVATIONS), len(ALTITUDES), dirs.shape[0], sky0.n_wavelengths))
    for i, e in enumerate(ELEVATIONS):
        for j, h in enumerate(ALTITUDES):
            s = sky0.with_sun(sd.Sun(elevation_deg=float(e), azimuth_deg=180.0),
                              observer_altitude_m=h)
            rad[i, j] = s.radiance_table(dirs)
    ap = []
    d = dirs[dirs[:, 2] > -0.3][:300]
    for e in AP_SUNS:
        s = sky0.with_sun(sd.Sun(elevation_deg=float(e), azimuth_deg=180.0))
        for dist in AP_DISTANCES:
            ap.append(s.aerial_perspective(d, dist, sky0.table_wavelengths_nm)[1])
    np.savez(out, rad=rad, dirs=dirs, els=ELEVATIONS, alts=ALTITUDES, ap=np.array(ap))
    print(f"done {time.perf_counter() - t0:.1f} s, peak "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6:.2f} GB")


def _stats(a, b):
    pos = a > 0
    r = b[pos] / a[pos] - 1.0
    return np.abs(r).max(), np.sqrt(np.mean(r * r))


def compare(fa, fb):
    a, b = np.load(fa), np.load(fb)
    ra, rb = a["rad"], b["rad"]
    print("sky radiance, every value: max %.2e RMS %.2e (%d values)"
          % (*_stats(ra, rb), int((ra > 0).sum())))
    for i, e in enumerate(a["els"]):
        per_alt = " ".join(f"{h / 1000:g} km {_stats(ra[i, j], rb[i, j])[0]:.1e}"
                           for j, h in enumerate(a["alts"]))
        print("sun %5.1f deg: max %.2e RMS %.2e; by altitude: %s"
              % (e, *_stats(ra[i], rb[i]), per_alt))
    print("summed over the wavelengths: max %.2e RMS %.2e" % _stats(ra.sum(-1), rb.sum(-1)))
    for i in range(a["ap"].shape[0]):
        print("aerial perspective, sun %g deg, %g km: max %.2e RMS %.2e"
              % (AP_SUNS[i // 3], AP_DISTANCES[i % 3] / 1e3, *_stats(a["ap"][i], b["ap"][i])))


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "grid":
        grid(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        compare(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)
