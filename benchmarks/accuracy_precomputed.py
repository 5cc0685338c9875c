"""Accuracy and cost of ``precomputed`` table settings against the Monte Carlo reference.

For a few skies (sun elevation, aerosol optical depth at 550 nm, ``Atmosphere.earth``) the
``montecarlo`` model gives the reference radiance on 20-deg rings of upper-hemisphere
directions (``validate_multiple_scattering.directions(20)``) at 6 wavelengths over
400-700 nm; the references are kept in an ``.npz`` file (``--refs``) so that several
settings can be compared against the same paths. For each named setting the script prints
the precomputation wall time and the luminance RMS / max relative error per sky (solid-angle
weighted, as in ``validate_multiple_scattering.py``) and the Monte Carlo noise floor.

Run: python benchmarks/accuracy_precomputed.py [--refs FILE] [--samples N] [--settings a,b]
[--skies 0,2] [--against full_orders] [--table-wavelengths] [--save FILE]
(``--save``: every setting's radiance per sky in an ``.npz`` file, to compare two versions
of the code on the same directions.)
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from validate_multiple_scattering import compare, directions  # noqa: E402

SKIES = [(60.0, 0.5), (30.0, 0.2), (10.0, 0.5), (2.0, 0.2), (60.0, 0.05), (-4.0, 0.2),
         (-6.0, 0.2)]
# the previous default (Bruneton's sizes, 4 orders), the previous validated settings, and
# candidates for the new default
SETTINGS = {
    "old_default": dict(orders=4, remaining_orders="none", sphere_samples=16,
                        scattering_nu_size=8, scattering_mu_s_size=32, integration_samples=20),
    "old_validated": dict(orders=6, remaining_orders="geometric", sphere_samples=32,
                          scattering_nu_size=16, scattering_mu_s_size=64, density_mu_s_size=64,
                          integration_samples=20),
    "default": {},
    # the orders >= 3 at every table wavelength (the default computes them at a subset)
    "all_wavelengths": dict(high_order_wavelengths=None),
    # the default with every order on the full table and sphere (what the coarser grids of
    # orders >= 3 give up)
    "full_orders": dict(order_table_divisor=1, high_order_sphere_samples=32),
    # one of the two at a time
    "grid2_sphere32": dict(order_table_divisor=2, high_order_sphere_samples=32),
    "grid1_sphere16": dict(order_table_divisor=1, high_order_sphere_samples=16),
    # the default with half the mu nodes (the mu axis on the angle from the horizon)
    "mu64": dict(scattering_mu_size=64),
    # the computed orders alone (what the geometric remainder adds)
    "no_remainder": dict(remaining_orders="none"),
}


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--refs", default=os.path.join(tempfile.gettempdir(), "skydome_mc_refs.npz"))
    ap.add_argument("--samples", type=int, default=4000)
    ap.add_argument("--twilight-samples", type=int, default=100_000)
    ap.add_argument("--settings", default=",".join(SETTINGS))
    ap.add_argument("--skies", default="", help="indices into SKIES, e.g. 0,1 (default all)")
    ap.add_argument("--against", default="", help="also print each setting's luminance RMS "
                    "against this setting's radiance (the first in --settings; no MC noise)")
    ap.add_argument("--table-wavelengths", action="store_true",
                    help="tables on the 6 compared wavelengths instead of 20 over 380-780 nm")
    ap.add_argument("--save", default="", help="write every radiance to this .npz file")
    args = ap.parse_args(argv)

    import skydome as sd
    from skydome.atmosphere import Atmosphere

    wl = np.linspace(400.0, 700.0, 6)
    dirs, w = directions(20.0)
    skies = [SKIES[int(i)] for i in args.skies.split(",")] if args.skies else SKIES
    refs = dict(np.load(args.refs)) if os.path.exists(args.refs) else {}
    for elev, aod in skies:
        k = f"{elev:g}_{aod:g}"
        if k in refs:
            continue
        n = args.twilight_samples if elev < 0 else args.samples
        t0 = time.perf_counter()
        mc = sd.model("montecarlo", sun=sd.Sun(elevation_deg=elev, azimuth_deg=180.0),
                      atmosphere=Atmosphere.earth(aerosol_optical_depth=aod), samples=n, seed=1)
        refs[k], refs[k + "_err"] = mc.radiance_with_error(dirs, wl)
        np.savez(args.refs, **refs)
        print(f"reference sun {elev:g} aod {aod:g}: {n} paths, {time.perf_counter() - t0:.0f} s",
              flush=True)
    print(f"load average {os.getloadavg()[0]:.1f} (shared machine)")
    got = {}
    table_wl = {"table_wavelengths_nm": wl} if args.table_wavelengths else {}
    for name in [n for n in args.settings.split(",") if n]:
        kw = SETTINGS[name]
        print(f"{name}: {kw}", flush=True)
        for aod in sorted({a for _, a in skies}):
            t0 = time.perf_counter()
            m = sd.model("precomputed", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=180.0),
                         atmosphere=Atmosphere.earth(aerosol_optical_depth=aod), cache=False,
                         **table_wl, **kw)
            print(f"  aod {aod:g}: precompute {time.perf_counter() - t0:.1f} s", flush=True)
            for elev in [e for e, a in skies if a == aod]:
                k = f"{elev:g}_{aod:g}"
                sky = m.with_sun(sd.Sun(elevation_deg=elev, azimuth_deg=180.0))
                L = got[name, k] = sky.radiance(dirs, wl)
                c = compare(refs[k], refs[k + "_err"], L, wl, w)
                extra = ""
                if args.against and (args.against, k) in got and name != args.against:
                    a = compare(got[args.against, k], np.zeros_like(L), L, wl, w)
                    extra = (f"; against {args.against}: RMS {100 * a['rms']:.2f} %, max "
                             f"{100 * a['max']:.2f} %")
                print(f"    sun {elev:5.1f}: lum RMS {100 * c['rms']:5.2f} %  max "
                      f"{100 * c['max']:5.2f} %  (MC noise {100 * c['noise']:.2f} %){extra}",
                      flush=True)
                if args.save:
                    np.savez(args.save, **{f"{n}_{kk}": v for (n, kk), v in got.items()})


if __name__ == "__main__":
    main()
