"""The main job of ``./scripts/demo``: render sample skies into an output folder.

Run as ``python -m skydome.apps.demo --out out``. Every image is rendered through the public API
(the same calls as the README's examples) and a labelled contact sheet ``gallery.png`` ties
them together.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

# (file stem, model, model params, sun spec, projection, size, label)
JOBS = [
    ("noon_fisheye", "precomputed", {}, {"elevation_deg": 60.0, "azimuth_deg": 180.0},
     "fisheye", "512", "precomputed (default), sun 60 deg"),
    ("morning_fisheye", "precomputed", {}, {"elevation_deg": 30.0, "azimuth_deg": 135.0},
     "fisheye", "512", "precomputed (default), sun 30 deg SE"),
    ("sunset_fisheye", "precomputed", {}, {"elevation_deg": 2.0, "azimuth_deg": 270.0},
     "fisheye", "512", "precomputed (default), sun 2 deg W"),
    ("hazy_fisheye", "precomputed", {"turbidity": 8.0}, {"elevation_deg": 30.0, "azimuth_deg": 180.0},
     "fisheye", "512", "precomputed (default), turbidity 8"),
    ("single_scattering_fisheye", "single_scattering", {}, {"elevation_deg": 30.0, "azimuth_deg": 135.0},
     "fisheye", "512", "single scattering only, sun 30 deg SE"),
    ("preetham_fisheye", "preetham1999", {"turbidity": 3.0}, {"elevation_deg": 30.0, "azimuth_deg": 135.0},
     "fisheye", "512", "Preetham 1999, T 3, sun 30 deg SE"),
    ("perez_fisheye", "perez1993", {"dni": 650.0, "dhi": 120.0}, {"elevation_deg": 40.0, "azimuth_deg": 180.0},
     "fisheye", "512", "Perez 1993, DNI 650 DHI 120 W/m2 (luminance)"),
    ("cie2003_type12_fisheye", "cie2003", {"sky_type": 12}, {"elevation_deg": 40.0, "azimuth_deg": 180.0},
     "fisheye", "512", "CIE 2003 type 12 (luminance)"),
    ("precomputed_twilight_fisheye", "precomputed", {}, {"elevation_deg": -4.0, "azimuth_deg": 270.0},
     "fisheye", "512", "precomputed, sun -4 deg W (civil twilight)"),
    ("hillaire_fisheye", "hillaire2020", {}, {"elevation_deg": 10.0, "azimuth_deg": 90.0},
     "fisheye", "512", "Hillaire 2020, sun 10 deg E"),
    ("earth_from_space", "nishita1993", {"camera_altitude_m": 36e6}, {"elevation_deg": 30.0, "azimuth_deg": 180.0},
     "camera", "384", "Nishita 1993, earth from 36000 km"),
    ("vienna_sunset_equirect", "precomputed", {},
     {"location": (48.21, 16.37, "2026-06-21T20:45+02:00")}, "equirect", "1024x512",
     "Vienna 2026-06-21 20:45, equirect"),
]


def _sun(spec):
    from skydome.sun import Sun

    if "location" in spec:
        lat, lon, t = spec["location"]
        return Sun.from_location(lat, lon, t)
    return Sun(**spec)


def run(out_dir: Path, only: list[str] | None = None) -> list[Path]:
    import skydome as sd
    from skydome.render import make_projection
    from skydome.spectra import wavelength_grid

    out_dir.mkdir(parents=True, exist_ok=True)
    wl = wavelength_grid(380.0, 780.0, n=16)
    written: list[Path] = []
    tiles = []
    for stem, name, params, sun_spec, proj_name, size, label in JOBS:
        if only and stem not in only:
            continue
        t0 = time.perf_counter()
        sky = sd.model(name, sun=_sun(sun_spec), **params)
        proj = sky.default_projection(int(size)) if proj_name == "camera" else make_projection(proj_name, size)
        image = sd.render(sky, proj, wl, output="xyz")
        png = out_dir / f"{stem}.png"
        exposure = None
        if proj_name == "camera":
            # a planet on black space: expose for the bright disc, not for the log-average
            import numpy as np

            Y = image.luminance()[image.mask]
            exposure = 0.8 / float(np.percentile(Y[Y > 0], 99))
        image.save(png, exposure=exposure)
        hdr = out_dir / f"{stem}.exr"
        image.save(hdr)
        written += [png, hdr]
        tiles.append((png, label))
        print(f"{png}  ({label}, {time.perf_counter() - t0:.1f} s)")
    if not only:
        written += _effects(out_dir)
    if tiles:
        sheet = out_dir / "gallery.png"
        _contact_sheet(tiles, sheet)
        written.append(sheet)
        print(sheet)
    return written


def _effects(out_dir: Path) -> list[Path]:
    """Small versions of the atmospheric effects (survey section 5) into out/effects/."""
    import importlib

    import skydome as sd

    eff = out_dir / "effects"
    eff.mkdir(exist_ok=True)
    written: list[Path] = []
    t0 = time.perf_counter()
    # 5.1 the colour of the sky through a day (Vienna, summer solstice, hourly)
    from skydome.apps.timelapse import day_times, run_timelapse

    times = day_times("2026-06-21", "+02:00", 60.0)
    run_timelapse(lambda sun: sd.model("precomputed", sun=sun), 48.21, 16.37, times,
                  eff / "timelapse", size=96, wavelengths=12)
    written.append(eff / "timelapse" / "contact_sheet.png")
    # 5.5 Bishop's ring: a close-up of the sun through a ~1 um volcanic layer
    from skydome.apps.aureole import render_closeup
    from skydome.effects.aureole import bishops_ring_atmosphere

    img = render_closeup(bishops_ring_atmosphere(), sd.Sun(elevation_deg=45.0, azimuth_deg=180.0),
                         fov_deg=60.0, size=161)
    img.save(eff / "bishops_ring.png")
    written.append(eff / "bishops_ring.png")
    # 5.7 polarisation: single-scattering Rayleigh field (analytic)
    from skydome.effects.polarisation_maps import polarisation_maps
    from skydome.render.plots import plot_polarisation_maps

    pm = polarisation_maps("rayleigh_single", sd.Sun(elevation_deg=20.0, azimuth_deg=180.0), size=64)
    plot_polarisation_maps(pm, eff / "polarisation_rayleigh.png")
    written.append(eff / "polarisation_rayleigh.png")
    # twilight and aerial perspective, where those modules provide a demo
    for mod in ("skydome.apps.twilight", "skydome.apps.airlight"):
        try:
            m = importlib.import_module(mod)
        except ImportError:
            continue
        if hasattr(m, "demo_effects"):
            written += list(m.demo_effects(eff) or [])
    labels = {"contact_sheet.png": "", "bishops_ring.png": "Bishop's ring (1 um ash, Mie)",
              "polarisation_rayleigh.png": "polarisation (single Rayleigh)",
              "twilight.png": "twilight: zenith luminance, Belt of Venus",
              "horizon_sheet.png": "twilight horizon, sun side | anti-sun side",
              "airlight_mountains.png": "airlight: none / clear / haze"}
    tiles = []
    for p in written:
        label = labels.get(p.name, p.name)
        if p.name == "contact_sheet.png":
            label = "timelapse, Vienna 21 June" if "timelapse" in str(p) else "twilight 0..-18 deg"
        tiles.append((p, label))
    sheet = eff / "effects_gallery.png"
    cols = min((3, 4), key=lambda c: (-len(tiles) % c, -c))   # fewest empty cells
    _contact_sheet(tiles, sheet, tile=(320, 240), cols=cols)
    written.append(sheet)
    for p in written:
        print(p)
    print(f"effects ({time.perf_counter() - t0:.1f} s)")
    return written


def _contact_sheet(tiles, path: Path, tile=256, cols: int = 3) -> None:
    """A grid of equal cells (``tile`` box, each image letterboxed into it), a caption under
    each, ``cols`` across."""
    from skydome.render.sheets import contact_sheet

    contact_sheet(tiles, path, cols=cols, tile=tile, line_height=18, background=(24, 24, 24),
                  text_colours=((230, 230, 230),), letterbox=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description="Render skydome's sample skies.")
    ap.add_argument("--out", default="out", help="output folder (default: out)")
    ap.add_argument("--only", nargs="*", help="render only these stems")
    args = ap.parse_args(argv)
    run(Path(args.out), args.only)


if __name__ == "__main__":
    main()
