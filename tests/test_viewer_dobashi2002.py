"""The viewer's dobashi2002 shader (light shafts over the synthetic mountain scene) against
the CPU effect :func:`skydome.effects.dobashi2002.apply_aerial_perspective`, in headless
Chromium (SwiftShader WebGL2).

The page marches the heightmap for the surface's distance, reads the [DYN02] tables and
tests the sun's visibility at the sampling planes; the reference is the CPU effect (float64
numpy) with the same tables (extent = the scene's march range, view cosines -1..1, the
server's sizes), the same heightmap and the distances the page found. PSNR on linear XYZ,
peak = the reference's largest value, floor 40 dB as for the sky models
(tests/test_viewer_shaders.py). The distances themselves are checked against
:func:`synthetic_mountains`' own march.
"""

from __future__ import annotations

import numpy as np
import pytest

from _viewer import browser_page, viewer_url  # noqa: F401 - fixtures
from test_viewer_shaders import PSNR_FLOOR_DB, psnr_db

W, H = 128, 72
CAMERA = [0.0, 2.0, 60.0]          # dobashi2002.DEFAULT_CAMERA: looking north, 2 deg up, 60 deg wide
FIGURES: dict[str, float] = {}


def _render(page, values, output):
    flat = page.evaluate("([v, w, h, o, c]) => window.skydomeViewer.renderFloat('dobashi2002', v, w, h, 0, "
                         "{camera: c, output: o})", [values, W, H, output, CAMERA])
    return np.asarray(flat, dtype=np.float64).reshape(H, W, 3)


def _cpu_parts(depth, elevation, azimuth, shafts=True):
    """(XYZ of the in-scattered light, XYZ of a white sunlit surface seen through the air)."""
    import skydome
    from skydome.effects import dobashi2002 as dy
    from skydome.spectra import spectrum_to_xyz
    from skydome.viewer.scene import Dobashi2002View as V

    sun = skydome.Sun(elevation_deg=elevation, azimuth_deg=azimuth)
    _, _, hm = dy.synthetic_mountains(8, 8, seed=0, sun=sun)
    atm = skydome.Atmosphere.earth(turbidity=2.5)
    wl = np.linspace(380.0, 780.0, V.N_WAVELENGTHS)
    _, T, L = dy.apply_aerial_perspective(
        np.zeros((H, W, wl.size)), depth, dy.DEFAULT_CAMERA, sun, atm, shafts=shafts, heightmap=hm,
        wavelengths_nm=wl, n_planes=48, n_distance=V.N_DISTANCE, n_angle=V.N_ANGLE,
        extent_m=1000.0 * 35.0 * dy.MARCH_RANGE, mu_range=(-1.0, 1.0), return_parts=True)
    ref = dy.reference_sunlight(atm, sun, dy.DEFAULT_CAMERA.altitude_m, wl)
    Tx = spectrum_to_xyz(T * ref / np.pi, wl)
    return spectrum_to_xyz(L, wl), np.where(np.isfinite(depth)[..., None], Tx, 0.0)


@pytest.mark.parametrize("elevation", [60.0, 20.0, 5.0])
def test_dobashi2002_shader_matches_cpu(browser_page, elevation):  # noqa: F811
    from skydome.effects.dobashi2002 import synthetic_mountains
    from skydome.sun import Sun

    page, messages = browser_page
    values = {"sun_elevation": elevation, "sun_azimuth": 135.0, "shafts": "true"}
    d = _render(page, values, 3)[..., 0]
    depth = np.where(d > 0.0, d, np.inf)
    # the page's march finds the CPU march's surface (same steps, float32)
    _, cpu_depth, _ = synthetic_mountains(W, H, sun=Sun(elevation_deg=elevation, azimuth_deg=135.0))
    assert np.mean(np.isfinite(depth) == np.isfinite(cpu_depth)) >= 0.99
    both = np.isfinite(depth) & np.isfinite(cpu_depth)
    assert 0.3 < both.mean() < 0.9                                   # terrain and sky in view
    assert np.mean(np.abs(depth[both] / cpu_depth[both] - 1.0) < 1e-3) >= 0.99
    L_ref, T_ref = _cpu_parts(depth, elevation, 135.0)
    L_gpu, T_gpu = _render(page, values, 1), _render(page, values, 2)
    assert np.max(L_ref) > 0 and np.max(T_ref) > 0
    for name, gpu, ref in (("in-scattering", L_gpu, L_ref), ("transmittance", T_gpu, T_ref)):
        value = psnr_db(gpu, ref)
        FIGURES[f"{name} sun {elevation:g}"] = value
        print(f"PSNR dobashi2002 {name} sun {elevation:g} deg: {value:.1f} dB")
        assert value >= PSNR_FLOOR_DB
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]]


def test_dobashi2002_shafts_visible(browser_page):  # noqa: F811
    """A low sun ahead of the camera (5 deg, azimuth 20 deg): the ridges' shadows cut the
    air, so with the shadow test the in-scattered light in the shadowed columns of air
    falls well below that without it, while in the lit ones it stays; and the shafts
    show in the picture (the composite differs)."""
    page, messages = browser_page
    base = {"sun_elevation": 5.0, "sun_azimuth": 20.0}
    on = _render(page, {**base, "shafts": "true"}, 1)[..., 1]
    off = _render(page, {**base, "shafts": "false"}, 1)[..., 1]
    air = off > 0.0
    ratio = on[air] / off[air]
    assert np.all(ratio <= 1.0 + 1e-4)                      # shadows only remove light
    assert np.mean(ratio < 0.5) > 0.1                       # shadowed columns
    assert np.mean(ratio > 0.8) > 0.005                     # lit ones (the camera is in a shadow)
    # along one image column, the shaft boundary: neighbouring rows in shadow and in light
    col = np.argmax(np.sum((on < 0.5 * off) & air, axis=0) * np.sum((on > 0.8 * off) & air, axis=0))
    assert np.any((on[:, col] < 0.5 * off[:, col]) & air[:, col])
    assert np.any((on[:, col] > 0.8 * off[:, col]) & air[:, col])
    img_on = _render(page, {**base, "shafts": "true"}, 0)[..., 1]
    img_off = _render(page, {**base, "shafts": "false"}, 0)[..., 1]
    assert np.mean(img_on[air]) < 0.9 * np.mean(img_off[air])
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]]
