"""skydome's environment map and sun light inside real renderers (test extra: mitsuba, bpy):
white Lambertian planes (horizontal, and vertical facing N, E, S, W) lit by the map plus the
sun light; the plane's rendered radiance x pi must equal skydome's irradiance of that plane
(sky and ground of a finer skydome map, integrated, plus the sun's irradiance x cos) within
3 %; in Blender also the direction of a vertical pole's shadow within 2 deg."""

import numpy as np
import pytest

import skydome as sd
from skydome.export.conventions import CONVENTIONS
from skydome.export.envmap import render_envmap
from skydome.export.sun import sun_light

PLANES = {"up": [0, 0, 1.0], "N": [0, 1.0, 0], "E": [1.0, 0, 0], "S": [0, -1.0, 0],
          "W": [-1.0, 0, 0]}


@pytest.fixture(scope="module")
def sky():
    return sd.model("hosek_wilkie2012", sun=sd.Sun(elevation_deg=35.0, azimuth_deg=150.0),
                    turbidity=3.0, albedo=0.3)


@pytest.fixture(scope="module")
def expected(sky):
    """skydome's RGB irradiance [W m^-2, 683 lm/W scale] of each plane: a 1024 x 512 map in
    skydome's own convention integrated with exact pixel solid angles, plus the sun."""
    ref = render_envmap(sky, "skydome", size="1024x512")
    d, w = ref.directions()
    L = ref.pixels()
    E_sun = np.array(sun_light(sky)["rgb_irradiance_W_m2"])
    s = sky.sun.direction
    return {k: (L * (np.maximum(d @ np.array(n), 0.0) * w)[:, None]).sum(axis=0)
            + E_sun * max(float(np.array(n) @ s), 0.0) for k, n in PLANES.items()}


def test_mitsuba_planes(sky, expected):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    # photometric units (683 lm/W), as skydome's expectation; Mitsuba's own units (the
    # convention's default) are checked in tests/test_mitsuba_units.py
    env = render_envmap(sky, "mitsuba", size="512x256", units="photometric")
    light = sun_light(sky, "mitsuba", units="photometric")
    conv = CONVENTIONS["mitsuba"]
    bitmap = mi.Bitmap(env.images["map"].astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    for name, n in PLANES.items():
        nt = [float(x) for x in conv.to_tool(n)]
        up = [0, 1, 0] if abs(nt[1]) < 0.9 else [1, 0, 0]
        T = mi.ScalarTransform4f()
        scene = mi.load_dict({
            "type": "scene", "integrator": {"type": "direct"},
            "env": {"type": "envmap", "bitmap": bitmap},
            "sun": {"type": "directional", "direction": light["targets"]["mitsuba"]["direction"],
                    "irradiance": {"type": "rgb", "value": light["rgb_irradiance_W_m2"]}},
            "plane": {"type": "rectangle", "to_world": T.look_at(origin=[0, 0, 0], target=nt, up=up),
                      "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}},
            "cam": {"type": "perspective", "fov": 10,
                    "to_world": T.look_at(origin=[3 * x for x in nt], target=[0, 0, 0], up=up),
                    "film": {"type": "hdrfilm", "width": 8, "height": 8, "rfilter": {"type": "box"}},
                    "sampler": {"type": "independent", "sample_count": 512}}})
        radiance = np.array(mi.render(scene)).reshape(-1, 3).mean(axis=0)
        np.testing.assert_allclose(radiance * np.pi, expected[name], rtol=3e-2, err_msg=name)


def test_blender_planes_and_pole_shadow(sky, expected, tmp_path):
    """Cycles (CPU) in a subprocess: tests/_blender_check.py loads the map (blender
    convention, Environment Texture with default mapping) and a sun lamp from sun.json."""
    import importlib.util
    import json
    import subprocess
    import sys
    from pathlib import Path

    if importlib.util.find_spec("bpy") is None:
        pytest.skip("bpy (Blender as a Python module) is not installed")
    from skydome.export.sun import write_sun_json
    from skydome.imaging.image import read_exr

    render_envmap(sky, "blender", size="512x256").write(tmp_path / "map.exr")
    write_sun_json(sun_light(sky, "blender"), tmp_path / "sun.json")
    script = Path(__file__).with_name("_blender_check.py")
    proc = subprocess.run([sys.executable, str(script), str(tmp_path / "map.exr"),
                           str(tmp_path / "sun.json"), str(tmp_path)],
                          capture_output=True, text=True, timeout=900)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    assert proc.returncode == 0 and lines, proc.stderr[-2000:]
    result = json.loads(lines[-1][len("RESULT "):])
    for name, radiance in result["planes"].items():
        np.testing.assert_allclose(np.array(radiance) * np.pi, expected[name], rtol=3e-2,
                                   err_msg=name)
    # the pole's shadow, seen from straight above with north up: the dark pixels' centroid
    # from the pole's foot must point away from the sun's azimuth
    ch = read_exr(result["pole_image"])
    Y = 0.2126 * ch["R"] + 0.7152 * ch["G"] + 0.0722 * ch["B"]
    rows, cols = np.nonzero(Y < 0.5 * np.median(Y))
    assert rows.size > 10
    H, W = Y.shape
    east, north = cols + 0.5 - W / 2, -(rows + 0.5 - H / 2)
    shadow_az = np.degrees(np.arctan2(east.mean(), north.mean())) % 360.0
    want = (sky.sun.azimuth_deg + 180.0) % 360.0
    assert abs((shadow_az - want + 180.0) % 360.0 - 180.0) < 2.0
