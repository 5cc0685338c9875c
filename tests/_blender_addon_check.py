"""Run by tests/test_blender_addon.py in a subprocess (bpy owns its process): install the
skydome add-on zip into a fresh Blender (BLENDER_USER_RESOURCES points at an empty folder),
enable it, run its operator, render with Cycles on the CPU a white Lambertian plane and a
post's shadow, and print JSON results.

Usage: python _blender_addon_check.py ADDON.zip {legacy|extension} SKYDOME_PYTHON OUT_DIR
       SETTINGS_JSON
"""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from _blender_check import _camera, _render  # noqa: E402  (the manual set-up's helpers)


def _install(zip_path, how):
    import bpy

    if how == "legacy":
        bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
        bpy.ops.preferences.addon_enable(module="skydome_sky")
        return "skydome_sky"
    bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                             enable_on_install=True)
    return "bl_ext.user_default.skydome_sky"


def _white():
    import bpy

    mat = bpy.data.materials.new("white")
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    diff = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diff.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(diff.outputs["BSDF"], out.inputs["Surface"])
    return mat


def _fcurves(action):
    """An action's F-curves: ``action.fcurves`` before Blender 5, the channelbags of its
    layered slots from 5.0."""
    if hasattr(action, "fcurves") and not hasattr(action, "layers"):
        return list(action.fcurves)
    out = []
    for layer in action.layers:
        for strip in layer.strips:
            for bag in strip.channelbags:
                out.extend(bag.fcurves)
    return out


def tex_of(scene):
    return [n for n in scene.world.node_tree.nodes if n.type == "TEX_ENVIRONMENT"][0]


def _clear_meshes(scene):
    import bpy

    for obj in list(scene.collection.objects):
        if obj.type in ("MESH", "CAMERA"):
            bpy.data.objects.remove(obj)


def main():
    import bpy

    zip_path, how, python, out_dir, settings = sys.argv[1:6]
    settings = json.loads(settings)
    out_dir = Path(out_dir)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    module = _install(zip_path, how)
    prefs = bpy.context.preferences.addons[module].preferences
    prefs.python = python
    scene = bpy.context.scene
    props = scene.skydome_sky
    for k, v in settings.items():
        setattr(props, k, v)
    props.output_dir = str(out_dir / "maps")
    res = bpy.ops.skydome.bake_sky()
    assert res == {"FINISHED"}, res
    sun = bpy.data.objects["skydome sun"]
    world = scene.world
    tex = [n for n in world.node_tree.nodes if n.type == "TEX_ENVIRONMENT"][0]
    bg = [n for n in world.node_tree.nodes if n.type == "BACKGROUND"][0]
    result = {"blender": bpy.app.version_string, "module": module,
              "world": world.name, "map": bpy.path.abspath(tex.image.filepath),
              "colorspace": tex.image.colorspace_settings.name,
              "background_strength": bg.inputs["Strength"].default_value,
              "sun_rotation_deg": [float(x) * 180.0 / 3.141592653589793
                                   for x in sun.rotation_euler],
              "sun_rotation_mode": sun.rotation_mode,
              "sun_strength": sun.data.energy, "sun_color": list(sun.data.color),
              "sun_angle": sun.data.angle,
              "exposure": scene.view_settings.exposure,
              "view_transform": scene.view_settings.view_transform}
    if props.use_sequence:
        # a day sequence: no render; the image sequence and the keyframes
        act = sun.animation_data.action
        result["sequence"] = {
            "image_source": tex.image.source, "frame_duration": tex.image_user.frame_duration,
            "frame_start": tex.image_user.frame_start, "scene_frames": [scene.frame_start,
                                                                        scene.frame_end],
            "rotation_keys": [[list(k.co) for k in fc.keyframe_points]
                              for fc in _fcurves(act) if fc.data_path == "rotation_euler"],
            "exposure_keys": [list(k.co) for fc in _fcurves(scene.animation_data.action)
                              if fc.data_path.endswith("exposure") for k in fc.keyframe_points]}
        # then a single bake: the sequence's keys must go
        props.use_sequence = False
        props.sun_mode = "ANGLES"
        assert bpy.ops.skydome.bake_sky() == {"FINISHED"}
        left = [fc.data_path for idb in (sun, sun.data, scene)
                if idb.animation_data and idb.animation_data.action
                for fc in _fcurves(idb.animation_data.action)]
        result["after_single_bake"] = {
            "fcurves": left, "image_source": tex_of(scene).image.source,
            "rotation_deg": [float(x) * 180.0 / 3.141592653589793 for x in sun.rotation_euler]}
        print("RESULT " + json.dumps(result))
        return
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.max_bounces = 0                  # direct light only
    scene.cycles.use_denoising = False
    scene.cycles.seed = 1
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    mat = _white()
    # a white horizontal plane, seen from above (16 x 16 pixels)
    bpy.ops.mesh.primitive_plane_add(size=2.0, location=(0, 0, 0))
    bpy.context.active_object.data.materials.append(mat)
    scene.cycles.samples = 128
    _camera(scene, (0.0, 0.0, 3.0), (0, 0, 0), 1.0, 16)
    img = _render(scene, out_dir / "plane.exr")
    result["plane_rgb"] = [float(x) for x in img.reshape(-1, 3).mean(axis=0)]
    # a post 0.2 wide and 1 high on a 12 x 12 ground, seen from straight above, north up
    _clear_meshes(scene)
    bpy.ops.mesh.primitive_plane_add(size=12.0, location=(0, 0, 0))
    bpy.context.active_object.data.materials.append(mat)
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, 0.5))
    post = bpy.context.active_object
    post.scale = (0.2, 0.2, 1.0)
    post.data.materials.append(mat)
    scene.cycles.samples = 16
    _camera(scene, (0, 0, 10), (0, 0, 0), 6.0, 64)
    _render(scene, out_dir / "post.exr")
    result["post_image"] = str(out_dir / "post.exr")
    print("RESULT " + json.dumps(result))


if __name__ == "__main__":
    main()
