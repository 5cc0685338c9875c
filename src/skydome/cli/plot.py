"""``skydome plot``: luminance maps and model comparisons as figures."""

from __future__ import annotations

import typer

from skydome.cli._kit import (EXTRA, _check_figure_path, _check_shared, _model_spec, _run,
                              _split_specs, _sun_from, sun_options)

# the figures place the sun by angles or by place, with the SPA sun
PLACE_OR_ANGLES = ("sun_elevation", "sun_azimuth", "lat", "lon", "time")

plot_app = typer.Typer(no_args_is_help=True, help="Figures: luminance maps and model comparisons.")


@plot_app.command("luminance", context_settings=EXTRA)
@sun_options(*PLACE_OR_ANGLES)
def plot_luminance(
    ctx: typer.Context,
    model: str = typer.Option(..., help="Model name, optionally name:value for its first option (e.g. cie2003:12)."),
    out: str = typer.Option(..., help="Output figure (.png, .pdf or .svg)."),
    linear: bool = typer.Option(False, "--linear", help="Linear instead of logarithmic colour scale."),
    **sun,
):
    """Polar false-colour luminance map [cd/m^2] with a colour bar and the sun marked."""
    def go():
        from skydome.models import get_model_class

        _check_figure_path(out)
        _check_shared(ctx.args, [get_model_class(model.partition(":")[0])])
        s = _sun_from(sun)
        sky = _model_spec(model, ctx.args, s)
        from skydome.imaging.plots import plot_luminance_map

        plot_luminance_map(sky, out, log=not linear, title=f"{model}: luminance [cd/m$^2$]")
        typer.echo(f"wrote {out}")
    _run(go)


@plot_app.command("compare", context_settings=EXTRA)
@sun_options(*PLACE_OR_ANGLES)
def plot_compare_cmd(
    ctx: typer.Context,
    models: str = typer.Option(..., help="Comma-separated model specs, e.g. cie2003:12,perez1993,preetham1999."),
    out: str = typer.Option(..., help="Output figure (.png, .pdf or .svg)."),
    relative: bool = typer.Option(False, "--relative", help="Plot L/Lz instead of absolute luminance."),
    **sun,
):
    """Luminance along the solar meridian and along the almucantar for several models, one figure.

    Options after the list (e.g. --dni 650 --dhi 120 --turbidity 3) go to every model that has them.
    """
    def go():
        from skydome.models import get_model_class

        _check_figure_path(out)
        specs = _split_specs(models)
        _check_shared(ctx.args, [get_model_class(sp.partition(":")[0]) for sp in specs])
        s = _sun_from(sun)
        skies = [_model_spec(sp, ctx.args, s) for sp in specs]
        from skydome.imaging.plots import plot_compare

        plot_compare(skies, specs, out, relative=relative)
        typer.echo(f"wrote {out}")
    _run(go)

