"""The bpy side shared by the Blender sky comparisons: one Cycles equirectangular
panorama per world, saved as .npy (runs inside the bpy interpreter, which imports this
module from the benchmarks folder)."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np


def render_panoramas(job: dict, sky_texture: Callable, width: int, height: int) -> None:
    """Render each world of ``job["worlds"]`` into ``job["dir"]/NAME.npy`` (linear RGB).

    A world of kind ``"map"`` shows the lat-long map ``item["map"]``; any other kind gets
    the node ``sky_texture(node_tree, item, job)`` returns (Blender's own sky texture).
    """
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
        if world.node_tree is None:                  # Blender 4.x: nodes are opt-in
            world.use_nodes = True
        nt = world.node_tree
        nt.nodes.clear()
        if item["kind"] == "map":
            tex = nt.nodes.new("ShaderNodeTexEnvironment")
            tex.image = bpy.data.images.load(item["map"])
            tex.image.colorspace_settings.name = "Linear Rec.709"
        else:
            tex = sky_texture(nt, item, job)
        bg = nt.nodes.new("ShaderNodeBackground")
        out = nt.nodes.new("ShaderNodeOutputWorld")
        nt.links.new(tex.outputs["Color"], bg.inputs["Color"])
        nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
        cam = bpy.data.cameras.new("c")
        cam.type = "PANO"
        if hasattr(cam, "panorama_type"):
            cam.panorama_type = "EQUIRECTANGULAR"
        else:                                        # older Cycles: the type on cam.cycles
            cam.cycles.panorama_type = "EQUIRECTANGULAR"
        obj = bpy.data.objects.new("c", cam)
        sc.collection.objects.link(obj)
        sc.camera = obj
        # looking along +X with +Z up: the panorama then has the layout of Blender's own
        # Environment Texture (checked by the control render of skydome's map)
        obj.rotation_euler = (np.pi / 2, 0.0, -np.pi / 2)
        sc.render.resolution_x, sc.render.resolution_y = width, height
        sc.render.resolution_percentage = 100
        path = str(Path(job["dir"]) / f"{item['name']}.exr")
        sc.render.filepath = path
        bpy.ops.render.render(write_still=True)
        with OpenEXR.File(path, separate_channels=True) as f:
            ch = f.channels()
            img = np.stack([np.array(ch[c].pixels) for c in "RGB"], axis=-1)
        np.save(Path(job["dir"]) / f"{item['name']}.npy", img)
