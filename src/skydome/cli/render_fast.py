"""``skydome render`` and ``skydome export envmap`` for a plain command line, without
building the typer application.

typer (0.29) builds the command line's whole application (27 commands) and, for each option
of the command it runs, a pydantic ``TypeAdapter`` that converts its value: for ``skydome
render`` (19 options) that and the imports it needs (pydantic's validators, typing
introspection, ``importlib.metadata`` for pydantic's plugins) were 0.15-0.2 s of CPU of a
warm ``skydome render --sun-elevation 30 --out x.png`` (about 2 s) on a 2-core EPYC
(docs/performance.md). :func:`fast_render`, which ``skydome`` (:mod:`skydome.__main__`) tries
first for a ``render`` command line, reads the command's options from the signature of the
typer command :func:`skydome.cli.render.render` (names, types, defaults: one declaration) and
parses a plain command line itself: each option of that command at most once, spelled
``--name value`` (a flag alone), a number written as plain decimal digits, and a model's own
options as ``--name value`` pairs (e.g. ``--turbidity 3``: a name that is not the command's,
a value that does not start with ``-``), passed on in their order as typer passes them (the
command's extra arguments; the model's parameter parser reads them in both cases). It then
calls the command's own work (:func:`skydome.cli.render._render` through
:func:`skydome.cli._kit._run`) with the values typer would have passed, so that the work, its
output and its errors (one line on stderr naming the option, exit code 2) are the same.
Anything else (help, ``--name=value``, a repeated option of the command, a value it does not
read as plainly valid) goes to the typer command, untouched: the fast path prints nothing and
does nothing before it has decided to take the command line.

:func:`fast_export_envmap` does the same for ``skydome export envmap`` (its typer command
:func:`skydome.cli.export.envmap`, its work :func:`skydome.cli.export._envmap`); a model's own
options, which that command passes on to the model, are taken there as ``--name value`` (a
value that does not start with ``-``) and handed on in their order as typer hands them on
(``ctx.args``), to be checked by the same parser of model options.
"""

from __future__ import annotations

import inspect
import re

# a number as every parser reads it alike: decimal digits, an optional fraction and exponent
_FLOAT = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
_INT = re.compile(r"[+-]?\d+")


def _kind(annotation) -> str | None:
    """'str', 'int', 'float' or 'flag' of an option's annotation (a string under postponed
    annotations, else a type or typing form), None for any other."""
    text = annotation if isinstance(annotation, str) else repr(annotation)
    text = text.replace("typing.", "").replace("<class '", "").replace("'>", "")
    return {"str": "str", "Optional[str]": "str", "int": "int", "float": "float",
            "Optional[float]": "float", "bool": "flag"}.get(text)


def command_options(command) -> dict | None:
    """{long option: (parameter, kind, default)} of a typer command declared with typer
    options (the command's ``ctx`` left out), or None where an option is of a kind this
    parser does not take (a bool option without a flag of its own, a list, another type).
    A required option has the default ``...``."""
    opts = {}
    for name, p in inspect.signature(command).parameters.items():
        if name == "ctx":
            continue
        info = p.default
        kind = _kind(p.annotation)
        decls = tuple(getattr(info, "param_decls", ()) or ())
        if kind is None or not hasattr(info, "default"):
            return None
        if kind == "flag":
            if len(decls) != 1 or "/" in decls[0] or info.default is not False:
                return None
        elif decls and decls != ("--" + name.replace("_", "-"),):
            return None
        opt = decls[0] if decls else "--" + name.replace("_", "-")
        opts[opt] = (name, kind, info.default)
    return opts


#: a model's own option as the fast paths take it (``--name``, lower case)
_MODEL_OPTION = re.compile(r"--[a-z][a-z0-9]*(-[a-z0-9]+)*")


def parse(argv, opts: dict, extra: list | None = None) -> dict | None:
    """{parameter: value} of a plain command line over ``opts`` (:func:`command_options`),
    every parameter given its default where not given, or None where the command line is
    not plain (see the module's notes) or a required option is missing.

    ``extra``: a list that receives a model's own options, ``--name value`` pairs of a name
    that is not the command's (nor ``--help``) and a value that does not start with ``-``,
    in their order (what typer passes on as the command's extra arguments); without it
    such a command line is not plain."""
    values = {}
    i = 0
    while i < len(argv):
        a = argv[i]
        if (extra is not None and a not in opts and a != "--help"
                and _MODEL_OPTION.fullmatch(a) and i + 1 < len(argv)
                and argv[i + 1] and not argv[i + 1].startswith("-")):
            extra += [a, argv[i + 1]]
            i += 2
            continue
        if a not in opts or opts[a][0] in values:
            return None
        name, kind, _ = opts[a]
        if kind == "flag":
            values[name] = True
            i += 1
            continue
        if i + 1 >= len(argv):
            return None
        v = argv[i + 1]
        if kind == "float":
            if not _FLOAT.fullmatch(v):
                return None
            values[name] = float(v)
        elif kind == "int":
            if not _INT.fullmatch(v):
                return None
            values[name] = int(v)
        else:
            if v.startswith("-") or not v:
                return None
            values[name] = v
        i += 2
    for name, kind, default in opts.values():
        if name not in values:
            if default is ...:
                return None
            values[name] = default
    return values


def _plain(command, argv):
    """(options, values, a model's own options) of a plain command line of the typer
    ``command`` (:func:`command_options`, :func:`parse`), or None where it is not plain."""
    opts = command_options(command)
    if opts is None:
        return None
    extra: list = []
    v = parse(argv, opts, extra)
    return None if v is None else (opts, v, extra)


def fast_render(argv) -> int | None:
    """Run a plain ``skydome render`` command line in this process without the typer
    application; the exit code (0, or 2 after a one-line error), or None where the typer
    command should take the command line (nothing has been done then)."""
    from skydome.cli.render import render

    plain = _plain(render, argv)
    if plain is None:
        return None
    opts, v, extra = plain
    from skydome.cli._kit import SUN_BY_ANGLES_OR_PLACE
    from skydome.cli.render import _render

    sun = {k: v.pop(k) for k in SUN_BY_ANGLES_OR_PLACE if k in v}
    args = [v.pop(k) for k in ("model", "out")] + [sun] + [
        v.pop(k) for k in ("projection", "size", "wavelengths", "exposure", "tonemap", "bits")]
    args += [not v.pop("no_sun"), v.pop("ev100"), v.pop("sun_light"), not v.pop("no_hunt")]
    if v:       # an option of the command that this call does not pass on: typer's
        return None
    return _run_fast(opts, _render, extra, args)


def _run_fast(opts: dict, work, extra: list, args: list) -> int:
    """Run a command's work through :func:`skydome.cli._kit._run` as its typer command
    would (the errors of ``_run`` naming the command's options as typer spells them);
    the exit code."""
    import typer

    from skydome.cli import _kit

    _kit._FAST_COMMAND = (set(opts), True)
    try:
        _kit._run(work, extra, *args)
    except typer.Exit as exc:
        return int(exc.exit_code)
    finally:
        _kit._FAST_COMMAND = None
    return 0


#: the parameters of :func:`skydome.cli.export._envmap` after ``extra``, in its order
_ENVMAP_ARGS = ("model", "out", "convention", "layout", "size", "half", "sun_in_map", "ground",
                "ground_albedo", "sh", "mips", "sun", "wavelengths", "units")


def fast_export_envmap(argv) -> int | None:
    """Run a plain ``skydome export envmap`` command line (the words after ``export
    envmap``) in this process without the typer application; the exit code (0, or 2 after a
    one-line error), or None where the typer command should take the command line (nothing
    has been done then)."""
    from skydome.cli.export import envmap

    plain = _plain(envmap, argv)
    if plain is None:
        return None
    opts, v, extra = plain
    from skydome.cli._kit import SUN_BY_ANGLES_OR_PLACE
    from skydome.cli.export import _envmap

    v["sun"] = {k: v.pop(k) for k in SUN_BY_ANGLES_OR_PLACE if k in v}
    args = [v.pop(k) for k in _ENVMAP_ARGS]
    if v:       # an option of the command that this call does not pass on: typer's
        return None
    return _run_fast(opts, _envmap, extra, args)
