"""Stage timeline of a new atmosphere, or of any warm command, as a command (issue 27,
item 2).

Runs ``skydome render --turbidity 4 --sun-elevation 30 --out DIR/x.png`` (or the command
line given after ``--``) in this process, through ``skydome.__main__.main``, with
``SKYDOME_CACHE_DIR`` a new empty folder (the table cache empty; numba's cache as the
environment has it, warm after the set-up), and prints one row per stage: when it started
and ended (wall, from the process's start), its wall time, the process's CPU time over it
(user + system of every thread, ``os.times``), their ratio (about 2 where both cores of a
2-core machine are busy, 1 where one thread works) and the thread it ran on. Stages are the
functions listed in ``STAGES`` (wrapped for the run); nested stages are indented; the time
between two outermost stages is printed as "(between)".

Run: ``python benchmarks/timeline_new_atmosphere.py [--keep | --warm] [-- ARGS...]``
(``--keep``: leave the table cache folder and print its path; ``--warm``: use the table
cache as the environment has it, for the timeline of a warm command, e.g.
``--warm -- export envmap --model hosek_wilkie2012 --turbidity 3 --size 4096x2048 --half
--out DIR/x.exr``).
"""

from __future__ import annotations

import importlib
import os
import shutil
import sys
import tempfile
import threading
import time

# (module, attribute path) of the stages, wrapped in the order given; a missing one is skipped
STAGES = [
    ("skydome.cli._kit", "_build_model"),
    ("skydome._numba_start", "start_numba_without_blas"),
    ("skydome.atmosphere", "Atmosphere.optical_properties"),
    ("skydome.models.simulated.precomputed._cache", "key"),
    ("skydome.models.simulated.precomputed._cache", "load"),
    ("skydome.models.simulated.precomputed._cache", "_read_table"),
    ("skydome.models.simulated.precomputed._cache", "_HalfTable.decode"),
    ("skydome.models.simulated.precomputed._tables", "Tables.scattering_density_rows"),
    ("skydome.models.simulated.precomputed._precompute", "precompute"),
    ("skydome.models.simulated.precomputed._precompute", "transmittance_columns"),
    ("skydome.models.simulated.precomputed._precompute", "single_scattering"),
    ("skydome.models.simulated.precomputed._precompute", "_DensityQuadrature.__init__"),
    ("skydome.models.simulated.precomputed._precompute", "second_order_batch"),
    ("skydome.models.simulated.precomputed._density", "incident_radiance"),
    ("skydome.models.simulated.precomputed._irradiance", "indirect_irradiance"),
    ("skydome.models.simulated.precomputed._precompute", "density_products"),
    ("skydome.models.simulated.precomputed._precompute", "source_total"),
    ("skydome.models.simulated.precomputed._precompute", "higher_orders_summed"),
    ("skydome.models.simulated.precomputed._density", "incident_radiance_rays"),
    ("skydome.models.simulated.precomputed._incident", "incident_rays"),
    ("skydome.models.simulated.precomputed._incident", "incident_radiance_stored"),
    ("skydome.models.simulated.precomputed._precompute", "irradiance_of_density"),
    ("skydome.models.simulated.precomputed._precompute", "_SourceFunctional.__init__"),
    ("skydome.models.simulated.precomputed._precompute", "_SourceFunctional.__call__"),
    ("skydome.models.simulated.precomputed._cache", "store"),
    ("skydome.models.simulated.precomputed._cache", "_quadratic_fit"),
    ("skydome.models.simulated.precomputed._cache", "_quadratic_eval"),
    ("skydome.models.simulated.precomputed._cache", "_encode_table"),
    ("skydome.models.simulated.precomputed._cache", "_write_entry"),
    ("skydome.models.simulated.precomputed._cache", "wait_for_writes"),
    ("skydome.models.simulated.precomputed._cache", "_evict"),
    ("skydome.imaging", "render"),
    ("skydome.models.simulated.precomputed", "PrecomputedSky._observer_slices"),
    ("skydome.models.simulated.precomputed._tables", "Tables.single_scattering_rows"),
    ("skydome.models.simulated.precomputed._multiple", "multiple_scattering_slice"),
    ("skydome.models.simulated.precomputed._render", "render_observer"),
    ("skydome.cli._kit", "_sky"),
    ("skydome.export.envmap", "render_envmap"),
    ("skydome.export.envmap", "MapProjection._latlong_rows"),
    ("skydome.models.analytic._kernels_analytic", "flat_directions"),
    ("skydome.models.analytic._kernels_analytic", "hosek_wilkie"),
    ("skydome.models.analytic._kernels_analytic", "preetham"),
    ("skydome.export.envmap", "_xyz_to_map_rgb"),
    ("skydome.export.sun", "sun_light_from"),
    ("skydome.export.envmap", "EnvironmentMap.write"),
    ("skydome.export.envmap", "_channel_planes"),
    ("skydome._io", "write_exr"),
    ("skydome.export.sun", "sun_json_writer"),
    ("skydome.imaging.image", "SkyImage.save"),
    ("skydome.imaging.image", "SkyImage._write_png"),
]

_T0 = time.perf_counter()
_C0 = sum(os.times()[:2])
_S0 = os.times()[1]
_EVENTS = []        # (start, end, cpu0, cpu1, depth, name, thread, system time)
_DEPTH = threading.local()


def _cpu():
    t = os.times()
    return t[0] + t[1]


def _sys():
    return os.times()[1]


def _wrap(name, f):
    def g(*a, **kw):
        d = getattr(_DEPTH, "d", 0)
        _DEPTH.d = d + 1
        w0, c0, s0 = time.perf_counter(), _cpu(), _sys()
        try:
            return f(*a, **kw)
        finally:
            _DEPTH.d = d
            _EVENTS.append((w0 - _T0, time.perf_counter() - _T0, c0, _cpu(), d, name,
                            threading.current_thread().name, _sys() - s0))
    g.__wrapped__ = f
    return g


def _install():
    for mod_name, attr in STAGES:
        try:
            mod = importlib.import_module(mod_name)
        except ImportError:
            continue
        owner, parts = mod, attr.split(".")
        for p in parts[:-1]:
            owner = getattr(owner, p, None)
        if owner is None or not hasattr(owner, parts[-1]):
            continue
        f = getattr(owner, parts[-1])
        setattr(owner, parts[-1], _wrap(attr, f))


def _print():
    ev = sorted(_EVENTS)
    print(f"{'stage':58s} {'start':>7s} {'end':>7s} {'wall':>7s} {'CPU':>7s} {'of it sys':>9s} "
          f"{'CPU/wall':>8s}  thread")
    last_end = None
    for w0, w1, c0, c1, d, name, th, sy in ev:
        if d == 0 and last_end is not None and w0 - last_end > 0.02 and th == "MainThread":
            print(f"{'(between)':58s} {last_end:7.2f} {w0:7.2f} {w0 - last_end:7.2f}")
        wall = w1 - w0
        print(f"{'  ' * d + name:58s} {w0:7.2f} {w1:7.2f} {wall:7.2f} {c1 - c0:7.2f} {sy:9.2f} "
              f"{(c1 - c0) / wall if wall > 0 else 0:8.2f}  {th}")
        if d == 0 and th == "MainThread":
            last_end = w1 if last_end is None else max(last_end, w1)
    wall, cpu = time.perf_counter() - _T0, _cpu() - _C0
    print(f"{'whole run (from this script start)':58s} {0:7.2f} {wall:7.2f} {wall:7.2f} "
          f"{cpu:7.2f} {_sys() - _S0:9.2f} {cpu / wall:8.2f}")
    print(f"load average {os.getloadavg()}")


def main():
    argv = sys.argv[1:]
    keep = "--keep" in argv
    warm = "--warm" in argv
    argv = [a for a in argv if a not in ("--keep", "--warm")]
    if "--" in argv:
        cmd = argv[argv.index("--") + 1:]
        out = None
    else:
        out = tempfile.mkdtemp(prefix="skydome-timeline-out-")
        cmd = ["render", "--turbidity", "4", "--sun-elevation", "30", "--out",
               os.path.join(out, "x.png")]
    cache = None if warm else tempfile.mkdtemp(prefix="skydome-timeline-cache-")
    if cache is not None:
        os.environ["SKYDOME_CACHE_DIR"] = cache
    os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")   # as skydome.__main__ sets it
    print(f"load average {os.getloadavg()}; command: skydome {' '.join(cmd)}", flush=True)
    t_imp = time.perf_counter()
    _install()       # imports the staged modules (their import time is in this row)
    _EVENTS.append((t_imp - _T0, time.perf_counter() - _T0, _C0, _cpu(), 0,
                    "(imports of the staged modules)", "MainThread", _sys() - _S0))
    sys.argv = ["skydome"] + cmd
    from skydome.__main__ import main as skydome_main

    code = 0
    try:
        skydome_main()
    except SystemExit as e:
        code = e.code or 0
    finally:
        _print()
        if cache is None:
            pass
        elif keep:
            print(f"table cache: {cache}")
        else:
            shutil.rmtree(cache, ignore_errors=True)
        if out is not None:
            shutil.rmtree(out, ignore_errors=True)
    sys.exit(code)


if __name__ == "__main__":
    main()
