"""``skydome render``, ``sun``, ``models`` and ``table1``: one sky into an image, the sun's
position, the catalogue of models, the survey's Table 1."""

from __future__ import annotations

import time as _time
from typing import Optional

import typer

from skydome.cli._kit import (EXTRA, PROJECTIONS, UserError, _build_model, _check_memory,
                              _parse_model_params, _Progress, _run, _sun_from, sun_option,
                              sun_options)

commands = typer.Typer()


@commands.command(context_settings=EXTRA)
@sun_options()
def render(
    ctx: typer.Context,
    model: str = typer.Option("precomputed", help="Registered model name (see `skydome models`); the default is the accurate multiple-scattering sky."),
    out: str = typer.Option(..., help="Output file: .exr (float, linear), .hdr (Radiance RGBE) or .png (tone mapped)."),
    projection: str = typer.Option("fisheye", help="fisheye (Radiance angular fisheye), equirect, equirect-hemisphere, angular or camera (the model's own camera view, e.g. nishita1993)."),
    size: str = typer.Option("512", help="Image size in pixels: N (square / width) or WxH."),
    wavelengths: int = typer.Option(16, help="Number of wavelengths 380-780 nm for spectral models, 3..401."),
    exposure: Optional[float] = typer.Option(None, help="PNG only: exposure multiplier on luminance in cd/m^2 (default automatic)."),
    tonemap: str = typer.Option("hue-preserving", help="PNG only: hue-preserving (default: keeps hue, compresses the gamut), agx (Blender 4.x AgX base), aces-hill (ACES 1.x fit by Hill), filmic (per-channel ACES fit by Narkowicz), reinhard or clamp."),
    bits: int = typer.Option(8, help="PNG only: 8 or 16 bits per channel."),
    no_sun: bool = typer.Option(False, "--no-sun", help="Do not draw the sun disc."),
    ev100: Optional[float] = typer.Option(None, help="PNG only: exposure value at ISO 100, -20..30 (instead of --exposure)."),
    sun_light: Optional[str] = typer.Option(None, help="Leave the sun out of the image and write it as a light (direction, angular radius, spectral irradiance) to this .json file."),
    no_hunt: bool = typer.Option(False, "--no-hunt", help="PNG only: show the sky's chromaticities as they are, without the Hunt-effect chroma gain (which keeps the bright sky's colourfulness on the dimmer display)."),
    **sun,
):
    """Render a sky model into an image file.

    Model parameters are given as extra options, e.g. `--turbidity 3` or `--sky-type 12`
    (see `skydome models` for each model's options, units and ranges).
    """
    _run(_render, ctx.args, model, out, sun, projection, size, wavelengths, exposure, tonemap,
         bits, not no_sun, ev100, sun_light, not no_hunt)


def _render(extra, model, out, sun: dict, projection, size, wavelengths, exposure, tonemap, bits,
            draw_sun, ev100=None, sun_light=None, hunt=True):
    from skydome._io import check_output_file
    from skydome._validate import check_choice, check_int, check_number
    from skydome.models import get_model_class
    from skydome.imaging import make_projection, render as render_sky
    from skydome.imaging.image import check_output_path
    from skydome.spectra import wavelength_grid

    # 1. validate everything before any work
    cls = get_model_class(model)
    params = _parse_model_params(cls, extra)
    check_choice("projection", projection, PROJECTIONS)
    from skydome.imaging.display import DISPLAY_TRANSFORMS

    check_choice("tonemap", tonemap, DISPLAY_TRANSFORMS)
    check_choice("bits", bits, (8, 16))
    if ev100 is not None and exposure is not None:
        raise UserError("give --exposure or --ev100, not both")
    if ev100 is not None:
        check_number("ev100", ev100, -20.0, 30.0)
    if sun_light is not None:
        check_output_file(sun_light, (".json",), name="--sun-light")
        draw_sun = False
    check_int("wavelengths", wavelengths, 3, 401)
    if exposure is not None:
        check_number("exposure", exposure, 0.0, None, low_open=True)
    sun = _sun_from(sun)
    n_channels = wavelengths if cls.native == "spectral" else 3
    if projection == "camera":
        if not hasattr(cls, "default_projection"):
            raise UserError(f"projection = 'camera' needs a model with its own camera "
                            f"(e.g. nishita1993); model {model!r} has none")
        from skydome.imaging.projections import _parse_size

        w, h = _parse_size(size)
        _check_memory("size", size, w * (w if h is None else h), n_channels)
        check_output_file(out, (".exr", ".hdr", ".png"))
        check_output_path(out)
        proj = None
    else:
        proj = make_projection(projection, size)
        _check_memory("size", size, proj.shape[0] * proj.shape[1], n_channels)
        check_output_file(out, (".exr", ".hdr", ".png"))
        check_output_path(out)
    wl = wavelength_grid(380.0, 780.0, n=wavelengths)

    # 2. work: the time printed includes the model's construction (precomputation)
    progress = _Progress(f"rendering {model}")
    t0 = _time.perf_counter()
    try:
        sky = _build_model(cls, progress, sun=sun, **params)
        if proj is None:
            proj = sky.default_projection(size)
        image = render_sky(sky, proj, wl, progress=progress, draw_sun=draw_sun, output="xyz")
    finally:
        progress.close()
    image.save(out, exposure=exposure, tonemap=tonemap, bits=bits, ev100=ev100, hunt=hunt)
    if sun_light is not None:
        if image.sun_light is None:
            typer.echo("no sun light written: the model has no sun above the horizon", err=True)
        else:
            image.sun_light.write_json(sun_light)
    dt = _time.perf_counter() - t0
    typer.echo(f"wrote {out} ({proj.shape[1]}x{proj.shape[0]}, {model}, sun elevation "
               f"{sun.elevation_deg:.2f} deg azimuth {sun.azimuth_deg:.2f} deg, {dt:.1f} s)")


@commands.command()
def table1():
    """The survey's Table 1 recomputed from the physics: eq 8 with eqs 5 and 6."""
    from skydome.atmosphere.rayleigh import rayleigh_scattering_coefficient

    rows = [("red", 700, 4.184e-6, 239), ("yellow", 570, 9.517e-6, 105), ("green", 540, 1.181e-5, 84.6),
            ("blue", 470, 2.059e-5, 48.5), ("violet", 400, 3.924e-5, 25.5)]
    typer.echo("Rayleigh attenuation coefficient beta = 8 pi^3 (n^2-1)^2 / (3 N_s lambda^4)")
    typer.echo("with n = 1.000278 (eq. 6) and N_s = 2.545e25 m^-3 (eq. 5)\n")
    typer.echo(f"{'colour':<8}{'lambda [nm]':>12}{'beta [1/m]':>14}{'1/beta [km]':>13}"
               f"{'survey beta':>14}{'survey 1/beta':>15}")
    for name, wl, beta_s, inv_s in rows:
        b = float(rayleigh_scattering_coefficient(wl))
        typer.echo(f"{name:<8}{wl:>12d}{b:>14.4e}{1e-3 / b:>13.4g}{beta_s:>14.4e}{inv_s:>15g}")


@commands.command()
def sun(
    lat: float = sun_option("lat", ...),
    lon: float = sun_option("lon", ...),
    time: str = sun_option("time", ...),
    method: str = sun_option("sun_method", "spa", spelling="--method"),
):
    """Solar position for a place and time: geometric (true) elevation, the apparent elevation
    and the flattening of the disc by atmospheric refraction, azimuth from north towards east."""
    from skydome.sun import Sun

    s = _run(Sun.from_location, lat, lon, time, method=method)
    typer.echo(f"time            {time}")
    typer.echo(f"method          {method}")
    typer.echo(f"elevation       {s.elevation_deg:.4f} deg (geometric)")
    if s.elevation_deg > -2.0:
        from skydome.effects.refraction import apparent_elevation, sun_disc_shape

        shape = sun_disc_shape(s.elevation_deg)
        ratio = shape["ratio"]
        typer.echo(f"apparent        {float(apparent_elevation(s.elevation_deg)):.4f} deg "
                   f"(Saemundsson refraction, 101 kPa, 10 C)")
        typer.echo(f"disc shape      {float(ratio):.3f} (apparent height / width)")
    typer.echo(f"azimuth         {s.azimuth_deg:.4f} deg (from north towards east)")
    typer.echo(f"zenith          {s.zenith_deg:.4f} deg")
    typer.echo(f"distance        {s.distance_au:.6f} au")


@commands.command()
def models():
    """Every registered model with its parameters, units and valid ranges."""
    from skydome.models import available

    for name, cls in available().items():
        typer.echo(f"{name}  [{cls.native}]  {cls.summary}")
        if cls.reference:
            typer.echo(f"    reference: {cls.reference}")
        for p in cls.parameters:
            unit = f" [{p.unit}]" if p.unit else ""
            rng = p.range_text()
            default = "" if p.default is None else f" (default {p.default})"
            opt = "--" + p.name.replace("_", "-") if p.kind != "object" else f"{p.name} (Python API)"
            typer.echo(f"    {opt}{unit} {rng}{default}: {p.doc}")
        typer.echo("")

