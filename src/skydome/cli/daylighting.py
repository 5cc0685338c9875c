"""The daylighting commands: ``weather info``, ``skymatrix``, ``illuminance`` and
``daylight-factor``.

Heavy modules (pvlib, numba kernels) are imported inside the commands only; the perez1993
``skymatrix`` work is :func:`skydome.daylighting.skymatrix_run.run_perez_skymatrix`, which
the fast path :mod:`skydome.cli.skymatrix_fast` runs without typer.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from skydome.cli._kit import (_check_dask, _fail, _param_options, _parse_model_params, _run,
                              connect_timeout_option)
from skydome.daylighting.skymatrix_run import SKYMATRIX_DEFAULTS as D

commands = typer.Typer()
weather_app = typer.Typer(no_args_is_help=True, help="Hourly weather files (EPW, TMY3).")


@weather_app.command("info")
def weather_info(path: str = typer.Argument(..., help="EPW or TMY3 file")):
    """Site, period and what the weather file holds."""
    from skydome.daylighting.weather import read_weather

    w = _run(read_weather, path)
    s = w.summary()
    typer.echo(f"site: {s['site']}  lat {s['latitude_deg']:.3f} deg N, lon "
               f"{s['longitude_deg']:.3f} deg E, UTC{s['utc_offset_h']:+g} h, "
               f"{s['elevation_m']:g} m")
    typer.echo(f"format: {s['format'].upper()}, {s['records']} records, {s['first']} .. "
               f"{s['last']} (local standard time), step {s['step']}")
    typer.echo(f"holds: {', '.join(s['quantities'])}")
    typer.echo(f"daylight hours (sun above the horizon at the midpoint): {s['daylight_hours']}")
    typer.echo(f"annual sums: GHI {s['annual_ghi_kwh_m2']:.1f}, DNI {s['annual_dni_kwh_m2']:.1f}, "
               f"DHI {s['annual_dhi_kwh_m2']:.1f} kWh/m^2")


@commands.command("skymatrix")
def skymatrix_cmd(
    weather: str = typer.Option(..., "--weather", help="EPW, TMY3 or Radiance .wea file"),
    out: str = typer.Option(..., "--out", help="output .mtx (Radiance matrix) or .npy"),
    patches: str = typer.Option(D["patches"], "--patches", help="tregenza | reinhart:MF"),
    model: str = typer.Option(D["model"], "--model",
                              help="perez1993, or any skydome model (e.g. precomputed; .zarr)"),
    components: Optional[str] = typer.Option(
        D["components"], "--components", help="rgb | luminance (perez1993, default rgb); luminance | "
        "spectral | spectral:N (other models, default spectral:16)"),
    sun: Optional[str] = typer.Option(D["sun"], "--sun",
                                      help="spread (default) | spread:N | disc:ANGLE | "
                                      "separate | none (perez1993)"),
    aod_from: Optional[str] = typer.Option(
        D["aod_from"], "--aod-from", help="aerosol optical depth per hour: 'weather' or a number "
        "(models with an atmosphere)"),
    param: list[str] = typer.Option(D["param"], "--param",
                                    help="model parameter NAME=VALUE (repeat; other models)"),
    order: Optional[str] = typer.Option(
        D["order"], "--order", help="patch quadrature: adaptive (perez1993 default) or an order "
        "0..16 (0 = the centre; other models' default 4)"),
    sun_position: str = typer.Option(D["sun_position"], "--sun-position",
                                     help="spa | radiance (gendaymtx's approximate sun)"),
    fmt: str = typer.Option(D["fmt"], "--format", help="ascii | float | double"),
    albedo: str = typer.Option(D["albedo"], "--albedo", help="ground reflectance, or 'weather'"),
    overwrite: bool = typer.Option(D["overwrite"], "--overwrite",
                                   help="replace existing outputs"),
    scheduler: Optional[str] = typer.Option(D["scheduler"], "--scheduler",
                                            help="run on a Dask cluster (tcp://HOST:8786)"),
    connect_timeout: float = connect_timeout_option(),
    workers: int = typer.Option(D["workers"], "--workers",
                                help="run on a local Dask cluster of N processes (0: in process)"),
    chunk_hours: int = typer.Option(D["chunk_hours"], "--chunk-hours", help="hours per Dask chunk"),
    backend: str = typer.Option(D["backend"], "--backend",
                                help="auto (default: numpy for perez1993) | numpy (no numba "
                                "start-up) | numba (the parallel kernel; equal to rounding)"),
):
    """Annual sky matrix (patches x hours) from a weather file, Radiance-compatible.

    With --scheduler or --workers the hours are computed as chunks on Dask, kept in
    OUT.chunks/ until the matrix is written: an interrupted run, rerun, reuses them."""
    from skydome.cli._notes import notes_as_lines
    from skydome.daylighting.patches import patches as make_patches
    from skydome.daylighting.skymatrix import ClearSkyNote, SunRangeNote
    from skydome.daylighting.skymatrix_run import (order_option, run_perez_skymatrix,
                                                   write_model_sky_matrix)

    # the library's notes (lit hours outside a model's sun range, hours beyond the clear-sky
    # limit) as one line each on stderr
    notes = notes_as_lines(SunRangeNote, ClearSkyNote, emit=lambda t: typer.echo(t, err=True))

    # -- validate everything before any work -------------------------------------------------
    scheduler, connect_timeout = _run(_check_dask, scheduler, connect_timeout)
    ps = _run(make_patches, patches)
    order = order_option(order, model, _fail)
    if model != "perez1993":
        from skydome.models import get_model_class

        cls = _run(get_model_class, model)
        params = _run(lambda: _parse_model_params(cls, _param_options(param)))
        with notes:
            line = _run(write_model_sky_matrix, weather, out, ps, model,
                        components or "spectral:16", sun=sun, aod_from=aod_from, params=params,
                        order=order, sun_position=sun_position, overwrite=overwrite,
                        scheduler=scheduler, workers=workers, chunk_hours=chunk_hours)
        typer.echo(line)
        return
    with notes:
        run_perez_skymatrix(weather=weather, out=out, ps=ps, components=components, sun=sun,
                            aod_from=aod_from, param=param, order=order,
                            sun_position=sun_position, fmt=fmt, albedo=albedo,
                            overwrite=overwrite, scheduler=scheduler, workers=workers,
                            chunk_hours=chunk_hours, model=model, fail=_fail, guard=_run,
                            echo=typer.echo, backend=backend,
                            connect_timeout=connect_timeout)


@commands.command("illuminance")
def illuminance_cmd(
    weather: str = typer.Option(..., "--weather", help="EPW or TMY3 file"),
    plane: list[str] = typer.Option(..., "--plane",
                                    help="horizontal | vertical:AZ | tilted:TILT:AZ (repeat)"),
    out: str = typer.Option(..., "--out", help="output .csv"),
    model: str = typer.Option("perez1993", "--model", help="sky model (perez1993)"),
    albedo: float = typer.Option(0.2, "--albedo", help="ground reflectance"),
    sun_position: str = typer.Option("spa", "--sun-position", help="spa | radiance"),
    overwrite: bool = typer.Option(False, "--overwrite", help="replace an existing output"),
):
    """Hourly sky, sun and ground illuminance and irradiance on planes."""
    from skydome.daylighting.series import parse_plane, plane_series, write_series_csv
    from skydome.daylighting.weather import read_weather

    planes = [_run(parse_plane, p) for p in plane]
    if model != "perez1993":
        _fail(f"model = {model!r} is not available for illuminance series (choices: perez1993)")
    if not 0.0 <= albedo <= 1.0:
        _fail(f"albedo = {albedo:g} is out of range [0, 1]")
    if sun_position not in ("spa", "radiance"):
        _fail(f"sun-position = {sun_position!r} is unknown (choices: spa, radiance)")
    out_p = Path(out)
    if out_p.exists() and not overwrite:
        _fail(f"out = {out!r} exists (use --overwrite)")
    if not out_p.parent.is_dir():
        _fail(f"out = {out!r}: folder {str(out_p.parent)!r} does not exist")
    w = _run(read_weather, weather)
    res = _run(plane_series, w, planes, ground_reflectance=albedo, sun_position=sun_position)
    _run(write_series_csv, out_p, res, overwrite=overwrite)
    typer.echo(f"wrote {out}: {len(w)} hours x {len(planes)} planes")


@commands.command("daylight-factor")
def daylight_factor_cmd(
    plane: list[str] = typer.Option([], "--plane", help="unobstructed plane: horizontal | "
                                    "vertical:AZ | tilted:TILT:AZ (repeat)"),
    scene: list[str] = typer.Option([], "--scene", help="Radiance scene file (repeat)"),
    sensors: Optional[str] = typer.Option(None, "--sensors",
                                          help="points file, one 'x y z dx dy dz' a line"),
    ground_reflectance: float = typer.Option(0.2, "--ground-reflectance",
                                             help="ground reflectance in [0, 1]"),
    ab: int = typer.Option(5, "--ab", help="rtrace ambient bounces, 0..16"),
    ad: int = typer.Option(2048, "--ad", help="rtrace ambient divisions, >= 1"),
    allow_commands: bool = typer.Option(
        False, "--allow-commands", help="let the scene files hold command lines ('!command', "
        "which Radiance runs as shell commands); refused by default"),
    out: Optional[str] = typer.Option(None, "--out", help="output .csv (default: stdout)"),
    overwrite: bool = typer.Option(False, "--overwrite", help="replace an existing output"),
):
    """Daylight factor [%] under the CIE overcast sky: of unobstructed planes (--plane), or of
    sensor points in a Radiance scene by rtrace (--scene, --sensors)."""
    from skydome.daylighting.daylight_factor import (check_rtrace_parameters,
                                                     plane_daylight_factor, read_sensors,
                                                     room_daylight_factor)
    from skydome.daylighting.scene import check_scene_files
    from skydome.daylighting.series import parse_plane

    if bool(plane) == bool(scene or sensors):
        _fail("give --plane (unobstructed planes) or --scene with --sensors, not both")
    if scene and sensors is None or sensors is not None and not scene:
        _fail("--scene and --sensors go together")
    if not 0.0 <= ground_reflectance <= 1.0:
        _fail(f"ground-reflectance = {ground_reflectance:g} is out of range [0, 1]")
    _run(check_rtrace_parameters, ab=ab, ad=ad)
    out_p = Path(out) if out else None
    if out_p is not None:
        if out_p.exists() and not overwrite:
            _fail(f"out = {out!r} exists (use --overwrite)")
        if not out_p.parent.is_dir():
            _fail(f"out = {out!r}: folder {str(out_p.parent)!r} does not exist")
    if plane:
        planes = [_run(parse_plane, p) for p in plane]
        df = [_run(plane_daylight_factor, p.tilt_deg, p.azimuth_deg,
                     ground_reflectance=ground_reflectance) for p in planes]
        rows = [f"{p.name},{p.tilt_deg:g},{p.azimuth_deg:g},{v:.4f}" for p, v in zip(planes, df)]
        text = "plane,tilt_deg,azimuth_deg,daylight_factor_percent\n" + "\n".join(rows) + "\n"
    else:
        # the files exist and hold no command line (unless allowed), before any work
        _run(check_scene_files, scene, allow_commands=allow_commands)
        pts = _run(read_sensors, sensors)
        try:
            df = room_daylight_factor(scene, pts, ground_reflectance=ground_reflectance,
                                      ab=ab, ad=ad, allow_commands=allow_commands)
        except (RuntimeError, ValueError, TypeError) as exc:   # Radiance failed, bad input
            _fail((str(exc).splitlines() or [type(exc).__name__])[0])
        rows = [" ".join(f"{v:g}" for v in p) + f",{v:.4f}" for p, v in zip(pts, df)]
        text = "sensor,daylight_factor_percent\n" + "\n".join(rows) + "\n"
    if out_p is None:
        typer.echo(text, nl=False)
    else:
        from skydome.daylighting.radiance_io import atomic_write_bytes

        _run(atomic_write_bytes, out_p, text.encode())
        typer.echo(f"wrote {out}")
