"""skydome sky: physically based daylight in Blender from skydome.

A panel (World properties, and the 3D View's sidebar, tab "skydome") takes a sky model,
the sun (elevation and azimuth, or a place and a time; several times make a keyframed day
sequence) and the atmosphere (turbidity or aerosol optical depth, ground albedo; or
Blender 5's own atmosphere), bakes the environment map with skydome's own Python (an
add-on preference) in a subprocess, and creates:

* the World "skydome sky": Environment Texture of the baked EXR (Linear Rec.709, default
  mapping: the map is in skydome's ``blender`` convention) into a Background of strength 1;
* the sun lamp "skydome sun": strength [W m^-2], colour and angle (the disc's angular
  diameter) from the ``.sun.json`` beside the map, rotation as XYZ Euler angles
  (90 - elevation, 0, 180 - azimuth);
* the exposure: Color Management exposure = log2(pi x 683 / E_h) [EV], E_h the horizontal
  illuminance of sky and sun [lx], i.e. a white Lambertian horizontal surface at
  scene-linear 1.0; the view transform chosen in the panel (AgX by default).

Loaded as a legacy add-on (``bl_info``) or as an extension (``blender_manifest.toml``).
"""

import json
import math
import os
import subprocess
import tempfile
from datetime import datetime, timedelta

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, IntProperty,
                       PointerProperty, StringProperty)

bl_info = {
    "name": "skydome sky",
    "author": "the skydome developers",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "Properties > World > skydome sky; 3D View > Sidebar > skydome",
    "description": "Physically based sky map, sun lamp and exposure baked by skydome",
    "category": "Lighting",
}

WORLD_NAME = "skydome sky"
SUN_NAME = "skydome sun"
MODELS = (("hosek_wilkie2012", "Hosek-Wilkie 2012", "Analytic fit (turbidity, albedo)"),
          ("precomputed", "Precomputed (Bruneton)", "Multiple scattering, skydome's default"),
          ("hillaire2020", "Hillaire 2020", "Multiple scattering, real-time model"),
          ("nishita1996", "Nishita 1996", "Multiple scattering, spectral"),
          ("single_scattering", "Single scattering", "Spectral, single scattering"),
          ("preetham1999", "Preetham 1999", "Analytic (turbidity)"))
SIZES = (("1024", "1024 x 512", ""), ("2048", "2048 x 1024", ""), ("4096", "4096 x 2048", ""))
VIEWS = (("AgX", "AgX", "Blender's default view transform since 4.0"),
         ("Filmic", "Filmic", ""), ("Standard", "Standard", "No tone curve: clips at 1.0"),
         ("KEEP", "Keep", "Leave the scene's view transform as it is"))


def _prefs(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


class SKYDOME_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    python: StringProperty(
        name="skydome Python", subtype="FILE_PATH", default="",
        description="Python interpreter with skydome installed (e.g. the virtual "
                    "environment's bin/python); the environment variable SKYDOME_PYTHON "
                    "is used when this is empty")

    def draw(self, context):
        self.layout.prop(self, "python")


class SkydomeSkySettings(bpy.types.PropertyGroup):
    model: EnumProperty(name="Model", items=MODELS, default="hosek_wilkie2012")
    sun_mode: EnumProperty(name="Sun", items=(
        ("ANGLES", "Angles", "Sun elevation and azimuth"),
        ("PLACE_TIME", "Place and time", "Latitude, longitude and an ISO 8601 time")),
        default="ANGLES")
    sun_elevation: FloatProperty(name="Elevation [deg]", default=35.0, min=-90.0, max=90.0)
    sun_azimuth: FloatProperty(name="Azimuth [deg]", default=150.0, min=-360.0, max=360.0,
                               description="From north (+Y) towards east (+X)")
    latitude: FloatProperty(name="Latitude [deg]", default=48.0, min=-90.0, max=90.0)
    longitude: FloatProperty(name="Longitude [deg]", default=11.0, min=-180.0, max=180.0,
                             description="East positive")
    time: StringProperty(name="Time", default="2024-06-21T12:00:00+02:00",
                         description="ISO 8601 with UTC offset")
    use_sequence: BoolProperty(name="Day sequence", default=False,
                               description="Bake one map per step from Time to End, one "
                                           "frame each, and keyframe sun and exposure")
    time_end: StringProperty(name="End", default="2024-06-21T20:00:00+02:00")
    step_minutes: IntProperty(name="Step [min]", default=60, min=1, max=1440)
    atmosphere: EnumProperty(name="Atmosphere", items=(
        ("earth", "Earth", "Turbidity or aerosol optical depth, ground albedo"),
        ("blender", "Blender 5's", "Blender's MULTIPLE_SCATTERING atmosphere "
                                   "(models with an atmosphere)")), default="earth")
    aerosol: EnumProperty(name="Aerosol", items=(
        ("TURBIDITY", "Turbidity", ""), ("AOD", "Optical depth", "At 550 nm")),
        default="TURBIDITY")
    turbidity: FloatProperty(name="Turbidity", default=3.0, min=1.0, max=32.0)
    aod: FloatProperty(name="AOD 550 nm", default=0.1, min=0.0, max=10.0)
    albedo: FloatProperty(name="Ground albedo", default=0.2, min=0.0, max=1.0)
    size: EnumProperty(name="Map size", items=SIZES, default="2048")
    output_dir: StringProperty(name="Folder", subtype="DIR_PATH", default="//skydome_sky/")
    view_transform: EnumProperty(name="View", items=VIEWS, default="AgX")
    exposure_compensation: FloatProperty(name="Compensation [EV]", default=0.0,
                                         min=-20.0, max=20.0)


def _python(context):
    prefs = _prefs(context)
    py = (prefs.python if prefs else "") or os.environ.get("SKYDOME_PYTHON", "")
    return bpy.path.abspath(py) if py else ""


def _out_dir(props):
    d = props.output_dir or "//skydome_sky/"
    if d.startswith("//") and not bpy.data.filepath:
        return os.path.join(tempfile.gettempdir(), "skydome_sky")
    return bpy.path.abspath(d)


def _times(props):
    if not props.use_sequence:
        return [props.time]
    t0, t1 = datetime.fromisoformat(props.time), datetime.fromisoformat(props.time_end)
    if t1 < t0:
        raise ValueError(f"End ({props.time_end}) is before Time ({props.time})")
    out, t = [], t0
    while t <= t1 and len(out) < 1000:
        out.append(t.isoformat())
        t += timedelta(minutes=props.step_minutes)
    return out


def _job(props, out_path):
    w = int(props.size)
    job = {"model": props.model, "atmosphere": props.atmosphere, "albedo": props.albedo,
           "width": w, "height": w // 2, "half": True, "out": out_path,
           "exposure_compensation_ev": props.exposure_compensation}
    if props.aerosol == "AOD":
        job["aerosol_optical_depth"] = props.aod
    else:
        job["turbidity"] = props.turbidity
    if props.sun_mode == "ANGLES" and not props.use_sequence:
        job["sun_elevation_deg"] = props.sun_elevation
        job["sun_azimuth_deg"] = props.sun_azimuth
    else:
        job.update(latitude_deg=props.latitude, longitude_deg=props.longitude,
                   times=_times(props))
    return job


def run_bake(python, job):
    """Run skydome's bake with ``python``; the result dictionary, or RuntimeError with
    skydome's own message."""
    fd, path = tempfile.mkstemp(prefix="skydome_job_", suffix=".json")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(job, f)
        proc = subprocess.run([python, "-m", "skydome.export.integrations.blender.bake", path],
                              capture_output=True, text=True)
    finally:
        os.remove(path)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    if proc.returncode or not lines:
        msg = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"skydome failed ({python}): {msg}")
    return json.loads(lines[-1][len("RESULT "):])


def _load_image(path):
    img = bpy.data.images.load(path, check_existing=False)
    for name in ("Linear Rec.709", "Linear"):
        try:
            img.colorspace_settings.name = name
            break
        except TypeError:
            continue
    return img


def _world(scene, frames):
    world = bpy.data.worlds.get(WORLD_NAME) or bpy.data.worlds.new(WORLD_NAME)
    if hasattr(world, "use_nodes") and not world.use_nodes:
        world.use_nodes = True
    nt = world.node_tree
    nt.nodes.clear()
    tex = nt.nodes.new("ShaderNodeTexEnvironment")
    tex.location = (-300, 0)
    tex.image = _load_image(frames[0]["map"])
    if len(frames) > 1:
        tex.image.source = "SEQUENCE"
        tex.image_user.frame_duration = len(frames)
        tex.image_user.frame_start = scene.frame_start
        tex.image_user.frame_offset = 0
        tex.image_user.use_auto_refresh = True
    bg = nt.nodes.new("ShaderNodeBackground")
    bg.inputs["Strength"].default_value = 1.0
    out = nt.nodes.new("ShaderNodeOutputWorld")
    out.location = (300, 0)
    nt.links.new(tex.outputs["Color"], bg.inputs["Color"])
    nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
    scene.world = world
    return world


def _sun(scene):
    obj = bpy.data.objects.get(SUN_NAME)
    if obj is None or obj.type != "LIGHT" or obj.data.type != "SUN":
        lamp = bpy.data.lights.new(SUN_NAME, type="SUN")
        obj = bpy.data.objects.new(SUN_NAME, lamp)
    if scene.collection.objects.get(obj.name) is None:
        scene.collection.objects.link(obj)
    obj.rotation_mode = "XYZ"
    return obj


def _apply_frame(scene, obj, frame, key=None):
    lamp = obj.data
    lamp.energy = frame["strength_W_m2"]
    lamp.color = frame["color"]
    lamp.angle = math.radians(frame["angle_deg"])
    obj.rotation_euler = [math.radians(a) for a in frame["rotation_euler_deg"]]
    scene.view_settings.exposure = frame["exposure_ev"]
    if key is not None:
        obj.keyframe_insert("rotation_euler", frame=key)
        lamp.keyframe_insert("energy", frame=key)
        lamp.keyframe_insert("color", frame=key)
        scene.view_settings.keyframe_insert("exposure", frame=key)


def _fcurve_lists(id_data):
    """The F-curve collections of an ID's action: ``action.fcurves`` before Blender 4.4,
    the channelbags of its layered strips from 4.4 (the only form in 5.0)."""
    ad = getattr(id_data, "animation_data", None)
    act = ad.action if ad else None
    if act is None:
        return []
    if hasattr(act, "layers"):
        return [bag.fcurves for layer in act.layers for strip in layer.strips
                for bag in getattr(strip, "channelbags", [])]
    return [act.fcurves]


def _drop_keys(id_data, paths):
    """Remove the F-curves of ``paths`` (RNA paths) from an ID's action, other
    animation kept."""
    for fcurves in _fcurve_lists(id_data):
        for fc in [fc for fc in fcurves if fc.data_path in paths]:
            fcurves.remove(fc)


def apply_result(scene, result, view_transform="AgX"):
    """Create or update the World, the sun lamp and the exposure from a bake result
    (keys of an earlier day sequence removed first)."""
    frames = result["frames"]
    _world(scene, frames)
    obj = _sun(scene)
    _drop_keys(obj, {"rotation_euler"})
    _drop_keys(obj.data, {"energy", "color"})
    _drop_keys(scene, {"view_settings.exposure"})
    if view_transform != "KEEP":
        scene.view_settings.view_transform = view_transform
    if len(frames) == 1:
        _apply_frame(scene, obj, frames[0])
    else:
        for i, fr in enumerate(frames):
            _apply_frame(scene, obj, fr, key=scene.frame_start + i)
        scene.frame_end = scene.frame_start + len(frames) - 1
    return obj


class SKYDOME_OT_bake_sky(bpy.types.Operator):
    """Bake the sky with skydome and set up the World, the sun lamp and the exposure"""
    bl_idname = "skydome.bake_sky"
    bl_label = "Bake sky with skydome"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        props = context.scene.skydome_sky
        python = _python(context)
        if not python:
            self.report({"ERROR"}, "set skydome's Python in the add-on's preferences "
                                   "(or the SKYDOME_PYTHON environment variable)")
            return {"CANCELLED"}
        try:
            out_dir = _out_dir(props)
            os.makedirs(out_dir, exist_ok=True)
            result = run_bake(python, _job(props, os.path.join(out_dir, "sky.exr")))
            apply_result(context.scene, result, props.view_transform)
        except (RuntimeError, ValueError, OSError) as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        fr = result["frames"][0]
        self.report({"INFO"}, f"skydome: {len(result['frames'])} map(s); E_h "
                              f"{fr['illuminance_horizontal_lx']:.0f} lx, exposure "
                              f"{fr['exposure_ev']:.2f} EV")
        return {"FINISHED"}


def _draw(layout, props):
    layout.prop(props, "model")
    layout.prop(props, "sun_mode", expand=True)
    col = layout.column(align=True)
    if props.sun_mode == "ANGLES" and not props.use_sequence:
        col.prop(props, "sun_elevation")
        col.prop(props, "sun_azimuth")
    else:
        col.prop(props, "latitude")
        col.prop(props, "longitude")
        col.prop(props, "time")
    layout.prop(props, "use_sequence")
    if props.use_sequence:
        col = layout.column(align=True)
        col.prop(props, "time_end")
        col.prop(props, "step_minutes")
    layout.prop(props, "atmosphere")
    if props.atmosphere == "earth":
        layout.prop(props, "aerosol", expand=True)
        layout.prop(props, "turbidity" if props.aerosol == "TURBIDITY" else "aod")
        layout.prop(props, "albedo")
    layout.prop(props, "size")
    layout.prop(props, "output_dir")
    col = layout.column(align=True)
    col.prop(props, "view_transform")
    col.prop(props, "exposure_compensation")
    layout.operator(SKYDOME_OT_bake_sky.bl_idname, icon="WORLD")


class SKYDOME_PT_world(bpy.types.Panel):
    bl_label = "skydome sky"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "world"

    def draw(self, context):
        _draw(self.layout, context.scene.skydome_sky)


class SKYDOME_PT_view3d(bpy.types.Panel):
    bl_label = "skydome sky"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "skydome"

    def draw(self, context):
        _draw(self.layout, context.scene.skydome_sky)


_CLASSES = (SKYDOME_AP_preferences, SkydomeSkySettings, SKYDOME_OT_bake_sky,
            SKYDOME_PT_world, SKYDOME_PT_view3d)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.skydome_sky = PointerProperty(type=SkydomeSkySettings)


def unregister():
    del bpy.types.Scene.skydome_sky
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
