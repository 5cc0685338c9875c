"""The Blender add-on (skydome.export.integrations.blender): packed by pack_addon(),
installed into a fresh Blender (an empty BLENDER_USER_RESOURCES) as a legacy add-on and as
an extension, in the shared environment's bpy (4.2 LTS) and in bpy 5.0 (.venv-bpy5, made by
scripts/_setup test), enabled, its operator run; Cycles (CPU) then renders a white
Lambertian plane and a post's shadow. The plane's radiance x pi must equal skydome's own
horizontal irradiance (a finer map in skydome's convention integrated with exact pixel
solid angles, plus the sun's irradiance x sin(elevation)) within 1 %, the shadow must point
away from the sun within 2 deg."""

import importlib.util
import json
import math
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import skydome as sd
from skydome.export.envmap import render_envmap
from skydome.export.integrations.blender import pack_addon
from skydome.export.integrations.blender.bake import bake, exposure_ev, sun_rotation_euler_deg
from skydome.export.sun import sun_light

ROOT = Path(__file__).resolve().parents[1]
BPY5 = ROOT / ".venv-bpy5" / "bin" / "python"
SUN = (35.0, 150.0)                       # elevation, azimuth [deg]
SETTINGS = {"model": "hosek_wilkie2012", "sun_mode": "ANGLES", "sun_elevation": SUN[0],
            "sun_azimuth": SUN[1], "aerosol": "TURBIDITY", "turbidity": 3.0, "albedo": 0.3,
            "size": "1024", "view_transform": "AgX"}
Y709 = np.array([0.2126, 0.7152, 0.0722])


@pytest.fixture(scope="module")
def sky():
    return sd.model("hosek_wilkie2012", sun=sd.Sun(elevation_deg=SUN[0], azimuth_deg=SUN[1]),
                    turbidity=3.0, albedo=0.3)


@pytest.fixture(scope="module")
def expected(sky):
    """skydome's RGB horizontal irradiance [W m^-2, 683 lm/W scale]: a 1024 x 512 map in
    skydome's own convention, exact pixel solid angles, plus the sun."""
    ref = render_envmap(sky, "skydome", size="1024x512")
    d, w = ref.directions()
    E_sky = (ref.pixels() * (np.maximum(d[:, 2], 0.0) * w)[:, None]).sum(axis=0)
    E_sun = np.array(sun_light(sky)["rgb_irradiance_W_m2"]) * max(sky.sun.direction[2], 0.0)
    return E_sky + E_sun


def test_pack_addon(tmp_path):
    p = pack_addon(tmp_path / "addon.zip")
    with zipfile.ZipFile(p) as z:
        names = sorted(z.namelist())
        manifest = z.read("skydome_sky/blender_manifest.toml").decode()
        init = z.read("skydome_sky/__init__.py").decode()
    assert names == ["skydome_sky/__init__.py", "skydome_sky/blender_manifest.toml"]
    assert 'id = "skydome_sky"' in manifest and 'blender_version_min = "4.2.0"' in manifest
    assert "bl_info" in init and '"blender": (4, 2, 0)' in init
    with pytest.raises(ValueError, match="add-on zip"):
        pack_addon(tmp_path / "addon.tar")
    with pytest.raises(ValueError, match="does not exist"):
        pack_addon(tmp_path / "missing" / "addon.zip")


def test_sun_rotation_points_lamp_at_sun():
    """R = Rz(Z) Rx(X) applied to +Z (the lamp's back) gives the ENU direction to the sun
    (checked with explicit rotation matrices, Blender's XYZ Euler order)."""
    for el, az in ((35.0, 150.0), (5.0, 280.0), (80.0, 10.0), (-3.0, 90.0)):
        x, y, z = np.radians(sun_rotation_euler_deg(el, az))
        rx = np.array([[1, 0, 0], [0, np.cos(x), -np.sin(x)], [0, np.sin(x), np.cos(x)]])
        ry = np.array([[np.cos(y), 0, np.sin(y)], [0, 1, 0], [-np.sin(y), 0, np.cos(y)]])
        rz = np.array([[np.cos(z), -np.sin(z), 0], [np.sin(z), np.cos(z), 0], [0, 0, 1]])
        d = rz @ ry @ rx @ np.array([0.0, 0.0, 1.0])
        e, a = np.radians(el), np.radians(az)
        want = [np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)]
        np.testing.assert_allclose(d, want, atol=1e-12)


def test_exposure_ev():
    # a white Lambertian surface under E lx has luminance E / pi; in the maps' units
    # (683 lm/W) that is E / (pi 683), brought to 1.0 by 2^EV
    assert exposure_ev(math.pi * 683.0) == pytest.approx(0.0, abs=1e-12)
    assert exposure_ev(100000.0) == pytest.approx(math.log2(math.pi * 683.0 / 1e5))
    assert exposure_ev(1e5, compensation_ev=1.0) == pytest.approx(exposure_ev(1e5) + 1.0)
    assert exposure_ev(0.0) == 32.0


@pytest.mark.parametrize("job, match", [
    ({"sun_elevation_deg": 35}, "sun_elevation_deg and sun_azimuth_deg"),
    ({"sun_elevation_deg": 95, "sun_azimuth_deg": 0}, "sun_elevation_deg"),
    ({"sun_elevation_deg": 35, "sun_azimuth_deg": 0, "turbidity": 0.5}, "turbidity"),
    ({"sun_elevation_deg": 35, "sun_azimuth_deg": 0, "albedo": 2}, "albedo"),
    ({"sun_elevation_deg": 35, "sun_azimuth_deg": 0, "width": 100, "height": 100}, "width"),
    ({"latitude_deg": 48, "longitude_deg": 11, "times": ["noon"]}, "time"),
    ({"sun_elevation_deg": 35, "sun_azimuth_deg": 0, "model": "nope"}, "nope"),
    ({"sun_elevation_deg": 35, "sun_azimuth_deg": 0, "colour": 1}, "colour"),
    ({"sun_elevation_deg": 35, "sun_azimuth_deg": 0, "atmosphere": "blender"}, "atmosphere"),
    ({"sun_elevation_deg": 35, "sun_azimuth_deg": 0, "aerosol_optical_depth": 0.1},
     "aerosol_optical_depth"),
    ({"sun_elevation_deg": 35, "sun_azimuth_deg": 0, "out": "/nonexistent/sky.exr"},
     "does not exist"),
    ({"sun_elevation_deg": 35, "sun_azimuth_deg": 0, "out": "sky.png"}, "exr"),
])
def test_bake_rejects_bad_jobs_before_work(tmp_path, job, match):
    job = {"out": str(tmp_path / "sky.exr"), **job}
    with pytest.raises(ValueError, match=match):
        bake(job)
    assert list(tmp_path.iterdir()) == []


def test_bake_day_sequence(tmp_path):
    """Three times at one place: three numbered maps and sun lights, the sun's positions
    those of Sun.from_location."""
    times = ["2024-06-21T08:00:00+02:00", "2024-06-21T12:00:00+02:00",
             "2024-06-21T16:00:00+02:00"]
    res = bake({"model": "hosek_wilkie2012", "latitude_deg": 48.0, "longitude_deg": 11.0,
                "times": times, "width": 64, "height": 32, "out": str(tmp_path / "sky.exr")})
    assert [Path(f["map"]).name for f in res["frames"]] == [
        "sky0001.exr", "sky0002.exr", "sky0003.exr"]
    for f, t in zip(res["frames"], times):
        s = sd.Sun.from_location(48.0, 11.0, t)
        assert f["elevation_deg"] == pytest.approx(s.elevation_deg)
        assert f["azimuth_deg"] == pytest.approx(s.azimuth_deg)
        assert Path(f["sun_json"]).is_file()


def _run_check(python, how, settings, tmp_path):
    zip_path = pack_addon(tmp_path / "skydome_sky.zip")
    user = tmp_path / "blender_user"
    user.mkdir()
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(user),
               PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    script = Path(__file__).with_name("_blender_addon_check.py")
    proc = subprocess.run([str(python), str(script), str(zip_path), how, sys.executable,
                           str(tmp_path), json.dumps(settings)],
                          capture_output=True, text=True, timeout=600, env=env)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    assert proc.returncode == 0 and lines, (proc.stdout[-2000:], proc.stderr[-2000:])
    return json.loads(lines[-1][len("RESULT "):])


def _run_addon(python, how, sky, expected, tmp_path):
    r = _run_check(python, how, SETTINGS, tmp_path)
    light = sun_light(sky, "blender")["targets"]["blender"]
    # what the add-on created: the World, the lamp from sun.json, the exposure
    assert r["world"] == "skydome sky" and r["background_strength"] == 1.0
    assert r["colorspace"] == "Linear Rec.709"
    assert r["sun_rotation_mode"] == "XYZ"
    np.testing.assert_allclose(r["sun_rotation_deg"], [90.0 - SUN[0], 0.0, 180.0 - SUN[1]],
                               atol=1e-5)
    assert r["sun_strength"] == pytest.approx(light["strength_W_m2"], rel=1e-6)
    np.testing.assert_allclose(r["sun_color"], light["color"], rtol=1e-6)
    assert math.degrees(r["sun_angle"]) == pytest.approx(2 * sky.sun.angular_radius_deg,
                                                         rel=1e-5)
    E_h = 683.0 * float(expected @ Y709)
    assert r["exposure"] == pytest.approx(math.log2(math.pi * 683.0 / E_h), abs=0.015)
    assert r["view_transform"] == "AgX"
    # the white plane: radiance x pi = skydome's horizontal irradiance (1 %); the EXR holds
    # scene-linear values before the exposure
    np.testing.assert_allclose(np.array(r["plane_rgb"]) * np.pi, expected, rtol=1e-2)
    # the post's shadow, seen from straight above with north up
    from skydome.imaging.image import read_exr

    ch = read_exr(r["post_image"])
    Y = 0.2126 * ch["R"] + 0.7152 * ch["G"] + 0.0722 * ch["B"]
    rows, cols = np.nonzero(Y < 0.5 * np.median(Y))
    assert rows.size > 10
    H, W = Y.shape
    east, north = cols + 0.5 - W / 2, -(rows + 0.5 - H / 2)
    shadow_az = np.degrees(np.arctan2(east.mean(), north.mean())) % 360.0
    want = (SUN[1] + 180.0) % 360.0
    assert abs((shadow_az - want + 180.0) % 360.0 - 180.0) < 2.0, shadow_az
    return r


MODULES = {"legacy": "skydome_sky", "extension": "bl_ext.user_default.skydome_sky"}


@pytest.mark.parametrize("how", ["legacy", "extension"])
def test_addon_in_blender_4(how, sky, expected, tmp_path):
    """The shared environment's bpy (4.2 LTS): the zip installed as a legacy add-on and as
    an extension."""
    if importlib.util.find_spec("bpy") is None:
        pytest.skip("bpy (Blender as a Python module) is not installed")
    r = _run_addon(sys.executable, how, sky, expected, tmp_path)
    assert r["module"] == MODULES[how] and r["blender"].startswith("4.")


@pytest.mark.parametrize("how", ["legacy", "extension"])
def test_addon_in_blender_5(how, sky, expected, tmp_path):
    """bpy 5.0 in .venv-bpy5: the same zip, both ways."""
    if not BPY5.is_file():
        pytest.skip(f"{BPY5.relative_to(ROOT)} missing: `scripts/_setup test` makes it "
                    "(bpy 5.0.1, about 900 MB)")
    r = _run_addon(BPY5, how, sky, expected, tmp_path)
    assert r["module"] == MODULES[how] and r["blender"].startswith("5.")


@pytest.mark.parametrize("blender", ["4", "5"])
def test_addon_day_sequence(blender, tmp_path):
    """Three times at one place: the World's image is a 3-image sequence from the scene's
    first frame, and the lamp's rotation and the exposure are keyframed on frames 1-3 with
    the sun of Sun.from_location at each time (Blender 5 keeps keys in layered actions)."""
    if blender == "4" and importlib.util.find_spec("bpy") is None:
        pytest.skip("bpy (Blender as a Python module) is not installed")
    if blender == "5" and not BPY5.is_file():
        pytest.skip(f"{BPY5.relative_to(ROOT)} missing: `scripts/_setup test` makes it")
    python, how = (sys.executable, "legacy") if blender == "4" else (BPY5, "extension")
    times = ["2024-06-21T08:00:00+02:00", "2024-06-21T10:00:00+02:00",
             "2024-06-21T12:00:00+02:00"]
    settings = {"model": "hosek_wilkie2012", "sun_mode": "PLACE_TIME", "latitude": 48.0,
                "longitude": 11.0, "time": times[0], "time_end": times[-1],
                "step_minutes": 120, "use_sequence": True, "size": "1024",
                "sun_elevation": 35.0, "sun_azimuth": 150.0}
    r = _run_check(python, how, settings, tmp_path)
    assert r["blender"].startswith(blender + ".")
    seq = r["sequence"]
    assert seq["image_source"] == "SEQUENCE" and seq["frame_duration"] == 3
    assert seq["frame_start"] == 1 and seq["scene_frames"] == [1, 3]
    assert Path(r["map"]).name == "sky0001.exr"
    keys = np.array(seq["rotation_keys"])                  # (3 axes, 3 keys, (frame, value))
    assert keys.shape == (3, 3, 2)
    np.testing.assert_allclose(keys[:, :, 0], [[1, 2, 3]] * 3)
    for i, t in enumerate(times):
        s = sd.Sun.from_location(48.0, 11.0, t)
        x, z = keys[0, i, 1], keys[2, i, 1]
        d = [np.sin(x) * np.sin(z), -np.sin(x) * np.cos(z), np.cos(x)]   # Rz Rx (0, 0, 1)
        np.testing.assert_allclose(d, s.direction, atol=1e-6)
        assert keys[1, i, 1] == 0.0
    assert len(seq["exposure_keys"]) == 3
    # a single bake afterwards removes the sequence's keys and image sequence
    after = r["after_single_bake"]
    assert after["fcurves"] == [] and after["image_source"] == "FILE"
    np.testing.assert_allclose(after["rotation_deg"], [55.0, 0.0, 30.0], atol=1e-5)
