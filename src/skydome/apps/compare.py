"""Side-by-side comparison of sky models against a reference (``skydome compare``).

For every sun elevation, every model is rendered on the same fisheye grid and compared
with the reference model (by default the brute-force ``single_scattering``):

* ``grid.png``: models (rows) x sun elevations (columns), tone mapped with ONE exposure
  per column (the reference's automatic exposure), labelled;
* ``error_<model>.png``: the luminance ratio per sun elevation as log2(L / L_ref), false
  colour from -2 to +2 (a quarter to four times the reference);
* ``table.md`` and ``table.csv``: per model and sun elevation, the luminance RMS relative
  error and the mean / max chromaticity distance (CIE 1931 xy) over the upper hemisphere
  (solid-angle weighted), and the run time.

Luminance-only models carry no colour: their chromaticity error is reported as "n/a".
A model that refuses a sun elevation (outside its valid range) gets "n/a" with the reason.
"""

from __future__ import annotations

import csv
import io
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from skydome._io import atomic_folder, check_output_folder
from skydome.imaging.plots import plot_error_maps
from skydome.imaging.sheets import contact_sheet

__all__ = ["ComparisonRow", "run_comparison", "sky_errors"]


@dataclass
class ComparisonRow:
    model: str
    sun_elevation_deg: float
    luminance_rms: float = float("nan")        # relative, solid-angle weighted
    luminance_mean_bias: float = float("nan")  # relative
    chromaticity_mean: float = float("nan")    # xy distance
    chromaticity_max: float = float("nan")
    seconds: float = float("nan")
    note: str = ""
    extra: dict = field(default_factory=dict)


def sky_errors(xyz, xyz_ref, weights, has_colour: bool = True) -> dict:
    """Errors of one sky against a reference over the pixels with weight > 0.

    Returns luminance RMS relative error, mean relative bias, and mean/max xy distance.
    """
    Y, Yr = xyz[..., 1], xyz_ref[..., 1]
    m = (weights > 0) & (Yr > 0) & np.isfinite(Y)
    w = weights[m] / weights[m].sum()
    rel = Y[m] / Yr[m] - 1.0
    out = {"luminance_rms": float(np.sqrt(np.sum(w * rel * rel))),
           "luminance_mean_bias": float(np.sum(w * rel))}
    if has_colour:
        from skydome.spectra import xyz_to_xy

        d = np.linalg.norm(xyz_to_xy(xyz[m]) - xyz_to_xy(xyz_ref[m]), axis=-1)
        out["chromaticity_mean"] = float(np.sum(w * d))
        out["chromaticity_max"] = float(d.max())
    return out


def _call_spec(func, extra, spec, sun):
    return func(spec, extra, sun)


def spec_builder(func: Callable, extra) -> Callable:
    """``build(spec, sun) = func(spec, extra, sun)`` as a picklable partial of module-level
    functions, for :func:`run_comparison` on Dask."""
    import functools

    return functools.partial(_call_spec, func, extra)


def _default_build(spec, sun):
    from skydome.models import model as _model

    return _model(spec, sun=sun)


def _render_cell(build, spec: str, e: float, azimuth: float, size: int, wavelengths: int):
    """One grid cell as a Dask task: the image (no sun disc), its render time, its kind."""
    from skydome.apps._chunked import pack_image
    from skydome.imaging import render
    from skydome.imaging.projections import Fisheye
    from skydome.spectra import wavelength_grid
    from skydome.sun import Sun

    wl = wavelength_grid(380.0, 780.0, n=wavelengths)
    try:
        sky = build(spec, Sun(elevation_deg=e, azimuth_deg=azimuth))
        t0 = time.perf_counter()
        img = render(sky, Fisheye(size), wl, draw_sun=False)
        seconds = time.perf_counter() - t0
    except ValueError as exc:
        return pack_image(None, str(exc))
    return pack_image(img, seconds=seconds, native=np.array(sky.native))


def run_comparison(specs: Sequence[str], sun_elevations: Sequence[float], out_dir, *,
                   reference: str = "precomputed", sun_azimuth_deg: float = 180.0,
                   size: int = 128, wavelengths: int = 16,
                   build: Callable | None = None, progress: Callable | None = None,
                   scheduler: str | None = None, workers: int = 0,
                   connect_timeout_s: float = 10.0, client=None) -> list[ComparisonRow]:
    """Render and compare; write the report into ``out_dir`` (created if missing).

    With ``scheduler`` (a dask.distributed address), ``workers`` > 0 (a local cluster) or
    ``client``, every (model, sun elevation) cell is a chunk of
    :func:`skydome.distributed.run_chunks`, kept in ``OUT.chunks/`` until the report is
    written (a rerun renders only the missing cells); ``build`` must then be picklable
    (:func:`spec_builder`); ``connect_timeout_s`` bounds the wait for ``scheduler``
    (:func:`skydome.distributed.run_chunks`).

    Parameters
    ----------
    specs : sequence of str
        Model specs; ``build(spec, sun)`` turns each into a model (default: the registered
        model of that name with default parameters). The reference is added first if absent.
    sun_elevations : sequence of float
        Sun elevations [deg].
    out_dir : path
        Output folder; files are written to a temporary folder first and moved in at the end.
    """
    from skydome._validate import check_int, check_number
    from skydome.imaging import render
    from skydome.imaging.projections import Fisheye
    from skydome.spectra import wavelength_grid
    from skydome.sun import Sun

    size = check_int("size", size, 16, 4096)
    wavelengths = check_int("wavelengths", wavelengths, 3, 401)
    elevs = [check_number("sun_elevation", e, -90.0, 90.0, "deg") for e in sun_elevations]
    if not elevs:
        raise ValueError("sun_elevation is empty: give at least one sun elevation")
    if build is None:
        build = _default_build
    specs = list(specs)
    if reference not in [s.partition(":")[0] for s in specs]:
        specs.insert(0, reference)
    ref_spec = next(s for s in specs if s.partition(":")[0] == reference)
    out_dir = check_output_folder(out_dir)
    # build every model once up front so that bad specs fail before any work
    for spec in specs:
        try:
            build(spec, Sun(elevation_deg=45.0, azimuth_deg=sun_azimuth_deg))
        except ValueError as exc:
            if "elevation" not in str(exc):
                raise

    wl = wavelength_grid(380.0, 780.0, n=wavelengths)
    proj = Fisheye(size)
    dirs, mask = proj.directions()
    weights = np.where(mask & (dirs[..., 2] > 0), proj.solid_angles(), 0.0)

    images: dict[tuple[str, float], object] = {}
    xyzs: dict[tuple[str, float], np.ndarray] = {}
    rows: list[ComparisonRow] = []
    total = len(specs) * len(elevs)
    done = 0
    chunk_dir = None
    if scheduler is not None or workers > 0 or client is not None:
        from skydome.apps._chunked import load_chunk, unpack_image
        from skydome.distributed import Chunk, run_chunks

        chunk_dir = Path(f"{out_dir}.chunks")
        cells = {(spec, e): f"cell{k:03d}_{m:03d}" for m, e in enumerate(elevs)
                 for k, spec in enumerate(specs)}
        run_chunks([Chunk(key, _render_cell, (build, spec, e, sun_azimuth_deg, size,
                                              wavelengths))
                    for (spec, e), key in cells.items()], chunk_dir, scheduler=scheduler,
                   n_workers=max(workers, 1), client=client, progress=progress is not None,
                   connect_timeout_s=connect_timeout_s)
    for e in elevs:
        sun = Sun(elevation_deg=e, azimuth_deg=sun_azimuth_deg)
        for spec in specs:
            row = ComparisonRow(spec, e)
            if chunk_dir is not None:
                img, note, ex = unpack_image(load_chunk(chunk_dir, cells[spec, e]), proj)
                if img is None:
                    row.note = note
                else:
                    row.seconds = float(ex["seconds"])
                    images[spec, e] = img
                    xyzs[spec, e] = img.xyz()
                    row.extra["native"] = str(ex["native"])
                rows.append(row)
                continue
            try:
                sky = build(spec, sun)
                t0 = time.perf_counter()
                img = render(sky, proj, wl, draw_sun=False)
                row.seconds = time.perf_counter() - t0
                images[spec, e] = img
                xyzs[spec, e] = img.xyz()
                row.extra["native"] = sky.native
            except ValueError as exc:
                row.note = str(exc)
            rows.append(row)
            done += 1
            if progress is not None:
                progress(done, total)
    if chunk_dir is not None and progress is not None:
        progress(total, total)
    for row in rows:
        ref = xyzs.get((ref_spec, row.sun_elevation_deg))
        got = xyzs.get((row.model, row.sun_elevation_deg))
        if ref is None or got is None:
            if not row.note:
                row.note = "reference unavailable"
            continue
        err = sky_errors(got, ref, weights, has_colour=row.extra.get("native") != "luminance")
        for k, v in err.items():
            setattr(row, k, v)

    with atomic_folder(out_dir) as tmp:
        _write_grid(tmp / "grid.png", specs, elevs, images, ref_spec)
        for spec in specs:
            if spec != ref_spec:
                plot_error_maps(tmp / f"error_{_safe(spec)}.png", spec, elevs, xyzs, ref_spec, weights)
        (tmp / "table.md").write_text(table_markdown(rows, ref_spec))
        (tmp / "table.csv").write_text(table_csv(rows))
    if chunk_dir is not None:
        import shutil

        shutil.rmtree(chunk_dir, ignore_errors=True)
    return rows


def _safe(spec: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in spec)


def _fmt(v, pct=False):
    if v is None or not np.isfinite(v):
        return "n/a"
    return f"{v * 100:.2f} %" if pct else f"{v:.4f}"


def table_markdown(rows: list[ComparisonRow], reference: str) -> str:
    lines = [f"Errors against `{reference}` over the upper hemisphere (solid-angle weighted).", "",
             "| model | sun elevation | luminance RMS error | luminance bias | xy error mean | xy error max | render time | note |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        t = "n/a" if not np.isfinite(r.seconds) else f"{r.seconds:.2f} s"
        note = r.note.replace("|", "/")[:120]
        lines.append(f"| {r.model} | {r.sun_elevation_deg:g} deg | {_fmt(r.luminance_rms, True)} | "
                     f"{_fmt(r.luminance_mean_bias, True)} | {_fmt(r.chromaticity_mean)} | "
                     f"{_fmt(r.chromaticity_max)} | {t} | {note} |")
    return "\n".join(lines) + "\n"


def table_csv(rows: list[ComparisonRow]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["model", "sun_elevation_deg", "luminance_rms", "luminance_mean_bias",
                "chromaticity_mean", "chromaticity_max", "seconds", "note"])
    for r in rows:
        w.writerow([r.model, r.sun_elevation_deg, r.luminance_rms, r.luminance_mean_bias,
                    r.chromaticity_mean, r.chromaticity_max, r.seconds, r.note])
    return buf.getvalue()


def _write_grid(path: Path, specs, elevs, images, ref_spec, tile: int = 192) -> None:
    """Models x elevations, one exposure per column (the reference's automatic one)."""
    ks = {}
    for e in elevs:
        ref = images.get((ref_spec, e))
        ks[e] = ref.auto_exposure() if ref is not None else None
    tiles = []
    for spec in specs:
        for e in elevs:
            img = images.get((spec, e))
            rgb = None if img is None else img.to_srgb(exposure=ks[e] if ks[e] is not None else img.auto_exposure())
            tiles.append((rgb, ()))
    contact_sheet(tiles, path, cols=len(elevs), tile=tile, upscale=True, background=(24, 24, 24),
                  column_labels=[f"sun {e:g} deg" for e in elevs], row_labels=list(specs),
                  text_colours=((230, 230, 230),))
