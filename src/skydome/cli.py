"""The ``skydome`` command line: a thin layer over the public API.

Every command validates all of its input before doing any work; a bad value prints one
line on stderr (``error: ...``) and exits with code 2, leaving nothing on disk.
"""

from __future__ import annotations

import re
import sys
import time as _time
from typing import Any, Optional

import typer
from typer.core import TyperGroup


def _given_value(args, opts) -> str | None:
    """The value given on the command line to the option spelled ``opts`` (last one wins)."""
    found = None
    for i, a in enumerate(args):
        for o in opts:
            if a == o and i + 1 < len(args):
                found = args[i + 1]
            elif a.startswith(o + "="):
                found = a[len(o) + 1:]
    return found


def _one_line(exc: Exception, args=()) -> str:
    """A usage error of the parser (typer/click) as one line: option, value, expected type."""
    param = getattr(exc, "param", None)
    opts = [o for o in getattr(param, "opts", ()) if o.startswith("--")]
    value = _given_value(list(args), opts) if opts else None
    if value is not None and type(exc).__name__ == "BadParameter":
        reason = " ".join(str(getattr(exc, "message", exc)).split()).lower()
        kind = ("an integer" if "integer" in reason else "a number" if "number" in reason or "float" in reason
                else None)
        if kind is not None:
            return f"{opts[0]} = {value!r} is not {kind}"
        return f"{opts[0]} = {value!r}: {reason.rstrip('.')}"
    msg = " ".join(str(exc.format_message() if hasattr(exc, "format_message") else exc).split())
    msg = msg.rstrip(".")
    return msg[:1].lower() + msg[1:]


class _OneLineGroup(TyperGroup):
    """The command group: parser errors (a non-numeric value, an unknown or missing option)
    are reported as one line ``error: ...`` on stderr with exit code 2, not a usage block."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        argv = list(sys.argv[1:] if args is None else args)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except typer.Abort:
            typer.echo("aborted", err=True)
            sys.exit(1)
        except typer.TyperException as exc:
            if type(exc).__name__ == "NoArgsIsHelpError":   # bare command: its help, as before
                exc.show()
                sys.exit(2)
            typer.echo(f"error: {_one_line(exc, argv)}", err=True)
            sys.exit(2)
        sys.exit(rv if isinstance(rv, int) and not isinstance(rv, bool) else 0)


def _version(value: bool) -> None:
    if value:
        from skydome import __version__

        typer.echo(f"skydome {__version__}")
        raise typer.Exit()


app = typer.Typer(cls=_OneLineGroup, add_completion=False, no_args_is_help=True, rich_markup_mode=None,
                  help="skydome: physically based daylight modelling (sky models, spectral sky images).")


@app.callback()
def _main_options(version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                               help="Print the version and exit.")) -> None:
    """skydome: physically based daylight modelling (sky models, spectral sky images)."""


PROJECTIONS = ("fisheye", "equirect", "equirect-hemisphere", "angular", "camera")
BOOL_WORDS = {"true": True, "yes": True, "1": True, "false": False, "no": False, "0": False}
AZIMUTH_RANGE = (-360.0, 360.0)   # [deg] every command's sun and view azimuths
# working copies of an image in a render and its conversion to a file: the spectral values
# (per direction and in the image), the spectrum -> XYZ products, and six 3-channel arrays
# (directions, XYZ, linear RGB, display values, the mask and the sun disc) [bytes per value 8]
MEMORY_SPECTRAL_COPIES = 3
MEMORY_RGB_COPIES = 6


class UserError(Exception):
    """Bad input: reported as one line on stderr with exit code 2."""


# internal parameter names that the CLI spells differently
_ALIASES = {"elevation_deg": "--sun-elevation", "azimuth_deg": "--sun-azimuth",
            "sun_elevation_deg": "--sun-elevation", "sun_azimuth_deg": "--sun-azimuth",
            "min_elevation_deg": "--min-elevation", "fov_deg": "--fov", "step_deg": "--step",
            "lat_deg": "--lat", "lon_deg": "--lon", "view_azimuth_deg": "--view-azimuth",
            "wavelength_nm": "--wavelength", "time": "--time", "out_dir": "--out"}
_LEAD = re.compile(r"^([a-z][a-z0-9_]*) = ")


def _current_options() -> tuple[set[str], bool]:
    """The long options of the running command, and whether it takes model options."""
    try:
        from typer._click.globals import get_current_context
    except ImportError:  # pragma: no cover - typer versions that use click itself
        from click import get_current_context
    ctx = get_current_context(silent=True)
    if ctx is None:
        return set(), False
    opts = {o for prm in ctx.command.params for o in getattr(prm, "opts", ()) if o.startswith("--")}
    return opts, bool(ctx.allow_extra_args)


_SUN_LEAD = re.compile(r"^sun[ .]elevation_deg(?= \(model | = )")


def _name_option(message: str) -> str:
    """Spell a leading ``name = value`` as the command's option ``--name = value`` (and a
    model's refusal of the sun's elevation as ``--sun-elevation``)."""
    if _SUN_LEAD.match(message) and "--sun-elevation" in _current_options()[0]:
        return _SUN_LEAD.sub("--sun-elevation", message, count=1)
    m = _LEAD.match(message)
    if not m:
        return message
    name = m.group(1)
    opts, extra = _current_options()
    dashed = "--" + name.replace("_", "-")
    if dashed in opts:
        opt = dashed
    elif _ALIASES.get(name) in opts:
        opt = _ALIASES[name]
    elif extra and name not in _ALIASES:
        opt = dashed            # a model option given as --name value
    else:
        return message
    return opt + message[len(name):]


def _fail(message: str) -> None:
    line = " ".join(_name_option(str(message)).split())
    typer.echo(f"error: {line}", err=True)
    raise typer.Exit(code=2)


def _run(func, *args, **kwargs):
    """Call ``func`` turning bad input (ValueError, TypeError, a missing file) and failed
    writes (a full disk, a read-only folder) into one line on stderr and exit code 2."""
    try:
        return func(*args, **kwargs)
    except (UserError, ValueError, TypeError, FileNotFoundError, KeyError) as exc:
        msg = exc.args[0] if exc.args else str(exc)
        _fail(str(msg))
    except MemoryError:
        _fail("out of memory: try a smaller --size or fewer --wavelengths")
    except OSError as exc:
        where = f" {exc.filename!r}" if getattr(exc, "filename", None) else ""
        _fail(f"could not write{where}: {exc.strerror or exc}")


def _available_memory() -> int:
    """Memory the process may use [bytes]: MemAvailable of /proc/meminfo, else the free
    physical pages; the SKYDOME_MEMORY_LIMIT environment variable (bytes) caps it."""
    import os

    avail = None
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    avail = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        pass
    if avail is None:
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError, AttributeError):  # pragma: no cover
            avail = 2 ** 62
    cap = os.environ.get("SKYDOME_MEMORY_LIMIT")
    if cap:
        try:
            avail = min(avail, int(float(cap)))
        except ValueError:
            raise UserError(f"SKYDOME_MEMORY_LIMIT = {cap!r} is not a number of bytes") from None
    return avail


def image_memory_bytes(n_pixels: int, n_channels: int, held_images: int = 0) -> int:
    """Estimated peak memory [bytes] of rendering and writing an image of ``n_pixels``
    pixels with ``n_channels`` values each, while ``held_images`` earlier images of that size
    are kept: pixels x 8 bytes x (3 copies of the channels + 6 three-channel arrays), plus
    pixels x channels x 8 bytes per held image."""
    n, c = int(n_pixels), int(n_channels)
    return n * 8 * (MEMORY_SPECTRAL_COPIES * c + 3 * MEMORY_RGB_COPIES) + int(held_images) * n * c * 8


def _check_memory(option: str, value, n_pixels: int, n_channels: int, held_images: int = 0) -> None:
    need = image_memory_bytes(n_pixels, n_channels, held_images)
    avail = _available_memory()
    if need > avail:
        what = f"{held_images + 1} images need" if held_images else "the image needs"
        raise UserError(f"{option} = {value}: {what} about {need / 2 ** 30:.1f} GiB of memory "
                        f"({n_pixels} pixels x {n_channels} channels x 8 bytes x working copies), more "
                        f"than the {avail / 2 ** 30:.1f} GiB available; give a smaller size")


def _check_azimuth(option: str, value) -> float:
    from skydome._validate import check_number

    try:
        return check_number(option, value, *AZIMUTH_RANGE, "deg")
    except ValueError as exc:
        raise UserError(str(exc)) from None


# -- helpers --------------------------------------------------------------------------------
def _make_sun(sun_elevation, sun_azimuth, lat, lon, time, sun_method):
    from skydome.sun import sun_from_options

    try:
        return sun_from_options(sun_elevation, sun_azimuth, lat, lon, time, sun_method,
                                option_prefix="--")
    except ValueError as exc:
        raise UserError(str(exc)) from None


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
                if value.lower() not in BOOL_WORDS:
                    raise UserError(f"--{key} = {value!r} is not a boolean: give true, false, yes, no, 1 or 0")
                out[name] = BOOL_WORDS[value.lower()]
            else:
                out[name] = value
        except ValueError:
            raise UserError(f"--{key} = {value!r} is not a valid {p.kind}") from None
        i += 1
    return out


class _Progress:
    """A rich progress bar on stderr that appears only once the work has run for a second.

    Called as ``progress(done, total)`` (a render's chunks) or, as the reporter of
    :mod:`skydome._progress`, ``progress(stage, done, total)`` (precomputation, table builds);
    each new stage restarts the bar under its own label."""

    def __init__(self, label: str):
        self.label = label
        self.t0 = _time.perf_counter()
        self.bar = None
        self.task = None
        self.stage = None

    def __call__(self, *args) -> None:
        if len(args) == 3:
            stage, done, total = args
        else:
            (done, total), stage = args, self.label
        if self.bar is None:
            if _time.perf_counter() - self.t0 < 1.0 or done >= total:
                return
            from rich.console import Console
            from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

            self.bar = Progress(TextColumn("{task.description}"), BarColumn(),
                                TextColumn("{task.percentage:>3.0f}%"), TimeRemainingColumn(),
                                console=Console(stderr=True), transient=True)
            self.bar.start()
        if stage != self.stage or self.task is None:
            if self.task is not None:
                self.bar.remove_task(self.task)
            self.task = self.bar.add_task(stage, total=total)
            self.stage = stage
        self.bar.update(self.task, completed=done, total=total)

    def close(self):
        if self.bar is not None:
            self.bar.stop()


def _build_model(cls, progress: "_Progress", **kwargs):
    """Construct a model, showing the progress its set-up reports (precomputed tables...)."""
    from skydome._progress import reporting

    with reporting(progress):
        return cls(**kwargs)


def _check_date(value: str) -> str:
    import datetime as dt

    try:
        dt.date.fromisoformat(value)
    except (ValueError, TypeError):
        raise UserError(f"date = {value!r} is not a date: give YYYY-MM-DD, e.g. 2026-06-21") from None
    if not re.fullmatch(r"\d{4}-\d{2}-\d{2}", value):
        raise UserError(f"date = {value!r} is not a date: give YYYY-MM-DD, e.g. 2026-06-21")
    return value


def _check_clock(name: str, value: str) -> str:
    m = re.fullmatch(r"(\d{2}):(\d{2})", value)
    if not m or int(m.group(1)) > 23 or int(m.group(2)) > 59:
        raise UserError(f"{name} = {value!r} is not a local time: give HH:MM from 00:00 to 23:59")
    return value


def _check_utc_offset(value: str) -> str:
    m = re.fullmatch(r"([+-])(\d{2}):(\d{2})", value)
    if not m or int(m.group(3)) > 59 or int(m.group(2)) * 60 + int(m.group(3)) > 14 * 60:
        raise UserError(f"utc_offset = {value!r} is not a UTC offset: give +HH:MM or -HH:MM "
                        "from -14:00 to +14:00, e.g. +02:00")
    return value


# -- commands ----------------------------------------------------------------------------------
@app.command(context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def render(
    ctx: typer.Context,
    model: str = typer.Option("precomputed", help="Registered model name (see `skydome models`); the default is the accurate multiple-scattering sky."),
    out: str = typer.Option(..., help="Output file: .exr (float, linear), .hdr (Radiance RGBE) or .png (tone mapped)."),
    sun_elevation: Optional[float] = typer.Option(None, help="Sun elevation above the horizon [deg], -90..90 (default 30)."),
    sun_azimuth: Optional[float] = typer.Option(None, help="Sun azimuth from north towards east [deg], -360..360 (default 180)."),
    lat: Optional[float] = typer.Option(None, help="Latitude [deg], -90..90, north positive (with --lon and --time)."),
    lon: Optional[float] = typer.Option(None, help="Longitude [deg], -180..180, east positive."),
    time: Optional[str] = typer.Option(None, help="ISO 8601 time with UTC offset, e.g. 2026-06-21T20:45+02:00."),
    sun_method: str = typer.Option("spa", help="Solar position algorithm: spa (NREL SPA via pvlib) or preetham1999."),
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
):
    """Render a sky model into an image file.

    Model parameters are given as extra options, e.g. `--turbidity 3` or `--sky-type 12`
    (see `skydome models` for each model's options, units and ranges).
    """
    _run(_render, ctx.args, model, out, sun_elevation, sun_azimuth, lat, lon, time, sun_method,
         projection, size, wavelengths, exposure, tonemap, bits, not no_sun, ev100, sun_light,
         not no_hunt)


def _render(extra, model, out, sun_elevation, sun_azimuth, lat, lon, time, sun_method, projection,
            size, wavelengths, exposure, tonemap, bits, draw_sun, ev100=None, sun_light=None,
            hunt=True):
    from skydome._io import check_output_file
    from skydome._validate import check_choice, check_int, check_number
    from skydome.models import get_model_class
    from skydome.render import make_projection, render as render_sky
    from skydome.render.image import check_output_path
    from skydome.spectra import wavelength_grid

    # 1. validate everything before any work
    cls = get_model_class(model)
    params = _parse_model_params(cls, extra)
    check_choice("projection", projection, PROJECTIONS)
    from skydome.render.display import DISPLAY_TRANSFORMS

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
    sun = _make_sun(sun_elevation, sun_azimuth, lat, lon, time, sun_method)
    n_channels = wavelengths if cls.native == "spectral" else 3
    if projection == "camera":
        if not hasattr(cls, "default_projection"):
            raise UserError(f"projection = 'camera' needs a model with its own camera "
                            f"(e.g. nishita1993); model {model!r} has none")
        from skydome.render.projections import _parse_size

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


cache_app = typer.Typer(no_args_is_help=True,
                        help="The on-disk cache of the precomputed model's tables.")
app.add_typer(cache_app, name="cache")


@cache_app.command("info")
def cache_info():
    """Where the cache is, its entries, their total size and the size limit."""
    from skydome.models.simulated.precomputed import _cache

    entries = _cache._entries(_cache.cache_dir())
    total = sum(size for _, size, _ in entries)
    typer.echo(f"folder   {_cache.cache_dir()}")
    typer.echo(f"entries  {len(entries)} table sets, {total / 2**20:.1f} MiB")
    typer.echo(f"limit    {_run(_cache.limit_bytes) / 2**20:.0f} MiB "
               "(SKYDOME_CACHE_LIMIT_BYTES; least recently used sets go first)")


@cache_app.command("clear")
def cache_clear():
    """Remove every cached table set (the next run precomputes again)."""
    from skydome.models.simulated.precomputed import clear_cache

    freed = _run(clear_cache)
    typer.echo(f"cleared {freed / 2**20:.1f} MiB")


plot_app = typer.Typer(no_args_is_help=True, help="Figures: luminance maps and model comparisons.")
app.add_typer(plot_app, name="plot")


def _model_spec(spec: str, shared: list[str], sun, check_only: bool = False):
    """Build a model from 'name' or 'name:value' (value for the model's first option) or
    'name:key=value,key=value', with shared '--key value' options applied where the model
    has that option; ``check_only``: validate those parameters and build nothing."""
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
    if check_only:
        cls._validate_params(dict(params))
        return None
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
    sun_azimuth: Optional[float] = typer.Option(None, help="Sun azimuth from north towards east [deg], -360..360 (default 180)."),
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
    sun_azimuth: Optional[float] = typer.Option(None, help="Sun azimuth from north towards east [deg], -360..360 (default 180)."),
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
    sun_azimuth: float = typer.Option(180.0, help="Sun azimuth from north towards east [deg], -360..360."),
    reference: str = typer.Option("precomputed", help="Model the others are measured against (default: the accurate multiple-scattering sky)."),
    size: int = typer.Option(128, help="Fisheye size in pixels, 16..4096."),
    wavelengths: int = typer.Option(16, help="Number of wavelengths 380-780 nm, 3..401."),
    out: str = typer.Option(..., help="Output folder (created if missing): grid.png, error_*.png, table.md, table.csv."),
):
    """Render several models for several sun elevations and measure each against a reference.

    Options after the list (e.g. --turbidity 3) go to every model that has them.
    """
    def go():
        from skydome.apps.compare import run_comparison
        from skydome.models import get_model_class

        from skydome._io import check_output_folder
        from skydome._validate import check_int, check_number

        from skydome.models import available

        check_output_folder(out)
        if reference not in available():
            raise UserError(f"reference = {reference!r} is not a registered model (see skydome models)")
        specs = _split_specs(models)
        classes = [get_model_class(sp.partition(":")[0]) for sp in specs + [reference]]
        _check_shared(ctx.args, classes)
        for sp in specs + [reference]:   # every model's options, before any model is built
            _model_spec(sp, ctx.args, None, check_only=True)
        try:
            elevs = [float(v) for v in sun_elevation.split(",") if v.strip()]
        except ValueError:
            raise UserError(f"sun_elevation = {sun_elevation!r} is not a comma-separated list of numbers") from None
        if not elevs:
            raise UserError(f"sun_elevation = {sun_elevation!r} is empty: give at least one sun elevation")
        for e in elevs:
            check_number("sun_elevation", e, -90.0, 90.0, "deg")
        _check_azimuth("sun_azimuth", sun_azimuth)
        check_int("size", size, 16, 4096)
        check_int("wavelengths", wavelengths, 3, 401)
        _check_memory("size", size, size * size, max(wavelengths if c.native == "spectral" else 3 for c in classes))
        progress = _Progress("comparing models")
        try:
            rows = run_comparison(specs, elevs, out, reference=reference, sun_azimuth_deg=sun_azimuth,
                                  size=size, wavelengths=wavelengths,
                                  build=lambda spec, sun: _model_spec(spec, ctx.args, sun),
                                  progress=progress)
        finally:
            progress.close()
        from skydome.apps.compare import table_markdown

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
    model: str = typer.Option("precomputed", help="Registered model name (see `skydome models`); the default is the accurate multiple-scattering sky."),
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
        from skydome.apps.timelapse import day_times, parse_every, run_timelapse
        from skydome.models import get_model_class

        from skydome._io import check_output_folder
        from skydome._validate import check_int, check_number

        check_output_folder(out)
        cls = get_model_class(model)
        params = _parse_model_params(cls, ctx.args)
        cls._validate_params(dict(params))
        check_choice("projection", projection, PROJECTIONS[:-1])
        check_number("lat", lat, -90.0, 90.0, "deg")
        check_number("lon", lon, -180.0, 180.0, "deg")
        check_number("min_elevation", min_elevation, -90.0, 90.0, "deg")
        check_int("size", size, 16, 4096)
        check_int("wavelengths", wavelengths, 3, 401)
        times = day_times(_check_date(date), _check_utc_offset(utc_offset), parse_every(every),
                          _check_clock("start", start), _check_clock("end", end))
        from skydome.sun import solar_position

        import numpy as np

        el = np.atleast_1d(solar_position(lat, lon, times)[0])
        _check_memory("size", size, size * size, wavelengths if cls.native == "spectral" else 3,
                      held_images=max(int(np.sum(el >= min_elevation)) - 1, 0))
        progress = _Progress("timelapse")
        try:
            frames = run_timelapse(lambda sun: _build_model(cls, progress, sun=sun, **params), lat, lon, times, out,
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
    sun_azimuth: float = typer.Option(180.0, help="Sun azimuth from north towards east [deg], -360..360."),
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
                azimuth_deg=_check_azimuth("sun_azimuth", sun_azimuth))
        from skydome.apps.polarisation import run_polarisation

        dop, angle = run_polarisation(out, s, method=method, csv=csv, size=size, samples=samples, seed=seed,
                                      wavelength_nm=wavelength, turbidity=turbidity)
        typer.echo(f"maximum degree of polarisation {dop:.3f} at {angle:.1f} deg from the sun; wrote {out}"
                   + (f" and {csv}" if csv else ""))
    _run(go)


@app.command("twilight", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def twilight_cmd(
    ctx: typer.Context,
    model: str = typer.Option("precomputed", help="Model valid with the sun below the horizon (precomputed, single_scattering, montecarlo)."),
    step: float = typer.Option(2.0, help="Step in sun depression [deg], 0.25..9; the sequence runs 0..-18 deg."),
    size: int = typer.Option(192, help="Fisheye frame size in pixels, 16..2048."),
    wavelengths: int = typer.Option(16, help="Number of wavelengths 380-780 nm, 3..401."),
    exposure: str = typer.Option("ramp", help="ramp (default): exposure makes up 80 % of the fall in log zenith luminance (frames darken frame by frame, by 10^1.4 over 0..-18 deg); one: the first frame's exposure for all; auto: each frame its own (not faithful)."),
    out: str = typer.Option(..., help="Output folder: fisheye and horizon frames, contact_sheet.png, horizon_sheet.png, twilight.png, twilight.csv."),
):
    """Twilight: the sky for the sun from 0 to -18 deg, zenith luminance and illuminance against depression,
    the earth's shadow and the Belt of Venus opposite the sun.

    Model parameters are given as extra options, e.g. --turbidity 3.
    """
    def go():
        from skydome.apps.twilight import run_twilight
        from skydome.models import get_model_class

        from skydome._io import check_output_folder
        from skydome._progress import reporting
        from skydome._validate import check_int

        check_output_folder(out)
        cls = get_model_class(model)
        params = _parse_model_params(cls, ctx.args)
        cls._validate_params(dict(params))
        lo, hi = cls.sun_elevation_range_deg
        if not (lo <= -18.0 and hi >= 0.0) and cls.sun_outside_range == "raise":
            raise UserError(f"--model = {model!r} does not cover the sun from 0 to -18 deg "
                            f"(its range is [{lo:g}, {hi:g}] deg)")
        check_int("size", size, 16, 2048)
        check_int("wavelengths", wavelengths, 3, 401)
        _check_memory("size", size, size * size, wavelengths if cls.native == "spectral" else 3)
        progress = _Progress("twilight")
        try:
            with reporting(progress):
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
    sun_azimuth: float = typer.Option(120.0, help="Sun azimuth from north towards east [deg], -360..360."),
    method: str = typer.Option("precomputed", help="precomputed, hillaire2020, preetham1999, hoffman_preetham2002 or dobashi2002."),
    turbidity: float = typer.Option(2.5, help="Turbidity of the air, 2..10 for the Preetham methods, 1..32 otherwise."),
    fov: float = typer.Option(60.0, help="Horizontal field of view of the (pinhole) camera [deg]."),
    view_azimuth: float = typer.Option(0.0, help="Azimuth the camera looks towards [deg], -360..360 (horizontal view)."),
    white_balance: str = typer.Option("fixed", help="fixed: true colour relative to a white surface under the unattenuated sun (clear and hazy air on one scale); sun: output in the input's units (white = white card facing the sun)."),
    fill_sky: bool = typer.Option(False, "--fill-sky", help="Replace the sky pixels (depth inf) by the model's sky along their rays (not for dobashi2002)."),
    out: str = typer.Option(..., help="Output .png (sRGB; before/after sheet with --synthetic), .exr or .npy (linear)."),
):
    """Aerial perspective / airlight: extinction and in-scattered light over an image with a depth map."""
    def go():
        from skydome._io import check_output_file
        from skydome._validate import check_number
        from skydome.apps.airlight import airlight_cli
        from skydome.sun import Sun

        check_output_file(out, (".png", ".exr", ".npy"))
        sun = Sun(elevation_deg=check_number("sun_elevation", sun_elevation, -90.0, 90.0, "deg"),
                  azimuth_deg=_check_azimuth("sun_azimuth", sun_azimuth))
        _check_azimuth("view_azimuth", view_azimuth)
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
        from skydome.apps.aureole import run_aureole

        for ln in run_aureole(out, aerosol=aerosol, sun_elevation_deg=sun_elevation, fov_deg=fov, size=size):
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


from skydome.viewer.cli import view as _view  # noqa: E402 - `skydome view`, its own module

app.command("view")(_view)
from skydome.export.cli import export_app  # noqa: E402  (environment maps, sun lights)

app.add_typer(export_app, name="export")
from skydome.daylighting.cli import register as _register_daylighting  # noqa: E402

_register_daylighting(app)
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
