"""``skydome`` / ``python -m skydome``: the command line.

A plain perez1993 ``skymatrix`` command line is run without the CLI framework
(:func:`skydome.daylighting.skymatrix_cli.fast_skymatrix`: no typer, no numba for a fixed
order, the start-up of a gendaymtx-like run); every other command line, and any that the
fast path does not take, goes to the typer application :mod:`skydome.cli`.
"""

from __future__ import annotations

import sys


def main() -> None:  # console-script entry point
    argv = sys.argv[1:]
    if argv[:1] == ["skymatrix"]:
        from skydome.daylighting.skymatrix_cli import fast_skymatrix

        try:
            if fast_skymatrix(argv[1:]):
                sys.exit(0)
        except KeyboardInterrupt:  # pragma: no cover
            sys.exit(130)
    from skydome.cli import main as cli_main

    cli_main()


if __name__ == "__main__":  # pragma: no cover
    main()
