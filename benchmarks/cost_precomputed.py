"""Where the precomputation of ``precomputed`` spends its CPU time and memory.

Prints, for one precomputation (cache off, 20 table wavelengths, ``Atmosphere.earth``):
per stage (each numba kernel and the numpy matrix products of the scattering density) the
wall and CPU time (``time.process_time``: all threads of this process, so that figures
taken on a machine shared with other jobs stay comparable), the process's peak resident
memory (``ru_maxrss``), and per scattering order its share of the source strength of
orders 2..N (``_precompute.source_total``, the quantity whose ratio gives the geometric
remainder: how much orders >= 3 weigh).

The idle wall time on a 2-core machine is estimated as CPU time / 2 x (share of the time
in parallel kernels) + CPU time x (the rest); both figures are printed.

Run: python benchmarks/cost_precomputed.py [--aod A] [--settings key=value,...]
(e.g. ``--settings orders=4,sphere_samples=16``; ``None`` for an optional setting)
"""

from __future__ import annotations

import argparse
import contextlib
import os
import resource
import time

import numpy as np

STAGES = ("build_column_table", "single_scattering_table", "incident_radiance",
          "incident_radiance_rays", "indirect_irradiance", "indirect_irradiance_rays",
          "multiple_scattering_table", "table_from_coarse", "density_products",
          "add_density", "source_total")


def _parse(text):
    out = {}
    for item in [s for s in text.split(",") if s]:
        k, v = item.split("=", 1)
        if v == "None":
            out[k] = None
            continue
        for conv in (int, float):
            try:
                v = conv(v)
                break
            except ValueError:
                pass
        out[k] = v
    return out


@contextlib.contextmanager
def _instrument(rec, order_totals):
    """Wrap the kernels that the precomputation calls through their modules; record wall
    and CPU time per call, and each order's source strength (``_precompute.source_total``,
    summed over the wavelengths; the calls come batch by batch of wavelengths, orders 2..N
    within each)."""
    from skydome.models.simulated.precomputed import (_density, _irradiance, _multiple,
                                                      _precompute, _single)
    from skydome.transport import _kernels as K

    saved = []
    for mod in (_single, _density, _irradiance, _multiple, _precompute, K):
        for name in STAGES:
            if not hasattr(mod, name) or not callable(getattr(mod, name)):
                continue
            f = getattr(mod, name)
            saved.append((mod, name, f))

            def g(*a, _f=f, _n=name):
                w0, c0 = time.perf_counter(), time.process_time()
                r = _f(*a)
                rec.setdefault(_n, []).append((time.perf_counter() - w0,
                                               time.process_time() - c0))
                if _n == "source_total":
                    order_totals.append(float(np.sum(r)))
                return r

            setattr(mod, name, g)
    try:
        yield
    finally:
        for mod, name, f in saved:
            setattr(mod, name, f)


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--aod", type=float, default=0.2)
    ap.add_argument("--settings", default="")
    args = ap.parse_args(argv)
    import skydome as sd
    from skydome.atmosphere import Atmosphere

    kw = _parse(args.settings)
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    small = dict(scattering_r_size=4, scattering_mu_size=8, scattering_mu_s_size=4,
                 scattering_nu_size=2, irradiance_mu_s_size=4, irradiance_r_size=4,
                 transmittance_mu_size=8, transmittance_r_size=4)
    from skydome.models.simulated.precomputed import _precompute

    t0 = time.perf_counter()
    # one wavelength per batch, so that the kernels taking a batch's view of the
    # single-scattering table (not contiguous) are compiled here too
    budgets = {k: getattr(_precompute, k) for k in ("ORDER_BATCH_BYTES", "HIGH_ORDER_BATCH_BYTES")
               if hasattr(_precompute, k)}
    for k in budgets:
        setattr(_precompute, k, 1)
    sd.model("precomputed", sun=sun, n_wavelengths=2, orders=3, cache=False, **small)
    for k, v in budgets.items():
        setattr(_precompute, k, v)
    print(f"kernel compile/load: {time.perf_counter() - t0:.1f} s")
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    rec, totals = {}, []
    atm = Atmosphere.earth(aerosol_optical_depth=args.aod)
    load0 = os.getloadavg()[0]
    with _instrument(rec, totals):
        w0, c0 = time.perf_counter(), time.process_time()
        sd.model("precomputed", sun=sun, atmosphere=atm, n_wavelengths=20, cache=False, **kw)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    print(f"settings {kw or 'default'}, aod {args.aod:g}, 20 wavelengths; load average "
          f"{load0:.1f} -> {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"precompute: {wall:.1f} s wall, {cpu:.1f} s CPU; peak RSS {rss:.2f} GB "
          f"(before: {rss0:.2f} GB)")
    par = 0.0
    for name in STAGES:
        if name in rec:
            v = np.array(rec[name])
            par += v[:, 1].sum()
            print(f"  {name:28s} {v[:, 0].sum():7.1f} s wall {v[:, 1].sum():7.1f} s CPU "
                  f"({100 * v[:, 1].sum() / cpu:4.1f} %) x{len(v)} "
                  f"[{', '.join(f'{x:.1f}' for x in v[:, 1])}]")
    print(f"  {'other':28s} {'':7s}         {cpu - par:7.1f} s CPU")
    print(f"estimated idle wall on 2 cores: {par / 2 + (cpu - par):.1f} s")
    n_orders = int(kw.get("orders", 6)) - 1
    if totals and n_orders > 0:
        # each order's source strength, summed over the wavelength batches: order 2 batch by
        # batch, then orders 3..N per batch of the higher orders
        from skydome.models.simulated.precomputed import PrecomputedSky

        p = PrecomputedSky._validate_params(kw)
        n_sc = 2   # Atmosphere.earth: Rayleigh and aerosol
        n2 = -(-20 // _precompute.order_batch_size(p, 20, n_sc))
        tot = np.zeros(n_orders)
        tot[0] = sum(totals[:n2])
        if n_orders > 1:
            tot[1:] = np.array(totals[n2:]).reshape(-1, n_orders - 1).sum(axis=0)
        print("source strength per order (share of orders 2..N, without the remainder):")
        for i, t in enumerate(tot):
            print(f"  order {i + 2}: {100 * t / tot.sum():5.2f} %")

if __name__ == "__main__":
    main()
