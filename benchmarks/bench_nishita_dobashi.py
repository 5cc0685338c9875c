"""Benchmark: nishita1996 (multiple scattering) and dobashi1995 (cosine series over a base).

Prints precompute time, rays/s and the error against the base model and against the
single_scattering reference (the brute-force reference of issue 4; dobashi1995 must be
at least 10x faster than it at under 1 % error). Run: python benchmarks/bench_nishita_dobashi.py
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


def best(f, repeat=3):
    f()
    return min(timed(f)[1] for _ in range(repeat))


# a larger batch on which single_scattering and dobashi1995 are both timed (the dobashi
# kernel runs serially below 131072 rays; the error statistics use DIRS)
N_BIG = 32768
DIRS_BIG = direction_from_angles(rng.uniform(2, 88, N_BIG), rng.uniform(0, 360, N_BIG))


def errors(a, b):
    e = np.abs(lum(a) / lum(b) - 1.0)
    return f"median {np.median(e) * 100:.2f} %, p95 {np.percentile(e, 95) * 100:.2f} %, max {e.max() * 100:.2f} %"


def main():
    # warm-up (numba compilation / cache load)
    sd.model("nishita1996", sun=SUN, orders=2, lattice_size=5, sky_directions=6).radiance(DIRS[:4], WL[:2])
    sd.model("single_scattering", sun=SUN).radiance(DIRS[:4], WL[:2])

    ss = sd.model("single_scattering", sun=SUN)
    L_ss = ss.radiance(DIRS, WL)
    t_ss = best(lambda: ss.radiance(DIRS, WL), 2)
    t_ss_big = best(lambda: ss.radiance(DIRS_BIG, WL), 2)
    ss_rate = N_BIG / t_ss_big
    print(f"single_scattering: {ss_rate:,.0f} rays/s on {N_BIG} rays, {N / t_ss:,.0f} rays/s "
          f"on {N} rays ({WL.size} wavelengths)")

    n1 = sd.model("nishita1996", sun=SUN, orders=1)
    L1, t1 = timed(lambda: n1.radiance(DIRS, WL))
    print(f"nishita1996 orders=1: {N / t1:,.0f} rays/s; vs single_scattering: {errors(L1, L_ss)}")

    n6 = sd.model("nishita1996", sun=SUN)
    _, tp = timed(lambda: n6.radiance(DIRS[:1], WL))
    L6, t6 = timed(lambda: n6.radiance(DIRS, WL))
    print(f"nishita1996 orders=6: precompute {tp:.2f} s, {N / t6:,.0f} rays/s; "
          f"total/single luminance mean {np.mean(lum(L6) / lum(L_ss)):.3f}")

    for base, kw, ref_L in [("preetham1999", {}, None),
                            ("single_scattering", {}, L_ss),
                            ("single_scattering", {"evaluation": "series"}, L_ss),
                            ("single_scattering", {"ring_interpolation": "linear",
                                                   "evaluation": "series"}, L_ss),
                            ("single_scattering", {"rings": 65}, L_ss),
                            ("nishita1996", {"orders": 6}, L6)]:
        # 19 sun altitudes (the default) and 33 rings unless given (the default is 65)
        m = sd.model("dobashi1995", sun=SUN, base=base, **{"sun_altitudes": 19, "rings": 33, **kw})
        _, tpre = timed(lambda: m.table(WL))
        L = m.radiance(DIRS, WL)
        t_small = best(lambda: m.radiance(DIRS, WL), 5)
        t_big = best(lambda: m.radiance(DIRS_BIG, WL), 5)
        t_ref = best(lambda: m._radiance_reference(DIRS, WL), 1)
        if ref_L is None:
            ref_L, tb = timed(lambda: sd.models.get_model_class(base)(sun=SUN).radiance(DIRS, WL))
        t = m.table(WL)
        rate = N_BIG / t_big
        label = ", ".join(f"{k}={v}" for k, v in kw.items() if k != "orders")
        print(f"dobashi1995(base={base}{', ' + label if label else ''}): precompute {tpre:.2f} s, "
              f"{rate:,.0f} rays/s on {N_BIG} rays ({rate / ss_rate:.0f}x single_scattering), "
              f"{N / t_small:,.0f} rays/s on {N} rays, numpy reference {N / t_ref:,.0f} rays/s; "
              f"memory {t['memory_bytes'] / 1024:.0f} KiB, "
              f"terms per ring max {t['terms'].max()} mean {t['terms'].mean():.1f}; "
              f"vs base: {errors(L, ref_L)}; vs single_scattering: {errors(L, L_ss)}")


if __name__ == "__main__":
    main()
