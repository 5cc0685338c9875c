"""Generate the data set of the ``fitted`` sky model from the ``precomputed`` reference.

    python tools/fitted_dataset.py OUT [--grid fit|heldout|fit-v5|heldout-v5|fit-v4|
                                        heldout-v4|fit-v3|heldout-v3|fit-v2|fit-v1|
                                        heldout-v1|small]
        [--scheduler ADDR] [--workers N] [--twilight-reference] [--max-aod A]
        [--atmospheres A:B,...] [--wavelength-step NM] [--gas-bands | --with-gas-bands]
        [--altitudes M,...] [--elevations DEG,...] [--wavelengths NM,...]

One chunk per atmosphere (aerosol optical depth at 550 nm x ground albedo), each holding
every (sun elevation, observer altitude) node of the grid: the reference's tables hold every
sun zenith and altitude, so one precomputation serves a whole chunk
(skydome/models/fitted/_dataset.py says what a chunk holds). The chunks run on Dask
(``skydome.distributed``: a local cluster of ``--workers`` processes by default,
``--scheduler tcp://HOST:PORT`` for a cluster whose workers see OUT); a rerun skips the
chunks already in OUT (verified by their hash), so an interrupted run resumes. A progress
bar shows the chunks; at the end the run prints its cost (wall time, chunks computed).

Grids (skydome/models/fitted/_grid.py):

* ``fit``: the fitting nodes (13 AOD x 3 albedo = 39 atmospheres, 28 sun elevations
  -12..90 deg, 14 altitudes 0..15 km);
* ``heldout``: the held-out grid (12 atmospheres, their AODs and albedos off the nodes, 13
  sun elevations -11.5..70 deg off the nodes and 5 altitudes of which only 0 and 15 km
  are fitting nodes), every view direction at the centre of a cell of the view grid (the
  farthest from its nodes);
* ``fit-v5``, ``heldout-v5``: the fifth file's grids (``fit`` without the AOD node
  0.00625; its held-out AOD 0.006 for the present 0.003 and 0.009): the shipped file is the
  fifth file extended with the chunks of AOD 0.00625 (tools/fit_fitted.py --extend);
* ``fit-v4``, ``heldout-v4``: the fourth file's grids (``fit-v5`` without the AOD nodes 0.35
  and 0.75; its held-out AOD 0.7 for the 0.3, 0.42, 0.6 and 0.87 of ``heldout-v5``): the
  fifth file is the full fit of ``fit-v4`` extended with the chunks of AOD 0.35 and 0.75
  (tools/fit_fitted.py --extend);
* ``fit-v3``, ``heldout-v3``: the third file's grids (``fit-v4`` without the AOD nodes
  0.0125, 0.075 and 0.15; its five held-out atmospheres, AOD 0.0125 among them), whose
  chunks are the present grids' chunks of the same atmospheres;
* ``fit-v2``: the second file's grid (``fit-v3`` without the altitudes 4, 5, 8 and 12 km),
  which a supplement in ``--altitudes 4000,5000,8000,12000`` completes;
* ``fit-v1``, ``heldout-v1``: the grids of the first coefficient file (6 AOD nodes 0-1, 26
  sun elevations, 7 altitudes; held out: sun -11 and -9 deg, AOD 0.025 and 0.05), to
  reproduce it and its figures;
* ``small``: 2 atmospheres of the fit grid, for a quick check of the pipeline.

``--wavelength-step`` sets the reference's table wavelengths: 300-1100 nm every 20 nm by
default (the fitting wavelengths), 10 nm for a held-out set that measures the model between
them too (81 wavelengths: the 20-nm ones are every other one, so the set's 20-nm subset is
the default set; the chunk layout is the same, with 81 on the wavelength axis).
``--gas-bands``: the reference at the gas bands' own table wavelengths only (310, 330, 570,
590, 610, 690, 710, 730, 770, 890, 930 nm; skydome/models/fitted/_grid.py), a supplement to
the 20-nm set of the same grid in a folder of its own, which ``tools/fit_fitted.py
--wavelength-supplement`` joins to it;
``--with-gas-bands``: the 20-nm wavelengths and the gas bands' together (52): a whole data
set in one run (the twilight reference's geometry costs the same whatever the number of
wavelengths, so this is cheaper than a 20-nm set and its gas-band supplement), which
``tools/fit_fitted.py`` fits as it is.

``--altitudes``: only these of the grid's altitudes (a supplement: the nodes a data set of an
earlier grid lacks, which ``tools/fit_fitted.py --altitude-supplement`` joins to it). Every
(sun elevation, altitude) node is computed from the same tables on its own, and every table
wavelength independently of the others, so a supplement's values are those a run of the
whole grid gives at its nodes.
``--elevations``: likewise only these of the grid's sun elevations (the sun node 0.5 deg
that the sixth file's data set lacks, joined by ``tools/fit_fitted.py
--elevation-supplement``; the held-out sun elevations 0.25 and 0.75 deg that replace the
sixth file's 0.5, joined by ``tools/fitted_accuracy.py --supplement``).
``--wavelengths``: only these table wavelengths (on the 10-nm grid, 300-1100 nm): a
supplement of table wavelengths of their own, such as 570, 590 and 610 nm (ozone's Chappuis
band, between the 20-nm ones) that the seventh file's 49-wavelength data set lacks, joined
by ``tools/fit_fitted.py --wavelength-supplement``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np


def grid(name: str):
    """(elevations [deg], altitudes [m], atmospheres [(aod, albedo)]) of a named grid."""
    from skydome.models.fitted import _grid as G

    return G.grid(name)[:3]


#: Resident memory of one worker per table wavelength [GB], the largest measured
#: (docs/models.md, "fitted", "Cost"): the twilight reference's table build held 4.5-5.5 GB
#: at 41 wavelengths (0.134 GB each) and 8.6-11.2 GB at 81 (10-nm steps: 0.138 GB each);
#: two such workers at 10 nm filled a 24 GB machine.
WORKER_GB_PER_WAVELENGTH = 0.14


def worker_memory_gb(n_wavelengths: int) -> float:
    """The resident memory one worker is expected to need [GB] for a data set of
    ``n_wavelengths`` table wavelengths (:data:`WORKER_GB_PER_WAVELENGTH`)."""
    return WORKER_GB_PER_WAVELENGTH * int(n_wavelengths)


def available_memory_gb() -> float | None:
    """This machine's available memory [GB] (``MemAvailable`` of /proc/meminfo; else the
    physical memory), None where neither can be read."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024 / 1e9
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") / 1e9
    except (AttributeError, OSError, ValueError):
        return None


def _subset(option: str, text: str, values, what: str, unit: str) -> np.ndarray:
    """The values of ``values`` listed in ``text`` (comma-separated, sorted, each once);
    ValueError naming ``option`` and its value where one is not a number or not among
    them."""
    try:
        want = [float(x) for x in text.split(",")]
    except ValueError:
        raise ValueError(f"{option} = {text!r} is not a list of numbers in {unit}") from None
    bad = [x for x in want if not np.any(np.isclose(values, x))]
    if bad or not want:
        raise ValueError(f"{option} = {text!r}: not among {what} "
                         f"{[float(x) for x in values]} {unit}")
    return np.array(sorted(set(float(values[np.isclose(values, x)][0]) for x in want)))


def main(argv=None) -> int:
    from skydome.models.fitted import _grid as G

    gas = ", ".join(f"{x:g}" for x in G.GAS_BAND_WAVELENGTHS_NM)     # for the messages
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="folder of the chunks (created; a rerun resumes)")
    ap.add_argument("--grid", default="fit",
                    choices=G.GRID_NAMES)
    ap.add_argument("--scheduler", default=None,
                    help="Dask scheduler address (default: a local cluster)")
    ap.add_argument("--twilight-reference", action="store_true",
                    help="run precomputed in its twilight reference configuration "
                         "(twilight_reference=True: validated to sun -12 deg, about 4x the "
                         "CPU); the shipped coefficients are fitted to it (sun nodes down "
                         "to -12 deg)")
    ap.add_argument("--max-aod", type=float, default=None,
                    help="leave out the grid's atmospheres whose AOD exceeds this (a data set "
                         "for a model fitted to a subset of the AOD nodes)")
    ap.add_argument("--atmospheres", default=None,
                    help="compute only these atmospheres of the grid, in this order "
                         "(AOD:albedo,...; the others are left for a later run, which "
                         "resumes): the most telling chunks first")
    ap.add_argument("--workers", type=int, default=1,
                    help="local cluster processes (default 1: each precomputation already "
                         "uses every core through numba)")
    ap.add_argument("--wavelength-step", type=float, default=20.0,
                    help="table wavelengths 300-1100 nm every this many nm (default 20: the "
                         "fitting wavelengths; 10, 5, 4, 2 or 1 nm to measure the model "
                         "between them)")
    ap.add_argument("--gas-bands", action="store_true",
                    help=f"table wavelengths: the gas bands' own ({gas} nm) only: the "
                         "supplement that tools/fit_fitted.py --wavelength-supplement adds "
                         "to a 20-nm data set of the same grid")
    ap.add_argument("--with-gas-bands", action="store_true",
                    help=f"table wavelengths: the 20-nm ones and the gas bands' "
                         f"({G.TABLE_WAVELENGTHS_NM.size}): the whole data set in one run "
                         "(what tools/fit_fitted.py fits without a wavelength supplement), "
                         "or a supplement in --altitudes or --elevations to a data set "
                         "joined with its gas-band supplement")
    ap.add_argument("--altitudes", default=None, metavar="M,...",
                    help="compute only these of the grid's altitudes [m] (a supplement that "
                         "tools/fit_fitted.py --altitude-supplement joins to a data set of "
                         "the other altitudes)")
    ap.add_argument("--elevations", default=None, metavar="DEG,...",
                    help="compute only these of the grid's sun elevations [deg] (a supplement "
                         "that tools/fit_fitted.py --elevation-supplement joins to a data set "
                         "of the other elevations; tools/fitted_accuracy.py --supplement to a "
                         "held-out set)")
    ap.add_argument("--wavelengths", default=None, metavar="NM,...",
                    help="table wavelengths: only these of the 10-nm grid 300-1100 nm (a "
                         "supplement that tools/fit_fitted.py --wavelength-supplement joins "
                         "to a data set of the other wavelengths)")
    ap.add_argument("--ignore-memory-check", action="store_true",
                    help="start the local cluster even where --workers times the memory a "
                         "worker is expected to need (about 0.14 GB per table wavelength: "
                         "5.7 GB at 20 nm, 11.3 GB at 10 nm) exceeds the machine's available "
                         "memory (by default refused before any work)")
    a = ap.parse_args(argv)
    if not 1 <= a.workers <= 256:
        print(f"error: --workers = {a.workers} is out of range [1, 256]", file=sys.stderr)
        return 2
    from skydome.distributed import Chunk, check_scheduler, run_chunks
    from skydome.models.fitted import _dataset

    try:
        check_scheduler(a.scheduler, "--scheduler")
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        wl = _dataset.wavelengths_nm(a.wavelength_step)
        if a.gas_bands:
            if a.wavelength_step != 20.0:
                print(f"error: --gas-bands takes no --wavelength-step (its wavelengths are "
                      f"fixed: {gas} nm)", file=sys.stderr)
                return 2
            wl = _dataset.gas_band_wavelengths_nm()
        if a.with_gas_bands:
            if a.gas_bands or a.wavelength_step != 20.0:
                print(f"error: --with-gas-bands takes neither --gas-bands nor "
                      f"--wavelength-step (its wavelengths are fixed: 300-1100 nm every 20 nm "
                      f"and {gas} nm)", file=sys.stderr)
                return 2
            wl = np.union1d(wl, _dataset.gas_band_wavelengths_nm())
        if a.wavelengths is not None:
            if a.gas_bands or a.with_gas_bands or a.wavelength_step != 20.0:
                print("error: --wavelengths takes neither --gas-bands, --with-gas-bands nor "
                      "--wavelength-step (it lists the table wavelengths itself)",
                      file=sys.stderr)
                return 2
            try:
                wl = _subset("--wavelengths", a.wavelengths, _dataset.wavelengths_nm(10.0),
                             "the 10-nm grid's wavelengths", "nm")
            except ValueError as exc:
                print(f"error: {exc}", file=sys.stderr)
                return 2
    except ValueError:
        print(f"error: --wavelength-step = {a.wavelength_step:g} nm is out of range: one of "
              "20, 10, 5, 4, 2, 1 nm (a divisor of the fitting wavelengths' 20 nm)",
              file=sys.stderr)
        return 2
    if a.scheduler is None and not a.ignore_memory_check:
        # a local cluster: its workers share this machine's memory (a cluster's workers
        # are elsewhere and not checked)
        need, have = worker_memory_gb(wl.size), available_memory_gb()
        if have is not None and a.workers * need > have:
            fit = int(have // need)
            print(f"error: --workers = {a.workers} needs about {a.workers * need:.1f} GB "
                  f"({need:.1f} GB per worker at {wl.size} table wavelengths) and this "
                  f"machine has {have:.1f} GB available: use --workers "
                  + (f"{fit} or fewer" if fit >= 1 else "1 on a larger machine")
                  + " (or --ignore-memory-check)", file=sys.stderr)
            return 2
    el, alt, atms = grid(a.grid)
    try:
        if a.altitudes is not None:
            alt = _subset("--altitudes", a.altitudes, alt, f"the {a.grid} grid's altitudes",
                          "m")
        if a.elevations is not None:
            el = _subset("--elevations", a.elevations, el,
                         f"the {a.grid} grid's sun elevations", "deg")
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if a.max_aod is not None:
        if not 0.0 <= a.max_aod <= 1.0:
            print(f"error: --max-aod = {a.max_aod:g} is out of range [0, 1]", file=sys.stderr)
            return 2
        atms = [x for x in atms if x[0] <= a.max_aod + 1e-12]
    grid_atms = list(atms)
    if a.atmospheres is not None:
        try:
            want = [tuple(float(v) for v in x.split(":")) for x in a.atmospheres.split(",")]
            if any(len(x) != 2 for x in want):
                raise ValueError
        except ValueError:
            print(f"error: --atmospheres = {a.atmospheres!r} is not a list AOD:albedo,...",
                  file=sys.stderr)
            return 2
        bad = [x for x in want if not any(np.allclose(x, y) for y in atms)]
        if bad:
            print(f"error: --atmospheres: {bad} not in the {a.grid} grid's atmospheres "
                  f"{atms}", file=sys.stderr)
            return 2
        atms = [next(y for y in atms if np.allclose(x, y)) for x in want]
    mid = a.grid.startswith("heldout")    # held out in direction too: the cells' centres
    chunks = [Chunk(_dataset.chunk_key(aod, alb), _dataset.compute_chunk,
                    (aod, alb, np.asarray(el), np.asarray(alt), mid, a.twilight_reference, wl))
              for aod, alb in atms]
    t0, c0 = time.perf_counter(), time.process_time()
    report = run_chunks(chunks, a.out, scheduler=a.scheduler, n_workers=a.workers,
                        progress=True)
    _dataset.write_grid(a.out, el, alt, grid_atms, mid, a.twilight_reference, wl)
    wall = time.perf_counter() - t0
    n = len(report.computed)
    print(f"\n{n} chunk(s) computed, {len(report.verified)} already there; "
          f"{wall:.1f} s wall ({wall / max(n, 1):.1f} s per computed chunk of "
          f"{len(el) * len(alt)} sun/altitude nodes x {wl.size} wavelengths); client CPU "
          f"{time.process_time() - c0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
