"""The ``skymatrix`` work once its options are parsed, as plain functions: the perez1993
matrix with its files (:func:`run_perez_skymatrix`) and any other model's matrix as a Zarr
array (:func:`write_model_sky_matrix`).

Both validate everything before any work and raise ValueError naming the option, its value
and what is valid (or call the ``fail`` given); they import no command-line framework, so
that the command line's fast path (``skydome.cli.skymatrix_fast``) runs a perez1993 matrix
without typer.
"""

from __future__ import annotations

from pathlib import Path

#: The command's options and their defaults (the typer command declares the same).
SKYMATRIX_DEFAULTS = {
    "weather": None, "out": None, "patches": "tregenza", "model": "perez1993",
    "components": None, "sun": None, "aod_from": None, "param": [], "order": None,
    "sun_position": "spa", "fmt": "float", "albedo": "0.2", "overwrite": False,
    "scheduler": None, "workers": 0, "chunk_hours": 730, "backend": "auto",
    "connect_timeout": 10.0,
}


def _refuse(message: str) -> None:
    raise ValueError(message)


def _call(func, *args, **kwargs):
    return func(*args, **kwargs)


def _quiet(text, err=False) -> None:
    pass


def order_option(order, model, fail=_refuse):
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
                        model, fail=_refuse, guard=_call, echo=_quiet, backend="auto",
                        connect_timeout=10.0):
    """The perez1993 ``skymatrix`` command with parsed options (``ps`` the PatchSet, ``order``
    from :func:`order_option`): validates everything, then computes and writes the matrix
    (and with ``--sun separate`` the sun matrix and the suns' scene). ``fail(message)``
    reports bad input and does not return (default: raise ValueError); ``guard(func, *args)``
    calls func turning bad input and failed writes (a full disk) into ``fail`` (default: a
    plain call); ``echo(text, err=False)`` reports (default: nothing). ``connect_timeout``
    [s] bounds the wait for ``scheduler`` (``connect_timeout_s`` of
    :func:`skydome.distributed.distributed_sky_matrix`). A failed write leaves none of the
    outputs, nor ``OUT.chunks/`` if this run made it (an interrupted run keeps it: a rerun
    reuses its chunks)."""
    import shutil

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
    if workers < 0 or chunk_hours < 1:
        fail(f"workers = {workers} must be >= 0 and chunk-hours = {chunk_hours} >= 1")
    from skydome._validate import check_number

    if scheduler is not None:
        from skydome.distributed import check_scheduler

        scheduler = guard(check_scheduler, scheduler)
    connect_timeout = guard(check_number, "connect_timeout", connect_timeout, 0.0, 3600.0, "s",
                            low_open=True)
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

    if not distributed and backend == "numba":  # only the Perez kernels run: no BLAS probe
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
    made_chunk_dir = False
    if distributed:
        from skydome.daylighting.skymatrix_chunks import distributed_sky_matrix

        chunk_dir = Path(f"{out_p}.chunks")
        made_chunk_dir = not chunk_dir.exists()
        sky, rep = guard(distributed_sky_matrix, w, chunk_dir, chunk_hours=chunk_hours,
                         scheduler=scheduler, n_workers=max(workers, 1), progress=True,
                         connect_timeout_s=connect_timeout,
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
            guard(write_matrix, out_p, m.sky, fmt=fmt, info=info, overwrite=overwrite,
                  transpose=out_p.suffix.lower() != ".npy")
        written.append(out_p)
        if mode == "separate":
            guard(write_matrix, targets[1], m.sun[None, :, :], fmt=fmt,
                  info=info + [f"sun matrix: radiance of the {SUN_ANGLE_DEG} deg solar disc"],
                  overwrite=overwrite)
            written.append(targets[1])
            minute = 24 * 60 * (w.day_of_year - 1) + (w.hour * 60.0 + 0.5).astype(int)
            up = m.sun_directions[:, 2] > -np.sin(np.radians(SUN_ANGULAR_RADIUS_DEG))
            guard(atomic_write_bytes, targets[2], _sun_scene(m, minute, up).encode())
            written.append(targets[2])
    except BaseException as exc:
        for t in written:
            t.unlink(missing_ok=True)
        # a failed write (through guard: the command's exit, or the error itself) removes
        # the chunks this run made; Ctrl-C keeps them for a rerun
        if made_chunk_dir and not isinstance(exc, KeyboardInterrupt):
            shutil.rmtree(chunk_dir, ignore_errors=True)
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



def write_model_sky_matrix(weather, out, ps, model, components, *, sun=None, aod_from=None,
                           params=None, order=4, sun_position="spa", overwrite=False,
                           scheduler=None, workers=0, chunk_hours=730) -> str:
    """``skymatrix --model NAME`` for any model but perez1993: a Zarr array (hours, patches,
    components) written one chunk of hours at a time into a temporary folder beside ``out``,
    renamed when complete. ``params`` are the model's keyword parameters. Every option is
    checked first (ValueError naming it); returns the line that says what was written. A
    failed write (a full disk) raises OSError naming ``out`` and leaves nothing; so does
    SIGTERM (the temporary is registered with :func:`skydome._io.temporary`)."""
    import os
    import shutil

    from skydome._io import temporary
    from skydome.daylighting.skymatrix import parse_components, weather_model_sky_matrix
    from skydome.daylighting.weather import read_weather
    from skydome.models import get_model_class

    get_model_class(model)
    parse_components(components)
    if sun not in (None, "none"):
        raise ValueError(f"sun = {sun!r}: model {model!r} matrices hold the sky only (give "
                         "--sun none or leave it out)")
    if scheduler is not None or workers > 0:
        raise ValueError(f"--scheduler/--workers are available for perez1993 matrices only, "
                         f"not {model!r}")
    if sun_position not in ("spa", "radiance"):
        raise ValueError(f"sun-position = {sun_position!r} is unknown (choices: spa, radiance)")
    if chunk_hours < 1:
        raise ValueError(f"chunk-hours = {chunk_hours} must be >= 1")
    out_p = Path(out)
    if out_p.suffix.lower() != ".zarr":
        raise ValueError(f"out = {out!r}: model {model!r} matrices are written as Zarr "
                         "(OUT.zarr)")
    if out_p.exists() and not overwrite:
        raise ValueError(f"out = {out!r} exists (use --overwrite)")
    if not out_p.parent.is_dir():
        raise ValueError(f"out = {out!r}: folder {str(out_p.parent)!r} does not exist")
    w = read_weather(weather, sun_position=sun_position)
    tmp = out_p.parent / f".{out_p.name}.part"
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        # tmp is registered for the SIGTERM clean-up (skydome._io.temporary) from before the
        # library creates it until the rename; the library's own registration of it for the
        # chunks' writing nests inside this one (a SIGTERM between the two blocks found it
        # unregistered: the folder was left, under load)
        with temporary(tmp, is_dir=True):
            arr = weather_model_sky_matrix(w, model, aod_from=aod_from,
                                           params=dict(params or {}), patches=ps, order=order,
                                           components=components, sun_position=sun_position,
                                           zarr_path=tmp, chunk_hours=chunk_hours)
            arr.attrs.update({"model": model, "components": components, "patches": ps.name,
                              "order": order, "aod_from": str(aod_from), "weather":
                              Path(weather).name, "axes": ["hour", "patch", "component"],
                              "units": "cd/m^2" if components == "luminance" else
                              "W m^-2 sr^-1 nm^-1"})
            if out_p.exists():
                shutil.rmtree(out_p)
            os.replace(tmp, out_p)
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        if exc.errno is None:
            raise
        # the error names the user's OUT, not the temporary .OUT.part (or a file in it)
        raise OSError(exc.errno, exc.strerror or os.strerror(exc.errno), str(out_p)) from exc
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return f"wrote {out}: {len(w)} hours x {len(ps)} patches x {arr.shape[2]} components"
