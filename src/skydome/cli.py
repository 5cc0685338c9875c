"""The ``skydome`` command line: a thin layer over the public API.

Every command validates all of its input before doing any work; a bad value prints one
line on stderr (``error: ...``) and exits with code 2, leaving nothing on disk.
"""

from __future__ import annotations

import sys
import time as _time
from typing import Any, Optional

import typer

app = typer.Typer(add_completion=False, no_args_is_help=True, rich_markup_mode=None,
                  help="skydome: physically based daylight modelling (sky models, spectral sky images).")

PROJECTIONS = ("fisheye", "equirect", "equirect-hemisphere", "angular", "camera")


class UserError(Exception):
    """Bad input: reported as one line on stderr with exit code 2."""


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def _run(func, *args, **kwargs):
    """Call ``func`` turning ValueError/TypeError/FileNotFoundError into exit code 2."""
    try:
        return func(*args, **kwargs)
    except (UserError, ValueError, TypeError, FileNotFoundError, KeyError) as exc:
        msg = exc.args[0] if exc.args else str(exc)
        _fail(str(msg))


# -- helpers --------------------------------------------------------------------------------
def _make_sun(sun_elevation, sun_azimuth, lat, lon, time, sun_method):
    from skydome.sun import Sun

    by_angles = sun_elevation is not None or sun_azimuth is not None
    by_place = any(v is not None for v in (lat, lon, time))
    if by_angles and by_place:
        raise UserError("give either --sun-elevation/--sun-azimuth or --lat/--lon/--time, not both")
    if by_place:
        missing = [n for n, v in (("--lat", lat), ("--lon", lon), ("--time", time)) if v is None]
        if missing:
            raise UserError(f"{', '.join(missing)} missing: --lat, --lon and --time go together")
        return Sun.from_location(lat, lon, time, method=sun_method)
    return Sun(elevation_deg=30.0 if sun_elevation is None else sun_elevation,
               azimuth_deg=180.0 if sun_azimuth is None else sun_azimuth)


def _parse_model_params(cls, extra: list[str]) -> dict[str, Any]:
    """Turn ``--name value`` pairs into keyword parameters of model class ``cls``."""
    params = {p.name: p for p in cls.parameters}
    out: dict[str, Any] = {}
    i = 0
    while i < len(extra):
        tok = extra[i]
        if not tok.startswith("--"):
            raise UserError(f"unexpected argument {tok!r}")
        key, _, value = tok[2:].partition("=")
        name = key.replace("-", "_")
        if name not in params or params[name].kind == "object":
            valid = ", ".join("--" + p.name.replace("_", "-") for p in cls.parameters if p.kind != "object")
            raise UserError(f"model {cls.name!r} has no option --{key}; its options: {valid or 'none'}")
        if not value:
            if i + 1 >= len(extra):
                raise UserError(f"--{key} needs a value")
            value = extra[i + 1]
            i += 1
        p = params[name]
        try:
            if p.kind == "int":
                out[name] = int(value)
            elif p.kind == "float":
                out[name] = float(value)
            elif p.kind == "choice":
                # choices may be numbers or strings
                conv = type(p.choices[0]) if p.choices else str
                out[name] = conv(value)
            elif p.kind == "bool":
                out[name] = value.lower() in ("1", "true", "yes", "on")
            else:
                out[name] = value
        except ValueError:
            raise UserError(f"--{key} = {value!r} is not a valid {p.kind}") from None
        i += 1
    return out


class _Progress:
    """A rich progress bar that appears only once a render has run for a second."""

    def __init__(self, label: str):
        self.label = label
        self.t0 = _time.perf_counter()
        self.bar = None
        self.task = None

    def __call__(self, done: int, total: int) -> None:
        if self.bar is None:
            if _time.perf_counter() - self.t0 < 1.0 or done >= total:
                return
            from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
            from rich.console import Console

            self.bar = Progress(TextColumn(self.label), BarColumn(), TextColumn("{task.percentage:>3.0f}%"),
                                TimeRemainingColumn(), console=Console(stderr=True), transient=True)
            self.bar.start()
            self.task = self.bar.add_task(self.label, total=total)
        self.bar.update(self.task, completed=done)

    def close(self):
        if self.bar is not None:
            self.bar.stop()


# -- commands ----------------------------------------------------------------------------------
@app.command(context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def render(
    ctx: typer.Context,
    model: str = typer.Option("single_scattering", help="Registered model name (see `skydome models`)."),
    out: str = typer.Option(..., help="Output file: .exr (float, linear), .hdr (Radiance RGBE) or .png (tone mapped)."),
    sun_elevation: Optional[float] = typer.Option(None, help="Sun elevation above the horizon [deg], -90..90 (default 30)."),
    sun_azimuth: Optional[float] = typer.Option(None, help="Sun azimuth from north towards east [deg] (default 180)."),
    lat: Optional[float] = typer.Option(None, help="Latitude [deg], -90..90, north positive (with --lon and --time)."),
    lon: Optional[float] = typer.Option(None, help="Longitude [deg], -180..180, east positive."),
    time: Optional[str] = typer.Option(None, help="ISO 8601 time with UTC offset, e.g. 2026-06-21T20:45+02:00."),
    sun_method: str = typer.Option("spa", help="Solar position algorithm: spa (NREL SPA via pvlib) or preetham1999."),
    projection: str = typer.Option("fisheye", help="fisheye (Radiance angular fisheye), equirect, equirect-hemisphere, angular or camera (the model's own camera view, e.g. nishita1993)."),
    size: str = typer.Option("512", help="Image size in pixels: N (square / width) or WxH."),
    wavelengths: int = typer.Option(16, help="Number of wavelengths 380-780 nm for spectral models, 3..401."),
    exposure: Optional[float] = typer.Option(None, help="PNG only: exposure multiplier on luminance in cd/m^2 (default automatic)."),
    tonemap: str = typer.Option("filmic", help="PNG only: clamp, reinhard or filmic (ACES-like)."),
    bits: int = typer.Option(8, help="PNG only: 8 or 16 bits per channel."),
    no_sun: bool = typer.Option(False, "--no-sun", help="Do not draw the sun disc."),
):
    """Render a sky model into an image file.

    Model parameters are given as extra options, e.g. `--turbidity 3` or `--sky-type 12`
    (see `skydome models` for each model's options, units and ranges).
    """
    _run(_render, ctx.args, model, out, sun_elevation, sun_azimuth, lat, lon, time, sun_method,
         projection, size, wavelengths, exposure, tonemap, bits, not no_sun)


def _render(extra, model, out, sun_elevation, sun_azimuth, lat, lon, time, sun_method, projection,
            size, wavelengths, exposure, tonemap, bits, draw_sun):
    from skydome._validate import check_choice, check_int
    from skydome.models import get_model_class
    from skydome.render import make_projection, render as render_sky
    from skydome.render.image import check_output_path
    from skydome.spectra import wavelength_grid

    # 1. validate everything before any work
    cls = get_model_class(model)
    params = _parse_model_params(cls, extra)
    check_choice("projection", projection, PROJECTIONS)
    check_choice("tonemap", tonemap, ("clamp", "reinhard", "filmic"))
    check_choice("bits", bits, (8, 16))
    check_int("wavelengths", wavelengths, 3, 401)
    if exposure is not None and not exposure > 0:
        raise UserError(f"exposure = {exposure} must be > 0")
    sun = _make_sun(sun_elevation, sun_azimuth, lat, lon, time, sun_method)
    if projection == "camera":
        if not hasattr(cls, "default_projection"):
            raise UserError(f"projection = 'camera' needs a model with its own camera "
                            f"(e.g. nishita1993); model {model!r} has none")
        from skydome.render.projections import _parse_size

        _parse_size(size)
        check_output_path(out)
        sky = cls(sun=sun, **params)
        proj = sky.default_projection(size)
    else:
        proj = make_projection(projection, size)
        check_output_path(out)
        sky = cls(sun=sun, **params)
    wl = wavelength_grid(380.0, 780.0, n=wavelengths)

    # 2. work
    progress = _Progress(f"rendering {model}")
    t0 = _time.perf_counter()
    try:
        image = render_sky(sky, proj, wl, progress=progress, draw_sun=draw_sun)
    finally:
        progress.close()
    image.save(out, exposure=exposure, tonemap=tonemap, bits=bits)
    dt = _time.perf_counter() - t0
    typer.echo(f"wrote {out} ({proj.shape[1]}x{proj.shape[0]}, {model}, sun elevation "
               f"{sun.elevation_deg:.2f} deg azimuth {sun.azimuth_deg:.2f} deg, {dt:.1f} s)")


@app.command()
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


@app.command()
def sun(
    lat: float = typer.Option(..., help="Latitude [deg], -90..90, north positive."),
    lon: float = typer.Option(..., help="Longitude [deg], -180..180, east positive."),
    time: str = typer.Option(..., help="ISO 8601 time with UTC offset, e.g. 2026-06-21T12:00+02:00."),
    method: str = typer.Option("spa", help="spa (NREL SPA via pvlib) or preetham1999."),
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


@app.command()
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


plot_app = typer.Typer(no_args_is_help=True, help="Figures: luminance maps and model comparisons.")
app.add_typer(plot_app, name="plot")


def _model_spec(spec: str, shared: list[str], sun):
    """Build a model from 'name' or 'name:value' (value for the model's first option) or
    'name:key=value,key=value', with shared '--key value' options applied where the model
    has that option."""
    from skydome.models import get_model_class

    name, _, rest = spec.partition(":")
    cls = get_model_class(name.strip())
    params: dict[str, Any] = {}
    options = [p for p in cls.parameters if p.kind != "object"]
    if rest:
        for item in rest.split(","):
            key, eq, value = item.partition("=")
            if not eq:
                if not options:
                    raise UserError(f"model {cls.name!r} takes no options (got {spec!r})")
                key, value = options[0].name, item
            params.update(_parse_model_params(cls, [f"--{key.strip()}", value.strip()]))
    names = {p.name for p in options}
    pairs = [(shared[i], shared[i + 1]) for i in range(0, len(shared) - 1, 2)]
    for key, value in pairs:
        if key.lstrip("-").replace("-", "_") in names:
            params.update(_parse_model_params(cls, [key, value]))
    return cls(sun=sun, **params)


def _check_shared(shared: list[str], classes) -> None:
    if len(shared) % 2:
        raise UserError(f"options must come as --name value pairs, got {' '.join(shared)}")
    for key in shared[::2]:
        name = key.lstrip("-").replace("-", "_")
        if not key.startswith("--") or not any(name in {p.name for p in c.parameters} for c in classes):
            raise UserError(f"no model given accepts the option {key}")


@plot_app.command("luminance", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def plot_luminance(
    ctx: typer.Context,
    model: str = typer.Option(..., help="Model name, optionally name:value for its first option (e.g. cie2003:12)."),
    out: str = typer.Option(..., help="Output figure (.png, .pdf or .svg)."),
    sun_elevation: Optional[float] = typer.Option(None, help="Sun elevation [deg] (default 30)."),
    sun_azimuth: Optional[float] = typer.Option(None, help="Sun azimuth from north towards east [deg] (default 180)."),
    lat: Optional[float] = typer.Option(None, help="Latitude [deg] (with --lon and --time)."),
    lon: Optional[float] = typer.Option(None, help="Longitude [deg], east positive."),
    time: Optional[str] = typer.Option(None, help="ISO 8601 time with UTC offset."),
    linear: bool = typer.Option(False, "--linear", help="Linear instead of logarithmic colour scale."),
):
    """Polar false-colour luminance map [cd/m^2] with a colour bar and the sun marked."""
    def go():
        from skydome.models import get_model_class

        _check_figure_path(out)
        _check_shared(ctx.args, [get_model_class(model.partition(":")[0])])
        s = _make_sun(sun_elevation, sun_azimuth, lat, lon, time, "spa")
        sky = _model_spec(model, ctx.args, s)
        from skydome.render.plots import plot_luminance_map

        plot_luminance_map(sky, out, log=not linear, title=f"{model}: luminance [cd/m$^2$]")
        typer.echo(f"wrote {out}")
    _run(go)


@plot_app.command("compare", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def plot_compare_cmd(
    ctx: typer.Context,
    models: str = typer.Option(..., help="Comma-separated model specs, e.g. cie2003:12,perez1993,preetham1999."),
    out: str = typer.Option(..., help="Output figure (.png, .pdf or .svg)."),
    sun_elevation: Optional[float] = typer.Option(None, help="Sun elevation [deg] (default 30)."),
    sun_azimuth: Optional[float] = typer.Option(None, help="Sun azimuth from north towards east [deg] (default 180)."),
    lat: Optional[float] = typer.Option(None, help="Latitude [deg] (with --lon and --time)."),
    lon: Optional[float] = typer.Option(None, help="Longitude [deg], east positive."),
    time: Optional[str] = typer.Option(None, help="ISO 8601 time with UTC offset."),
    relative: bool = typer.Option(False, "--relative", help="Plot L/Lz instead of absolute luminance."),
):
    """Luminance along the solar meridian and along the almucantar for several models, one figure.

    Options after the list (e.g. --dni 650 --dhi 120 --turbidity 3) go to every model that has them.
    """
    def go():
        from skydome.models import get_model_class

        _check_figure_path(out)
        specs = _split_specs(models)
        _check_shared(ctx.args, [get_model_class(sp.partition(":")[0]) for sp in specs])
        s = _make_sun(sun_elevation, sun_azimuth, lat, lon, time, "spa")
        skies = [_model_spec(sp, ctx.args, s) for sp in specs]
        from skydome.render.plots import plot_compare

        plot_compare(skies, specs, out, relative=relative)
        typer.echo(f"wrote {out}")
    _run(go)


@app.command("compare", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def compare_cmd(
    ctx: typer.Context,
    models: str = typer.Option(..., help="Comma-separated model specs, e.g. single_scattering,kaneda1991,preetham1999:3."),
    sun_elevation: str = typer.Option("5,30,60", help="Comma-separated sun elevations [deg], -90..90."),
    sun_azimuth: float = typer.Option(180.0, help="Sun azimuth from north towards east [deg]."),
    reference: str = typer.Option("single_scattering", help="Model the others are measured against."),
    size: int = typer.Option(128, help="Fisheye size in pixels, 16..4096."),
    wavelengths: int = typer.Option(16, help="Number of wavelengths 380-780 nm, 3..401."),
    out: str = typer.Option(..., help="Output folder (created if missing): grid.png, error_*.png, table.md, table.csv."),
):
    """Render several models for several sun elevations and measure each against a reference.

    Options after the list (e.g. --turbidity 3) go to every model that has them.
    """
    def go():
        from skydome.compare import run_comparison
        from skydome.models import get_model_class

        specs = _split_specs(models)
        _check_shared(ctx.args, [get_model_class(sp.partition(":")[0]) for sp in specs + [reference]])
        get_model_class(reference)
        try:
            elevs = [float(v) for v in sun_elevation.split(",") if v.strip()]
        except ValueError:
            raise UserError(f"sun_elevation = {sun_elevation!r} is not a comma-separated list of numbers") from None
        progress = _Progress("comparing models")
        try:
            rows = run_comparison(specs, elevs, out, reference=reference, sun_azimuth_deg=sun_azimuth,
                                  size=size, wavelengths=wavelengths,
                                  build=lambda spec, sun: _model_spec(spec, ctx.args, sun),
                                  progress=progress)
        finally:
            progress.close()
        from skydome.compare import table_markdown

        typer.echo(table_markdown(rows, reference))
        typer.echo(f"wrote {out}/grid.png, error_*.png, table.md, table.csv")
    _run(go)


@app.command("timelapse", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def timelapse_cmd(
    ctx: typer.Context,
    lat: float = typer.Option(..., help="Latitude [deg], -90..90, north positive."),
    lon: float = typer.Option(..., help="Longitude [deg], -180..180, east positive."),
    date: str = typer.Option(..., help="Local date YYYY-MM-DD."),
    utc_offset: str = typer.Option("+00:00", help="UTC offset of the local times, e.g. +02:00."),
    every: str = typer.Option("10min", help="Time step: 10min, 1h, 30s (1 min .. 12 h)."),
    start: str = typer.Option("00:00", help="First local time HH:MM."),
    end: str = typer.Option("23:59", help="Last local time HH:MM."),
    min_elevation: float = typer.Option(-6.0, help="Render only while the sun is above this elevation [deg]."),
    model: str = typer.Option("single_scattering", help="Registered model name (see `skydome models`)."),
    projection: str = typer.Option("fisheye", help="fisheye, equirect, equirect-hemisphere or angular."),
    size: int = typer.Option(256, help="Frame size in pixels, 16..4096."),
    wavelengths: int = typer.Option(16, help="Number of wavelengths 380-780 nm, 3..401."),
    out: str = typer.Option(..., help="Output folder: frame_HHMM.png, contact_sheet.png, colours.png, colours.csv."),
):
    """The colour of the sky through a day: frames, a contact sheet and a colour-against-time plot.

    Model parameters are given as extra options, e.g. --turbidity 3.
    """
    def go():
        from skydome._validate import check_choice
        from skydome.effects.timelapse import day_times, parse_every, run_timelapse
        from skydome.models import get_model_class

        cls = get_model_class(model)
        params = _parse_model_params(cls, ctx.args)
        check_choice("projection", projection, PROJECTIONS)
        times = day_times(date, utc_offset, parse_every(every), start, end)
        progress = _Progress("timelapse")
        try:
            frames = run_timelapse(lambda sun: cls(sun=sun, **params), lat, lon, times, out,
                                   min_elevation_deg=min_elevation, size=size, wavelengths=wavelengths,
                                   projection=projection, progress=progress)
        finally:
            progress.close()
        done = [f for f in frames if f.image_path is not None]
        typer.echo(f"wrote {len(done)} frames ({done[0].time.strftime('%H:%M')}-{done[-1].time.strftime('%H:%M')}), "
                   f"contact_sheet.png, colours.png, colours.csv into {out}")
        skipped = [f for f in frames if f.image_path is None]
        if skipped:
            typer.echo(f"skipped {len(skipped)} frames the model refused: {skipped[0].note}")
    _run(go)


@app.command("polarisation")
def polarisation_cmd(
    sun_elevation: float = typer.Option(20.0, help="Sun elevation [deg], -90..90."),
    sun_azimuth: float = typer.Option(180.0, help="Sun azimuth from north towards east [deg], 0..360."),
    method: str = typer.Option("montecarlo", help="montecarlo (multiple scattering, aerosols) or rayleigh_single (analytic)."),
    size: int = typer.Option(48, help="Fisheye size in pixels, 4..1024."),
    samples: int = typer.Option(2000, help="Monte Carlo paths per pixel, 2..10^8."),
    seed: int = typer.Option(0, help="Monte Carlo seed, >= 0."),
    wavelength: float = typer.Option(550.0, help="Wavelength [nm], 300..1000."),
    turbidity: float = typer.Option(2.5, help="Turbidity of the atmosphere, 1..32."),
    out: str = typer.Option(..., help="Output figure (.png, .pdf or .svg): degree and angle of polarisation maps."),
    csv: Optional[str] = typer.Option(None, help="Also write the numbers per pixel to this .csv file."),
):
    """Maps of the degree and angle of polarisation of the sky (fisheye, north up, east left)."""
    def go():
        from pathlib import Path

        from skydome._validate import check_choice, check_int, check_number
        from skydome.effects.polarisation_maps import METHODS
        from skydome.sun import Sun

        _check_figure_path(out)
        if csv is not None:
            p = Path(csv)
            if p.suffix.lower() != ".csv":
                raise UserError(f"csv = {csv!r}: the file must end in .csv")
            if not p.parent.is_dir():
                raise UserError(f"csv = {csv!r}: folder {str(p.parent)!r} does not exist")
        check_choice("method", method, METHODS)
        check_int("size", size, 4, 1024)
        check_int("samples", samples, 2, 100_000_000)
        check_int("seed", seed, 0, 2 ** 63 - 1)
        check_number("wavelength", wavelength, 300.0, 1000.0, "nm")
        check_number("turbidity", turbidity, 1.0, 32.0)
        s = Sun(elevation_deg=check_number("sun_elevation", sun_elevation, -90.0, 90.0, "deg"),
                azimuth_deg=check_number("sun_azimuth", sun_azimuth, 0.0, 360.0, "deg"))
        from skydome.effects.polarisation_maps import plot_polarisation_maps, polarisation_maps, write_map_csv

        kw = dict(samples=samples, seed=seed) if method == "montecarlo" else {}
        pmap = polarisation_maps(method, s, size=size, wavelength_nm=wavelength, turbidity=turbidity, **kw)
        plot_polarisation_maps(pmap, out)
        if csv is not None:
            write_map_csv(pmap, csv)
        sky = pmap.mask & (pmap.dirs[..., 2] > 0)
        i = np.nanargmax(np.where(sky, pmap.dop, -1.0))
        typer.echo(f"maximum degree of polarisation {pmap.dop.flat[i]:.3f} at "
                   f"{np.degrees(np.arccos(np.clip(pmap.dirs.reshape(-1, 3)[i] @ s.direction, -1, 1))):.1f} deg "
                   f"from the sun; wrote {out}" + (f" and {csv}" if csv else ""))
    import numpy as np

    _run(go)


@app.command("twilight", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def twilight_cmd(
    ctx: typer.Context,
    model: str = typer.Option("precomputed", help="Model valid with the sun below the horizon (precomputed, single_scattering, montecarlo)."),
    step: float = typer.Option(2.0, help="Step in sun depression [deg], 0.25..9; the sequence runs 0..-18 deg."),
    size: int = typer.Option(192, help="Fisheye frame size in pixels, 16..2048."),
    wavelengths: int = typer.Option(16, help="Number of wavelengths 380-780 nm, 3..401."),
    exposure: str = typer.Option("auto", help="auto: each fisheye/horizon pair at its own automatic exposure; ramp: exposure makes up 80 % of the fall in log zenith luminance (frames darken visibly, by 10^1.4 over 0..-18 deg)."),
    out: str = typer.Option(..., help="Output folder: fisheye and horizon frames, contact_sheet.png, horizon_sheet.png, twilight.png, twilight.csv."),
):
    """Twilight: the sky for the sun from 0 to -18 deg, zenith luminance and illuminance against depression,
    the earth's shadow and the Belt of Venus opposite the sun.

    Model parameters are given as extra options, e.g. --turbidity 3.
    """
    def go():
        from skydome.effects.twilight import run_twilight
        from skydome.models import get_model_class

        cls = get_model_class(model)
        params = _parse_model_params(cls, ctx.args)
        progress = _Progress("twilight")
        try:
            res = run_twilight(out, model=model, step_deg=step, size=size, wavelengths=wavelengths,
                               exposure=exposure, progress=progress, **params)
        finally:
            progress.close()
        for d, z, e in zip(res["depression_deg"], res["zenith_luminance"], res["horizontal_illuminance"]):
            typer.echo(f"sun {-d + 0.0:6.2f} deg: zenith {z:.3g} cd/m^2, horizontal illuminance {e:.3g} lx")
        typer.echo(f"wrote frames, contact_sheet.png, horizon_sheet.png, twilight.png, twilight.csv into {out}")
    _run(go)


@app.command("airlight")
def airlight_cmd(
    image: Optional[str] = typer.Option(None, help="Input image: .png (sRGB) or .exr/.npy (linear), white-balanced to the sun."),
    depth: Optional[str] = typer.Option(None, help="Depth map [m]: .exr (Z, Y or R channel) or .npy; inf = sky."),
    synthetic: bool = typer.Option(False, "--synthetic", help="Use the generated synthetic mountain scene instead of --image/--depth."),
    sun_elevation: float = typer.Option(20.0, help="Sun elevation [deg]."),
    sun_azimuth: float = typer.Option(120.0, help="Sun azimuth from north towards east [deg]."),
    method: str = typer.Option("precomputed", help="precomputed, hillaire2020, preetham1999, hoffman_preetham2002 or dobashi2002."),
    turbidity: float = typer.Option(2.5, help="Turbidity of the air, 2..10 for the Preetham methods, 1..32 otherwise."),
    fov: float = typer.Option(60.0, help="Horizontal field of view of the (pinhole) camera [deg]."),
    view_azimuth: float = typer.Option(0.0, help="Azimuth the camera looks towards [deg] (horizontal view)."),
    white_balance: str = typer.Option("fixed", help="fixed: true colour relative to a white surface under the unattenuated sun (clear and hazy air on one scale); sun: output in the input's units (white = white card facing the sun)."),
    fill_sky: bool = typer.Option(False, "--fill-sky", help="Replace the sky pixels (depth inf) by the model's sky along their rays (not for dobashi2002)."),
    out: str = typer.Option(..., help="Output .png (sRGB; before/after sheet with --synthetic), .exr or .npy (linear)."),
):
    """Aerial perspective / airlight: extinction and in-scattered light over an image with a depth map."""
    def go():
        from skydome.effects.airlight import airlight_cli
        from skydome.sun import Sun

        sun = Sun(elevation_deg=sun_elevation, azimuth_deg=sun_azimuth)
        airlight_cli(image, depth, out, sun, method=method, turbidity=turbidity, fov_deg=fov,
                     view_azimuth_deg=view_azimuth, synthetic=synthetic, white_balance=white_balance,
                     fill_sky=fill_sky)
        typer.echo(f"wrote {out} ({method}, turbidity {turbidity:g})")
    _run(go)


@app.command("aureole")
def aureole_cmd(
    aerosol: str = typer.Option("earth", help="earth (turbidity 2, 4, 8), volcanic_ash (blue sun), forest_fire_smoke (blue sun) or bishops_ring (~1 um layer)."),
    sun_elevation: float = typer.Option(30.0, help="Sun elevation [deg], 1..90."),
    fov: float = typer.Option(50.0, help="Field of view of the close-up around the sun [deg], 2..120."),
    size: int = typer.Option(161, help="Close-up size in pixels, 16..1024."),
    out: str = typer.Option(..., help="Output folder: profile.png (radiance against angle from the sun), closeup.png, sun.txt."),
):
    """The aureole, Bishop's ring and the blue sun (survey 5.4-5.6): radiance around the sun with
    Lorenz-Mie aerosols, a close-up image and the sun's transmittance at 450 and 650 nm."""
    def go():
        import os
        import shutil
        import tempfile
        from pathlib import Path

        import numpy as np

        from skydome._validate import check_choice, check_int, check_number
        from skydome.atmosphere import Atmosphere
        from skydome.effects.aureole import (bishops_ring_atmosphere, plot_radiance_profiles,
                                             radiance_profile, render_closeup, sun_disc_radiance)
        from skydome.sun import Sun

        check_choice("aerosol", aerosol, ("earth", "volcanic_ash", "forest_fire_smoke", "bishops_ring"))
        elev = check_number("sun_elevation", sun_elevation, 1.0, 90.0, "deg")
        check_number("fov", fov, 2.0, 120.0, "deg")
        check_int("size", size, 16, 1024)
        o = Path(out)
        if not (o.parent if str(o.parent) else Path(".")).is_dir():
            raise UserError(f"out = {out!r}: folder {str(o.parent)!r} does not exist")
        sun = Sun(elevation_deg=elev, azimuth_deg=180.0)
        if aerosol == "earth":
            atms = [Atmosphere.earth(turbidity=t) for t in (2.0, 4.0, 8.0)]
            labels = ["turbidity 2", "turbidity 4", "turbidity 8"]
        elif aerosol == "bishops_ring":
            atms, labels = [Atmosphere.earth(turbidity=2.0), bishops_ring_atmosphere()], ["clear", "1 um layer"]
        else:
            make = getattr(Atmosphere, aerosol)
            atms, labels = [Atmosphere.earth(turbidity=2.0), make()], ["clear", aerosol.replace("_", " ")]
        ang = np.concatenate([np.linspace(1.0, 10.0, 19), np.linspace(11.0, 60.0, 25)])
        wl = np.array([450.0, 550.0, 650.0])
        prof = radiance_profile(atms, elev, ang, wl)
        tmp = Path(tempfile.mkdtemp(prefix=".skydome-aureole-", dir=o.parent if str(o.parent) else "."))
        try:
            plot_radiance_profiles(ang, [p[:, 1] for p in prof], labels, tmp / "profile.png",
                                   title=f"radiance at 550 nm against the angle from the sun (sun {elev:g} deg)")
            render_closeup(atms[-1], sun, fov_deg=fov, size=size).save(tmp / "closeup.png")
            lines = []
            for a, lab in zip(atms, labels):
                t = sun_disc_radiance(a, sun, wl) / sun_disc_radiance(Atmosphere.custom(rayleigh_scattering=0.0), sun, wl)
                lines.append(f"{lab}: sun transmittance T(450) = {t[0]:.4f}, T(650) = {t[2]:.4f}, "
                             f"T(450)/T(650) = {t[0] / t[2]:.3f}" + (" (blue sun)" if t[0] > t[2] else ""))
            (tmp / "sun.txt").write_text("\n".join(lines) + "\n")
            o.mkdir(exist_ok=True)
            for f in sorted(tmp.iterdir()):
                os.replace(f, o / f.name)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        for ln in lines:
            typer.echo(ln)
        typer.echo(f"wrote {out}/profile.png, closeup.png, sun.txt")
    _run(go)


def _split_specs(models: str) -> list[str]:
    """Split 'a:1,b,c:k=v,k2=v2' at commas that start a new model name."""
    from skydome.models import available

    names = set(available())
    specs: list[str] = []
    for part in models.split(","):
        part = part.strip()
        if not part:
            continue
        if part.partition(":")[0] in names or not specs or "=" not in part:
            specs.append(part)
        else:
            specs[-1] += "," + part
    if not specs:
        raise UserError("models is empty")
    return specs


def _check_figure_path(out: str) -> None:
    from pathlib import Path

    p = Path(out)
    if p.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UserError(f"out = {out!r}: figure must be .png, .pdf or .svg")
    if not p.parent.exists() or not p.parent.is_dir():
        raise UserError(f"out = {out!r}: folder {str(p.parent)!r} does not exist")
    import os

    if not os.access(p.parent, os.W_OK):
        raise UserError(f"out = {out!r}: folder {str(p.parent)!r} is not writable")


# `skydome validate ...` lives in its own module (imports nothing heavy until run)
from skydome.validation.cli import validate_app  # noqa: E402

app.add_typer(validate_app, name="validate")


def main() -> None:  # console-script entry point
    try:
        app()
    except KeyboardInterrupt:  # pragma: no cover
        sys.exit(130)


if __name__ == "__main__":  # pragma: no cover
    main()
