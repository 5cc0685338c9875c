"""Twilight (survey section 5.2): the sky with the sun from 0 to -18 deg below the horizon.

Civil (0..-6 deg), nautical (-6..-12 deg) and astronomical (-12..-18 deg) twilight. The
functions here evaluate any model that supports the sun below the horizon (``precomputed``,
valid to -18 deg with multiple scattering, is the default; ``single_scattering`` and
``montecarlo`` also work):

* :func:`zenith_luminance_curve`: zenith luminance [cd m^-2] against sun depression;
* :func:`horizontal_illuminance`: the sky's illuminance on a horizontal plane [lx];
* :func:`anti_solar_profile`: luminance and colour (R/B of linear sRGB) along the vertical
  opposite the sun, where the earth's shadow (a blue-grey band on the horizon) rises under
  the Belt of Venus (a pinkish band above it);
* :func:`belt_of_venus`: locates the two bands in that profile;
* :func:`run_twilight`: frames, a contact sheet, the curves as figure and CSV
  (``skydome twilight``).

The night sky's own light (airglow, starlight, zodiacal light: about 1e-4 cd m^-2 in total)
is not modelled: below -18 deg ``precomputed`` returns 0.
"""

from __future__ import annotations

import csv
import os
import shutil
import tempfile
from pathlib import Path
from typing import Callable

import numpy as np

__all__ = ["twilight_models", "zenith_luminance_curve", "horizontal_illuminance",
           "anti_solar_profile", "belt_of_venus", "run_twilight", "demo_effects"]

SUN_AZIMUTH_DEG = 270.0   # the sun sets in the west in every figure


def twilight_models(model: str = "precomputed", depressions_deg=(0.0,), **params):
    """One model per sun elevation -depression; models with ``with_sun`` (``precomputed``)
    share their tables."""
    import skydome as sd
    from skydome._validate import check_number

    elevs = [-check_number("depression", d, -90.0, 90.0, "deg") for d in depressions_deg]
    first = sd.model(model, sun=sd.Sun(elevation_deg=elevs[0], azimuth_deg=SUN_AZIMUTH_DEG), **params)
    out = [first]
    for e in elevs[1:]:
        sun = sd.Sun(elevation_deg=e, azimuth_deg=SUN_AZIMUTH_DEG)
        out.append(first.with_sun(sun) if hasattr(first, "with_sun") else sd.model(model, sun=sun, **params))
    return out


def _luminance(sky, dirs, wl):
    from skydome.spectra import spectrum_to_xyz

    if sky.native == "spectral":
        return spectrum_to_xyz(sky.radiance(dirs, wl), wl)[..., 1]
    return sky.luminance(dirs)


def zenith_luminance_curve(model: str = "precomputed", depressions_deg=np.arange(0.0, 18.1, 1.0),
                           wavelengths_nm=None, **params) -> np.ndarray:
    """Zenith luminance [cd m^-2] for each sun depression [deg] (sun elevation = -depression)."""
    from skydome.spectra import wavelength_grid

    wl = wavelength_grid(380.0, 780.0, n=21) if wavelengths_nm is None else wavelengths_nm
    skies = twilight_models(model, list(depressions_deg), **params)
    zen = np.array([0.0, 0.0, 1.0])
    return np.array([float(_luminance(s, zen, wl)) for s in skies])


def horizontal_illuminance(sky, wavelengths_nm=None, n_mu: int = 100, n_phi: int = 48) -> float:
    """Illuminance of the sky on a horizontal plane [lx]: the integral of L cos(theta) over
    the upper hemisphere (midpoint rule in cos(theta) and azimuth; the sun's disc excluded)."""
    from skydome.spectra import wavelength_grid

    wl = wavelength_grid(380.0, 780.0, n=21) if wavelengths_nm is None else wavelengths_nm
    mu = (np.arange(n_mu) + 0.5) / n_mu
    ph = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    M, P = np.meshgrid(mu, ph, indexing="ij")
    s = np.sqrt(1 - M * M)
    d = np.stack([s * np.sin(P), s * np.cos(P), M], axis=-1)
    Y = _luminance(sky, d, wl)
    return float(np.sum(Y * M) / n_mu * 2 * np.pi / n_phi)


def anti_solar_profile(sky, elevations_deg=np.arange(0.5, 40.0, 0.5), wavelengths_nm=None):
    """(luminance [cd m^-2], R/B of linear sRGB) along the vertical opposite the sun."""
    from skydome.spectra import spectrum_to_xyz, wavelength_grid, xyz_to_linear_srgb
    from skydome.transport.geometry import direction_from_angles

    wl = wavelength_grid(380.0, 780.0, n=21) if wavelengths_nm is None else wavelengths_nm
    az = (sky.sun.azimuth_deg + 180.0) % 360.0
    d = direction_from_angles(np.asarray(elevations_deg, dtype=float), az)
    xyz = spectrum_to_xyz(sky.radiance(d, wl), wl)
    rgb = xyz_to_linear_srgb(xyz)
    with np.errstate(divide="ignore", invalid="ignore"):
        rb = np.where(rgb[:, 2] > 0, rgb[:, 0] / rgb[:, 2], np.nan)
    return xyz[:, 1], rb


def belt_of_venus(elevations_deg, red_blue) -> dict:
    """The Belt of Venus as the elevation of the reddest point (maximum R/B) of the
    anti-solar profile above 2 deg, and the earth's shadow as the bluer band below it:
    returns {"belt_deg", "belt_rb", "shadow_rb", "contrast"} with contrast = belt_rb -
    shadow_rb (the shadow's R/B is the minimum below the belt)."""
    e = np.asarray(elevations_deg, dtype=float)
    rb = np.asarray(red_blue, dtype=float)
    ok = (e >= 2.0) & np.isfinite(rb)
    i = int(np.flatnonzero(ok)[np.argmax(rb[ok])])
    below = np.isfinite(rb) & (e < e[i])
    shadow = float(np.min(rb[below])) if below.any() else float("nan")
    return {"belt_deg": float(e[i]), "belt_rb": float(rb[i]), "shadow_rb": shadow,
            "contrast": float(rb[i] - shadow)}


def run_twilight(out_dir, model: str = "precomputed", step_deg: float = 2.0, size: int = 192,
                 wavelengths: int = 16, progress: Callable | None = None, **params) -> dict:
    """Render the twilight sequence 0..-18 deg into ``out_dir`` (written atomically):
    ``frame_sun_minus_DDD.png`` fisheyes (DDD in tenths of a degree) (each with its own automatic exposure, labelled with the
    zenith luminance in the contact sheet, since the sky dims by 10^7), ``contact_sheet.png``,
    ``twilight.png`` (zenith luminance and horizontal illuminance against depression, the
    anti-solar profiles) and ``twilight.csv``."""
    from skydome._validate import check_int, check_number
    from skydome.render import render
    from skydome.render.projections import Fisheye
    from skydome.spectra import wavelength_grid

    step = check_number("step", step_deg, 0.25, 9.0, "deg")
    size = check_int("size", size, 16, 2048)
    wl = wavelength_grid(380.0, 780.0, n=check_int("wavelengths", wavelengths, 3, 401))
    out_dir = Path(out_dir)
    parent = out_dir.parent if str(out_dir.parent) else Path(".")
    if not parent.is_dir() or not os.access(parent, os.W_OK):
        raise ValueError(f"out = '{out_dir}': folder '{parent}' does not exist or is not writable")
    deps = np.arange(0.0, 18.0 + 1e-9, step)
    skies = twilight_models(model, list(deps), **params)
    prof_el = np.arange(0.5, 40.0, 0.5)
    rows, frames = [], []
    tmp = Path(tempfile.mkdtemp(prefix=".skydome-twilight-", dir=parent))
    try:
        for n, (dep, sky) in enumerate(zip(deps, skies)):
            zen = float(_luminance(sky, np.array([0.0, 0.0, 1.0]), wl))
            eh = horizontal_illuminance(sky, wl)
            lum, rb = anti_solar_profile(sky, prof_el, wl)
            img = render(sky, Fisheye(size), wl, draw_sun=False)
            name = f"frame_sun_minus_{int(round(dep * 10)):03d}.png"   # tenths of a degree
            if zen > 0:
                img.save(tmp / name)
                frames.append((dep, zen, tmp / name))
            rows.append((dep, zen, eh, lum, rb))
            if progress is not None:
                progress(n + 1, len(deps))
        _contact_sheet(frames, tmp / "contact_sheet.png")
        _plot(rows, prof_el, tmp / "twilight.png")
        with open(tmp / "twilight.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["sun_elevation_deg", "zenith_luminance_cd_m2", "horizontal_illuminance_lx"])
            for dep, zen, eh, _, _ in rows:
                w.writerow([-dep, f"{zen:.6g}", f"{eh:.6g}"])
        out_dir.mkdir(exist_ok=True)
        for f in sorted(tmp.iterdir()):
            os.replace(f, out_dir / f.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return {"depression_deg": deps, "zenith_luminance": np.array([r[1] for r in rows]),
            "horizontal_illuminance": np.array([r[2] for r in rows])}


def _contact_sheet(frames, path: Path, tile: int = 160) -> None:
    from PIL import Image, ImageDraw

    cols = min(5, max(1, len(frames)))
    rows = (len(frames) + cols - 1) // cols
    lab = 28
    sheet = Image.new("RGB", (cols * tile, max(1, rows) * (tile + lab)), (12, 12, 12))
    draw = ImageDraw.Draw(sheet)
    for n, (dep, zen, p) in enumerate(frames):
        im = Image.open(p).convert("RGB")
        im.thumbnail((tile, tile))
        x, y = (n % cols) * tile, (n // cols) * (tile + lab)
        sheet.paste(im, (x, y))
        draw.text((x + 3, y + tile + 1), f"sun {-dep + 0.0:g} deg", fill=(220, 220, 220))
        draw.text((x + 3, y + tile + 14), f"zenith {zen:.2g} cd/m2", fill=(170, 170, 170))
    sheet.save(path)


def _plot(rows, prof_el, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    deps = np.array([r[0] for r in rows])
    fig, ax = plt.subplots(1, 3, figsize=(14, 4))
    ax[0].semilogy(-deps, [max(r[1], 1e-12) for r in rows], "o-", label="zenith luminance [cd/m$^2$]")
    ax[0].semilogy(-deps, [max(r[2], 1e-12) for r in rows], "s-", label="horizontal illuminance [lx]")
    for x, name in ((-6, "civil"), (-12, "nautical"), (-18, "astronomical")):
        ax[0].axvline(x, color="0.7", lw=0.8)
        ax[0].text(x + 0.2, 1e2, name, rotation=90, fontsize=8, color="0.4")
    ax[0].set_xlabel("sun elevation [deg]")
    ax[0].legend(fontsize=8)
    ax[0].grid(alpha=0.3, which="both")
    for dep, _, _, lum, rb in rows:
        if dep <= 6:
            ax[1].plot(prof_el, rb, label=f"sun {-dep + 0.0:g}")
            ax[2].semilogy(prof_el, np.maximum(lum, 1e-12), label=f"sun {-dep + 0.0:g}")
    ax[1].set_xlabel("elevation opposite the sun [deg]")
    ax[1].set_ylabel("R/B (linear sRGB)")
    ax[1].set_title("Belt of Venus (R/B peak) over the earth's shadow")
    ax[1].legend(fontsize=7)
    ax[1].grid(alpha=0.3)
    ax[2].set_xlabel("elevation opposite the sun [deg]")
    ax[2].set_ylabel("luminance [cd/m$^2$]")
    ax[2].grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def demo_effects(out_dir) -> list[Path]:
    """A small twilight sequence for ./scripts/demo (steps of 3 deg, 128 px)."""
    target = Path(out_dir) / "twilight"
    run_twilight(target, step_deg=3.0, size=128, wavelengths=12)
    return [target / "contact_sheet.png", target / "twilight.png"]
