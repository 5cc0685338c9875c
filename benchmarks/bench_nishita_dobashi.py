"""Benchmark: nishita1996 (multiple scattering) and dobashi1995 (cosine series over a base).

Prints precompute time, rays/s and the error against the base model and against the
single_scattering reference. Run: python benchmarks/bench_nishita_dobashi.py
"""

import time

import numpy as np

import skydome as sd
from skydome.spectra import spectrum_to_xyz
from skydome.transport.geometry import direction_from_angles

WL = np.linspace(380.0, 780.0, 9)
SUN = sd.Sun(elevation_deg=37.0, azimuth_deg=150.0)
rng = np.random.default_rng(0)
N = 4096
DIRS = direction_from_angles(rng.uniform(2, 88, N), rng.uniform(0, 360, N))


def lum(L):
    return spectrum_to_xyz(L, WL)[..., 1]


def timed(f):
    t = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t


def errors(a, b):
    e = np.abs(lum(a) / lum(b) - 1.0)
    return f"median {np.median(e) * 100:.2f} %, p95 {np.percentile(e, 95) * 100:.2f} %, max {e.max() * 100:.2f} %"


def main():
    # warm-up (numba compilation / cache load)
    sd.model("nishita1996", sun=SUN, orders=2, lattice_size=5, sky_directions=6).radiance(DIRS[:4], WL[:2])
    sd.model("single_scattering", sun=SUN).radiance(DIRS[:4], WL[:2])

    ss = sd.model("single_scattering", sun=SUN)
    L_ss, t_ss = timed(lambda: ss.radiance(DIRS, WL))
    print(f"single_scattering: {N / t_ss:,.0f} rays/s ({WL.size} wavelengths)")

    n1 = sd.model("nishita1996", sun=SUN, orders=1)
    L1, t1 = timed(lambda: n1.radiance(DIRS, WL))
    print(f"nishita1996 orders=1: {N / t1:,.0f} rays/s; vs single_scattering: {errors(L1, L_ss)}")

    n6 = sd.model("nishita1996", sun=SUN)
    _, tp = timed(lambda: n6.radiance(DIRS[:1], WL))
    L6, t6 = timed(lambda: n6.radiance(DIRS, WL))
    print(f"nishita1996 orders=6: precompute {tp:.2f} s, {N / t6:,.0f} rays/s; "
          f"total/single luminance mean {np.mean(lum(L6) / lum(L_ss)):.3f}")

    for base, kw, ref_L in [("preetham1999", {}, None), ("single_scattering", {}, L_ss),
                            ("nishita1996", {"orders": 6}, L6)]:
        m = sd.model("dobashi1995", sun=SUN, base=base, sun_altitudes=19, **kw)
        _, tpre = timed(lambda: m.table(WL))
        L, te = timed(lambda: m.radiance(DIRS, WL))
        if ref_L is None:
            ref_L, tb = timed(lambda: sd.models.get_model_class(base)(sun=SUN).radiance(DIRS, WL))
        t = m.table(WL)
        print(f"dobashi1995(base={base}): precompute {tpre:.2f} s, {N / te:,.0f} rays/s "
              f"({t_ss / te:.2f}x single_scattering), memory {t['memory_bytes'] / 1024:.0f} KiB, "
              f"terms per ring max {t['terms'].max()} mean {t['terms'].mean():.1f}; "
              f"vs base: {errors(L, ref_L)}; vs single_scattering: {errors(L, L_ss)}")


if __name__ == "__main__":
    main()
