"""`skydome export envmap` and `skydome export sun`: files written, one-line errors with exit
code 2 and nothing on disk for bad input."""

import json

import numpy as np
from typer.testing import CliRunner

from skydome.cli import app

runner = CliRunner()
HW = ("--model", "hosek_wilkie2012", "--turbidity", "3", "--albedo", "0.2")


def test_export_envmap_with_sun_json_and_sh(tmp_path):
    from skydome.imaging.image import read_exr

    out = tmp_path / "sky.exr"
    res = runner.invoke(app, ["export", "envmap", *HW, "--lat", "48.21", "--lon", "16.37",
                              "--time", "2026-06-21T18:00+02:00", "--convention", "blender",
                              "--size", "64x32", "--half", "--sh", "--out", str(out)])
    assert res.exit_code == 0, res.output
    ch = read_exr(out)
    assert ch["R"].shape == (32, 64) and ch["R"].dtype == np.float16
    sun = json.loads((tmp_path / "sky.sun.json").read_text())
    assert sun["convention"] == "blender"
    # 18:00 CEST at Vienna on the solstice: the sun is in the west-north-west
    assert 270 < sun["azimuth_deg"] < 300 and 20 < sun["elevation_deg"] < 35
    sh = json.loads((tmp_path / "sky.sh.json").read_text())
    assert np.array(sh["coefficients_rgb"]).shape == (9, 3)


def test_export_envmap_cross(tmp_path):
    out = tmp_path / "cube.hdr"
    res = runner.invoke(app, ["export", "envmap", *HW, "--convention", "unity", "--layout",
                              "cross", "--size", "16", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert out.exists() and (tmp_path / "cube.sun.json").exists()


def test_export_bad_input_exit_2_nothing_written(tmp_path):
    cases = [
        (["--convention", "maya"], "convention = 'maya' is not one of"),
        (["--convention", "blender", "--layout", "cross"], "not available for convention"),
        (["--layout", "spiral"], "layout = 'spiral'"),
        (["--size", "1x1"], "size"),
        (["--half", "--sun-in-map"], "--half cannot hold the sun"),
        (["--turbidity", "12"], "turbidity"),
    ]
    for extra, msg in cases:
        res = runner.invoke(app, ["export", "envmap", "--model", "hosek_wilkie2012", *extra,
                                  "--out", str(tmp_path / "x.exr")])
        assert res.exit_code == 2, (extra, res.output)
        assert msg in res.output, (extra, res.output)
    res = runner.invoke(app, ["export", "envmap", *HW, "--out", str(tmp_path / "x.png")])
    assert res.exit_code == 2 and "must be .exr or .hdr" in res.output
    res = runner.invoke(app, ["export", "sun", *HW, "--out", str(tmp_path / "x.txt")])
    assert res.exit_code == 2 and ".json" in res.output
    assert list(tmp_path.iterdir()) == []


def test_export_sun(tmp_path):
    out = tmp_path / "sun.json"
    res = runner.invoke(app, ["export", "sun", *HW, "--sun-elevation", "40", "--sun-azimuth",
                              "200", "--convention", "mitsuba", "--out", str(out)])
    assert res.exit_code == 0, res.output
    light = json.loads(out.read_text())
    el, az = np.radians(40.0), np.radians(200.0)
    # Mitsuba axes: x east, y up, z south
    np.testing.assert_allclose(light["direction_to_sun"],
                               [np.cos(el) * np.sin(az), np.sin(el), -np.cos(el) * np.cos(az)],
                               atol=1e-12)
    np.testing.assert_allclose(light["targets"]["mitsuba"]["direction"],
                               -np.array(light["direction_to_sun"]), atol=1e-12)


# Mitsuba 3's normalisation of y-bar, include/mitsuba/core/spectrum.h:
# MI_CIE_Y_NORMALIZATION = 1 / 106.7502593994140625
MITSUBA_CIE_Y_NORMALIZATION = 1.0 / 106.7502593994140625


def test_export_units_mitsuba_scales_map_sun_and_sh(tmp_path):
    """--units mitsuba: the map, its sun light and its SH in Mitsuba's units, the photometric
    values times Mitsuba's MI_CIE_Y_NORMALIZATION; the SH says which units it holds."""
    from skydome.imaging.image import read_exr

    common = [*HW, "--sun-elevation", "35", "--sun-azimuth", "150", "--convention", "blender",
              "--size", "32x16", "--sh"]
    res = runner.invoke(app, ["export", "envmap", *common, "--out", str(tmp_path / "p.exr")])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["export", "envmap", *common, "--units", "mitsuba",
                              "--out", str(tmp_path / "m.exr")])
    assert res.exit_code == 0, res.output
    p, m = read_exr(tmp_path / "p.exr"), read_exr(tmp_path / "m.exr")
    for c in "RGB":
        np.testing.assert_allclose(m[c], p[c] * MITSUBA_CIE_Y_NORMALIZATION, rtol=1e-6)
    sh_p = json.loads((tmp_path / "p.sh.json").read_text())
    sh_m = json.loads((tmp_path / "m.sh.json").read_text())
    assert sh_p["units"] == "photometric" and "[W m^-2]" in sh_p["irradiance"]
    assert sh_m["units"] == "mitsuba" and "mitsuba" in sh_m["irradiance"]
    assert "W m^-2]" not in sh_m["irradiance"]
    np.testing.assert_allclose(np.array(sh_m["coefficients_rgb"]),
                               np.array(sh_p["coefficients_rgb"]) * MITSUBA_CIE_Y_NORMALIZATION,
                               rtol=1e-5, atol=1e-12)
    sun_p = json.loads((tmp_path / "p.sun.json").read_text())
    sun_m = json.loads((tmp_path / "m.sun.json").read_text())
    assert sun_p["map_units"] == "photometric" and sun_m["map_units"] == "mitsuba"
    np.testing.assert_allclose(sun_m["rgb_irradiance_map_units"],
                               np.array(sun_p["rgb_irradiance_W_m2"]) * MITSUBA_CIE_Y_NORMALIZATION,
                               rtol=1e-12)


def test_export_sun_units(tmp_path):
    sun = [*HW, "--sun-elevation", "40", "--sun-azimuth", "200"]
    res = runner.invoke(app, ["export", "sun", *sun, "--convention", "mitsuba", "--units",
                              "photometric", "--out", str(tmp_path / "p.json")])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["export", "sun", *sun, "--convention", "mitsuba",
                              "--out", str(tmp_path / "m.json")])
    assert res.exit_code == 0, res.output
    p = json.loads((tmp_path / "p.json").read_text())
    m = json.loads((tmp_path / "m.json").read_text())
    assert p["map_units"] == "photometric" and m["map_units"] == "mitsuba"  # mitsuba's own
    np.testing.assert_allclose(p["rgb_irradiance_map_units"], p["rgb_irradiance_W_m2"])
    np.testing.assert_allclose(m["rgb_irradiance_map_units"],
                               np.array(m["rgb_irradiance_W_m2"]) * MITSUBA_CIE_Y_NORMALIZATION,
                               rtol=1e-12)


def test_export_bad_units_one_line_nothing_written(tmp_path):
    for command, out in (("envmap", "x.exr"), ("sun", "x.json")):
        for units in ("Mitsuba", "radiometric", ""):
            res = runner.invoke(app, ["export", command, *HW, "--units", units,
                                      "--out", str(tmp_path / out)])
            lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
            assert res.exit_code == 2 and len(lines) == 1, (command, units, res.output)
            assert lines[0].startswith(f"error: --units = {units!r} is not one of "
                                       "photometric, mitsuba"), lines[0]
    assert list(tmp_path.iterdir()) == []


def test_export_blender_addon_and_threejs_write_the_package_sources(tmp_path):
    """`export blender-addon` packs the add-on folder's files under its module name (what
    Blender's installer reads; the bpy tests install such a zip); `export threejs` copies the
    module, the example page and the one source of the shader byte for byte."""
    import zipfile

    from skydome.export.integrations.blender import ADDON_MODULE, addon_dir
    from skydome.export.integrations.threejs import FILES

    z = tmp_path / "addon.zip"
    res = runner.invoke(app, ["export", "blender-addon", "--out", str(z)])
    assert res.exit_code == 0, res.output
    with zipfile.ZipFile(z) as f:
        names = f.namelist()
        assert f"{ADDON_MODULE}/__init__.py" in names
        for n in names:
            assert f.read(n) == (addon_dir() / n.split("/", 1)[1]).read_bytes()
    folder = tmp_path / "tj"
    res = runner.invoke(app, ["export", "threejs", "--out", str(folder)])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in folder.iterdir()) == sorted(FILES)
    for name, src in FILES.items():
        assert (folder / name).read_bytes() == src.read_bytes()


def test_export_blender_addon_and_threejs_refuse_bad_outputs(tmp_path):
    for args in (["export", "blender-addon", "--out", str(tmp_path / "addon.txt")],
                 ["export", "blender-addon", "--out", str(tmp_path / "no" / "a.zip")],
                 ["export", "threejs", "--out", str(tmp_path / "no" / "such" / "dir")]):
        res = runner.invoke(app, args)
        assert res.exit_code == 2, (args, res.output)
        assert res.output.count("\n") == 1 and res.output.startswith("error: "), res.output
    assert list(tmp_path.iterdir()) == []
