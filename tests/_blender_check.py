"""Run by tests/test_renderers.py in a subprocess (bpy owns its process): render, with
Cycles on the CPU, white Lambertian planes and a pole's shadow under an environment map in
the ``blender`` convention and the sun lamp of its sun.json; print JSON results.

Usage: python _blender_check.py MAP.exr SUN.json OUT_DIR
"""

import json
import sys
from pathlib import Path

import numpy as np


def _reset(map_path, light):
    import bpy
    from mathutils import Vector

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.max_bounces = 0                  # direct light only: the planes are alone
    scene.cycles.use_denoising = False
    scene.cycles.samples = 256
    scene.cycles.seed = 1
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.film_transparent = False
    world = bpy.data.worlds.new("sky")
    scene.world = world
    world.use_nodes = True
    nt = world.node_tree
    nt.nodes.clear()
    tex = nt.nodes.new("ShaderNodeTexEnvironment")
    tex.image = bpy.data.images.load(str(map_path))
    tex.image.colorspace_settings.name = "Linear Rec.709"
    bg = nt.nodes.new("ShaderNodeBackground")
    out = nt.nodes.new("ShaderNodeOutputWorld")
    nt.links.new(tex.outputs["Color"], bg.inputs["Color"])
    nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
    b = light["targets"]["blender"]
    lamp = bpy.data.lights.new("sun", type="SUN")
    lamp.energy = b["strength_W_m2"]
    lamp.color = b["color"]
    lamp.angle = np.radians(b["angle_deg"])
    obj = bpy.data.objects.new("sun", lamp)
    scene.collection.objects.link(obj)
    # the lamp shines along its local -Z: point +Z at the sun
    obj.rotation_euler = Vector(light["direction_to_sun"]).to_track_quat("Z", "Y").to_euler()
    mat = bpy.data.materials.new("white")
    mat.use_nodes = True
    mnt = mat.node_tree
    mnt.nodes.clear()
    diff = mnt.nodes.new("ShaderNodeBsdfDiffuse")
    diff.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    mout = mnt.nodes.new("ShaderNodeOutputMaterial")
    mnt.links.new(diff.outputs["BSDF"], mout.inputs["Surface"])
    return scene, mat


def _camera(scene, location, target, ortho_scale, size):
    import bpy
    from mathutils import Vector

    cam = bpy.data.cameras.new("cam")
    cam.type = "ORTHO"
    cam.ortho_scale = ortho_scale
    obj = bpy.data.objects.new("cam", cam)
    scene.collection.objects.link(obj)
    obj.location = location
    obj.rotation_euler = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    scene.camera = obj
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100


def _render(scene, path):
    import bpy
    import OpenEXR

    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        return np.stack([np.array(ch[c].pixels) for c in ("R", "G", "B")], axis=-1)


def main():
    import bpy
    from mathutils import Vector

    map_path, sun_path, out_dir = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
    light = json.loads(sun_path.read_text())
    result = {"planes": {}}
    planes = {"up": (0, 0, 1), "N": (0, 1, 0), "E": (1, 0, 0), "S": (0, -1, 0), "W": (-1, 0, 0)}
    for name, n in planes.items():
        scene, mat = _reset(map_path, light)
        bpy.ops.mesh.primitive_plane_add(size=2.0, location=(0, 0, 0))
        plane = bpy.context.active_object
        plane.rotation_euler = Vector(n).to_track_quat("Z", "Y").to_euler()
        plane.data.materials.append(mat)
        _camera(scene, tuple(3.0 * x for x in n), (0, 0, 0), 1.0, 16)
        img = _render(scene, out_dir / f"plane_{name}.exr")
        result["planes"][name] = [float(x) for x in img.reshape(-1, 3).mean(axis=0)]
    # the pole: 0.05 wide, 1 high, on a 12 x 12 ground, seen from straight above (north up)
    scene, mat = _reset(map_path, light)
    bpy.ops.mesh.primitive_plane_add(size=12.0, location=(0, 0, 0))
    bpy.context.active_object.data.materials.append(mat)
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, 0.5))
    pole = bpy.context.active_object
    pole.scale = (0.05, 0.05, 1.0)
    pole.data.materials.append(mat)
    scene.cycles.samples = 32
    _camera(scene, (0, 0, 10), (0, 0, 0), 6.0, 128)
    result["pole_image"] = str(out_dir / "pole.exr")
    _render(scene, out_dir / "pole.exr")
    print("RESULT " + json.dumps(result))


if __name__ == "__main__":
    main()
