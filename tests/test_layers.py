"""The layers hold one way, the merged Camera, the one contact-sheet function and render()'s
refusal of a model name."""

import math
import pkgutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import skydome
from skydome.camera import Camera

SRC = Path(__file__).resolve().parents[1] / "src"


def _modules(package: str) -> list[str]:
    root = SRC.joinpath(*package.split("."))
    return [package] + [f"{package}.{m.name}" for m in pkgutil.iter_modules([str(root)])
                        if not m.ispkg] + [
        f"{package}.{m.name}.{s.name}" for m in pkgutil.iter_modules([str(root)]) if m.ispkg
        for s in pkgutil.iter_modules([str(root / m.name)])]


@pytest.mark.parametrize("package", ["skydome.models", "skydome.effects", "skydome.transport",
                                     "skydome.atmosphere", "skydome.camera"])
def test_lower_layers_import_no_render_apps_or_plotting(package):
    mods = _modules(package) if SRC.joinpath(*package.split(".")).is_dir() else [package]
    code = ("import importlib, sys\n"
            f"for m in {mods!r}:\n    importlib.import_module(m)\n"
            "bad = sorted(m for m in sys.modules if m.startswith(('skydome.render', 'skydome.apps', "
            "'skydome.cli', 'matplotlib', 'PIL')))\nprint(','.join(bad))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env={"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == ""


def test_render_refuses_a_model_name_with_a_type_error():
    with pytest.raises(TypeError, match="'preetham1999'.*skydome.model"):
        skydome.render("preetham1999", skydome.Fisheye(8))
    with pytest.raises(TypeError, match="sky model"):
        skydome.render(object(), skydome.Fisheye(8))


def _enu(elevation_deg, azimuth_deg):
    el, az = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)])


def test_camera_by_view_direction_matches_camera_by_points():
    a = Camera(fov_deg=50.0, azimuth_deg=30.0, elevation_deg=10.0, altitude_m=120.0)
    d = _enu(10.0, 30.0)
    b = Camera(8, 6, 50.0, position=(0.0, 0.0, 120.0), look_at=(d[0], d[1], 120.0 + d[2]), up=(0, 0, 1))
    dirs_a = a.ray_directions(8, 6)
    dirs_b, mask = b.directions()
    assert mask.all()
    np.testing.assert_allclose(dirs_a, dirs_b, atol=1e-12)
    assert (a.altitude_m, a.azimuth_deg) == (120.0, 30.0)
    assert b.elevation_deg == pytest.approx(10.0) and b.azimuth_deg == pytest.approx(30.0)


def test_camera_geometry_from_first_principles():
    """Pinhole geometry: the optical axis is the view direction; the rays through the middle
    of the left and right image edges are fov apart; the image top is towards the zenith;
    the pixel solid angles sum to the frustum's 4 asin(sin(a) sin(b)) for half-angles a, b."""
    cam = Camera(64, 32, 60.0, azimuth_deg=200.0, elevation_deg=5.0, altitude_m=10.0)
    np.testing.assert_allclose(cam.direction_from_pixel(16.0, 32.0), _enu(5.0, 200.0), atol=1e-12)
    left, right = cam.direction_from_pixel(16.0, 0.0), cam.direction_from_pixel(16.0, 64.0)
    assert math.degrees(math.acos(float(left @ right))) == pytest.approx(60.0, abs=1e-9)
    assert cam.direction_from_pixel(0.0, 32.0)[2] > cam.direction_from_pixel(32.0, 32.0)[2]
    a = math.radians(30.0)
    b = math.atan(math.tan(a) * 32 / 64)
    assert cam.solid_angles().sum() == pytest.approx(4 * math.asin(math.sin(a) * math.sin(b)), rel=1e-3)
    row, col = cam.pixel_from_direction(_enu(5.0, 200.0))
    assert (float(row), float(col)) == pytest.approx((16.0, 32.0))


def test_camera_refuses_bad_placements():
    with pytest.raises(ValueError, match="fov_deg"):
        Camera(8, 8, 180.0)
    with pytest.raises(ValueError, match="elevation_deg"):
        Camera(fov_deg=40.0, elevation_deg=90.0)
    with pytest.raises(ValueError, match="position"):
        Camera(8, 8, 40.0, position=(0, 0, 1))
    with pytest.raises(ValueError, match="not both"):
        Camera(8, 8, 40.0, position=(0, 0, 1), look_at=(0, 1, 1), azimuth_deg=3.0)
    with pytest.raises(ValueError, match="no image size"):
        Camera(fov_deg=40.0).directions()


def test_dobashi2002_and_render_share_one_camera_class():
    from skydome.effects import dobashi2002
    from skydome.render.projections import Projection

    assert dobashi2002.Camera is Camera
    assert issubclass(Camera, Projection)


def test_contact_sheet_layout(tmp_path):
    from PIL import Image

    from skydome.render.sheets import contact_sheet

    red = np.zeros((20, 20, 3))
    red[..., 0] = 1.0
    blue = np.zeros((10, 40, 3))
    blue[..., 2] = 1.0
    out = contact_sheet([(red, "a"), (blue, ["b", "second"]), (None, "missing")], tmp_path / "s.png",
                        cols=2, tile=40, background=(0, 0, 0))
    im = np.asarray(Image.open(out))
    # 2 columns of 40 px; 2 rows of (tallest image 20 px + two label lines of 14 px)
    assert im.shape == (2 * (20 + 28), 80, 3)
    assert tuple(im[10, 20]) == (255, 0, 0)          # red tile centred in its 40 px cell
    assert tuple(im[10, 60]) == (0, 0, 255)          # the 40x10 tile centred vertically
    assert tuple(im[2, 60]) == (0, 0, 0)
    assert [p.name for p in tmp_path.iterdir()] == ["s.png"]
    with pytest.raises(ValueError, match="tiles is empty"):
        contact_sheet([], tmp_path / "t.png")


def test_contact_sheet_letterbox_cells(tmp_path):
    # every cell the box (60 x 40): a square image scaled up to 40 x 40 and centred, a wide
    # one to 60 x 15; the last, shorter row centred; captions in a band under each box
    from PIL import Image

    from skydome.render.sheets import contact_sheet

    red = np.zeros((10, 10, 3))
    red[..., 0] = 1.0
    blue = np.zeros((10, 40, 3))
    blue[..., 2] = 1.0
    tiles = [(red, "a"), (blue, "b"), (red, "c")]
    out = contact_sheet(tiles, tmp_path / "s.png", cols=2, tile=(60, 40), line_height=10,
                        background=(0, 0, 0), letterbox=True)
    im = np.asarray(Image.open(out))
    assert im.shape == (2 * (40 + 10), 120, 3)
    assert tuple(im[20, 30]) == (255, 0, 0) and tuple(im[2, 30]) == (255, 0, 0)   # filled 40 px high
    assert tuple(im[20, 5]) == (0, 0, 0)                                           # letterbox bar
    assert tuple(im[20, 62]) == (0, 0, 255) and tuple(im[10, 90]) == (0, 0, 0)     # 60 x 15, centred
    assert tuple(im[50 + 20, 60]) == (255, 0, 0) and tuple(im[50 + 20, 20]) == (0, 0, 0)  # last row centred
