"""The three.js module (src/skydome/export/integrations/threejs) drawing a fitted bake
(`skydome export luts --model fitted --format bin`) in real headless Chromium.

npm's three (vendored by scripts/_setup into .vendor/npm), the module, its example page and
the bake are served from a local static server on 127.0.0.1 (tests/_threejs.py); Chromium
(Debian's, SwiftShader WebGL2) renders the sky through three.js into a float render
target, read back as linear CIE XYZ (or linear sRGB) and compared with the CPU model,
``skydome.model("fitted", ...)`` at the same sun, built independently of the bake: its
``xyz()`` in the same directions (and ``xyz_to_linear_srgb`` of it for the RGB output: the
model has no RGB table of its own), and for the sun's disc ``skydome.render``'s drawing of
the model's ``sun_radiance`` (energy-true, limb-darkened: skydome.imaging.sun_disc).

PSNR on linear values, peak = the reference's largest value (tests/_viewer.py's psnr_db);
floor 40 dB (issue 29: the fitted model's GLSL evaluators against the CPU model).
"""

from __future__ import annotations

import io
import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import _glsl_fitted as G  # noqa: E402
from _threejs import missing, pinhole_dirs, static_server, wait, write_site  # noqa: E402
from _viewer import CHROMIUM, CHROMIUM_ARGS, psnr_db  # noqa: E402

PSNR_FLOOR_DB = 40.0
W, H = 128, 64
AZIMUTH = 135.0
PARAMS = {"aerosol_optical_depth": 0.2, "ground_albedo": 0.3, "observer_altitude_m": 1000.0}


def _cpu(elevation, azimuth=AZIMUTH, **kw):
    import skydome

    return skydome.model("fitted", sun=skydome.Sun(elevation_deg=elevation,
                                                   azimuth_deg=azimuth, **kw), **PARAMS)


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """(url, textures, desc, root): the pack, three and a fitted bake (written by the
    command) on a local static server."""
    why = missing()
    if why:
        pytest.skip(why)
    from typer.testing import CliRunner

    from skydome.cli import app

    root = tmp_path_factory.mktemp("threejs_fitted")
    args = ["export", "luts", "--model", "fitted", "--out", str(root / "luts"),
            "--format", "bin"]
    for k, v in PARAMS.items():
        args += [f"--{k.replace('_', '-')}", str(v)]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    # the model's defaults (AOD 0.1, albedo 0.1, on the ground) for the example page
    res = CliRunner().invoke(app, ["export", "luts", "--model", "fitted", "--out",
                                   str(root / "luts_default"), "--format", "bin"])
    assert res.exit_code == 0, res.output
    write_site(root)
    desc = json.loads((root / "luts" / "luts.json").read_text())
    tex = {n: np.fromfile(root / "luts" / f"{n}.bin", dtype="<f4").astype(np.float64)
           .reshape(desc["textures"][n]["shape"]) for n in ("sky", "sun")}
    with static_server(root) as url:
        yield url, tex, desc, root


@pytest.fixture(scope="module")
def browser(served):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture(scope="module")
def harness(served, browser):
    page = browser.new_page(viewport={"width": 320, "height": 200})
    messages = []
    page.on("console", lambda m: messages.append((m.type, m.text)))
    page.on("pageerror", lambda e: messages.append(("pageerror", str(e))))
    page.goto(f"{served[0]}/threejs/harness.html")
    wait(page, "window.harness")
    yield page, messages
    assert not [m for m in messages if m[0] in ("error", "pageerror")], messages
    page.close()


def _equirect(page, sky, output="xyz"):
    out = page.evaluate("([e, a, w, h, s, o]) => window.harness.equirect(e, a, w, h, s, o)",
                        [float(sky.sun.elevation_deg), AZIMUTH, W, H,
                         sky.sun.irradiance_scale, output])
    return np.asarray(out, dtype=np.float64).reshape(H, W, 3)


def test_the_module_reads_the_fitted_bake(harness):
    """luts.json's format picks the fitted shader; the bake's sun range and altitude are
    enforced with errors that name the value and the range."""
    page, _ = harness
    assert page.evaluate("() => window.harness.sky.kind") == "fitted"
    assert "valid range -12..90 deg" in page.evaluate("() => window.harness.tryCall('low')")
    msg = page.evaluate("() => window.harness.tryCall('altitude')")
    assert msg.startswith("RangeError") and "1000 m" in msg, msg


@pytest.mark.parametrize("elevation", [60.0, 30.0, 12.5, 3.5, -0.5, -4.0, -9.5])
def test_equirect_against_the_cpu_model(served, harness, elevation):
    """The module's equirectangular render (full sphere 128 x 64, sky and ground, no disc)
    in XYZ against the CPU model's xyz() in the same directions (PSNR >= 40 dB), and
    against the shader's numpy transcription on the same textures (the GPU's float32)."""
    from skydome.imaging.projections import Equirect

    _, tex, desc, _ = served
    page, _ = harness
    sky = _cpu(elevation)
    gpu = _equirect(page, sky)
    d, _ = Equirect(W, H).directions()
    ref = np.asarray(sky.xyz(d), dtype=np.float64)
    s = np.asarray(sky.sun.direction, dtype=np.float64)
    tr = G.fitted_sky(tex["sky"], G.struct_from_desc(desc), d, s) * sky.sun.irradiance_scale
    p_model, p_tr = psnr_db(gpu, ref), psnr_db(gpu, tr)
    print(f"three.js fitted equirect sun {elevation:g} deg: PSNR {p_model:.1f} dB against "
          f"the CPU model's xyz(), {p_tr:.1f} dB against the transcription")
    assert np.isfinite(gpu).all() and gpu.min() >= 0.0
    assert p_tr >= PSNR_FLOOR_DB
    assert p_model >= PSNR_FLOOR_DB


@pytest.mark.parametrize("elevation", [30.0, -4.0])
def test_equirect_rgb_against_the_cpu_model(harness, elevation):
    """The module's linear sRGB output against the CPU model's xyz() through
    skydome.spectra.xyz_to_linear_srgb (PSNR >= 40 dB, peak = the largest |RGB|)."""
    from skydome.imaging.projections import Equirect
    from skydome.spectra import xyz_to_linear_srgb

    page, _ = harness
    sky = _cpu(elevation)
    gpu = _equirect(page, sky, "rgb")
    d, _ = Equirect(W, H).directions()
    ref = xyz_to_linear_srgb(np.asarray(sky.xyz(d), dtype=np.float64))
    p = psnr_db(gpu, ref)
    print(f"three.js fitted equirect RGB sun {elevation:g} deg: PSNR {p:.1f} dB against "
          "xyz_to_linear_srgb(xyz())")
    assert p >= PSNR_FLOOR_DB


@pytest.mark.parametrize("elevation", [20.0, -4.0])
def test_pinhole_view_against_the_cpu_model(harness, elevation):
    """The sky mesh through a three.js PerspectiveCamera (128 x 64, 90 deg vertical field
    of view, looking 10 deg below the horizon towards the sun's azimuth, sky and ground,
    no disc) against xyz() in the same directions (PSNR >= 40 dB)."""
    page, _ = harness
    sky = _cpu(elevation)
    a = np.radians(AZIMUTH)
    look = [float(np.sin(a)), float(np.tan(np.radians(-10.0))), float(-np.cos(a))]
    res = page.evaluate("([e, a, w, h, f, l, s]) => window.harness.pinhole(e, a, w, h, f, l, s, "
                        "false)", [elevation, AZIMUTH, W, H, 90.0, look,
                                   sky.sun.irradiance_scale])
    gpu = np.asarray(res["pixels"], dtype=np.float64).reshape(H, W, 3)
    d = pinhole_dirs(res["matrixWorld"], W, H, 90.0)
    assert (d[..., 2] < 0).any() and (d[..., 2] > 0).any()       # ground and sky in view
    ref = np.asarray(sky.xyz(d.reshape(-1, 3)), dtype=np.float64).reshape(H, W, 3)
    p = psnr_db(gpu, ref)
    print(f"three.js fitted pinhole sun {elevation:g} deg: PSNR {p:.1f} dB against xyz()")
    assert p >= PSNR_FLOOR_DB


@pytest.mark.parametrize("elevation", [30.0, 4.0])
def test_sun_disc_against_the_cpu_render(harness, elevation):
    """Looking at the sun (three.js camera, 2 deg field of view, 128 x 128: the disc 17
    pixels in radius): the disc's flux, sum over pixels of (L with the disc - L without)
    x the pixel's solid angle, against skydome.render's drawing of the CPU model into the
    same pixels (skydome.Camera, the same view; its energy-true, limb-darkened disc,
    skydome.imaging.sun_disc) within 1 % in X, Y and Z, and both against the model's own
    (sun_radiance in XYZ - the sky) x the disc's solid angle within 1 %; the profile:
    pixels whose centre lies within 0.9 of the disc's radius follow [Nec05]'s law
    (skydome.imaging.sun_disc, as skydome.render applies it) times the model's sun within
    1 %, and rings of pixels 2 wide the CPU render's within 1 %."""
    import skydome
    from skydome.camera import Camera
    from skydome.spectra import default_wavelengths, spectrum_to_xyz

    page, _ = harness
    sky = _cpu(elevation)
    s = np.asarray(sky.sun.direction)
    look = [float(s[0]), float(s[2]), float(-s[1])]
    n, fov = 128, 2.0
    shots = {}
    for disc in (True, False):
        res = page.evaluate("([e, a, w, h, f, l, sc, dd]) => window.harness.pinhole(e, a, w, h, "
                            "f, l, sc, dd)", [elevation, AZIMUTH, n, n, fov, look,
                                              sky.sun.irradiance_scale, disc])
        shots[disc] = np.asarray(res["pixels"], dtype=np.float64).reshape(n, n, 3)
    cam = Camera(n, n, fov, azimuth_deg=AZIMUTH, elevation_deg=elevation, altitude_m=0.0)
    d = pinhole_dirs(res["matrixWorld"], n, n, fov)
    dc, _ = cam.directions()
    assert np.max(np.abs(d - dc)) < 1e-6                   # the same pixels
    omega = np.asarray(cam.solid_angles(), dtype=np.float64)[..., None]
    # the render on xyz()'s wavelength grid (its own default, 16 wavelengths, sums the
    # colour 1 % differently in Z)
    wl = default_wavelengths()
    cpu = {disc: np.asarray(skydome.render(sky, cam, wl, draw_sun=disc, output="xyz").data,
                            dtype=np.float64) for disc in (True, False)}
    flux_gpu = np.sum((shots[True] - shots[False]) * omega, axis=(0, 1))
    flux_cpu = np.sum((cpu[True] - cpu[False]) * omega, axis=(0, 1))
    sun_xyz = spectrum_to_xyz(sky.sun_radiance(wl), wl)
    model = (sun_xyz - np.asarray(sky.xyz(s))) * sky.sun.solid_angle_sr
    print(f"three.js fitted sun disc, sun {elevation:g} deg: flux / CPU render - 1 = "
          f"{np.array2string(flux_gpu / flux_cpu - 1, precision=5)}, / model - 1 = "
          f"{np.array2string(flux_gpu / model - 1, precision=5)} (XYZ)")
    np.testing.assert_allclose(flux_gpu, flux_cpu, rtol=0.01)
    np.testing.assert_allclose(flux_gpu, model, rtol=0.01)
    np.testing.assert_allclose(flux_cpu, model, rtol=0.01)
    # the profile: the limb-darkening law skydome.render draws with, at the pixels' centres
    from skydome.imaging import sun_disc as sd

    r = np.radians(sky.sun.angular_radius_deg)
    ang = np.arccos(np.clip(d @ s, -1.0, 1.0))
    inside = ang < 0.9 * r
    ch = np.asarray(sd.XYZ_CHANNEL_WAVELENGTHS_NM)
    mu = np.sqrt(np.clip(1.0 - (np.sin(ang[inside]) / np.sin(r)) ** 2, 0.0, 1.0))
    law = sun_xyz * sd.limb_darkening(mu, ch) / sd.limb_darkening_mean(ch)
    rel = np.abs(shots[True][inside] / law - 1.0)
    # and against the CPU render's pixels, averaged over rings 2 pixels wide (a pixel of
    # the render holds its ring samples: about 3 % sampling noise per pixel at this size)
    ring = np.floor(ang / (2.0 * np.radians(fov) / n)).astype(int)
    worst = 0.0
    for k in range(int(ring[ang < 0.9 * r].max()) + 1):
        m = (ring == k) & (ang < 0.9 * r)
        worst = max(worst, float(np.max(np.abs(shots[True][m].mean(axis=0)
                                                / cpu[True][m].mean(axis=0) - 1.0))))
    centre = shots[True][inside][np.argmin(ang[inside])]
    limb = shots[True][inside][np.argmax(ang[inside])]
    print(f"three.js fitted sun disc: {inside.sum()} pixels within 0.9 radius, max "
          f"|GPU / law - 1| {rel.max():.2e}; rings within 0.9 radius, max |GPU / CPU render "
          f"- 1| {worst:.2e}; Y at {np.degrees(ang[inside].max()) / sky.sun.angular_radius_deg:.2f}"
          f" radius / centre {limb[1] / centre[1]:.3f}")
    assert rel.max() <= 0.01
    assert worst <= 0.01
    assert limb[1] < 0.8 * centre[1]                        # darker towards the limb


@pytest.mark.parametrize("n, fov", [(256, 30.0), (128, 60.0)])
def test_small_sun_disc_flux(harness, n, fov):
    """The disc a few pixels wide (256 x 256, 30 deg: 2.3 pixels in radius) and smaller
    than a pixel (128 x 128, 60 deg: 0.57 of a pixel), sun 30 deg: the module spreads it
    over the pixels' footprints, so its flux (the image with the disc minus without,
    times the pixels' solid angles) is the CPU model's (sun_radiance - sky) x Omega_sun
    and skydome.render's in the same pixels within 1 % in X, Y and Z."""
    import skydome
    from skydome.camera import Camera
    from skydome.spectra import default_wavelengths, spectrum_to_xyz

    page, _ = harness
    elevation = 30.0
    sky = _cpu(elevation)
    s = np.asarray(sky.sun.direction)
    look = [float(s[0]), float(s[2]), float(-s[1])]
    shots = {}
    for disc in (True, False):
        res = page.evaluate("([e, a, w, h, f, l, sc, dd]) => window.harness.pinhole(e, a, w, h, "
                            "f, l, sc, dd)", [elevation, AZIMUTH, n, n, fov, look,
                                              sky.sun.irradiance_scale, disc])
        shots[disc] = np.asarray(res["pixels"], dtype=np.float64).reshape(n, n, 3)
    cam = Camera(n, n, fov, azimuth_deg=AZIMUTH, elevation_deg=elevation, altitude_m=0.0)
    omega = np.asarray(cam.solid_angles(), dtype=np.float64)[..., None]
    wl = default_wavelengths()
    cpu = {disc: np.asarray(skydome.render(sky, cam, wl, draw_sun=disc, output="xyz").data,
                            dtype=np.float64) for disc in (True, False)}
    flux_gpu = np.sum((shots[True] - shots[False]) * omega, axis=(0, 1))
    flux_cpu = np.sum((cpu[True] - cpu[False]) * omega, axis=(0, 1))
    model = (spectrum_to_xyz(sky.sun_radiance(wl), wl) - np.asarray(sky.xyz(s))) \
        * sky.sun.solid_angle_sr
    lit = int(np.sum(shots[True][..., 1] != shots[False][..., 1]))
    print(f"three.js fitted sun disc, {n} px over {fov:g} deg ({lit} pixels touched): flux / "
          f"model - 1 = {np.array2string(flux_gpu / model - 1, precision=5)}, / CPU render "
          f"- 1 = {np.array2string(flux_gpu / flux_cpu - 1, precision=5)} (XYZ)")
    np.testing.assert_allclose(flux_gpu, model, rtol=0.01)
    np.testing.assert_allclose(flux_gpu, flux_cpu, rtol=0.01)


def _screenshot(browser, url, root, values, name):
    from PIL import Image

    page = browser.new_page(viewport={"width": 960, "height": 540})
    messages = []
    page.on("console", lambda m: messages.append((m.type, m.text)))
    page.on("pageerror", lambda e: messages.append(("pageerror", str(e))))
    page.goto(f"{url}/threejs/example.html?luts=../luts_default/")
    wait(page, "window.skydomeExample")
    for key, value in values:
        page.fill(key, value)
        page.dispatch_event(key, "input")
    status = page.inner_text("#status")
    png = page.screenshot()
    (root / name).write_bytes(png)
    out = os.environ.get("SKYDOME_SCREENSHOT_DIR")
    if out:
        Path(out, name).write_bytes(png)
    assert not [m for m in messages if m[0] in ("error", "pageerror")], messages
    page.close()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float64), status


def _saturation(rgb):
    return (rgb.max() - rgb.min()) / max(rgb.max(), 1e-9)


def _bands(img, top, bottom):
    """Mean RGB of 10-row bands from row top to bottom, over the middle columns."""
    return np.array([img[r:r + 10, 300:900].mean(axis=(0, 1)) for r in range(top, bottom, 10)])


# The example's view: 960 x 540, 70 deg vertical field of view, 20 deg above the horizon:
# the horizon at row 270 + 270 tan 20 deg / tan 35 deg = 410, the top row about 55 deg up.

def test_example_page_day(served, browser):
    """example.html on a fitted bake (the model's defaults), sun 30 deg, azimuth 180,
    EV100 14, camera towards the sun: a deep blue sky high up, whitening (brighter, less
    saturated) down to the horizon, the dark ground below."""
    url, _, _, root = served
    img, status = _screenshot(browser, url, root, (("#elevation", "30"), ("#azimuth", "180"),
                                                   ("#view", "0"), ("#ev", "14")),
                              "threejs-fitted-sun30.png")
    assert status.startswith("fitted bake"), status
    high = img[10:60, 40:200].mean(axis=(0, 1))            # about 50 deg up, 30 deg aside
    low = img[390:405, 300:900].mean(axis=(0, 1))          # just above the horizon
    ground = img[440:540].mean(axis=(0, 1))
    print(f"example, sun 30 deg: high {high.round()}, low {low.round()}, "
          f"ground {ground.round()}")
    assert high[2] > high[0] + 40 and high[2] > high[1], high            # blue
    assert low.mean() > high.mean() + 60 and _saturation(low) < 0.5 * _saturation(high)
    assert ground.mean() < 0.5 * low.mean(), (low, ground)


def test_example_page_twilight_towards_the_sun(served, browser):
    """Sun -4 deg (civil twilight), EV100 6, camera towards the sun's azimuth: blue high
    up, the sky whitening downwards and a warm (red above blue) band on the horizon."""
    url, _, _, root = served
    img, _ = _screenshot(browser, url, root, (("#elevation", "-4"), ("#azimuth", "180"),
                                              ("#view", "0"), ("#ev", "6")),
                         "threejs-fitted-sun-4.png")
    bands = _bands(img, 10, 410)
    warm = bands[:, 0] - bands[:, 2]
    k = int(np.argmax(warm))
    print(f"example, sun -4 deg towards the sun: top {bands[0].round()}, warmest band row "
          f"{10 + 10 * k} {bands[k].round()}")
    assert bands[0, 2] > bands[0, 0] + 50, bands[0]                       # blue high up
    assert 10 + 10 * k >= 340 and warm[k] > 20, (k, bands[k])            # warm horizon


def test_example_page_twilight_belt(served, browser):
    """Sun -2 deg, EV100 8, camera turned away from the sun: over the earth's bluish
    shadow on the horizon a pinker band (red as high as green, red minus blue far above
    the blue sky's higher up): the Belt of Venus."""
    url, _, _, root = served
    img, _ = _screenshot(browser, url, root, (("#elevation", "-2"), ("#azimuth", "180"),
                                              ("#view", "180"), ("#ev", "8")),
                         "threejs-fitted-sun-2-antisolar.png")
    bands = _bands(img, 10, 410)
    warm = bands[:, 0] - bands[:, 2]
    k = int(np.argmax(warm))
    print(f"example, sun -2 deg away from the sun: top {bands[0].round()}, belt row "
          f"{10 + 10 * k} {bands[k].round()}, shadow {bands[-1].round()}")
    assert 280 <= 10 + 10 * k <= 380, k
    assert bands[k, 0] >= bands[k, 1] - 2, bands[k]
    assert warm[k] > warm[0] + 30 and warm[k] > warm[-1] + 15, (bands[0], bands[k], bands[-1])
