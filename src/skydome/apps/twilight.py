"""Twilight as files (``skydome twilight``): the fisheye frames and horizon views from 0 to
-18 deg, their exposure, the contact sheets, the figure and the CSV. The physics (the
models per depression, zenith luminance, horizontal illuminance, the anti-solar profile,
the Belt of Venus and the earth's shadow) is in :mod:`skydome.effects.twilight`.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Callable

import numpy as np

from skydome._io import atomic_folder, check_output_folder
from skydome.effects.twilight import (SUN_AZIMUTH_DEG, anti_solar_profile, belt_of_venus,
                                      horizontal_illuminance, sky_luminance, twilight_models)
from skydome.imaging.plots import plot_twilight
from skydome.imaging.sheets import contact_sheet, to_uint8

__all__ = ["horizon_views", "run_twilight", "demo_effects", "EXPOSURES"]


def horizon_views(size: int, sun_azimuth_deg: float = SUN_AZIMUTH_DEG, fov_deg: float = 100.0,
                  centre_elevation_deg: float = 25.0):
    """Two pinhole cameras (:class:`skydome.camera.Camera`) looking at the horizon:
    towards the sun (the twilight arch) and away from it (the earth's shadow under the Belt
    of Venus). Each is ``size`` x ``size // 2`` pixels with a horizontal field ``fov_deg``,
    its centre ``centre_elevation_deg`` above the horizon (so the horizon lies near the
    bottom edge), image top towards the zenith."""
    from skydome.camera import Camera
    from skydome.transport.geometry import direction_from_angles

    cams = []
    for az in (sun_azimuth_deg, (sun_azimuth_deg + 180.0) % 360.0):
        d = direction_from_angles(centre_elevation_deg, az)
        cams.append(Camera(size, max(2, size // 2), fov_deg=fov_deg, position=(0.0, 0.0, 0.0),
                           look_at=tuple(d), up=(0.0, 0.0, 1.0)))
    return cams


EXPOSURES = ("ramp", "one", "auto")


def run_twilight(out_dir, model: str = "precomputed", step_deg: float = 2.0, size: int = 192,
                 wavelengths: int = 16, exposure: str = "ramp", progress: Callable | None = None,
                 **params) -> dict:
    """Render the twilight sequence 0..-18 deg into ``out_dir`` (written atomically):
    ``frame_sun_minus_DDD.png`` fisheyes and ``horizon_sun_minus_DDD.png`` horizon views
    (towards the sun above the view away from it, see :func:`horizon_views`) (DDD in tenths
    of a degree), ``contact_sheet.png`` (fisheyes) and ``horizon_sheet.png`` (horizon views),
    both 5 frames a row, ``twilight.png``
    (zenith luminance and horizontal illuminance against depression, the anti-solar
    profiles) and ``twilight.csv``.

    Exposure (the sky dims by 10^7 from 0 to -18 deg): each fisheye and its horizon view
    share one exposure multiplier k [m^2/cd]. ``exposure="ramp"`` (default): k = k_0
    (A_0 / A)^0.8, with A the log-average sky luminance (the statistic of the automatic
    exposure) and k_0, A_0 the first frame's: the exposure makes up 80 % of the fall in
    log luminance, so the frames darken frame by frame (by 10^1.4 over 10^7) and stay
    readable. ``exposure="one"``: the
    first frame's k for every frame (true relative brightness; deep twilight is black).
    ``exposure="auto"``: k is each fisheye's own automatic exposure (Reinhard's key 0.18 on
    the log-average sky luminance), so every pair looks about equally bright (-12 deg
    looks like day): not a faithful sequence, kept for inspecting colours."""
    from skydome._validate import check_int, check_number
    from skydome.imaging import render
    from skydome.imaging.projections import Fisheye
    from skydome.spectra import wavelength_grid

    from skydome._validate import check_choice

    step = check_number("step", step_deg, 0.25, 9.0, "deg")
    check_choice("exposure", exposure, EXPOSURES)
    size = check_int("size", size, 16, 2048)
    wl = wavelength_grid(380.0, 780.0, n=check_int("wavelengths", wavelengths, 3, 401))
    out_dir = check_output_folder(out_dir)
    deps = np.arange(0.0, 18.0 + 1e-9, step)
    skies = twilight_models(model, list(deps), **params)
    prof_el = np.arange(0.5, 40.0, 0.5)
    rows, frames, horizons = [], [], []
    cams = horizon_views(max(16, size), skies[0].sun.azimuth_deg)
    k0 = None
    with atomic_folder(out_dir) as tmp:
        for n, (dep, sky) in enumerate(zip(deps, skies)):
            zen = float(sky_luminance(sky, np.array([0.0, 0.0, 1.0]), wl))
            eh = horizontal_illuminance(sky, wl)
            lum, rb = anti_solar_profile(sky, prof_el, wl)
            img = render(sky, Fisheye(size), wl, draw_sun=False)
            tag = f"sun_minus_{int(round(dep * 10)):03d}.png"   # tenths of a degree
            if zen > 0:
                k = img.auto_exposure()
                if exposure != "auto":
                    if k0 is None:
                        k0 = k
                    # auto exposure is inversely proportional to the log-average luminance
                    k = k0 * (k / k0) ** (0.8 if exposure == "ramp" else 0.0)
                img.save(tmp / f"frame_{tag}", exposure=k)
                frames.append((dep, zen, tmp / f"frame_{tag}"))
                halves = [render(sky, c, wl, draw_sun=False).to_srgb(exposure=k) for c in cams]
                gap = np.zeros((2, halves[0].shape[1], 3))
                _save_srgb(np.concatenate([halves[0], gap, halves[1]], axis=0), tmp / f"horizon_{tag}")
                horizons.append((dep, zen, tmp / f"horizon_{tag}"))
            belt = belt_of_venus(prof_el, rb, lum) if (zen > 0 and dep <= 6.0) else None
            rows.append((dep, zen, eh, lum, rb, belt if belt is not None and belt["found"] else None))
            if progress is not None:
                progress(n + 1, len(deps))
        # both sheets 5 frames a row (10 frames at the default step: about 2:1)
        _sheet(frames, tmp / "contact_sheet.png", tile=min(160, size), cols=5)
        hv = max(16, size)
        _sheet(horizons, tmp / "horizon_sheet.png", tile=(hv, 2 * max(2, hv // 2) + 2), cols=5,
               header="each: sun side above, anti-sun side below")
        plot_twilight(rows, prof_el, tmp / "twilight.png")
        with open(tmp / "twilight.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["sun_elevation_deg", "zenith_luminance_cd_m2", "horizontal_illuminance_lx",
                        "belt_of_venus_elevation_deg", "belt_red_blue", "shadow_red_blue",
                        "shadow_top_deg", "belt_luminance_cd_m2", "shadow_luminance_cd_m2"])
            for dep, zen, eh, _, _, b in rows:
                extra = ([f"{b[k]:.4g}" for k in ("belt_deg", "belt_rb", "shadow_rb", "shadow_top_deg",
                                                   "belt_luminance", "shadow_luminance")]
                         if b is not None else [""] * 6)
                w.writerow([-dep + 0.0, f"{zen:.6g}", f"{eh:.6g}"] + extra)
    return {"depression_deg": deps, "zenith_luminance": np.array([r[1] for r in rows]),
            "horizontal_illuminance": np.array([r[2] for r in rows])}


def _save_srgb(rgb, path: Path) -> None:
    from PIL import Image

    Image.fromarray(to_uint8(rgb)).save(path)


def _sheet(frames, path: Path, tile, cols: int, header: str | None = None) -> None:
    """Frames (depression, zenith luminance, png) as a contact sheet with both in the label
    and an optional ``header`` line above the grid."""
    if frames:
        contact_sheet([(p, [f"sun {-dep + 0.0:g} deg", f"zenith {zen:.2g} cd/m2"])
                       for dep, zen, p in frames], path, cols=cols, tile=tile, background=(12, 12, 12),
                      column_labels=None if header is None else [header], line_height=15, font_size=12)


def demo_effects(out_dir) -> list[Path]:
    """A small twilight sequence for ./scripts/demo (steps of 2 deg, 156 px: 10 frames, two
    rows of 5, so both sheets are about 2:1 like the demo's gallery cells)."""
    target = Path(out_dir) / "twilight"
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    # half-size precomputed tables (the docs figures use the defaults)
    run_twilight(target, step_deg=2.0, size=156, wavelengths=10, scattering_r_size=16,
                 scattering_mu_size=64, scattering_mu_s_size=16, orders=3, n_wavelengths=10)
    return [target / "contact_sheet.png", target / "horizon_sheet.png", target / "twilight.png"]
