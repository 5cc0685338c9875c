"""``skydome skymatrix`` for perez1993, without the CLI framework (typer, pydantic, rich).

:func:`run_perez_skymatrix` is the command's work once its options are parsed; the typer
command (:func:`skydome.daylighting.cli.skymatrix_cmd`) calls it, and so does
:func:`fast_skymatrix`, which ``skydome`` (:mod:`skydome.__main__`) tries first for a
``skymatrix`` command line: it parses the plain options itself (``--name value``,
``--name=value``, ``--overwrite``) so that a run imports neither typer (with pydantic, 0.2-0.3
s of CPU on a 2-core EPYC), nor numba with ``--backend numpy`` or ``auto`` and a fixed order
(0.4-0.5 s): a whole gendaymtx-like run (``--order 0 --sun-position radiance --backend
numpy``) is then numpy's start-up plus the work (gendaymtx's CPU time / 5.3 at MF:4 by
the best rounds, / 4.9 by the medians, docs/performance.md). Anything
else (help, an unknown or repeated-list option, another model, Dask, a value it refuses)
goes to the typer command, which parses it and reports an error as one line with exit code 2
as every command does: the fast path reports nothing itself, and leaves nothing on disk.
"""

from __future__ import annotations

import sys
from pathlib import Path

#: The command's options and their defaults (the typer command declares the same).
SKYMATRIX_DEFAULTS = {
    "weather": None, "out": None, "patches": "tregenza", "model": "perez1993",
    "components": None, "sun": None, "aod_from": None, "param": [], "order": None,
    "sun_position": "spa", "fmt": "float", "albedo": "0.2", "overwrite": False,
    "scheduler": None, "workers": 0, "chunk_hours": 730, "backend": "numba",
}
#: Long option -> parameter, for the options :func:`fast_skymatrix` parses (string values).
_FAST_OPTIONS = {"--weather": "weather", "--out": "out", "--patches": "patches",
                 "--model": "model", "--components": "components", "--sun": "sun",
                 "--order": "order", "--sun-position": "sun_position", "--format": "fmt",
                 "--albedo": "albedo", "--backend": "backend"}


def order_option(order, model, fail):
    """``--order``: "adaptive" (perez1993's default) or an integer in [0, 16] (the other
    models' default 4); a bad value goes to ``fail``."""
    perez = model == "perez1993"
    text = (order or ("adaptive" if perez else "4")).strip().lower()
    if perez and text == "adaptive":
        return text
    if not text.isdigit() or not 0 <= int(text) <= 16:
        valid = "'adaptive' or an integer in [0, 16]" if perez else \
            f"an integer in [0, 16] for model {model!r}"
        fail(f"order = {order!r} must be {valid}")
    return int(text)


def run_perez_skymatrix(*, weather, out, ps, components, sun, aod_from, param, order,
                        sun_position, fmt, albedo, overwrite, scheduler, workers, chunk_hours,
                        model, fail, guard, echo, backend="numba"):
    """The perez1993 ``skymatrix`` command with parsed options (``ps`` the PatchSet, ``order``
    from :func:`order_option`): validates everything, then computes and writes the matrix
    (and with ``--sun separate`` the sun matrix and the suns' scene). ``fail(message)``
    reports bad input and does not return; ``guard(func, *args)`` calls func turning bad
    input into ``fail``; ``echo(text, err=False)`` prints."""
    import numpy as np

    from skydome.constants import SUN_ANGULAR_RADIUS_DEG
    from skydome.daylighting.radiance_io import FORMATS, atomic_write_bytes, write_matrix
    from skydome.daylighting.skymatrix import (SUN_ANGLE_DEG, parse_sun_option,
                                               perez_sky_matrix_file,
                                               perez_sky_matrix_from_weather)

    if aod_from is not None or param:
        fail("--aod-from and --param apply to physically based models, not perez1993")
    components = components or "rgb"
    sun = sun or "spread"
    mode = guard(parse_sun_option, sun)[0]
    if components not in ("rgb", "luminance"):
        fail(f"components = {components!r} is unknown (choices: rgb, luminance)")
    if fmt not in FORMATS:
        fail(f"format = {fmt!r} is unknown (choices: {', '.join(FORMATS)})")
    if sun_position not in ("spa", "radiance"):
        fail(f"sun-position = {sun_position!r} is unknown (choices: spa, radiance)")
    if backend not in ("numba", "numpy", "auto"):
        fail(f"backend = {backend!r} is unknown (choices: numba, numpy, auto)")
    if backend == "numpy" and order == "adaptive":
        fail("backend = 'numpy' takes a fixed --order (0..16), not the adaptive rule")
    if workers < 0 or chunk_hours < 1:
        fail(f"workers = {workers} must be >= 0 and chunk-hours = {chunk_hours} >= 1")
    distributed = scheduler is not None or workers > 0
    rho = None
    if albedo != "weather":
        try:
            rho = float(albedo)
        except ValueError:
            fail(f"albedo = {albedo!r} must be a number in [0, 1] or 'weather'")
        if not 0.0 <= rho <= 1.0:
            fail(f"albedo = {albedo!r} is out of range [0, 1]")
    out_p = Path(out)
    targets = [out_p]
    if mode == "separate":
        stem = out_p.with_suffix("")
        targets += [Path(f"{stem}.sun{out_p.suffix or '.mtx'}"), Path(f"{stem}.suns.rad")]
    for t in targets:
        if t.exists() and not overwrite:
            fail(f"out = {str(t)!r} exists (use --overwrite)")
        if not t.parent.is_dir():
            fail(f"out = {str(t)!r}: folder {str(t.parent)!r} does not exist")
    from skydome.daylighting.weather import read_weather

    if not distributed and (backend == "numba" or order == "adaptive"):  # only the Perez kernels run: no BLAS probe
        from skydome.daylighting.skymatrix import start_numba_without_blas

        start_numba_without_blas()
    w = guard(read_weather, weather, sun_position=sun_position)
    if rho is None:
        rho_v = w.albedo if w.albedo is not None else np.full(len(w), 0.2)
        rho_v = np.where(np.isfinite(rho_v), rho_v, 0.2)
    else:
        rho_v = rho
    dtype = np.float32 if fmt == "float" else np.float64
    chunk_dir = None
    if distributed:
        import shutil

        from skydome.daylighting.skymatrix_chunks import distributed_sky_matrix

        chunk_dir = Path(f"{out_p}.chunks")
        sky, rep = guard(distributed_sky_matrix, w, chunk_dir, chunk_hours=chunk_hours,
                         scheduler=scheduler, n_workers=max(workers, 1), progress=True,
                         sun_position=sun_position, ground_reflectance=rho_v, patches=ps.name,
                         order=order, sun=sun, components=components, dtype=dtype)
        echo(f"chunks: {len(rep.computed)} computed, {len(rep.verified)} reused", err=True)

        class _M:  # the parts of a SkyMatrix the writer needs
            pass

        m = _M()
        m.sky = sky
        if mode == "separate":
            from skydome.daylighting.skymatrix_chunks import split_sun

            m.sky, m.sun = split_sun(sky)
            m.sun_directions = (w.spa_sun_directions() if sun_position == "spa" else
                                w.radiance_sun_directions())
    info = [f"skydome skymatrix --weather {Path(weather).name} --patches {ps.name} "
            f"--model {model} --components {components} --sun {sun} --order {order} "
            f"--sun-position {sun_position}",
            f"LATLONG= {w.site.latitude_deg:.8f} {w.site.longitude_deg:.8f}"]
    written = []
    kw = dict(sun_position=sun_position, patches=ps, order=order, sun=sun,
              components=components, ground_reflectance=rho_v)
    try:
        if not distributed and fmt != "ascii" and out_p.suffix.lower() != ".npy":
            # written in Radiance's order as it is computed: no copy, one pass
            m = guard(perez_sky_matrix_file, out_p, w, fmt=fmt, info=info,
                      overwrite=overwrite, backend=backend, **kw)
        else:
            if not distributed:
                m = guard(perez_sky_matrix_from_weather, w, dtype=dtype, backend=backend,
                          **kw)
            write_matrix(out_p, m.sky, fmt=fmt, info=info, overwrite=overwrite,
                         transpose=out_p.suffix.lower() != ".npy")
        written.append(out_p)
        if mode == "separate":
            write_matrix(targets[1], m.sun[None, :, :], fmt=fmt,
                         info=info + [f"sun matrix: radiance of the {SUN_ANGLE_DEG} deg solar disc"],
                         overwrite=overwrite)
            written.append(targets[1])
            minute = 24 * 60 * (w.day_of_year - 1) + (w.hour * 60.0 + 0.5).astype(int)
            up = m.sun_directions[:, 2] > -np.sin(np.radians(SUN_ANGULAR_RADIUS_DEG))
            atomic_write_bytes(targets[2], _sun_scene(m, minute, up).encode())
            written.append(targets[2])
    except BaseException:
        for t in written:
            t.unlink(missing_ok=True)
        raise
    if chunk_dir is not None:
        shutil.rmtree(chunk_dir, ignore_errors=True)
    echo(f"wrote {', '.join(str(t) for t in written)}: {len(ps)} patches x {len(w)} hours "
         f"x {m.sky.shape[2]} components")


def _sun_scene(m, hours_minute, alt_ok) -> str:
    """gendaymtx -D style scene: one light + source per hour with the sun in the sky."""
    from skydome.daylighting.skymatrix import SUN_ANGLE_DEG

    out = []
    for k in range(m.sky.shape[0]):
        if not alt_ok[k]:
            continue
        r = m.sun[k]
        d = m.sun_directions[k]
        i = int(hours_minute[k])
        rgb = " ".join(f"{v:.6e}" for v in (list(r) * 3 if r.size == 1 else r))
        out.append(f"\nvoid light solar{i}\n0\n0\n3 {rgb}\n\nsolar{i} source sun{i}\n0\n0\n"
                   f"4 {d[0]:.6f} {d[1]:.6f} {d[2]:.6f} {SUN_ANGLE_DEG:.4f}\n")
    return "".join(out)


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
    from skydome.daylighting.patches import patches as make_patches

    try:
        ps = _try(make_patches, opts.pop("patches"))
        opts["order"] = order_option(opts["order"], opts["model"], _refuse)
        run_perez_skymatrix(ps=ps, fail=_refuse, guard=_try, echo=_echo, **opts)
    except _Refused:
        return False
    return True
