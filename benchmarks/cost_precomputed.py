"""Where the precomputation of ``precomputed`` spends its CPU time and memory.

Prints, for one precomputation (cache off, 20 table wavelengths, ``Atmosphere.earth``):
per stage (each numba kernel and the numpy matrix products of the scattering density) the
wall and CPU time (``time.process_time``: all threads of this process, so that figures
taken on a machine shared with other jobs stay comparable), the process's peak resident
memory (``ru_maxrss``), and per scattering order its share of the source strength of
orders 2..N (``_precompute.source_total``, or on the default's summed path
``_precompute._SourceFunctional`` for the orders >= 3: the quantity whose ratio gives the
geometric remainder, how much orders >= 3 weigh).

The idle wall time on a 2-core machine is estimated as CPU time / 2 x (share of the time
in parallel kernels) + CPU time x (the rest); both figures are printed.

Then, separately, the stored 4-D table of orders 2..N, which the precomputation leaves to
its first read: the first aerial-perspective call of the same model (64 x 32 directions
at 5 km), which builds it in memory (cache off): wall, CPU and the peak resident memory
during the call (``VmHWM`` of /proc/self/status, reset to the current resident size
before the call: what the build adds on top of the tables already held; the process's
peak so far is printed too).

``--cache``: the same in fresh processes with the cache on (a temporary cache folder):
(1) precompute, write the entry, first aerial perspective (the table written slab by slab
into the entry); (2) a later process with a cache hit: the first aerial perspective reads
the table's file; (3) the same entry without the table's file: a later process builds it
from the memory-mapped tables. Each prints its figures.

Run: python benchmarks/cost_precomputed.py [--aod A] [--settings key=value,...] [--cache]
(e.g. ``--settings orders=4,sphere_samples=16``; ``None`` for an optional setting)
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

STAGES = ("build_column_table", "single_scattering_table", "incident_radiance",
          "incident_radiance_rays", "indirect_irradiance", "indirect_irradiance_rays",
          "multiple_scattering_table", "table_from_coarse", "density_products",
          "add_density", "source_total", "incident_rays", "incident_radiance_stored")


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
    and CPU time per call, and each order's source strength (``_precompute.source_total`` or
    ``_SourceFunctional``, summed over the wavelengths; the calls come batch by batch of wavelengths, orders 2..N
    within each)."""
    from skydome.models.simulated.precomputed import (_density, _incident, _irradiance,
                                                      _multiple, _precompute, _single)
    from skydome.transport import _kernels as K

    saved = []
    for mod in (_single, _density, _incident, _irradiance, _multiple, _precompute, K):
        for name in STAGES:
            if not hasattr(mod, name) or not callable(getattr(mod, name)):
                continue
            f = getattr(mod, name)
            saved.append((mod, name, f))

            def g(*a, _f=f, _n=name, **kw):
                w0, c0 = time.perf_counter(), time.process_time()
                r = _f(*a, **kw)
                rec.setdefault(_n, []).append((time.perf_counter() - w0,
                                               time.process_time() - c0))
                if _n == "source_total":
                    order_totals.append((float(np.sum(r)), np.size(r)))
                return r

            setattr(mod, name, g)
    # the summed path takes the orders >= 3's source strengths from their incident radiance
    # (_precompute._SourceFunctional), not from source_total
    call = _precompute._SourceFunctional.__call__

    def strength(self, L, _f=call):
        r = _f(self, L)
        order_totals.append((float(np.sum(r)), np.size(r)))
        return r

    _precompute._SourceFunctional.__call__ = strength
    try:
        yield
    finally:
        for mod, name, f in saved:
            setattr(mod, name, f)
        _precompute._SourceFunctional.__call__ = call


def _status_kb(field):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    return 0


def _reset_peak():
    """Reset the process's peak resident size (VmHWM) to its current one (Linux >= 4.0)."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


def _ap_directions():
    from skydome.transport.geometry import direction_from_angles

    el, az = np.meshgrid(np.linspace(-10.0, 60.0, 32), np.linspace(0.0, 360.0, 64, endpoint=False),
                         indexing="ij")
    return direction_from_angles(el.ravel(), az.ravel())


def first_aerial_perspective(model):
    """The model's first aerial-perspective call (the stored table's first read): (wall s,
    CPU s, resident GB before, peak resident GB during) and whether it built the table."""
    t = model._t
    built_before = t.has_multiple_scattering
    rss_before = _status_kb("VmRSS") / 1e6
    _reset_peak()
    w0, c0 = time.perf_counter(), time.process_time()
    model.aerial_perspective(_ap_directions(), 5e3, [450.0, 550.0, 650.0])
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    return dict(wall=wall, cpu=cpu, rss_before=rss_before, peak=_status_kb("VmHWM") / 1e6,
                built=not built_before)


def _print_first_use(label, r):
    print(f"{label}: {r['wall']:.1f} s wall, {r['cpu']:.1f} s CPU; resident {r['rss_before']:.2f} GB "
          f"before, peak {r['peak']:.2f} GB during the call")


def _warm(sd, sun, small):
    """Compile or load every kernel on a tiny table set (the precomputation's and the
    stored table's, aerial perspective's)."""
    from skydome.models.simulated.precomputed import _precompute

    budgets = {k: getattr(_precompute, k) for k in ("ORDER_BATCH_BYTES", "HIGH_ORDER_BATCH_BYTES")
               if hasattr(_precompute, k)}
    for k in budgets:
        setattr(_precompute, k, 1)
    m = sd.model("precomputed", sun=sun, n_wavelengths=2, orders=3, cache=False, **small)
    for k, v in budgets.items():
        setattr(_precompute, k, v)
    m.aerial_perspective(_ap_directions()[:4], 5e3, [450.0, 550.0])
    m.radiance(_ap_directions()[:4], [450.0, 550.0])


SMALL = dict(scattering_r_size=4, scattering_mu_size=8, scattering_mu_s_size=4,
             scattering_nu_size=2, irradiance_mu_s_size=4, irradiance_r_size=4,
             transmittance_mu_size=8, transmittance_r_size=4)


def child(kw, aod):
    """One fresh process of ``--cache`` (the cache folder from $SKYDOME_CACHE_DIR): prints a
    JSON line of its figures."""
    import skydome as sd
    from skydome.atmosphere import Atmosphere

    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    _warm(sd, sun, SMALL)
    # peaks from VmHWM (this process's own: ru_maxrss would carry the parent's over the exec)
    out = {"rss_warm": _status_kb("VmHWM") / 1e6}
    w0, c0 = time.perf_counter(), time.process_time()
    m = sd.model("precomputed", sun=sun, atmosphere=Atmosphere.earth(aerosol_optical_depth=aod),
                 n_wavelengths=20, **kw)
    out.update(model_wall=time.perf_counter() - w0, model_cpu=time.process_time() - c0,
               from_cache=m.from_cache, peak_model=_status_kb("VmHWM") / 1e6,
               table_cached=m._t.has_multiple_scattering)
    r = first_aerial_perspective(m)
    out.update(first_ap=r, peak_process=max(out["peak_model"], r["peak"]))
    print("RESULT " + json.dumps(out))


def run_cache_scenarios(args):
    from skydome.models.simulated.precomputed import _cache

    with tempfile.TemporaryDirectory() as folder:
        env = dict(os.environ, SKYDOME_CACHE_DIR=folder)
        for stage, label in (("store", "(1) precompute + store, first aerial perspective"),
                             ("hit", "(2) later process, cache hit with the table's file"),
                             ("rebuild", "(3) later process, cache hit without the table's file")):
            if stage == "rebuild":
                for d in os.listdir(folder):
                    f = os.path.join(folder, d, _cache._STORED + ".npy")
                    if os.path.exists(f):
                        os.remove(f)
            res = subprocess.run([sys.executable, __file__, "--child", stage, "--aod",
                                  str(args.aod), "--settings", args.settings], env=env,
                                 capture_output=True, text=True, check=True)
            line = next(x for x in res.stdout.splitlines() if x.startswith("RESULT "))
            o = json.loads(line[7:])
            print(f"{label}:")
            print(f"  model: {o['model_wall']:.1f} s wall, {o['model_cpu']:.1f} s CPU, from cache "
                  f"{o['from_cache']}, stored table already there {o['table_cached']}; peak "
                  f"{o['peak_model']:.2f} GB (after the kernels: {o['rss_warm']:.2f} GB)")
            _print_first_use(f"  first aerial perspective (built the table: {o['first_ap']['built']})",
                             o["first_ap"])
            print(f"  process peak (VmHWM): {o['peak_process']:.2f} GB")


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--aod", type=float, default=0.2)
    ap.add_argument("--settings", default="")
    ap.add_argument("--cache", action="store_true")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        return child(_parse(args.settings), args.aod)
    import skydome as sd
    from skydome.atmosphere import Atmosphere

    kw = _parse(args.settings)
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    from skydome.models.simulated.precomputed import _precompute

    t0 = time.perf_counter()
    # one wavelength per batch, so that the kernels taking a batch's view of the
    # single-scattering table (not contiguous) are compiled here too
    _warm(sd, sun, SMALL)
    print(f"kernel compile/load: {time.perf_counter() - t0:.1f} s")
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    rec, totals = {}, []
    atm = Atmosphere.earth(aerosol_optical_depth=args.aod)
    load0 = os.getloadavg()[0]
    with _instrument(rec, totals):
        w0, c0 = time.perf_counter(), time.process_time()
        model = sd.model("precomputed", sun=sun, atmosphere=atm, n_wavelengths=20, cache=False,
                         **kw)
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
        # each order's source strength per computed wavelength (the mean over the wavelength
        # batches: order 2 batch by batch at every table wavelength, then orders 3..N per
        # batch of the higher orders, at the wavelengths they are computed at: with
        # high_order_wavelengths, the subset of _spectral.subset_indices)
        from skydome.models.simulated.precomputed import PrecomputedSky

        p = PrecomputedSky._validate_params(kw)
        n_sc = 2   # Atmosphere.earth: Rayleigh and aerosol
        n2 = -(-20 // _precompute.order_batch_size(p, 20, n_sc))
        tot = np.zeros(n_orders)
        t2 = np.array(totals[:n2])
        tot[0] = t2[:, 0].sum() / t2[:, 1].sum()
        if n_orders > 1:
            th = np.array(totals[n2:]).reshape(-1, n_orders - 1, 2)
            tot[1:] = th[..., 0].sum(axis=0) / th[..., 1].sum(axis=0)

        print("source strength per order, mean over the wavelengths each is computed at "
              "(share of orders 2..N, without the remainder):")
        for i, t in enumerate(tot):
            print(f"  order {i + 2}: {100 * t / tot.sum():5.2f} %")
    if hasattr(model._t, "has_multiple_scattering"):
        print("the stored table of orders 2..N, first use (cache off: built in memory):")
        peak_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
        rec.clear()
        with _instrument(rec, []):
            r = first_aerial_perspective(model)
        _print_first_use("  first aerial perspective", r)
        for name in ("multiple_scattering_table", "table_from_coarse"):
            if name in rec:
                v = np.array(rec[name])
                print(f"  {name:28s} {v[:, 0].sum():7.1f} s wall {v[:, 1].sum():7.1f} s CPU "
                      f"x{len(v)}")
        print(f"  process peak: {max(peak_before, r['peak']):.2f} GB")
    if args.cache:
        run_cache_scenarios(args)

if __name__ == "__main__":
    main()
