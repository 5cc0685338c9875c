"""The three.js module (src/skydome/export/integrations/threejs) in real headless Chromium.

npm's three (vendored by scripts/_setup into .vendor/npm, never fetched at run time), the
module, its example page and a precomputed bake (`write_luts(..., ("bin",))`) are served
from a local static server on 127.0.0.1; Chromium (Debian's, SwiftShader WebGL2, the
launch settings of tests/_viewer.py) renders the sky through three.js into a float render
target, read back as linear CIE XYZ and compared with two CPU references:

* the model: ``skydome.render`` of the same precomputed sky (equirectangular 128 x 64,
  ``output="xyz"``, no sun disc) and ``sky.xyz`` in the pinhole camera's directions;
* the shader's numpy transcription (tests/_glsl_precomputed.py) on the same textures, the
  fair reference for a renderer that reads the stored tables (the model's ``radiance()``
  integrates orders 2..N at the observer, the tables interpolate them:
  tests/test_export_precomputed_luts.py).

PSNR on linear XYZ, peak = the reference's largest value (tests/test_viewer_shaders.py's
measure); floor 40 dB (issue 28; Bruneton's GPU-vs-CPU tests give 35-47 dB).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import _glsl_precomputed as G  # noqa: E402
from _threejs import ROOT, missing, pinhole_dirs, static_server, wait, write_site  # noqa: E402
from _viewer import CHROMIUM, CHROMIUM_ARGS, psnr_db  # noqa: E402

PSNR_FLOOR_DB = 40.0
W, H = 128, 64
AZIMUTH = 135.0
FIGURES: dict[str, float] = {}


def test_psnr_self_check():
    ref = np.linspace(0.0, 1.0, 100)
    assert psnr_db(ref + 0.01, ref) == pytest.approx(40.0)


def test_write_threejs_ships_the_one_shader(tmp_path):
    """The pack holds the module, the example and byte copies of export/glsl's shaders
    (precomputed.glsl and fitted.glsl)."""
    from skydome.export.integrations.threejs import write_threejs

    paths = write_threejs(tmp_path / "pack")
    assert sorted(p.name for p in paths) == ["example.html", "fitted.glsl", "precomputed.glsl",
                                             "skydome-sky.js"]
    glsl = ROOT / "src/skydome/export/glsl/precomputed.glsl"
    assert (tmp_path / "pack/precomputed.glsl").read_bytes() == glsl.read_bytes()
    fitted = ROOT / "src/skydome/export/glsl/fitted.glsl"
    assert (tmp_path / "pack/fitted.glsl").read_bytes() == fitted.read_bytes()
    js = (tmp_path / "pack/skydome-sky.js").read_text()
    # the module carries none of the shader's functions itself: it runs the fetched file
    assert "skydomeScatteringUvwz" not in js and "skydomeFittedAxis" not in js
    assert "from 'three'" in js
    with pytest.raises(ValueError, match="out"):
        write_threejs(tmp_path / "pack/skydome-sky.js")


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """(url, sky, textures, desc): the pack, three and a bake of the default precomputed
    sky on a local static server."""
    why = missing()
    if why:
        pytest.skip(why)
    import skydome
    from skydome.export.luts import bake_precomputed, write_luts

    root = tmp_path_factory.mktemp("threejs")
    sky = skydome.model("precomputed", sun=skydome.Sun(elevation_deg=20.0,
                                                       azimuth_deg=AZIMUTH))
    write_luts(sky, root / "luts", ("bin",), density=False)   # the module reads tables only
    write_site(root)
    tex, desc = bake_precomputed(sky)
    assert json.loads((root / "luts" / "luts.json").read_text())["sizes"] == desc["sizes"]
    with static_server(root) as url:
        yield (url, sky, {k: v.astype(np.float64) for k, v in tex.items()}, desc, root)


@pytest.fixture(scope="module")
def browser(served):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture(scope="module")
def harness(served, browser):
    url = served[0]
    page = browser.new_page(viewport={"width": 320, "height": 200})
    messages = []
    page.on("console", lambda m: messages.append((m.type, m.text)))
    page.on("pageerror", lambda e: messages.append(("pageerror", str(e))))
    page.goto(f"{url}/threejs/harness.html")
    wait(page, "window.harness")
    yield page, messages
    assert not [m for m in messages if m[0] in ("error", "pageerror")], messages
    page.close()


def _transcription(served, sky, d):
    """The shader's numpy transcription in directions d (ENU), for sky's sun and scale."""
    _, _, tex, desc, _ = served
    cam = np.array([0.0, 0.0, desc["bottom_radius_m"] + sky.observer_altitude_m])
    flat = d.reshape(-1, 3)
    out = G.radiance(tex["scattering"], tex["single_mie_scattering"],
                     tex["multiple_scattering"], tex["transmittance"], tex["optical_depth"],
                     tex["irradiance_spectral"], G.atmosphere_from_desc(desc), cam, flat,
                     np.asarray(sky.sun.direction))
    return out.reshape(d.shape[:-1] + (3,)) * sky.sun.irradiance_scale


@pytest.mark.parametrize("elevation", [60.0, 20.0, 5.0, -4.0])
def test_equirect_against_the_cpu_render(served, harness, elevation):
    """The module's equirectangular render (full sphere 128 x 64, sky and ground, no sun
    disc) against skydome.render of the same model (PSNR >= 40 dB) and against the shader's
    numpy transcription on the same textures (the GPU's float32 and filtering only)."""
    import skydome
    from skydome.imaging.projections import Equirect

    page, _ = harness
    sky = served[1].with_sun(skydome.Sun(elevation_deg=elevation, azimuth_deg=AZIMUTH))
    gpu = np.asarray(page.evaluate("([e, a, w, h, s]) => window.harness.equirect(e, a, w, h, s)",
                                   [elevation, AZIMUTH, W, H, sky.sun.irradiance_scale]),
                     dtype=np.float64).reshape(H, W, 3)
    proj = Equirect(W, H)
    img = skydome.render(sky, proj, draw_sun=False, output="xyz")
    ref = np.asarray(img.data, dtype=np.float64)
    d, _ = proj.directions()
    tr = _transcription(served, sky, d)
    p_model = psnr_db(gpu, ref)
    p_tr = psnr_db(gpu, tr)
    FIGURES[f"equirect {elevation:g}"] = p_model
    print(f"three.js equirect sun {elevation:g} deg: PSNR {p_model:.1f} dB against "
          f"skydome.render, {p_tr:.1f} dB against the transcription")
    assert np.isfinite(gpu).all() and gpu.min() >= 0.0
    assert p_tr >= PSNR_FLOOR_DB
    assert p_model >= PSNR_FLOOR_DB


@pytest.mark.parametrize("elevation", [20.0, 5.0])
def test_pinhole_view_against_the_model(served, harness, elevation):
    """The sky mesh through a three.js PerspectiveCamera (128 x 64, 90 deg vertical field
    of view, looking 10 deg below the horizon towards the sun's azimuth, sky and ground,
    no disc) against sky.xyz in the same directions (PSNR >= 40 dB)."""
    import skydome

    page, _ = harness
    sky = served[1].with_sun(skydome.Sun(elevation_deg=elevation, azimuth_deg=AZIMUTH))
    a = np.radians(AZIMUTH)
    look = [float(np.sin(a)), float(np.tan(np.radians(-10.0))), float(-np.cos(a))]
    res = page.evaluate("([e, a, w, h, f, l, s]) => window.harness.pinhole(e, a, w, h, f, l, s, "
                        "false)", [elevation, AZIMUTH, W, H, 90.0, look,
                                   sky.sun.irradiance_scale])
    gpu = np.asarray(res["pixels"], dtype=np.float64).reshape(H, W, 3)
    d = pinhole_dirs(res["matrixWorld"], W, H, 90.0)
    assert (d[..., 2] < 0).any() and (d[..., 2] > 0).any()       # ground and sky in view
    ref = np.asarray(sky.xyz(d.reshape(-1, 3)), dtype=np.float64).reshape(H, W, 3)
    tr = _transcription(served, sky, d)
    p_model = psnr_db(gpu, ref)
    p_tr = psnr_db(gpu, tr)
    FIGURES[f"pinhole {elevation:g}"] = p_model
    print(f"three.js pinhole sun {elevation:g} deg: PSNR {p_model:.1f} dB against sky.xyz, "
          f"{p_tr:.1f} dB against the transcription")
    assert p_tr >= PSNR_FLOOR_DB
    assert p_model >= PSNR_FLOOR_DB


def test_sun_disc(served, harness):
    """Looking at the sun (2 deg field of view, 64 x 64): pixels whose centre lies inside
    the disc's 0.8 radius show the sky plus the model's sun_radiance reduced to XYZ
    (uniform disc) within 1 % in Y; the disc covers the geometric number of pixels (of
    its angular radius) within 5 %; outside it the sky alone."""
    import skydome
    from skydome.spectra import default_wavelengths, spectrum_to_xyz

    page, _ = harness
    elevation = 20.0
    sky = served[1].with_sun(skydome.Sun(elevation_deg=elevation, azimuth_deg=AZIMUTH))
    s = np.asarray(sky.sun.direction)
    look = [float(s[0]), float(s[2]), float(-s[1])]
    n, fov = 64, 2.0
    res = page.evaluate("([e, a, w, h, f, l, s]) => window.harness.pinhole(e, a, w, h, f, l, s, "
                        "true)", [elevation, AZIMUTH, n, n, fov, look, sky.sun.irradiance_scale])
    gpu = np.asarray(res["pixels"], dtype=np.float64).reshape(n, n, 3)
    d = pinhole_dirs(res["matrixWorld"], n, n, fov)
    ang = np.degrees(np.arccos(np.clip(d @ s, -1.0, 1.0)))
    r = sky.sun.angular_radius_deg
    sky_xyz = np.asarray(sky.xyz(d.reshape(-1, 3)), dtype=np.float64).reshape(n, n, 3)
    wl = default_wavelengths()
    sun_xyz = spectrum_to_xyz(sky.sun_radiance(wl), wl)
    inside = ang < 0.8 * r
    outside = ang > 1.2 * r
    print(f"three.js sun disc, sun 20 deg: inside/model - 1 = max "
          f"{np.abs(gpu[inside][:, 1] / (sky_xyz[inside] + sun_xyz)[:, 1] - 1).max():.2e}, "
          f"{inside.sum()} pixels inside")
    np.testing.assert_allclose(gpu[inside][:, 1], (sky_xyz[inside] + sun_xyz)[:, 1], rtol=0.01)
    np.testing.assert_allclose(gpu[outside][:, 1], sky_xyz[outside][:, 1], rtol=0.05)
    pix = np.radians(fov) / n                              # rad per pixel at the centre
    geometric = np.pi * np.radians(r) ** 2 / pix ** 2
    lit = gpu[..., 1] > 10.0 * sky_xyz[..., 1].max()
    print(f"three.js sun disc: {lit.sum()} pixels lit, {geometric:.1f} geometric")
    assert abs(lit.sum() / geometric - 1.0) < 0.05, (lit.sum(), geometric)


def test_example_page(served, browser):
    """example.html loads the bake and draws (sun 12 deg, azimuth 180, EV100 15, camera
    20 deg above the horizon towards the sun, 70 deg field of view): blue high up, bright
    low towards the sun, the dark ground below, the sun's disc white where it projects;
    the screenshot goes to the test's folder (and SKYDOME_SCREENSHOT_DIR if set)."""
    import io

    from PIL import Image

    url, _, _, _, root = served
    page = browser.new_page(viewport={"width": 960, "height": 540})
    messages = []
    page.on("console", lambda m: messages.append((m.type, m.text)))
    page.on("pageerror", lambda e: messages.append(("pageerror", str(e))))
    page.goto(f"{url}/threejs/example.html")
    wait(page, "window.skydomeExample")
    for key, value in (("#elevation", "12"), ("#azimuth", "180"), ("#ev", "15")):
        page.fill(key, value)
        page.dispatch_event(key, "input")
    png = page.screenshot()
    (root / "example.png").write_bytes(png)
    out = os.environ.get("SKYDOME_SCREENSHOT_DIR")
    if out:
        Path(out, "threejs-example.png").write_bytes(png)
    assert not [m for m in messages if m[0] in ("error", "pageerror")], messages
    page.close()
    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float64)
    high = img[20:80, 800:950].mean(axis=(0, 1))          # about 50 deg up, 30 deg aside
    low = img[385:405, 600:900].mean(axis=(0, 1))         # just above the horizon
    ground = img[450:540].mean(axis=(0, 1))
    assert high[2] > high[0] + 25 and high[2] > high[1], high          # blue
    assert low.mean() > 2.0 * high.mean() and ground.mean() < 0.25 * low.mean(), (low, ground)
    # the sun: 8 deg below the view's centre, row 270 + 270 tan 8 deg / tan 35 deg = 324
    disc = img[319:330, 475:486]
    assert (disc.min(axis=-1) >= 254).sum() >= 4, disc.min(axis=-1)
    assert img[324, 460, 2] < 240                          # its surroundings are not white
