"""Blender's own sky textures against skydome's models at matched settings.

Blender 4.2 (bpy) renders, with Cycles, its Sky Texture (Hosek / Wilkie and Preetham
variants, turbidity 3, ground albedo 0.3, the sun direction of skydome's sun in Blender's
axes) through an equirectangular panoramic camera; the same camera renders skydome's map
of the same sky in the ``blender`` convention (a control: it must give back the map). The
comparison is relative (each image divided by its median over the upper hemisphere), as
Blender scales its sky textures with its own factors; the scale factor is printed.

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
         ("PREETHAM", "preetham1999", {"turbidity": 3.0}))


def _blender(job: dict) -> None:
    """In the subprocess: render each world of ``job`` and save .npy files."""
    import bpy
    import OpenEXR

    for item in job["worlds"]:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        sc = bpy.context.scene
        sc.render.engine = "CYCLES"
        sc.cycles.device = "CPU"
        sc.cycles.samples = 16
        sc.cycles.use_denoising = False
        sc.view_settings.view_transform = "Standard"
        sc.render.image_settings.file_format = "OPEN_EXR"
        sc.render.image_settings.color_depth = "32"
        world = bpy.data.worlds.new("w")
        sc.world = world
        world.use_nodes = True
        nt = world.node_tree
        nt.nodes.clear()
        if item["kind"] == "map":
            tex = nt.nodes.new("ShaderNodeTexEnvironment")
            tex.image = bpy.data.images.load(item["map"])
            tex.image.colorspace_settings.name = "Linear Rec.709"
        else:
            tex = nt.nodes.new("ShaderNodeTexSky")
            tex.sky_type = item["kind"]
            tex.turbidity = 3.0
            tex.ground_albedo = 0.3
            tex.sun_direction = job["sun_direction"]
        bg = nt.nodes.new("ShaderNodeBackground")
        out = nt.nodes.new("ShaderNodeOutputWorld")
        nt.links.new(tex.outputs["Color"], bg.inputs["Color"])
        nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
        cam = bpy.data.cameras.new("c")
        cam.type = "PANO"
        cam.panorama_type = "EQUIRECTANGULAR"
        obj = bpy.data.objects.new("c", cam)
        sc.collection.objects.link(obj)
        sc.camera = obj
        # looking along +X with +Z up: the panorama then has the layout of Blender's own
        # Environment Texture (checked by the control render of skydome's map)
        obj.rotation_euler = (np.pi / 2, 0.0, -np.pi / 2)
        sc.render.resolution_x, sc.render.resolution_y = W, H
        sc.render.resolution_percentage = 100
        path = str(Path(job["dir"]) / f"{item['name']}.exr")
        sc.render.filepath = path
        bpy.ops.render.render(write_still=True)
        with OpenEXR.File(path, separate_channels=True) as f:
            ch = f.channels()
            img = np.stack([np.array(ch[c].pixels) for c in "RGB"], axis=-1)
        np.save(Path(job["dir"]) / f"{item['name']}.npy", img)


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
            env = render_envmap(sd.model(model, sun=sun, **params), "blender", size=f"{W}x{H}",
                                ground="black")
            env.write(Path(tmp) / f"{model}.exr")
            maps[model] = env.images["map"]
            worlds += [{"kind": "map", "map": str(Path(tmp) / f"{model}.exr"), "name": f"ctl_{model}"},
                       {"kind": kind, "name": f"blender_{kind}"}]
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
