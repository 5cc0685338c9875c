"""``skydome export``: environment maps, sun lights, LUT bakes and Radiance skies for
renderers and engines.

Every command validates all of its input before any work; a bad value prints one line on
stderr and exits with code 2, leaving nothing on disk.
"""

from __future__ import annotations

import time as _time
from typing import Optional

import typer

from skydome.cli._kit import (EXTRA, UserError, _param_options, _parse_model_params, _Progress,
                              _run, _sky, _sun_from, sun_options)

export_app = typer.Typer(no_args_is_help=True, rich_markup_mode=None,
                         help="Environment maps and sun lights for Blender, Mitsuba, pbrt, "
                              "Unreal, Unity, three.js and Radiance.")

_MODEL = typer.Option("precomputed", help="Registered model name (see `skydome models`).")


def _sun_path(out: str):
    from pathlib import Path

    p = Path(out)
    return p.with_name(p.stem + ".sun.json")


@export_app.command("envmap", context_settings=EXTRA)
@sun_options()
def envmap(
    ctx: typer.Context,
    model: str = _MODEL,
    out: str = typer.Option(..., help="Output file: .exr (float32, or half with --half) or .hdr."),
    convention: str = typer.Option("skydome", help="skydome, blender, mitsuba, pbrt, unreal, unity, three or radiance."),
    layout: Optional[str] = typer.Option(None, help="latlong, equiarea (pbrt), fisheye (radiance), cubemap (6 faces stacked), faces (6 files) or cross; default the convention's own."),
    size: str = typer.Option("2048x1024", help="N or WxH [pixels]; N per face for cube layouts."),
    half: bool = typer.Option(False, "--half", help="Half-float EXR (the sun must then be separate)."),
    sun_in_map: bool = typer.Option(False, "--sun-in-map", help="Put the sun into the map (energy-true) instead of OUT.sun.json."),
    ground: str = typer.Option("lambertian", help="Below the horizon: lambertian (albedo x E_h / pi), black or model."),
    ground_albedo: Optional[float] = typer.Option(None, help="Ground albedo 0..1 (default the model's, else 0.2)."),
    sh: bool = typer.Option(False, "--sh", help="Also write OUT.sh.json: order-2 irradiance SH (9 RGB coefficients)."),
    mips: int = typer.Option(0, "--mips", help="Also write N-1 GGX-prefiltered levels OUT_mip1.. (roughness k/(N-1)) + OUT.mips.json; latlong and cube layouts; 0 = none."),
    wavelengths: int = typer.Option(16, help="Wavelengths 380-780 nm for spectral models, 3..401."),
    units: Optional[str] = typer.Option(
        None, help="Scale of the RGB values: photometric (683 lm/W) or mitsuba (Mitsuba 3's); "
                   "default the convention's own (mitsuba for mitsuba, else photometric)."),
    **sun,
):
    """Render a sky into an environment map in a renderer's convention (+ OUT.sun.json)."""
    _run(_envmap, ctx.args, model, out, convention, layout, size, half, sun_in_map, ground,
         ground_albedo, sh, mips, sun, wavelengths, units)


def _keep_freed_memory() -> None:
    """Let this process reuse the memory it frees (glibc's malloc; elsewhere nothing).

    By default glibc maps every block above its dynamic threshold (128 KiB, rising to
    at most 32 MiB) straight from the system and unmaps it when freed, and returns a
    free heap top beyond twice that threshold: the models' per-chunk arrays and the
    environment map's bands (a few to tens of MB each, allocated and freed over and over)
    are fresh pages each time, and on the 2-core virtual machine of docs/performance.md
    the first touch of a fresh page costs about 1 ms per MB (the `fitted` map's 4096 x
    2048 half EXR: 1253 MB of fresh pages, 357 MB with this). Blocks up to 128 MiB now come
    from the heap, and up to 512 MiB of freed heap is kept for reuse."""
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):             # not glibc (macOS, Windows)
        return
    m_trim_threshold, m_mmap_threshold = -1, -3   # <malloc.h>
    mallopt(m_mmap_threshold, 128 << 20)
    mallopt(m_trim_threshold, 512 << 20)


def _envmap(extra, model, out, convention, layout, size, half, sun_in_map, ground, ground_albedo,
            sh, mips, sun, wavelengths, units=None):
    import json

    from skydome._validate import check_int, check_number
    from skydome.export.envmap import check_envmap_options, check_map_path, render_envmap
    from skydome.export.sun import sun_json_writer, sun_light
    from skydome.spectra import wavelength_grid

    # 1. validate everything before any work
    sun_mode = "map" if sun_in_map else "separate"
    checked = {}

    def check():
        checked["conv"], checked["layout"], (_, height) = check_envmap_options(
            convention, layout, size, sun_mode, ground, units=units)
        if mips:
            from skydome.export.prefilter import check_mip_levels

            if checked["layout"] not in ("latlong", "cubemap", "faces", "cross"):
                raise ValueError(f"--mips: layout = {checked['layout']!r} has no prefiltered "
                                 "mips (latlong, cubemap, faces or cross)")
            check_mip_levels(mips, height, "mips")
        if half and sun_in_map:
            raise ValueError("--half cannot hold the sun (half floats end at 65504): drop "
                             "--sun-in-map or --half")
        checked["p"] = check_map_path(out, half)
        if ground_albedo is not None:
            check_number("ground_albedo", ground_albedo, 0.0, 1.0)
        check_int("wavelengths", wavelengths, 3, 401)

    _keep_freed_memory()
    # the model built as the render command builds it (_kit._build_model): numba's start
    # on a second thread while the model is constructed (a cached precomputed model reads
    # and decodes its tables meanwhile), its set-up's progress on the bar
    progress = _Progress(f"exporting {model}")
    try:
        sky = _sky(model, extra, sun, check, progress)
        conv, layout, p = checked["conv"], checked["layout"], checked["p"]

        # 2. work
        progress.label = f"exporting {model} ({conv.name}, {layout})"
        t0 = _time.perf_counter()
        env = render_envmap(sky, conv, size, layout, sun=sun_mode, ground=ground,
                            ground_albedo=ground_albedo,
                            wavelengths_nm=wavelength_grid(380.0, 780.0, n=wavelengths),
                            progress=progress, units=units)
    finally:
        progress.close()
    # the map and its sun light file are one unit: both or neither (a full disk)
    light = None if sun_in_map else sun_light(sky, conv, units=env.units.name)
    also = [] if light is None else [(_sun_path(out), sun_json_writer(light))]
    written = env.write(p, half=half, also=also)
    if mips:
        from skydome.export.prefilter import prefiltered_mips, write_mips

        try:
            written += write_mips(prefiltered_mips(env, mips), p, half=half)
        except BaseException:
            for w in written:
                w.unlink(missing_ok=True)
            raise
    if sh:
        coef = env.irradiance_sh()
        doc = {"convention": conv.name, "order": 2, "basis": "real SH Y00, Y1-1, Y10, Y11, "
               "Y2-2, Y2-1, Y20, Y21, Y22 in the convention's x, y, z (Ramamoorthi & "
               "Hanrahan 2001 eq. 3)", "coefficients_rgb": coef.tolist(),
               "irradiance": "E(n) = sum A_l L_lm Y_lm(n), A = (pi, 2 pi / 3, pi / 4): RGB "
               "irradiance " + ("[W m^-2] " if env.units.name == "photometric" else "")
               + f"in the map's units ({env.units.name}: its pixels' radiance units x sr)",
               "units": env.units.name,
               "includes_sun": bool(sun_in_map)}
        from pathlib import Path

        from skydome._io import atomic_write as _atomic_write

        shp = Path(out).with_name(Path(out).stem + ".sh.json")

        def w(tmp):
            with open(tmp, "w", encoding="utf-8") as f:
                json.dump(doc, f, indent=2)
        _atomic_write(shp, w)
        written.append(shp)
    dt = _time.perf_counter() - t0
    typer.echo(f"wrote {', '.join(str(x) for x in written)} ({model}, {conv.name} {layout}, "
               f"{dt:.1f} s)")


@export_app.command("sun", context_settings=EXTRA)
@sun_options()
def sun_cmd(
    ctx: typer.Context,
    model: str = _MODEL,
    out: str = typer.Option(..., help="Output .json file."),
    convention: str = typer.Option("skydome", help="Axes of the direction: a convention name."),
    units: Optional[str] = typer.Option(
        None, help="Scale of the map the RGB irradiance goes with: photometric (683 lm/W) or "
                   "mitsuba (Mitsuba 3's); default the convention's own (mitsuba for mitsuba, "
                   "else photometric)."),
    **sun,
):
    """The sun as a light: direction, angular radius, spectral and RGB irradiance, lx."""
    _run(_sun, ctx.args, model, out, convention, sun, units)


def _sun(extra, model, out, convention, sun, units=None):
    from pathlib import Path

    from skydome.export.conventions import get_convention, resolve_units
    from skydome.export.sun import sun_light, write_sun_json

    p = Path(out)

    def check():
        resolve_units(convention, units)                 # a convention and units it knows
        if p.suffix.lower() != ".json":
            raise UserError(f"out = {out!r} must end in .json")
        if not (p.parent if str(p.parent) else Path(".")).is_dir():
            raise UserError(f"out = {out!r}: folder {str(p.parent)!r} does not exist")

    conv = get_convention(convention)
    sky = _sky(model, extra, sun, check)
    light = sun_light(sky, conv, units=units)
    if light is None:
        raise UserError(f"model {model!r} has no sun above the horizon to export "
                        f"(sun elevation {sky.sun.elevation_deg:.2f} deg)")
    write_sun_json(light, p)
    typer.echo(f"wrote {out} ({light['illuminance_lx']:.0f} lx, {conv.name} axes)")


@export_app.command("luts", context_settings=EXTRA)
@sun_options()
def luts_cmd(
    ctx: typer.Context,
    model: str = _MODEL,
    out: str = typer.Option(..., help="Output folder (created complete, or files replaced in it)."),
    format: str = typer.Option("npy,bin", "--format", help="Comma-separated: exr, npy, bin."),
    half: bool = typer.Option(False, "--half", help="Half-float EXR (with --format exr)."),
    **sun,
):
    """Bake the model's tables for a real-time renderer: precomputed in Bruneton's layout,
    hillaire2020 in Hillaire's, fitted as its XYZ tables over sun elevation (+ luts.json:
    axes, mappings, units, XYZ conversion)."""
    _run(_luts, ctx.args, model, out, format, half, sun)


def _luts(extra, model, out, formats, half, sun):
    from skydome._io import check_output_folder
    from skydome.export.luts import LUT_MODELS, check_luts_options, write_luts

    checked = {}

    def check():
        if model not in LUT_MODELS:
            raise ValueError(f"model = {model!r} has no LUT bake; valid: {', '.join(LUT_MODELS)}")
        checked["formats"] = check_luts_options(formats, half)
        check_output_folder(out)

    from skydome._progress import reporting

    progress = _Progress(f"baking {model} LUTs")
    t0 = _time.perf_counter()
    try:
        sky = _sky(model, extra, sun, check, progress)
        with reporting(progress):
            written = write_luts(sky, out, checked["formats"], half=half, progress=progress)
    finally:
        progress.close()
    typer.echo(f"wrote {len(written)} files into {out} ({model}, "
               f"{_time.perf_counter() - t0:.1f} s)")



@export_app.command("radiance", context_settings=EXTRA)
@sun_options("sun_elevation", "sun_azimuth", "lat", "lon", "time")
def export_radiance_cmd(
    ctx: typer.Context,
    out: str = typer.Option(..., "--out", help="output .rad (with .dat and .cal beside it)"),
    model: str = typer.Option("perez1993", "--model", help="any skydome model"),
    dni: Optional[float] = typer.Option(None, "--dni", help="direct normal irradiance [W/m^2]"),
    dhi: Optional[float] = typer.Option(None, "--dhi",
                                        help="diffuse horizontal irradiance [W/m^2]"),
    param: list[str] = typer.Option([], "--param", help="model parameter NAME=VALUE (repeat); "
                                    "the same as --NAME VALUE"),
    overwrite: bool = typer.Option(False, "--overwrite", help="replace existing outputs"),
    **sun,
):
    """A Radiance sky for one time: the model's sky as a brightdata pattern, its sun as a
    light source.

    Model parameters are given as extra options, e.g. --turbidity 3 (or --param turbidity=3).
    """
    _run(_radiance, ctx.args, out, model, dni, dhi, param, overwrite, sun)


def _radiance(extra, out, model, dni, dhi, param, overwrite, sun):
    from skydome.daylighting.scene import write_radiance_sky
    from skydome.models import get_model_class

    cls = get_model_class(model)
    params = _parse_model_params(cls, _param_options(param) + list(extra))
    if dni is not None:
        params["dni"] = dni
    if dhi is not None:
        params["dhi"] = dhi
    m = cls(sun=_sun_from(sun), **params)
    files = write_radiance_sky(m, out, overwrite=overwrite)
    typer.echo(f"wrote {', '.join(str(f) for f in files)}")


@export_app.command("blender-addon")
def blender_addon_cmd(
    out: str = typer.Option(..., help="The add-on's zip file (.zip), for Blender 4.2 LTS to "
                                      "5.x: Edit > Preferences > Add-ons > Install from Disk."),
):
    """Pack skydome's Blender add-on (a World panel that bakes the sky through skydome and
    makes the World, the sun lamp and the exposure) as an installable zip."""
    from skydome.export.integrations.blender import pack_addon

    p = _run(pack_addon, out)
    typer.echo(f"wrote {p}")


@export_app.command("threejs")
def threejs_cmd(
    out: str = typer.Option(..., help="Output folder (created complete, or its files "
                                      "replaced): the ES module, its example page and the "
                                      "shaders."),
):
    """Write the three.js module that draws the precomputed or the fitted sky from an
    `export luts --model precomputed|fitted --format bin` folder, with an example page
    (docs/rendering.md)."""
    from skydome.export.integrations.threejs import write_threejs

    written = _run(write_threejs, out)
    typer.echo(f"wrote {len(written)} files into {out}")
