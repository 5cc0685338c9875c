"""``skydome`` / ``python -m skydome``: the command line.

A plain perez1993 ``skymatrix`` command line is run without the CLI framework
(:func:`skydome.cli.skymatrix_fast.fast_skymatrix`: no typer, and with ``--backend
numpy`` and a fixed order no numba, the start-up of a gendaymtx-like run), and a plain
``render`` command line without typer's application and parser
(:func:`skydome.cli.render_fast.fast_render`), and a plain ``export envmap`` command line
likewise (:func:`skydome.cli.render_fast.fast_export_envmap`); every other command line, and any that a
fast path does not take, goes to the typer application :mod:`skydome.cli`.

The console script (and ``python -m skydome``) is :func:`console`: :func:`main`, then the
process ends without the interpreter's teardown, once the threads, atexit handlers and
output streams a command's results depend on are done (:func:`_end_process`).
"""

from __future__ import annotations

import atexit
import gc
import os
import sys
import threading


def _run_fast(fast, args, collector_off: bool):
    """``fast(args)`` (a fast path of :func:`main`) with Python's cyclic collector off while
    it runs if ``collector_off``, Ctrl-C as exit 130; the collector is on again after."""
    if collector_off:
        gc.disable()
    try:
        return fast(args)
    except KeyboardInterrupt:  # pragma: no cover
        sys.exit(130)
    finally:
        gc.enable()


def main() -> None:  # the command line, in this process (console() ends the process after)
    argv = sys.argv[1:]
    # Before numpy is imported: no transparent huge pages for its large arrays (a matrix
    # held whole for a .npy or ascii output, the Perez work arrays, an environment map's
    # directions and pixels). On the 2-core EPYC virtual machine of docs/performance.md the
    # first touch of a 2 MiB page is slow: filling a new 161 MB array cost 0.37-0.44 s of
    # system time with them, 0.06-0.09 s with 4 KiB pages; a 4096 x 2048 environment map
    # of preetham1999 took 4.7 s (3.2 s CPU) in a fresh process with them, 1.7 s (1.1 s)
    # without. A value set by the user is kept.
    os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")
    if argv[:1] == ["skymatrix"]:
        from skydome.cli.skymatrix_fast import fast_skymatrix, parse_fast_options

        opts = parse_fast_options(argv[1:])  # no numpy imported yet
        perez = opts is not None and opts["model"] == "perez1993"
        if perez:
            # A perez1993 matrix makes no BLAS call worth a second thread (its matrix
            # products are of at most 2^18 multiply-adds). Started with a thread per core,
            # numpy's OpenBLAS cost 0.16 s of CPU for `import numpy` against 0.10 s with one
            # (best of ten fresh processes each, interleaved, 2-core EPYC); the whole run
            # (MF:4, numpy backend, .wea) took 0.56 s of CPU against 0.46 s (best of eight,
            # interleaved). A value set by the user is kept.
            os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
        # A short run that leaves no reference cycles worth collecting: Python's cyclic
        # collector, triggered by the allocations of the imports, took 4 % of the samples
        # of a profiled run (perf, five runs)
        if _run_fast(fast_skymatrix, argv[1:], collector_off=perez):
            sys.exit(0)
    if argv[:1] == ["render"]:
        # One picture, then the process ends: Python's cyclic collector, set off again and
        # again by the allocations of the imports (numba's above all), ran 271 times in a
        # warm shortest render for 0.10-0.11 s of CPU (timed by gc.callbacks, two runs on
        # the 2-core EPYC of docs/performance.md; the render leaves no cycles worth
        # collecting). It is on again for a command line the fast path leaves to typer.
        from skydome.cli.render_fast import fast_render

        code = _run_fast(fast_render, argv[1:], collector_off=True)
        if code is not None:
            sys.exit(code)
    if argv[:2] == ["export", "envmap"]:
        # the same for a plain `export envmap` command line (one map, then the process ends)
        from skydome.cli.render_fast import fast_export_envmap

        code = _run_fast(fast_export_envmap, argv[2:], collector_off=True)
        if code is not None:
            sys.exit(code)
    from skydome.cli import main as cli_main

    cli_main()


def _exit_status(code) -> int:
    """The process's exit status for ``sys.exit(code)`` as Python gives it: None 0, an int
    itself, anything else printed to stderr and 1."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code & 0xFF
    print(code, file=sys.stderr)
    return 1


def _end_process(status: int) -> None:
    """End the process now with ``status``, after everything Python's own exit does that a
    command's results depend on: the threading module's exit hooks run and non-daemon
    threads joined (a table cache entry being written), the atexit handlers run (logging,
    temporary folders, Dask's clusters), stdout and stderr flushed; a failed flush of
    stdout gives status 120 as Python's exit does.

    What is left out is the interpreter's teardown of its modules, whose garbage
    collections over the object graph numba builds (its types, registries and compiled
    libraries) took 0.23-0.29 s of a warm shortest render's 0.8-1.0 s (perf, 2-core EPYC,
    docs/performance.md); the operating system frees the memory."""
    # what the interpreter's exit calls first: the threading module's exit hooks (an idle
    # ThreadPoolExecutor's workers, Dask's threaded scheduler's pool, told to stop), then
    # every non-daemon thread joined
    threading._shutdown()
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):
            if stream is sys.stdout and status == 0:
                status = 120
    os._exit(status)


def console() -> None:  # console-script entry point (and ``python -m skydome``)
    """:func:`main`, then the process ends without the interpreter's teardown
    (:func:`_end_process`). An exception other than ``SystemExit`` propagates as usual
    (its traceback, Python's own exit)."""
    try:
        main()
        status = 0
    except SystemExit as exc:
        status = _exit_status(exc.code)
    _end_process(status)


if __name__ == "__main__":  # pragma: no cover
    console()
