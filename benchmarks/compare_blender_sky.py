"""Blender's own sky textures against skydome's models at matched settings.

Blender 4.2 (bpy) renders, with Cycles, its Sky Texture (Hosek / Wilkie and Preetham
variants, turbidity 3, ground albedo 0.3, the sun direction of skydome's sun in Blender's
axes) through an equirectangular panoramic camera; the same camera renders skydome's map
of the same sky in the ``blender`` convention (a control: it must give back the map). The
comparison is relative (each image divided by its median over the upper hemisphere), as
Blender scales its sky textures with its own factors; the scale factor is printed.

Blender 4.2's third variant, ``NISHITA``, is a single-scattering spectral sky
(intern/sky/source/sky_nishita.cpp, Apache-2.0): radii 6360 / 6420 km, Rayleigh
5.4248e-5 (lambda / 380 nm)^-4 m^-1 with an 8 km scale height, aerosol scattering 2e-5
m^-1 and extinction 1.11 x that (single-scattering albedo 0.9) with a 1.2 km scale height
and a Cornette-Shanks phase of g = 0.76, ozone on the 10-25-40 km tent with the peak
absorption coefficients of its OZONE_COEFF table (21 wavelengths, 380-780 nm). skydome
gets the same atmosphere (:func:`blender_nishita_atmosphere`, densities 1, observer at
sea level, sun disc off, sun_rotation = the sun's azimuth from north towards east: a
first run with sun_rotation = -azimuth put the brightest sky texel at azimuth 210.2 deg
for a sun at 150 deg, i.e. Blender 4.2's Nishita texture turns with the rotation, and the
script prints where the brightest texel lands) and renders it with its
``single_scattering`` model (the same physics), ``nishita1996`` and ``precomputed``
(multiple scattering, ground albedo 0.1).

Writes docs/figures/blender_sky_comparison.png and prints the numbers for
docs/rendering.md.

Run:  .venv/bin/python benchmarks/compare_blender_sky.py
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

W, H = 256, 128
SUN = (35.0, 150.0)                     # elevation, azimuth [deg]
CASES = (("HOSEK_WILKIE", "hosek_wilkie2012", {"turbidity": 3.0, "albedo": 0.3}),
         ("PREETHAM", "preetham1999", {"turbidity": 3.0}),
         ("NISHITA", "single_scattering", {"atmosphere": "blender_nishita"}),
         ("NISHITA", "nishita1996", {"atmosphere": "blender_nishita"}),
         ("NISHITA", "precomputed", {"atmosphere": "blender_nishita"}))
# Blender's NISHITA settings: sea level, unit densities, no sun disc (the sun is compared
# as a light elsewhere), the sun from SUN
NISHITA = {"altitude": 0.0, "air_density": 1.0, "dust_density": 1.0, "ozone_density": 1.0,
           "sun_disc": False, "sun_elevation": float(np.radians(SUN[0])),
           "sun_rotation": float(np.radians(SUN[1]))}


def blender_nishita_atmosphere():
    """skydome's Atmosphere with the constants of Blender's NISHITA sky (module notes):
    :meth:`skydome.Atmosphere.blender` with ``sky_type="nishita"``."""
    from skydome.atmosphere import Atmosphere

    return Atmosphere.blender("nishita")


def _sky_texture(nt, item: dict, job: dict):
    """Blender's sky texture of ``item`` (turbidity 3, ground albedo 0.3, skydome's sun)."""
    tex = nt.nodes.new("ShaderNodeTexSky")
    tex.sky_type = item["kind"]
    tex.turbidity = 3.0
    tex.ground_albedo = 0.3
    tex.sun_direction = job["sun_direction"]
    for k, v in item.get("settings", {}).items():
        setattr(tex, k, v)
    return tex


def _blender(job: dict) -> None:
    """In the subprocess: render each world of ``job`` and save .npy files."""
    from _blender_panorama import render_panoramas

    render_panoramas(job, _sky_texture, W, H)


def main() -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import skydome as sd
    from skydome.export.envmap import render_envmap
    from skydome.spectra import srgb_encode

    out = Path(__file__).resolve().parents[1] / "docs" / "figures" / "blender_sky_comparison.png"
    sun = sd.Sun(elevation_deg=SUN[0], azimuth_deg=SUN[1])
    with tempfile.TemporaryDirectory() as tmp:
        worlds, maps = [], {}
        for kind, model, params in CASES:
            params = dict(params)
            if params.get("atmosphere") == "blender_nishita":
                params["atmosphere"] = blender_nishita_atmosphere()
            env = render_envmap(sd.model(model, sun=sun, **params), "blender", size=f"{W}x{H}",
                                ground="black")
            env.write(Path(tmp) / f"{model}.exr")
            maps[model] = env.images["map"]
            worlds.append({"kind": "map", "map": str(Path(tmp) / f"{model}.exr"),
                           "name": f"ctl_{model}"})
            if not any(w["name"] == f"blender_{kind}" for w in worlds):
                worlds.append({"kind": kind, "name": f"blender_{kind}",
                               "settings": NISHITA if kind == "NISHITA" else {}})
        job = {"dir": tmp, "worlds": worlds, "sun_direction": [float(x) for x in sun.direction]}
        proc = subprocess.run([sys.executable, __file__, "--blender", json.dumps(job)],
                              capture_output=True, text=True)
        if proc.returncode:
            raise SystemExit(proc.stderr[-3000:])
        imgs = {w["name"]: np.load(Path(tmp) / f"{w['name']}.npy") for w in worlds}

    upper = (np.arange(H) + 0.5) / H < 0.5                     # rows above the horizon
    fig, axes = plt.subplots(len(CASES), 3, figsize=(15, 2.9 * len(CASES)))
    for row, (kind, model, _) in enumerate(CASES):
        mine, ctl, theirs = maps[model], imgs[f"ctl_{model}"], imgs[f"blender_{kind}"]
        ctl_err = np.median(np.abs(ctl[upper] / mine[upper] - 1.0))
        Ym = mine @ [0.2126, 0.7152, 0.0722]
        Yb = theirs @ [0.2126, 0.7152, 0.0722]
        scale = np.median(Ym[upper]) / np.median(Yb[upper])
        ratio = (Yb * scale)[upper] / Ym[upper]
        chroma_m = mine[upper] / Ym[upper][..., None]
        chroma_b = theirs[upper] / Yb[upper][..., None]
        if kind == "NISHITA" and row == [c[0] for c in CASES].index("NISHITA"):
            # where Blender put its sun: the brightest sky texel (the aureole's peak)
            r0, c0 = np.unravel_index(np.argmax(np.where(upper[:, None], Yb, 0.0)), Yb.shape)
            from skydome.export.envmap import MapProjection

            dpk = MapProjection("blender", W, H).direction_from_pixel(r0 + 0.5, c0 + 0.5)
            print(f"NISHITA brightest texel at azimuth "
                  f"{np.degrees(np.arctan2(dpk[0], dpk[1])) % 360:.1f} deg, elevation "
                  f"{np.degrees(np.arcsin(dpk[2])):.1f} deg (sun: {SUN[1]:g}, {SUN[0]:g})")
        print(f"{kind} vs skydome {model}: control |map through the camera / map - 1| median "
              f"{ctl_err:.3%}; Blender x {scale:.4g} matches skydome's median luminance; "
              f"relative luminance ratio median {np.median(ratio):.3f}, 5-95 % "
              f"{np.percentile(ratio, 5):.3f}-{np.percentile(ratio, 95):.3f}; RGB/Y "
              f"difference median {np.median(np.abs(chroma_b - chroma_m)):.3f}")
        peak = np.percentile(Ym[upper], 99.0)
        for col, (im, title) in enumerate(((mine, f"skydome {model}"),
                                           (theirs * scale, f"Blender {kind} x {scale:.3g}"))):
            axes[row, col].imshow(srgb_encode(np.clip(im / peak * 0.9, 0, 1)))
            axes[row, col].set_title(title, fontsize=9)
        r = np.where(upper[:, None], (Yb * scale) / np.maximum(Ym, 1e-12), np.nan)
        pcm = axes[row, 2].imshow(r, cmap="RdBu_r", vmin=0.5, vmax=1.5)
        axes[row, 2].set_title("relative luminance: Blender / skydome", fontsize=9)
        fig.colorbar(pcm, ax=axes[row, 2], fraction=0.025)
        for ax in axes[row]:
            ax.set_xticks([]); ax.set_yticks([])
    fig.suptitle(f"Blender 4.2 sky textures vs skydome, sun elevation {SUN[0]:g} deg, azimuth "
                 f"{SUN[1]:g} deg, T = 3 (Blender convention lat-long, upper half)")
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    print(f"wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--blender":
        _blender(json.loads(sys.argv[2]))
    else:
        main()
