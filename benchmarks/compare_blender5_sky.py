"""Blender 5's MULTIPLE_SCATTERING sky against skydome at the same atmosphere.

skydome's ``precomputed`` model (Bruneton's multiple scattering) gets Blender 5's own
atmosphere, :meth:`skydome.Atmosphere.blender` (intern/sky/source/
sky_multiple_scattering.cpp), and renders its sky (sun separate, so no disc) as a lat-long
map in the ``blender`` convention. bpy 5.0.1 (.venv-bpy5, made by ``scripts/_setup test``)
renders with Cycles, through one equirectangular panoramic camera, Blender's Sky Texture
(``MULTIPLE_SCATTERING``, air, aerosol and ozone densities 1, altitude 0, sun disc off,
``sun_elevation`` and ``sun_rotation`` = the sun's elevation and azimuth) and, as a
control, skydome's map. Both are on the same absolute scale: Blender's sky XYZ has Y =
y-bar-weighted spectral radiance (its SPECTRAL_XYZ rows hold the integrals of the CIE
functions over each of its four bands), i.e. luminance / 683, as skydome's maps.

For sun elevations of 10, 30 and 60 deg (azimuth 180 deg) the script prints the zenith
luminance (rows above 87 deg elevation), the horizon luminance (rows between 0 and 3 deg,
all azimuths) and the sky's illuminance of a horizontal plane (683 x sum Y sin(elevation)
dOmega over the upper hemisphere of the rendered panoramas), and writes
docs/figures/blender5_sky_comparison.png.

Run:  .venv/bin/python benchmarks/compare_blender5_sky.py
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

W, H = 256, 128
AZIMUTH = 180.0
ELEVATIONS = (10.0, 30.0, 60.0)
ROOT = Path(__file__).resolve().parents[1]
BPY5 = ROOT / ".venv-bpy5" / "bin" / "python"
Y709 = np.array([0.2126, 0.7152, 0.0722])


def _sky_texture(nt, item: dict, job: dict):
    """Blender 5's MULTIPLE_SCATTERING sky: unit densities, sea level, no sun disc."""
    tex = nt.nodes.new("ShaderNodeTexSky")
    tex.sky_type = "MULTIPLE_SCATTERING"
    tex.sun_disc = False
    tex.altitude = 0.0
    tex.air_density = tex.aerosol_density = tex.ozone_density = 1.0
    tex.sun_elevation = np.radians(item["elevation"])
    tex.sun_rotation = np.radians(item["azimuth"])
    return tex


def _blender(job: dict) -> None:
    """In the bpy 5 subprocess: render each world of ``job`` and save .npy files."""
    from _blender_panorama import render_panoramas

    render_panoramas(job, _sky_texture, W, H)


def _metrics(img: np.ndarray) -> dict:
    """Zenith and horizon luminance [cd m^-2], horizontal illuminance [lx] of a lat-long
    image (rows from the zenith down, luminance / 683 scale)."""
    Y = 683.0 * (img @ Y709)
    el = 90.0 - (np.arange(H) + 0.5) * 180.0 / H
    d_omega = np.cos(np.radians(el)) * (np.pi / H) * (2.0 * np.pi / W)
    up = el > 0
    E = float((Y[up] * (np.sin(np.radians(el[up])) * d_omega[up])[:, None]).sum())
    return {"zenith": float(Y[el > 87.0].mean()), "horizon": float(Y[(el > 0) & (el < 3.0)].mean()),
            "E_h": E}


def main() -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import skydome as sd
    from skydome.atmosphere import Atmosphere
    from skydome.export.envmap import MapProjection, render_envmap
    from skydome.spectra import srgb_encode

    if not BPY5.is_file():
        raise SystemExit(f"{BPY5} missing: run scripts/_setup test (bpy 5.0.1)")
    atm = Atmosphere.blender()
    out = ROOT / "docs" / "figures" / "blender5_sky_comparison.png"
    with tempfile.TemporaryDirectory() as tmp:
        worlds, maps = [], {}
        for el in ELEVATIONS:
            sky = sd.model("precomputed", sun=sd.Sun(elevation_deg=el, azimuth_deg=AZIMUTH),
                           atmosphere=atm)
            env = render_envmap(sky, "blender", size=f"{W}x{H}", ground="black")
            env.write(Path(tmp) / f"sd_{el:g}.exr")
            maps[el] = env.images["map"]
            worlds += [{"kind": "map", "map": str(Path(tmp) / f"sd_{el:g}.exr"),
                        "name": f"ctl_{el:g}"},
                       {"kind": "sky", "elevation": el, "azimuth": AZIMUTH,
                        "name": f"blender_{el:g}"}]
        job = {"dir": tmp, "worlds": worlds}
        proc = subprocess.run([str(BPY5), __file__, "--blender", json.dumps(job)],
                              capture_output=True, text=True)
        if proc.returncode:
            raise SystemExit(proc.stderr[-3000:])
        imgs = {w["name"]: np.load(Path(tmp) / f"{w['name']}.npy") for w in worlds}

    upper = (np.arange(H) + 0.5) / H < 0.5
    fig, axes = plt.subplots(len(ELEVATIONS), 3, figsize=(15, 2.9 * len(ELEVATIONS)))
    print("| sun elevation | zenith cd/m^2: skydome / Blender | horizon cd/m^2: skydome / "
          "Blender | sky E_h lx: skydome / Blender | Blender / skydome (zenith, horizon, E_h) |")
    for row, el in enumerate(ELEVATIONS):
        mine, ctl, theirs = maps[el], imgs[f"ctl_{el:g}"], imgs[f"blender_{el:g}"]
        ctl_err = np.median(np.abs(ctl[upper] / mine[upper] - 1.0))
        m_s, m_b = _metrics(ctl), _metrics(theirs)
        Yb = theirs @ Y709
        # where Blender put its sun: the brightest texel within 5 deg of the sun's elevation
        el_rows = 90.0 - (np.arange(H) + 0.5) * 180.0 / H
        near = np.abs(el_rows - el) < 5.0
        r0, c0 = np.unravel_index(np.argmax(np.where(near[:, None], Yb, 0.0)), Yb.shape)
        dpk = MapProjection("blender", W, H).direction_from_pixel(r0 + 0.5, c0 + 0.5)
        print(f"(control: skydome's map through Blender's camera / the map - 1, median "
              f"{ctl_err:.3%}; Blender's brightest texel at azimuth "
              f"{np.degrees(np.arctan2(dpk[0], dpk[1])) % 360:.1f} deg, elevation "
              f"{np.degrees(np.arcsin(dpk[2])):.1f} deg)")
        print(f"| {el:g} deg | {m_s['zenith']:.0f} / {m_b['zenith']:.0f} | "
              f"{m_s['horizon']:.0f} / {m_b['horizon']:.0f} | {m_s['E_h']:.0f} / "
              f"{m_b['E_h']:.0f} | {m_b['zenith'] / m_s['zenith']:.3f}, "
              f"{m_b['horizon'] / m_s['horizon']:.3f}, {m_b['E_h'] / m_s['E_h']:.3f} |")
        Ym = ctl @ Y709
        ratio = np.where(upper[:, None], Yb / np.maximum(Ym, 1e-12), np.nan)
        print(f"    luminance Blender / skydome over the upper hemisphere: median "
              f"{np.nanmedian(ratio):.3f}, 5-95 % {np.nanpercentile(ratio, 5):.3f}-"
              f"{np.nanpercentile(ratio, 95):.3f}")
        peak = np.percentile(Ym[upper], 99.0)
        for col, (im, title) in enumerate(((ctl, f"skydome precomputed, Atmosphere.blender(), "
                                                 f"sun {el:g} deg"),
                                           (theirs, "Blender 5.0.1 MULTIPLE_SCATTERING"))):
            axes[row, col].imshow(srgb_encode(np.clip(im / peak * 0.9, 0, 1)))
            axes[row, col].set_title(title, fontsize=9)
        pcm = axes[row, 2].imshow(ratio, cmap="RdBu_r", vmin=0.5, vmax=1.5)
        axes[row, 2].set_title("luminance: Blender / skydome", fontsize=9)
        fig.colorbar(pcm, ax=axes[row, 2], fraction=0.025)
        for ax in axes[row]:
            ax.set_xticks([])
            ax.set_yticks([])
    fig.suptitle("Blender 5 MULTIPLE_SCATTERING vs skydome at Blender's atmosphere "
                 f"(sun azimuth {AZIMUTH:g} deg; lat-long, Blender convention)")
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    print(f"wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--blender":
        _blender(json.loads(sys.argv[2]))
    else:
        main()
