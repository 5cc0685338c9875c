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
    ("earth_from_space", "nishita1993", {"camera_altitude_m": 36e6, "surface": "earth"},
     {"elevation_deg": 50.0, "azimuth_deg": 240.0},
     "camera", "384", "Nishita 1993, earth from 36000 km, sun 40 deg off"),
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
    from skydome.imaging import make_projection
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
            # a planet on black space, exposed as a satellite camera is calibrated: in
            # reflectance, a white Lambertian surface under the overhead sun, luminance
            # E_sun / pi, at scene value 2 (so the dark sea, the land and the glint read)
            import numpy as np

            from skydome.spectra import luminance_from_spectrum, solar_irradiance

            exposure = 2.0 * np.pi / float(luminance_from_spectrum(solar_irradiance(wl), wl))
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


# the effects gallery: 2 columns of equal cells, each a (width, height) box [pixels] that
# every composite fills (each is made at about this 2.05:1 aspect where it is rendered)
EFFECTS_COLS = 2
EFFECTS_CELL = (800, 390)
EFFECTS_CAPTION = 24   # caption band under each cell [pixels] (18 px font)


def _effects(out_dir: Path) -> list[Path]:
    """Small versions of the atmospheric effects (survey section 5) into out/effects/, and
    ``effects_gallery.png``: 8 composites in a grid of ``EFFECTS_COLS`` columns of equal
    ``EFFECTS_CELL`` cells with a caption under each."""
    import importlib

    import skydome as sd

    eff = out_dir / "effects"
    eff.mkdir(exist_ok=True)
    written: list[Path] = []
    tiles: list[tuple[Path, str]] = []
    t0 = time.perf_counter()
    # 5.1 the colour of the sky through a day (Vienna, summer solstice, every 50 min from
    # civil dawn: 21 frames, 7 x 3 at 112 px, about 2:1)
    from skydome.apps.timelapse import day_times, run_timelapse

    times = day_times("2026-06-21", "+02:00", 50.0, start="04:20")
    run_timelapse(lambda sun: sd.model("precomputed", sun=sun), 48.21, 16.37, times,
                  eff / "timelapse", size=112, wavelengths=12, sheet_cols=7)
    written.append(eff / "timelapse" / "contact_sheet.png")
    tiles.append((written[-1], "the sky through a day, Vienna 21 June (one exposure)"))
    # aerial perspective, where that module provides a demo
    twilight_files: list[Path] = []
    for mod in ("skydome.apps.airlight", "skydome.apps.twilight"):
        try:
            m = importlib.import_module(mod)
        except ImportError:
            continue
        if hasattr(m, "demo_effects"):
            files = list(m.demo_effects(eff) or [])
            written += files
            if mod.endswith("airlight"):
                tiles += [(p, "aerial perspective: no air / turbidity 2 / 4 / 8") for p in files]
            else:
                twilight_files = files
    # 5.5 Bishop's ring (a ~1 um volcanic layer) and the volcanic-ash aureole: close-ups
    # of the sun 100 x 60 deg at the cell's size, each at the automatic exposure of the
    # square 161 px close-up it stands for (60 deg for the ring, as the demo had it; 50 deg
    # for the ash, as `skydome aureole` writes it), so the wider field keeps the exposure
    from skydome.apps.aureole import render_closeup
    from skydome.atmosphere import Atmosphere
    from skydome.effects.aureole import bishops_ring_atmosphere

    for name, atm, elev, square_fov, label in (
            ("bishops_ring.png", bishops_ring_atmosphere(), 45.0, 60.0, "Bishop's ring (1 um ash layer, Mie)"),
            ("volcanic_ash_aureole.png", Atmosphere.volcanic_ash(), 30.0, 50.0, "aureole of volcanic ash, sun 30 deg (Mie)")):
        sun = sd.Sun(elevation_deg=elev, azimuth_deg=180.0)
        k = render_closeup(atm, sun, fov_deg=square_fov, size=161).auto_exposure()
        render_closeup(atm, sun, fov_deg=100.0, size=800, height=390).save(eff / name, exposure=k)
        written.append(eff / name)
        tiles.append((eff / name, label))
    # 5.7 polarisation: single-scattering Rayleigh field (analytic)
    from skydome.effects.polarisation_maps import polarisation_maps
    from skydome.imaging.plots import plot_polarisation_maps

    pm = polarisation_maps("rayleigh_single", sd.Sun(elevation_deg=20.0, azimuth_deg=180.0),
                           *sd.Fisheye(64).directions())
    plot_polarisation_maps(pm, eff / "polarisation_rayleigh.png")
    written.append(eff / "polarisation_rayleigh.png")
    tiles.append((written[-1], "polarisation of the sky (single Rayleigh scattering)"))
    labels = {"twilight.png": "twilight: zenith luminance, illuminance, Belt of Venus",
              "contact_sheet.png": "twilight 0 .. -18 deg (exposure ramp)",
              "horizon_sheet.png": "twilight horizon: sun side above, anti-sun side below"}
    tiles += [(p, labels.get(p.name, p.name)) for p in sorted(twilight_files, key=lambda p: p.name != "twilight.png")]
    sheet = eff / "effects_gallery.png"
    _contact_sheet(tiles, sheet, tile=EFFECTS_CELL, cols=EFFECTS_COLS, line_height=EFFECTS_CAPTION,
                   font_size=18)
    written.append(sheet)
    for p in written:
        print(p)
    print(f"effects ({time.perf_counter() - t0:.1f} s)")
    return written


def _contact_sheet(tiles, path: Path, tile=256, cols: int = 3, line_height: int = 18,
                   font_size: int | None = None) -> None:
    """A grid of equal cells (``tile`` box, each image letterboxed into it), a caption under
    each, ``cols`` across."""
    from skydome.imaging.sheets import contact_sheet

    contact_sheet(tiles, path, cols=cols, tile=tile, line_height=line_height, background=(24, 24, 24),
                  text_colours=((230, 230, 230),), letterbox=True, font_size=font_size)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description="Render skydome's sample skies.")
    ap.add_argument("--out", default="out", help="output folder (default: out)")
    ap.add_argument("--only", nargs="*", help="render only these stems")
    args = ap.parse_args(argv)
    run(Path(args.out), args.only)


if __name__ == "__main__":
    main()
