"""The command line's shared kit: errors as one line, the progress bar, the model and sun
options declared once, model building, the checks every command uses.

Every command validates all of its input before doing any work; a bad value prints one
line on stderr (``error: ...``) and exits with code 2, leaving nothing on disk. The kit
imports typer and the library's light modules only; the commands import the heavy ones
inside their bodies.
"""

from __future__ import annotations

import inspect
import re
import sys
import time as _time
from typing import Any, Optional

import typer
from typer.core import TyperGroup

#: context settings of a command that takes a model's parameters as extra ``--name value``
EXTRA = {"allow_extra_args": True, "ignore_unknown_options": True}

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


# (long options, takes model options) of a command run without typer's parser
# (:mod:`skydome.cli.render_fast`), for the error lines of :func:`_run`
_FAST_COMMAND: tuple[set[str], bool] | None = None


def _current_options() -> tuple[set[str], bool]:
    """The long options of the running command, and whether it takes model options."""
    try:
        from typer._click.globals import get_current_context
    except ImportError:  # pragma: no cover - typer versions that use click itself
        from click import get_current_context
    ctx = get_current_context(silent=True)
    if ctx is None:
        return _FAST_COMMAND if _FAST_COMMAND is not None else (set(), False)
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
    finally:
        # a table cache entry written beside the command's work (_build_model) is complete
        # when the command returns
        cache = sys.modules.get("skydome.models.simulated.precomputed._cache")
        if cache is not None:
            cache.wait_for_writes()


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


# -- the sun options, declared once ----------------------------------------------------------
# name -> (what it is, unit, valid range or None, what follows the range); every command that
# places the sun spells, documents and checks these the same way (skydome.sun.sun_from_options
# checks the same ranges)
SUN_OPTIONS = {
    "sun_elevation": ("Sun elevation above the horizon", "deg", (-90.0, 90.0), ""),
    "sun_azimuth": ("Sun azimuth from north towards east", "deg", AZIMUTH_RANGE, ""),
    "lat": ("Latitude", "deg", (-90.0, 90.0), ", north positive"),
    "lon": ("Longitude", "deg", (-180.0, 180.0), ", east positive"),
    "time": ("ISO 8601 time with UTC offset, e.g. 2026-06-21T20:45+02:00", "", None, ""),
    "sun_method": ("Solar position algorithm: spa (NREL SPA via pvlib) or preetham1999", "",
                   None, ""),
}
# the sun of a command given neither angles nor a place (skydome.sun.sun_from_options)
_SUN_DEFAULTS = {"sun_elevation": 30.0, "sun_azimuth": 180.0}
_PLACE_NOTE = {"lat": " (with --lon and --time)", "time": " (with --lat and --lon)"}


def sun_option(name: str, default: Any = None, *, spelling: Optional[str] = None,
               low: Optional[float] = None, many: bool = False):
    """The typer option of the sun option ``name`` (a key of :data:`SUN_OPTIONS`) with the
    command's ``default`` (``...``: required; None: the sun by angles defaults to 30 deg high
    in the south, or by place); ``low`` narrows the range's lower end for a command whose
    physics needs it, ``many`` takes a comma-separated list, ``spelling`` another option
    name than ``--name``."""
    what, unit, rng, after = SUN_OPTIONS[name]
    if many:
        what = what.replace("Sun elevation", "Comma-separated sun elevations")
    text = what + (f" [{unit}]" if unit else "")
    if rng is not None:
        text += f", {rng[0] if low is None else low:g}..{rng[1]:g}"
    text += after
    if default is None and name in _SUN_DEFAULTS:
        text += f" (default {_SUN_DEFAULTS[name]:g})"
    elif default is None:
        text += _PLACE_NOTE.get(name, "")
    return typer.Option(default, *([spelling] if spelling else []), help=text + ".")


# the annotations of the sun options
_SUN_TYPES = {"sun_elevation": Optional[float], "sun_azimuth": Optional[float],
              "lat": Optional[float], "lon": Optional[float], "time": Optional[str],
              "sun_method": str}
SUN_BY_ANGLES_OR_PLACE = tuple(SUN_OPTIONS)


def _add_options(command, options: dict):
    """Give a command declared with ``**kwargs`` the options ``{name: (annotation, typer
    option)}`` after its own (typer reads the parameters from the signature and the
    annotations; the command gets them in its ``**kwargs``)."""
    kw = inspect.Parameter.KEYWORD_ONLY
    sig = inspect.signature(command)
    params = [p for p in sig.parameters.values() if p.kind != inspect.Parameter.VAR_KEYWORD]
    params += [inspect.Parameter(n, kw, default=marker, annotation=ann)
               for n, (ann, marker) in options.items()]
    command.__signature__ = sig.replace(parameters=params)
    command.__annotations__ = {**command.__annotations__,
                               **{n: ann for n, (ann, _) in options.items()}}
    return command


def sun_options(*names: str, **defaults):
    """Give a command declared with ``**sun`` the sun options ``names`` and those given
    ``defaults`` (without either, all of :data:`SUN_OPTIONS`: --sun-elevation, --sun-azimuth,
    --lat, --lon, --time, --sun-method), each declared by :func:`sun_option` with the
    command's default (else None: the sun by angles or by place); the command gets them in
    ``sun`` (a dict), for :func:`_sun_from`."""
    names = names + tuple(defaults) or SUN_BY_ANGLES_OR_PLACE
    defaults = {"sun_method": "spa", **defaults}

    def add(command):
        return _add_options(command, {n: (_SUN_TYPES[n], sun_option(n, defaults.get(n)))
                                      for n in names})
    return add


#: --connect-timeout's default [s]: skydome.distributed.CONNECT_TIMEOUT_S (not imported here:
#: the kit imports the light modules only)
CONNECT_TIMEOUT_DEFAULT = 10.0


def connect_timeout_option():
    """--connect-timeout, declared once beside --scheduler (:func:`dask_options` and the
    ``skymatrix`` command): ``connect_timeout_s`` of :func:`skydome.distributed.run_chunks`,
    checked by :func:`_check_dask` (0 < t <= 3600 s)."""
    return typer.Option(CONNECT_TIMEOUT_DEFAULT, "--connect-timeout",
                        help="Seconds to wait for --scheduler to answer, 0 < t <= 3600.")


def dask_options(what: str):
    """Give a command declared with ``**dask`` the options --scheduler, --connect-timeout
    and --workers: its pieces of work (``what``) as Dask tasks on a cluster or on local
    processes; the command gets them in ``dask`` (a dict), for :func:`_dask_choice`."""
    def add(command):
        return _add_options(command, {
            "scheduler": (Optional[str], typer.Option(
                None, help=f"Render {what} as tasks on this Dask cluster (tcp://HOST:8786).")),
            "connect_timeout": (float, connect_timeout_option()),
            "workers": (int, typer.Option(
                0, help=f"Render {what} on a local Dask cluster of N processes (0: in "
                        "process)."))})
    return add


def _check_dask(scheduler, connect_timeout) -> tuple:
    """(scheduler, connect_timeout) checked before any work: the scheduler's address
    (:func:`skydome.distributed.check_scheduler`, syntax only) and the timeout in (0, 3600] s
    (the range ``connect_timeout_s`` of :func:`skydome.distributed.run_chunks` takes)."""
    from skydome._validate import check_number

    if scheduler is not None:
        from skydome.distributed import check_scheduler

        scheduler = check_scheduler(scheduler)
    return scheduler, check_number("connect_timeout", connect_timeout, 0.0, 3600.0, "s",
                                   low_open=True)


def _dask_choice(dask: dict) -> tuple:
    """(scheduler, workers, whether Dask runs the work, connect timeout [s]) of
    :func:`dask_options`, checked."""
    scheduler, workers = dask.get("scheduler"), dask.get("workers", 0)
    if workers < 0:
        raise ValueError(f"workers = {workers} is out of range [0, inf)")
    scheduler, timeout = _check_dask(scheduler, dask.get("connect_timeout",
                                                         CONNECT_TIMEOUT_DEFAULT))
    return scheduler, workers, scheduler is not None or workers > 0, timeout


def _check_sun_option(name: str, value) -> float:
    """``value`` of the sun option ``name`` checked against its declared range."""
    from skydome._validate import check_number

    _, unit, (low, high), _ = SUN_OPTIONS[name]
    try:
        return check_number(name, value, low, high, unit)
    except ValueError as exc:
        raise UserError(str(exc)) from None


def _sun_from(sun: dict):
    """The Sun of the options gathered by :func:`sun_options` (checked, before any work)."""
    return _make_sun(*(sun.get(n, "spa" if n == "sun_method" else None)
                       for n in SUN_BY_ANGLES_OR_PLACE))


# -- helpers --------------------------------------------------------------------------------
def _make_sun(sun_elevation, sun_azimuth, lat, lon, time, sun_method):
    from skydome.sun import sun_from_options

    try:
        return sun_from_options(sun_elevation, sun_azimuth, lat, lon, time, sun_method,
                                option_prefix="--")
    except ValueError as exc:
        raise UserError(str(exc)) from None


def _folder_model(out: str, model: str, extra: list[str]):
    """(model class, keyword parameters) of a folder-writing command: the output folder
    checked first, then the model name and its extra ``--name value`` options, validated
    against the model's declarations (all before any work)."""
    from skydome._io import check_output_folder
    from skydome.models import get_model_class

    check_output_folder(out)
    cls = get_model_class(model)
    params = _parse_model_params(cls, extra)
    cls._validate_params(dict(params))
    return cls, params


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


def _param_options(items) -> list[str]:
    """``--param NAME=VALUE`` items as the ``--name value`` options of
    :func:`_parse_model_params` (the one parser of a model's parameters)."""
    out: list[str] = []
    for item in items:
        name, eq, value = str(item).partition("=")
        if not eq or not name.strip():
            raise UserError(f"param = {item!r} must be NAME=VALUE")
        out += ["--" + name.strip().replace("_", "-"), value.strip()]
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
    """Construct a model, showing the progress its set-up reports (precomputed tables...).

    numba's target is started without SciPy's BLAS probe (0.25-0.3 s of a command's
    start-up; :mod:`skydome._numba_start`): a command line process runs skydome's kernels,
    none of which needs it. The start (about 0.5 s of CPU, Python holding the interpreter
    lock) runs on a second thread while the model is constructed: a cached precomputed
    model reads and decodes its tables meanwhile (file reads, CRC-32, NumPy, which release
    the lock), so that on two cores the two overlap; a model whose construction calls a
    kernel waits for the start there (numba's import and compiler locks)."""
    import contextlib

    from skydome._numba_start import start_numba_in_background
    from skydome._progress import reporting

    # a new precomputed atmosphere's cache entry is written on a thread beside the command's
    # next steps (the render, the picture), and complete before the command ends (_run
    # waits for it; the interpreter would too); the table cache's module is not imported
    # for a model that does not use it
    writes = contextlib.nullcontext()
    cache_module = "skydome.models.simulated.precomputed._cache"
    if (cls.__module__.startswith("skydome.models.simulated.precomputed")
            or cache_module in sys.modules):
        import importlib

        writes = importlib.import_module(cache_module).background_writes()
    start = start_numba_in_background()
    try:
        with reporting(progress), writes:
            return cls(**kwargs)
    finally:
        if start is not None:
            start.join()


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



def _sky(model, extra, sun: dict, check=None, progress=None):
    """The model and sun options of a command, validated before any work: the model class
    and its ``--name value`` parameters, then ``check()`` (the command's own options), then
    the sun (the options of :func:`sun_options`); returns the constructed sky (its set-up's
    progress shown on ``progress`` when given)."""
    from skydome._numba_start import start_numba_in_background
    from skydome.models import get_model_class

    cls = get_model_class(model)
    params = _parse_model_params(cls, extra)
    if check is not None:
        check()
    position = _sun_from(sun)
    if progress is None:
        # numba's start on a second thread while the model is constructed, as in
        # _build_model: a fitted model reads its coefficient file meanwhile (zlib and file
        # reads release the interpreter lock)
        start = start_numba_in_background()
        try:
            return cls(sun=position, **params)
        finally:
            if start is not None:
                start.join()
    return _build_model(cls, progress, sun=position, **params)
