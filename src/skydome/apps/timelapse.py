"""The colour of the sky through a day (survey section 5.1): ``skydome timelapse``.

For a place and a date, the sun's position is computed every ``every`` minutes (NREL SPA),
and for every time at which the sun is above ``min_elevation_deg`` the model is rendered
(a fisheye by default). Besides the frames, the sequence is summarised by

* ``contact_sheet.png``: the frames in order, labelled with the local time, all at ONE
  exposure (that of the brightest frame's automatic exposure, so that dusk is dark);
* ``colours.png``: the colour of the zenith, of the horizon under the sun (elevation 3 deg
  at the sun's azimuth) and of the sun's disc (where the model has a sun) against time, as
  colour strips (chromaticity at constant brightness) with their luminance [cd m^-2] and
  the sun's elevation below;
* ``colours.csv``: the numbers behind the figure (time, sun elevation/azimuth, XYZ of the
  zenith, horizon and sun).

Frames a model refuses (e.g. a sun below its valid range) are skipped and listed.
"""

from __future__ import annotations

import csv
import datetime as _dt
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from skydome._io import atomic_folder, check_output_folder
from skydome.imaging.plots import plot_day_colours
from skydome.imaging.sheets import contact_sheet

__all__ = ["TimelapseFrame", "day_times", "run_timelapse", "model_builder"]


@dataclass
class TimelapseFrame:
    time: _dt.datetime
    elevation_deg: float
    azimuth_deg: float
    image_path: Path | None
    zenith_xyz: np.ndarray | None
    horizon_xyz: np.ndarray | None
    sun_xyz: np.ndarray | None
    note: str = ""


def day_times(date: str, utc_offset: str = "+00:00", every_min: float = 10.0,
              start: str = "00:00", end: str = "23:59") -> list[_dt.datetime]:
    """Timezone-aware times on ``date`` (YYYY-MM-DD) from ``start`` to ``end`` (HH:MM local)
    every ``every_min`` minutes."""
    from skydome._validate import check_number
    from skydome.sun import parse_time

    every = check_number("every", every_min, 1.0, 720.0, "min")
    t0 = parse_time(f"{date}T{start}{utc_offset}")
    t1 = parse_time(f"{date}T{end}{utc_offset}")
    if t1 < t0:
        raise ValueError(f"end = {end!r} is before start = {start!r}")
    out = []
    t = t0
    while t <= t1:
        out.append(t)
        t = t + _dt.timedelta(minutes=every)
    return out


def parse_every(text: str) -> float:
    """'10min', '1h', '30s' or a number of minutes -> minutes."""
    s = str(text).strip().lower()
    for suffix, factor in (("min", 1.0), ("m", 1.0), ("h", 60.0), ("s", 1.0 / 60.0)):
        if s.endswith(suffix):
            try:
                return float(s[: -len(suffix)]) * factor
            except ValueError:
                break
    try:
        return float(s)
    except ValueError:
        raise ValueError(f"every = {text!r} is not a duration such as 10min, 1h or 30s") from None


def _build_model(name: str, params: dict, sun):
    import skydome as sd

    return sd.model(name, sun=sun, **params)


def model_builder(name: str, params: dict | None = None) -> Callable:
    """``build(sun)`` for :func:`run_timelapse` that can be sent to Dask workers (a partial of
    a module-level function, not a closure)."""
    import functools

    return functools.partial(_build_model, name, dict(params or {}))


def _probe_directions(az_deg: float) -> np.ndarray:
    from skydome.transport.geometry import direction_from_angles

    return direction_from_angles(np.array([90.0, 3.0]), np.array([0.0, az_deg]))


def _render_frame(build, el: float, az: float, projection: str, size: int, wavelengths: int):
    """One frame as a Dask task: the rendered image and the probe colours, packed
    (:func:`skydome.apps._chunked.pack_image`)."""
    from skydome.apps._chunked import pack_image
    from skydome.imaging import make_projection, render
    from skydome.spectra import spectrum_to_xyz, wavelength_grid
    from skydome.sun import Sun

    wl = wavelength_grid(380.0, 780.0, n=wavelengths)
    try:
        sky = build(Sun(elevation_deg=el, azimuth_deg=az))
        img = render(sky, make_projection(projection, str(size)), wl)
        zen, hor = sky.xyz(_probe_directions(az))
        sxyz = None
        if sky.native == "spectral" and sky.sun_radiance(wl) is not None:
            sxyz = spectrum_to_xyz(sky.sun_radiance(wl), wl)
    except ValueError as exc:
        return pack_image(None, str(exc))
    return pack_image(img, zenith=zen, horizon=hor, sun=sxyz)


def run_timelapse(build: Callable, lat_deg: float, lon_deg: float, times, out_dir, *,
                  min_elevation_deg: float = -6.0, size: int = 256, wavelengths: int = 16,
                  projection: str = "fisheye", progress: Callable | None = None,
                  scheduler: str | None = None, workers: int = 0,
                  connect_timeout_s: float = 10.0, client=None,
                  sheet_cols: int = 8) -> list[TimelapseFrame]:
    """Render ``build(sun)`` at each time with the sun above ``min_elevation_deg``.

    Everything is written into a temporary folder beside ``out_dir`` and moved in at the
    end, so a failure leaves nothing behind.

    With ``scheduler`` (a dask.distributed address), ``workers`` > 0 (a local cluster of
    that many processes) or ``client``, every frame is a chunk of
    :func:`skydome.distributed.run_chunks`, kept in ``OUT.chunks/`` until the folder is
    written: a rerun after an interruption renders only the missing frames. ``build`` must
    then be picklable (:func:`model_builder`); ``connect_timeout_s`` bounds the wait for
    ``scheduler`` (:func:`skydome.distributed.run_chunks`).

    ``contact_sheet.png`` has ``sheet_cols`` frames a row, each in a box of
    min(128, ``size``) pixels.
    """
    from skydome._validate import check_int, check_number
    from skydome.imaging import make_projection, render
    from skydome.spectra import spectrum_to_xyz, wavelength_grid
    from skydome.sun import Sun, solar_position
    check_number("lat", lat_deg, -90.0, 90.0, "deg")
    check_number("lon", lon_deg, -180.0, 180.0, "deg")
    min_el = check_number("min_elevation_deg", min_elevation_deg, -90.0, 90.0, "deg")
    check_int("size", size, 16, 4096)
    check_int("sheet_cols", sheet_cols, 1, 64)
    wl = wavelength_grid(380.0, 780.0, n=check_int("wavelengths", wavelengths, 3, 401))
    proj = make_projection(projection, str(size))
    out_dir = check_output_folder(out_dir)
    times = list(times)
    el, az = solar_position(lat_deg, lon_deg, times)
    el, az = np.atleast_1d(el), np.atleast_1d(az)
    todo = [i for i in range(len(times)) if el[i] >= min_el]
    if not todo:
        raise ValueError(f"the sun never rises above min_elevation_deg = {min_el:g} deg on that day")

    frames: list[TimelapseFrame] = []
    images = []
    chunk_dir = None
    if scheduler is not None or workers > 0 or client is not None:
        from skydome.apps._chunked import load_chunk, unpack_image
        from skydome.distributed import Chunk, run_chunks

        chunk_dir = Path(f"{out_dir}.chunks")
        chunks = [Chunk(f"frame{i:05d}", _render_frame,
                        (build, float(el[i]), float(az[i]), projection, size, wl.size))
                  for i in todo]
        run_chunks(chunks, chunk_dir, scheduler=scheduler, n_workers=max(workers, 1),
                   client=client, progress=progress is not None,
                   connect_timeout_s=connect_timeout_s)
    with atomic_folder(out_dir) as tmp:
        for n, i in enumerate(todo):
            t = times[i]
            frame = TimelapseFrame(t, float(el[i]), float(az[i]), None, None, None, None)
            name = f"frame_{t.strftime('%H%M')}.png"
            if chunk_dir is not None:
                img, note, ex = unpack_image(load_chunk(chunk_dir, f"frame{i:05d}"), proj)
                if img is None:
                    frame.note = note
                else:
                    images.append((t, img, name))
                    frame.zenith_xyz, frame.horizon_xyz = ex["zenith"], ex["horizon"]
                    frame.sun_xyz = ex.get("sun")
                    frame.image_path = out_dir / name
            else:
                sun = Sun(elevation_deg=float(el[i]), azimuth_deg=float(az[i]))
                try:
                    sky = build(sun)
                    img = render(sky, proj, wl)
                    images.append((t, img, name))
                    frame.zenith_xyz, frame.horizon_xyz = sky.xyz(_probe_directions(az[i]))
                    if sky.native == "spectral" and sky.sun_radiance(wl) is not None:
                        frame.sun_xyz = spectrum_to_xyz(sky.sun_radiance(wl), wl)
                    frame.image_path = out_dir / name
                except ValueError as exc:
                    frame.note = str(exc)
            frames.append(frame)
            if progress is not None and chunk_dir is None:
                progress(n + 1, len(todo))
        if not images:
            raise ValueError("the model refused every frame: " + frames[0].note)
        # one exposure for the whole day: the brightest frame's automatic exposure
        k = min(img.auto_exposure() for _, img, _ in images)
        for _, img, name in images:
            img.save(tmp / name, exposure=k)
        contact_sheet([(img.to_srgb(exposure=k), t.strftime("%H:%M")) for t, img, _ in images],
                      tmp / "contact_sheet.png", cols=sheet_cols, tile=min(128, int(size)),
                      line_height=15, font_size=12)
        _write_csv(frames, tmp / "colours.csv")
        plot_day_colours(frames, tmp / "colours.png", _display_colour)
    if chunk_dir is not None:
        import shutil

        shutil.rmtree(chunk_dir, ignore_errors=True)
    return frames


def _write_csv(frames, path: Path) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time", "sun_elevation_deg", "sun_azimuth_deg", "zenith_X", "zenith_Y", "zenith_Z",
                    "horizon_X", "horizon_Y", "horizon_Z", "sun_X", "sun_Y", "sun_Z", "note"])
        for f in frames:
            def tri(v):
                return ["" if v is None else f"{x:.6g}" for x in (v if v is not None else (None,) * 3)]
            w.writerow([f.time.isoformat(), f"{f.elevation_deg:.4f}", f"{f.azimuth_deg:.4f}",
                        *tri(f.zenith_xyz), *tri(f.horizon_xyz), *tri(f.sun_xyz), f.note])


def _display_colour(xyz) -> np.ndarray:
    """Chromaticity shown at constant brightness: linear sRGB / max, gamut-clipped, encoded."""
    from skydome.spectra import srgb_encode, xyz_to_linear_srgb

    if xyz is None or not np.all(np.isfinite(xyz)) or xyz[1] <= 0:
        return np.array([0.1, 0.1, 0.1])
    rgb = np.maximum(xyz_to_linear_srgb(np.asarray(xyz, dtype=float)), 0.0)
    return np.clip(srgb_encode(rgb / max(rgb.max(), 1e-30)), 0, 1)
