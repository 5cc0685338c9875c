"""The root of the ``skydome`` command line: the typer application, composed of the command
groups of this package (nothing below it imports it)."""

from __future__ import annotations

import sys

import typer

from skydome.cli import apps, cache, daylighting, export, plot, render, validate, view
from skydome.cli._kit import _OneLineGroup


def _version(value: bool) -> None:
    if value:
        from skydome import __version__

        typer.echo(f"skydome {__version__}")
        raise typer.Exit()


app = typer.Typer(cls=_OneLineGroup, add_completion=False, no_args_is_help=True,
                  rich_markup_mode=None,
                  help="skydome: physically based daylight modelling (sky models, spectral sky "
                       "images).")


@app.callback()
def _main_options(version: bool = typer.Option(False, "--version", callback=_version,
                                               is_eager=True,
                                               help="Print the version and exit.")) -> None:
    """skydome: physically based daylight modelling (sky models, spectral sky images)."""


# the top-level commands of each module, then the groups
app.registered_commands += render.commands.registered_commands + apps.commands.registered_commands
app.command("view")(view.view)
app.registered_commands += daylighting.commands.registered_commands
app.add_typer(cache.cache_app, name="cache")
app.add_typer(plot.plot_app, name="plot")
app.add_typer(export.export_app, name="export")
app.add_typer(daylighting.weather_app, name="weather")
app.add_typer(validate.validate_app, name="validate")


def main() -> None:  # console-script entry point
    try:
        app()
    except KeyboardInterrupt:  # pragma: no cover
        sys.exit(130)
