"""``skydome skymatrix`` for perez1993, without the CLI framework (typer, pydantic, rich).

:func:`skydome.daylighting.skymatrix_run.run_perez_skymatrix` is the command's work once its
options are parsed; the typer command (:func:`skydome.cli.daylighting.skymatrix_cmd`) calls
it, and so does :func:`fast_skymatrix`, which ``skydome`` (:mod:`skydome.__main__`) tries
first for a ``skymatrix`` command line: it parses the plain options itself (``--name value``,
``--name=value``, ``--overwrite``) so that a run imports neither typer (with pydantic, 0.2-0.3
s of CPU on a 2-core EPYC), nor numba with ``--backend numpy`` or ``auto`` and a fixed order
(0.4-0.5 s): a whole gendaymtx-like run (``--order 0 --sun-position radiance --backend
numpy``) is then numpy's start-up plus the work (gendaymtx's CPU time / 5.3 at MF:4 by
the best rounds, / 4.9 by the medians, docs/performance.md). Anything
else (help, an unknown or repeated-list option, another model, Dask, a value it refuses)
goes to the typer command, which parses it and reports an error as one line with exit code 2
as every command does: the fast path reports nothing itself, and leaves nothing on disk.
This module imports nothing of typer (``skydome.cli``'s ``__init__`` imports nothing).
"""

from __future__ import annotations

import sys

from skydome.daylighting.skymatrix_run import (SKYMATRIX_DEFAULTS, order_option,
                                               run_perez_skymatrix)

#: Long option -> parameter, for the options :func:`fast_skymatrix` parses (string values).
_FAST_OPTIONS = {"--weather": "weather", "--out": "out", "--patches": "patches",
                 "--model": "model", "--components": "components", "--sun": "sun",
                 "--order": "order", "--sun-position": "sun_position", "--format": "fmt",
                 "--albedo": "albedo", "--backend": "backend"}


class _Refused(Exception):
    """The fast path does not take this command line (the typer command will)."""


def _refuse(message=""):
    raise _Refused(message)


def _try(func, *args, **kwargs):
    try:
        return func(*args, **kwargs)
    except Exception as exc:  # bad input or a failed write: the typer command reports it
        raise _Refused(str(exc)) from exc


def _echo(text, err=False):
    print(text, file=sys.stderr if err else sys.stdout)


def parse_fast_options(argv):
    """The options of a plain ``skymatrix`` command line (``--name value``, ``--name=value``,
    ``--overwrite``; the last of a repeated option wins, as in typer), or None for anything
    else: help, other options, positional arguments, a missing value."""
    opts = dict(SKYMATRIX_DEFAULTS)
    i = 0
    while i < len(argv):
        a = argv[i]
        if a == "--overwrite":
            opts["overwrite"] = True
            i += 1
            continue
        name, eq, value = a.partition("=")
        if name not in _FAST_OPTIONS:
            return None
        if not eq:
            if i + 1 >= len(argv) or argv[i + 1].startswith("-"):
                return None  # a missing value (or one typer would read otherwise)
            value = argv[i + 1]
            i += 1
        opts[_FAST_OPTIONS[name]] = value
        i += 1
    if opts["weather"] is None or opts["out"] is None:
        return None
    return opts


def fast_skymatrix(argv) -> bool:
    """Run a plain perez1993 ``skymatrix`` command line in this process without typer;
    True if it ran to completion, False if the typer command should take it (nothing has
    been printed and no output is left on disk then)."""
    opts = parse_fast_options(argv)
    if opts is None or opts["model"] != "perez1993":
        return False
    from skydome.cli._notes import notes_as_lines
    from skydome.daylighting.patches import patches as make_patches
    from skydome.daylighting.skymatrix import ClearSkyNote

    notes: list[str] = []   # shown once the run has succeeded (else the typer command runs)
    try:
        ps = _try(make_patches, opts.pop("patches"))
        opts["order"] = order_option(opts["order"], opts["model"], _refuse)
        with notes_as_lines(ClearSkyNote, emit=notes.append):
            run_perez_skymatrix(ps=ps, fail=_refuse, guard=_try, echo=_echo, **opts)
    except _Refused:
        return False
    for note in notes:
        _echo(note, err=True)
    return True
