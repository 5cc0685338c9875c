"""The ``skydome`` command line: one package that owns every command.

- :mod:`skydome.cli.root`: the typer application ``app`` and the entry point ``main``;
- :mod:`skydome.cli._kit`: the shared kit (errors as one line on stderr with exit code 2,
  the progress bar, the sun options declared once, the one parser of a model's
  ``--name value`` parameters, model building);
- the command modules: :mod:`~skydome.cli.render` (render, sun, models, table1),
  :mod:`~skydome.cli.apps` (compare, timelapse, polarisation, twilight, airlight, aureole),
  :mod:`~skydome.cli.plot`, :mod:`~skydome.cli.cache`, :mod:`~skydome.cli.export`,
  :mod:`~skydome.cli.daylighting` (weather, skymatrix, illuminance, daylight-factor),
  :mod:`~skydome.cli.validate`, :mod:`~skydome.cli.view`;
- :mod:`skydome.cli.skymatrix_fast`: a plain perez1993 ``skymatrix`` run without typer.

The library below imports nothing of this package. This ``__init__`` imports nothing itself,
so that the fast path loads no typer: ``skydome.cli.app`` and ``skydome.cli.main`` are
looked up in :mod:`skydome.cli.root` on first use.
"""

from __future__ import annotations

__all__ = ["app", "main"]


def __getattr__(name: str):
    if name in __all__:
        from skydome.cli import root

        return getattr(root, name)
    raise AttributeError(f"module 'skydome.cli' has no attribute {name!r}")
