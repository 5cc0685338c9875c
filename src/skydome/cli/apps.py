"""The drivers' commands: ``compare``, ``timelapse``, ``polarisation``, ``twilight``,
``airlight`` and ``aureole`` (each checks its options, calls one driver of
:mod:`skydome.apps` and prints its result)."""

from __future__ import annotations

from typing import Optional

import typer

from skydome.cli._kit import (EXTRA, PROJECTIONS, UserError, _build_model, _check_azimuth,
                              _check_clock, _check_date, _check_figure_path, _check_memory,
                              _check_shared, _check_sun_option, _check_utc_offset,
                              _dask_choice, _folder_model, _model_spec, _Progress, _run,
                              _split_specs, _sun_from, dask_options, sun_option,
                              sun_options)

commands = typer.Typer()


@commands.command("compare", context_settings=EXTRA)
@dask_options("the grid's cells")
def compare_cmd(
    ctx: typer.Context,
    models: str = typer.Option(..., help="Comma-separated model specs, e.g. single_scattering,kaneda1991,preetham1999:3."),
    sun_elevation: str = sun_option("sun_elevation", "5,30,60", many=True),
    sun_azimuth: float = sun_option("sun_azimuth", 180.0),
    reference: str = typer.Option("precomputed", help="Model the others are measured against (default: the accurate multiple-scattering sky)."),
    size: int = typer.Option(128, help="Fisheye size in pixels, 16..4096."),
    wavelengths: int = typer.Option(16, help="Number of wavelengths 380-780 nm, 3..401."),
    out: str = typer.Option(..., help="Output folder (created if missing): grid.png, error_*.png, table.md, table.csv."),
    **dask,
):
    """Render several models for several sun elevations and measure each against a reference.

    Options after the list (e.g. --turbidity 3) go to every model that has them.
    """
    def go():
        from skydome.apps.compare import run_comparison
        from skydome.models import get_model_class

        from skydome._io import check_output_folder
        from skydome._validate import check_int
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
            _check_sun_option("sun_elevation", e)
        _check_sun_option("sun_azimuth", sun_azimuth)
        check_int("size", size, 16, 4096)
        check_int("wavelengths", wavelengths, 3, 401)
        _check_memory("size", size, size * size, max(wavelengths if c.native == "spectral" else 3 for c in classes))
        scheduler, workers, distributed, timeout = _dask_choice(dask)
        progress = _Progress("comparing models")
        try:
            if distributed:  # cells as Dask tasks, resumable from OUT.chunks/
                from skydome.apps.compare import spec_builder

                build = spec_builder(_model_spec, list(ctx.args))
            else:
                def build(spec, sun):
                    return _model_spec(spec, ctx.args, sun)
            rows = run_comparison(specs, elevs, out, reference=reference, sun_azimuth_deg=sun_azimuth,
                                  size=size, wavelengths=wavelengths, build=build,
                                  progress=None if distributed else progress,
                                  scheduler=scheduler, workers=workers,
                                  connect_timeout_s=timeout)
        finally:
            progress.close()
        from skydome.apps.compare import table_markdown

        typer.echo(table_markdown(rows, reference))
        typer.echo(f"wrote {out}/grid.png, error_*.png, table.md, table.csv")
    _run(go)


@commands.command("timelapse", context_settings=EXTRA)
@dask_options("the frames")
def timelapse_cmd(
    ctx: typer.Context,
    lat: float = sun_option("lat", ...),
    lon: float = sun_option("lon", ...),
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
    **dask,
):
    """The colour of the sky through a day: frames, a contact sheet and a colour-against-time plot.

    Model parameters are given as extra options, e.g. --turbidity 3.
    """
    def go():
        from skydome._validate import check_choice, check_int, check_number
        from skydome.apps.timelapse import day_times, parse_every, run_timelapse

        cls, params = _folder_model(out, model, ctx.args)
        check_choice("projection", projection, PROJECTIONS[:-1])
        _check_sun_option("lat", lat)
        _check_sun_option("lon", lon)
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
        scheduler, workers, distributed, timeout = _dask_choice(dask)
        progress = _Progress("timelapse")
        try:
            if distributed:  # frames as Dask tasks, resumable from OUT.chunks/
                from skydome.apps.timelapse import model_builder

                build = model_builder(model, params)
            else:
                def build(sun):
                    return _build_model(cls, progress, sun=sun, **params)
            frames = run_timelapse(build, lat, lon, times, out,
                                   min_elevation_deg=min_elevation, size=size, wavelengths=wavelengths,
                                   projection=projection, progress=None if distributed else progress,
                                   scheduler=scheduler, workers=workers,
                                   connect_timeout_s=timeout)
        finally:
            progress.close()
        done = [f for f in frames if f.image_path is not None]
        typer.echo(f"wrote {len(done)} frames ({done[0].time.strftime('%H:%M')}-{done[-1].time.strftime('%H:%M')}), "
                   f"contact_sheet.png, colours.png, colours.csv into {out}")
        skipped = [f for f in frames if f.image_path is None]
        if skipped:
            typer.echo(f"skipped {len(skipped)} frames the model refused: {skipped[0].note}")
    _run(go)


@commands.command("polarisation")
@sun_options(sun_elevation=20.0, sun_azimuth=180.0)
def polarisation_cmd(
    method: str = typer.Option("montecarlo", help="montecarlo (multiple scattering, aerosols) or rayleigh_single (analytic)."),
    size: int = typer.Option(48, help="Fisheye size in pixels, 4..1024."),
    samples: int = typer.Option(2000, help="Monte Carlo paths per pixel, 2..10^8."),
    seed: int = typer.Option(0, help="Monte Carlo seed, >= 0."),
    wavelength: float = typer.Option(550.0, help="Wavelength [nm], 300..1000."),
    turbidity: float = typer.Option(2.5, help="Turbidity of the atmosphere, 1..32."),
    out: str = typer.Option(..., help="Output figure (.png, .pdf or .svg): degree and angle of polarisation maps."),
    csv: Optional[str] = typer.Option(None, help="Also write the numbers per pixel to this .csv file."),
    **sun,
):
    """Maps of the degree and angle of polarisation of the sky (fisheye, north up, east left)."""
    def go():
        from pathlib import Path

        from skydome._validate import check_choice, check_int, check_number
        from skydome.effects.polarisation_maps import METHODS

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
        s = _sun_from(sun)
        from skydome._progress import reporting
        from skydome.apps.polarisation import run_polarisation

        # the Monte Carlo kernel reports its paths (stage "montecarlo paths") in blocks
        progress = _Progress(f"polarisation ({method})")
        try:
            with reporting(progress):
                dop, angle = run_polarisation(out, s, method=method, csv=csv, size=size,
                                              samples=samples, seed=seed,
                                              wavelength_nm=wavelength, turbidity=turbidity)
        finally:
            progress.close()
        typer.echo(f"maximum degree of polarisation {dop:.3f} at {angle:.1f} deg from the sun; wrote {out}"
                   + (f" and {csv}" if csv else ""))
    _run(go)


@commands.command("twilight", context_settings=EXTRA)
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
        from skydome._progress import reporting
        from skydome._validate import check_int
        from skydome.apps.twilight import run_twilight

        cls, params = _folder_model(out, model, ctx.args)
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


@commands.command("airlight")
@sun_options(sun_elevation=20.0, sun_azimuth=120.0)
def airlight_cmd(
    image: Optional[str] = typer.Option(None, help="Input image: .png (sRGB) or .exr/.npy (linear), white-balanced to the sun."),
    depth: Optional[str] = typer.Option(None, help="Depth map [m]: .exr (Z, Y or R channel) or .npy; inf = sky."),
    synthetic: bool = typer.Option(False, "--synthetic", help="Use the generated synthetic mountain scene instead of --image/--depth."),
    method: str = typer.Option("precomputed", help="A model with aerial perspective (its "
                               "airlight capability; skydome.effects.airlight.methods() "
                               "lists them) or dobashi2002."),
    turbidity: float = typer.Option(2.5, help="Turbidity of the air, 2..10 for the Preetham methods, 1..32 otherwise."),
    fov: float = typer.Option(60.0, help="Horizontal field of view of the (pinhole) camera [deg]."),
    view_azimuth: float = typer.Option(0.0, help="Azimuth the camera looks towards [deg], -360..360 (horizontal view)."),
    white_balance: str = typer.Option("fixed", help="fixed: true colour relative to a white surface under the unattenuated sun (clear and hazy air on one scale); sun: output in the input's units (white = white card facing the sun)."),
    fill_sky: bool = typer.Option(False, "--fill-sky", help="Replace the sky pixels (depth inf) by the model's sky along their rays (not for dobashi2002)."),
    out: str = typer.Option(..., help="Output .png (sRGB; before/after sheet with --synthetic), .exr or .npy (linear)."),
    **sun,
):
    """Aerial perspective / airlight: extinction and in-scattered light over an image with a depth map."""
    def go():
        from skydome._io import check_output_file
        from skydome.apps.airlight import airlight_cli

        check_output_file(out, (".png", ".exr", ".npy"))
        position = _sun_from(sun)
        _check_azimuth("view_azimuth", view_azimuth)
        airlight_cli(image, depth, out, position, method=method, turbidity=turbidity, fov_deg=fov,
                     view_azimuth_deg=view_azimuth, synthetic=synthetic, white_balance=white_balance,
                     fill_sky=fill_sky)
        typer.echo(f"wrote {out} ({method}, turbidity {turbidity:g})")
    _run(go)


@commands.command("aureole")
def aureole_cmd(
    aerosol: str = typer.Option("earth", help="earth (turbidity 2, 4, 8), volcanic_ash (blue sun), forest_fire_smoke (blue sun) or bishops_ring (~1 um layer)."),
    sun_elevation: float = sun_option("sun_elevation", 30.0, low=1.0),
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

