"""The shortcuts of the warm render, environment-map and sky-matrix paths give what the long
ways give: the solid angles of a few pixels, the adapting luminance computed once per
picture, numba started without SciPy's BLAS probe (docs/performance.md, "Warm paths")."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from skydome.camera import Camera
from skydome.imaging import AngularMap, Equirect, Fisheye
from skydome.imaging.image import SkyImage


def _projections():
    from skydome.export.envmap import MapProjection

    cam = Camera(64, 48, 40.0, position=(0.0, 0.0, 0.0), look_at=(1.0, 2.0, 0.5),
                 up=(0.0, 0.0, 1.0))
    return [Fisheye(97), AngularMap(64), Equirect(128), Equirect(90, 31, hemisphere=True), cam,
            MapProjection("blender", 64, 32), MapProjection("radiance", 40, 40)]


@pytest.mark.parametrize("proj", _projections(), ids=repr)
def test_solid_angles_at_equal_the_whole_images_bit_for_bit(proj):
    """solid_angles_at(pixels) is solid_angles() at those pixels, the same bits, masked
    pixels (outside a fisheye's disc) included."""
    whole = proj.solid_angles().reshape(-1)
    rng = np.random.default_rng(7)
    idx = np.concatenate([[0, whole.size - 1, whole.size // 2],
                          rng.integers(0, whole.size, 500)])
    got = proj.solid_angles_at(idx)
    assert got.shape == idx.shape
    assert np.array_equal(got, whole[idx], equal_nan=True)
    if isinstance(proj, (Fisheye, AngularMap)):
        assert got[0] == 0.0 and np.any(got > 0.0)  # a corner lies outside the disc


def test_adapting_luminance_once_per_picture_not_kept():
    """save() and to_srgb() compute the adapting luminance once for the exposure and the
    chroma gain; it is not kept: a changed image gets its own."""
    proj = Fisheye(32)
    d, m = proj.directions()
    data = np.zeros((32, 32, 3))
    data[..., 1] = np.where(m, 1000.0 + 500.0 * d[..., 2], 0.0)
    data[..., 0] = 0.95 * data[..., 1]
    data[..., 2] = 1.05 * data[..., 1]
    img = SkyImage(data, "xyz", None, m, proj, {})
    la = img.adapting_luminance()
    # [Rei02] eq. 1 over the sky pixels above the horizon, written out here
    Y = data[..., 1][m & (d[..., 2] > 0.0)]
    assert la == pytest.approx(float(np.exp(np.mean(np.log(1e-6 + Y)))), rel=1e-12)
    a = img.to_srgb()
    assert np.array_equal(a, img._display(0.18 / la, "hue-preserving", img.chroma_gain(True)))
    assert not hasattr(img, "_held_adapting")
    img.data[..., :] *= 4.0
    assert img.adapting_luminance() == pytest.approx(4.0 * la, rel=1e-3)
    assert img.auto_exposure() == pytest.approx(0.18 / img.adapting_luminance(), rel=1e-15)


def test_png_exposure_is_the_key_over_the_adapting_luminance(tmp_path):
    proj = Fisheye(24)
    d, m = proj.directions()
    data = np.where(m[..., None], 2000.0 * (0.5 + d[..., 2:3]) * [0.9, 1.0, 1.1], 0.0)
    img = SkyImage(data, "xyz", None, m, proj, {})
    out = img.save(tmp_path / "a.png")
    from PIL import Image

    info = Image.open(out).text
    assert float(info["exposure_m2_per_cd"]) == pytest.approx(0.18 / img.adapting_luminance(),
                                                              rel=1e-12)


def test_numba_started_without_blas_still_compiles_dot():
    """After start_numba_without_blas, SciPy's linalg is not imported, and a kernel using
    np.dot (BLAS through SciPy) compiles and gives numpy's product."""
    code = (
        "import sys, json, numpy as np\n"
        "from skydome._numba_start import start_numba_without_blas\n"
        "first = start_numba_without_blas()\n"
        "linalg = 'scipy.linalg' in sys.modules\n"
        "import numba\n"
        "@numba.njit\n"
        "def f(a, b):\n"
        "    return np.dot(a, b)\n"
        "a = np.arange(12.0).reshape(3, 4); b = np.arange(8.0).reshape(4, 2)\n"
        "print(json.dumps([first, linalg, start_numba_without_blas(),\n"
        "                  bool(np.array_equal(f(a, b), a @ b))]))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1]) == [True, False, False, True]
