"""Benchmark (issue 4): the table-driven models against the brute-force reference.

The brute-force reference is ``single_scattering`` with ``light_exact=True``: every light
path towards the sun is integrated directly at every node of every view ray (no table).
Each table-driven model is timed on the same machine in the same run and its error
measured against the brute-force result for the same rays:

* ``nishita1996`` at order 1 (the cylindrical optical-depth table, [NDKY96] sec. 3.2), and
  with all its orders (no brute-force counterpart at the same physics: rate only);
* ``dobashi1995`` over ``single_scattering`` (cosine series per ring), 33 and 65 rings;
* ``nishita1993`` from geostationary altitude (spheres x cylinders table) against the same
  model with ``light_exact=True`` (the disc of the earth, rays that hit the atmosphere);
* ``dobashi2002`` (look-up tables of the in-scattering integrals along view rays) against
  ``inscatter_direct`` (the same integrals by direct quadrature, 4000 nodes per ray).

Errors are relative, in luminance (CIE Y) for the sky models and per wavelength for the
dobashi2002 integrals. Run:
    .venv/bin/python benchmarks/bench_table_models.py [--write]
``--write`` replaces the ``table_models`` block of docs/performance.md.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_single_scattering import machine, write_section  # noqa: E402

import skydome as sd  # noqa: E402
from skydome.spectra import spectrum_to_xyz  # noqa: E402
from skydome.transport.geometry import direction_from_angles  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
WL = np.linspace(380.0, 780.0, 9)
SUN = sd.Sun(elevation_deg=37.0, azimuth_deg=150.0)


def lum(L):
    return spectrum_to_xyz(L, WL)[..., 1]


def rate(f, n, repeat=3):
    """Best-of-``repeat`` rays per second of f() over n rays (after one warm-up call)."""
    f()
    best = min(_timed(f) for _ in range(repeat))
    return n / best


def _timed(f):
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


def err_stats(a, b):
    e = np.abs(a / b - 1.0)
    return float(np.median(e)), float(np.percentile(e, 95)), float(e.max())


def sky_rows(n_fast, n_exact):
    rng = np.random.default_rng(0)
    dirs = direction_from_angles(rng.uniform(2, 88, n_fast), rng.uniform(0, 360, n_fast))
    sub = dirs[:n_exact]
    exact = sd.model("single_scattering", sun=SUN, light_exact=True)
    L_ref = exact.radiance(sub, WL)
    r_exact = rate(lambda: exact.radiance(sub, WL), n_exact, repeat=2)
    rows = [("single_scattering, `light_exact=True` (brute force)", "none", r_exact, 1.0, None)]
    ss = sd.model("single_scattering", sun=SUN)
    rows.append(("single_scattering (column table)", "0.00 s", rate(lambda: ss.radiance(dirs, WL), n_fast),
                 None, err_stats(lum(ss.radiance(sub, WL)), lum(L_ref))))
    t0 = time.perf_counter()
    n1 = sd.model("nishita1996", sun=SUN, orders=1)
    n1.radiance(dirs[:4], WL)
    pre = time.perf_counter() - t0
    rows.append(("nishita1996, order 1 (cylindrical table)", f"{pre:.2f} s",
                 rate(lambda: n1.radiance(dirs, WL), n_fast), None,
                 err_stats(lum(n1.radiance(sub, WL)), lum(L_ref))))
    for rings in (33, 65):
        t0 = time.perf_counter()
        db = sd.model("dobashi1995", sun=SUN, base="single_scattering", rings=rings)
        db.radiance(dirs[:4], WL)
        pre = time.perf_counter() - t0
        rows.append((f"dobashi1995 over single_scattering, {rings} rings", f"{pre:.2f} s",
                     rate(lambda: db.radiance(dirs, WL), n_fast), None,
                     err_stats(lum(db.radiance(sub, WL)), lum(L_ref))))
    t0 = time.perf_counter()
    n6 = sd.model("nishita1996", sun=SUN)
    n6.radiance(dirs[:4], WL)
    pre = time.perf_counter() - t0
    rows.append(("nishita1996, 6 orders (no brute-force counterpart)", f"{pre:.1f} s",
                 rate(lambda: n6.radiance(dirs[:4096], WL), 4096, repeat=2), None, None))
    return rows, r_exact


def earth_rows(n_fast, n_exact):
    """nishita1993 from 36 000 km: rays through the atmosphere's disc (the sunlit half)."""
    kw = dict(sun=sd.Sun(elevation_deg=50.0, azimuth_deg=90.0), camera_altitude_m=36e6, sun_disc=False)
    R, Rt = 6.36e6, 6.42e6
    h = R + 36e6
    half = np.arcsin(Rt / h)                    # angular radius of the atmosphere's disc
    rng = np.random.default_rng(1)
    ang = half * np.sqrt(rng.uniform(0, 1, n_fast))
    az = rng.uniform(0, 2 * np.pi, n_fast)
    dirs = np.stack([np.sin(ang) * np.cos(az), np.sin(ang) * np.sin(az), -np.cos(ang)], -1)
    sub = dirs[:n_exact]
    t0 = time.perf_counter()
    tab = sd.model("nishita1993", **kw)
    tab.radiance(dirs[:4], WL)
    pre = time.perf_counter() - t0
    exact = sd.model("nishita1993", light_exact=True, **kw)
    L_ref = lum(exact.radiance(sub, WL))
    L_tab = lum(tab.radiance(sub, WL))
    bright = L_ref > 0.05 * L_ref.max()         # the lit disc (the night side is 0)
    r_exact = rate(lambda: exact.radiance(sub, WL), n_exact, repeat=2)
    return [("nishita1993, `light_exact=True` (brute force)", "none", r_exact, 1.0, None),
            ("nishita1993 (spheres x cylinders table)", f"{pre:.2f} s",
             rate(lambda: tab.radiance(dirs, WL), n_fast), None,
             err_stats(L_tab[bright], L_ref[bright]))], r_exact


def dobashi2002_rows(n_fast, n_exact):
    from skydome.effects.dobashi2002 import build_tables, inscatter_direct

    atm = sd.Atmosphere.earth(turbidity=2.5)
    sun = sd.Sun(elevation_deg=10.0, azimuth_deg=150.0)
    t0 = time.perf_counter()
    tabs = build_tables(atm, WL, sun, 300.0, 40e3, (-0.3, 0.3))   # the camera's range of mu
    pre = time.perf_counter() - t0
    rng = np.random.default_rng(2)
    t = rng.uniform(200.0, 40e3, 4 * n_fast)
    mu = rng.uniform(-0.3, 0.3, 4 * n_fast)
    above = mu * t + t * t / (2 * 6360e3) + 300.0 > 0.0          # points above the ground
    t, mu = t[above][:n_fast], mu[above][:n_fast]
    r_tab = rate(lambda: tabs.inscatter_integrals(t, mu), n_fast)
    beta_s = atm.optical_properties(WL).scattering                # (nc, nl)
    ref = np.stack([(beta_s * inscatter_direct(atm, WL, sun, 300.0, t[i], mu[i])[0]).sum(0)
                    for i in range(n_exact)])
    r_exact = rate(lambda: [inscatter_direct(atm, WL, sun, 300.0, t[i], mu[i]) for i in range(n_exact)],
                   n_exact, repeat=1)
    got = (beta_s * tabs.inscatter_integrals(t[:n_exact], mu[:n_exact])).sum(1)
    return [("dobashi2002 integrals by direct quadrature (brute force)", "none", r_exact, 1.0, None),
            ("dobashi2002 look-up tables", f"{pre:.2f} s", r_tab, None,
             err_stats(got, ref))], r_exact


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--write", action="store_true", help="rewrite the block in docs/performance.md")
    ap.add_argument("--quick", action="store_true", help="small ray counts (smoke run)")
    args = ap.parse_args(argv)
    n_fast, n_exact = (4096, 256) if args.quick else (32768, 2048)
    lines = ["| model | precompute | rays/s | vs brute force | error vs brute force (median / p95 / max) |",
             "|---|---|---|---|---|"]
    for rows, r_ref in (sky_rows(n_fast, n_exact), earth_rows(n_fast, n_exact),
                        dobashi2002_rows(n_fast, min(n_exact, 200))):
        for name, pre, r, ratio, err in rows:
            ratio = r / r_ref if ratio is None else ratio
            e = "reference" if err is None and ratio == 1.0 else (
                "n/a" if err is None else f"{err[0] * 100:.3f} % / {err[1] * 100:.3f} % / {err[2] * 100:.3f} %")
            line = f"| {name} | {pre} | {r:,.0f} | {ratio:.1f}x | {e} |"
            lines.append(line)
            print(line, flush=True)
    text = "\n".join([
        f"Sky from the ground: sun 37 deg, {WL.size} wavelengths, random directions 2-88 deg "
        f"elevation ({n_fast} rays timed, {n_exact} for the brute force and the errors, in "
        "luminance). nishita1993: camera at 36 000 km, rays through the atmosphere's disc, errors "
        "on the lit disc. dobashi2002: in-scattering integrals (sum over constituents of beta_s J) "
        "for random points above the ground (distance <= 40 km, |mu| <= 0.3, camera at 300 m, "
        "sun 10 deg), errors per wavelength. Best of 3 runs.", "",
        *lines, "", f"Machine: {machine()}."])
    if args.write:
        write_section(ROOT / "docs" / "performance.md", "table_models", text)
        print("wrote docs/performance.md")


if __name__ == "__main__":
    main()
