"""The fitted model's bake for engines (``skydome export luts --model fitted``) and its GLSL
evaluator (src/skydome/export/glsl/fitted.glsl).

The GLSL is transcribed line by line into numpy (tests/_glsl_fitted.py, texelFetch
emulated by indexing the bake's arrays); the transcription over the baked textures is held
against the CPU model, ``skydome.model("fitted", ...)``'s ``xyz()`` (its numba kernel on
its own table) and ``sun_radiance`` in the same directions and at the same sun, built
independently of the bake: exact (to float32) at the bake's elevation slices, and at
elevations halfway between them (where the shader interpolates between slices) within the
viewer's PSNR floor of 40 dB (tests/test_viewer_shaders.py). The GLSL itself compiles with
the Khronos reference compiler as GLSL ES 3.00 and GLSL 3.30, and runs in WebGL2 (headless
Chromium, SwiftShader) against the CPU model.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import _glsl_fitted as glsl
from _viewer import psnr_db

GLSL = Path(__file__).parents[1] / "src/skydome/export/glsl/fitted.glsl"
PSNR_FLOOR_DB = 40.0
#: fitted.glsl in Chromium (float32) against its numpy transcription (float64) on the same
#: layers: 104-113 dB measured (2026-12); the lookup's earlier bilinear weights in the
#: shader, with the transcription's Catmull-Rom rows, gave 73 dB (sun 45.5 deg): the floor
#: checks that the shader's arithmetic is the transcription's.
MIRROR_FLOOR_DB = 92.0
PARAMS = {"aerosol_optical_depth": 0.2, "ground_albedo": 0.3, "observer_altitude_m": 1000.0}
SUN_AZIMUTH_DEG = 135.0

MAIN = """
uniform sampler2DArray skyTex; uniform sampler2D sunTex; uniform SkydomeFitted fit;
uniform vec3 dir; uniform vec3 sunDir;
out vec4 colour;
void main() {
    vec3 s = skydomeFittedSky(skyTex, fit, dir, sunDir);
    vec3 m = skydomeFittedSunMeanRadiance(sunTex, fit, sunDir);
    vec3 w = skydomeFittedSkyWithSun(skyTex, sunTex, fit, dir, sunDir);
    vec3 disc = skydomeFittedSunDisc(sunTex, fit, dir, sunDir);
    vec3 px = skydomeFittedSkyWithSunPixel(skyTex, sunTex, fit, dir, dFdx(dir), dFdy(dir),
                                           sunDir);
    colour = vec4(s + m + w + disc + px, 1.0);
}
"""


@pytest.mark.skipif(not Path("/usr/bin/glslangValidator").exists(),
                    reason="glslangValidator (Debian glslang-tools, installed by "
                           "scripts/_setup) missing")
@pytest.mark.parametrize("version", ["#version 300 es\nprecision highp float;\n"
                                     "precision highp sampler2DArray;\n", "#version 330 core\n"])
def test_glsl_compiles(tmp_path, version):
    """The shader compiles as GLSL ES 3.00 (WebGL2) and GLSL 3.30 with the Khronos reference
    compiler, called from a fragment shader that uses every entry point."""
    src = tmp_path / "fitted.frag"
    src.write_text(version + GLSL.read_text() + MAIN)
    res = subprocess.run(["/usr/bin/glslangValidator", str(src)], capture_output=True,
                         text=True)
    assert res.returncode == 0, res.stdout + res.stderr


@pytest.fixture(scope="module")
def baked(tmp_path_factory):
    """The bake written by the command (its textures and luts.json)."""
    from typer.testing import CliRunner

    from skydome.cli import app

    out = tmp_path_factory.mktemp("fitted") / "luts"
    args = ["export", "luts", "--model", "fitted", "--out", str(out), "--format", "npy,bin"]
    for k, v in PARAMS.items():
        args += [f"--{k.replace('_', '-')}", str(v)]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    desc = json.loads((out / "luts.json").read_text())
    sky = np.load(out / "sky.npy").astype(np.float64)
    sun = np.load(out / "sun.npy").astype(np.float64)
    raw = np.fromfile(out / "sky.bin", dtype="<f4").reshape(desc["textures"]["sky"]["shape"])
    assert np.array_equal(raw, np.load(out / "sky.npy"))
    return desc, sky, sun


def _cpu(elevation):
    import skydome

    return skydome.model("fitted", sun=skydome.Sun(elevation_deg=elevation,
                                                   azimuth_deg=SUN_AZIMUTH_DEG), **PARAMS)


def _directions():
    from skydome.imaging.projections import Equirect

    d, _ = Equirect(128, 64).directions()          # the whole sphere: sky and ground
    return d


def _cpu_sun_xyz(sky):
    from skydome.constants import K_M
    from skydome.spectra import default_wavelengths, integration_weights

    wl = default_wavelengths()
    return np.asarray(sky.sun_radiance(wl)) @ (K_M * np.asarray(integration_weights(wl)))


def test_bake_describes_itself(baked):
    from skydome.models import get_model_class
    from skydome.models.fitted import _grid

    desc, sky, sun = baked
    e = desc["elevation_axis"]
    lo, hi = get_model_class("fitted").sun_elevation_range_deg
    assert e["first_deg"] == lo and e["first_deg"] + (e["count"] - 1) * e["step_deg"] == \
        pytest.approx(hi)
    assert e["step_deg"] <= 1.0
    assert sky.shape == (e["count"], _grid.N_SKY + _grid.N_GROUND, _grid.N_PHI, 4)
    se = desc["sun_elevation_axis"]
    assert se["first_deg"] == lo and se["first_deg"] + (se["count"] - 1) * se["step_deg"] == \
        pytest.approx(hi)
    assert sun.shape == (se["count"], 4)
    assert desc["model_parameters"] == PARAMS
    assert np.all(np.isfinite(sky)) and np.all(sky >= 0.0) and np.all(sun >= 0.0)


def test_transcription_exact_at_the_slices(baked):
    """At a slice's elevation the shader reads that slice alone: the CPU model's xyz()
    in every direction of the whole sphere to float32 (relative 1e-6 of the image's peak),
    and its sun_radiance (the visible fraction included) to 1e-6."""
    desc, sky, sun = baked
    f = glsl.struct_from_desc(desc)
    d = _directions()
    e = desc["elevation_axis"]
    for k in (0, 1, 3, 12, 47, e["count"] - 1):
        el = e["first_deg"] + k * e["step_deg"]
        cpu = _cpu(el)
        ref = np.asarray(cpu.xyz(d))
        s = np.asarray(cpu.sun.direction, dtype=np.float64)
        got = glsl.fitted_sky(sky, f, d, s) * cpu.sun.irradiance_scale
        assert np.max(np.abs(got - ref)) <= 1e-6 * np.max(ref), el
        sref = _cpu_sun_xyz(cpu)
        sgot = glsl.sun_mean_radiance(sun, f, s) * cpu.sun.irradiance_scale
        np.testing.assert_allclose(sgot, sref, rtol=1e-6, atol=1e-9 * max(sref.max(), 1.0))


def _off_step(desc):
    """Elevations halfway between slices over the whole range, and a few elsewhere
    between them (none on a slice)."""
    e = desc["elevation_axis"]
    first, step, n = e["first_deg"], e["step_deg"], e["count"]
    half = first + step * (np.arange(n - 1) + 0.5)
    other = first + step * (np.array([0, 2, 5, 9, 30, 70]) + 0.27)
    return np.concatenate([half, other])


def test_between_the_slices_against_the_cpu_model(baked):
    """At off-step elevations (every midpoint between slices, and a few others) the
    shader's geometric interpolation between slices against the CPU model at that
    elevation: PSNR >= 40 dB over the whole sphere, and >= 40 dB over the ground alone
    (its own peak)."""
    desc, sky, sun = baked
    f = glsl.struct_from_desc(desc)
    d = _directions()
    below = d[..., 2] < 0.0
    worst = (np.inf, None)
    worst_ground = (np.inf, None)
    for el in _off_step(desc):
        cpu = _cpu(float(el))
        ref = np.asarray(cpu.xyz(d))
        s = np.asarray(cpu.sun.direction, dtype=np.float64)
        got = glsl.fitted_sky(sky, f, d, s) * cpu.sun.irradiance_scale
        assert np.all(np.isfinite(got)) and np.all(got >= 0.0)
        p, pg = psnr_db(got, ref), psnr_db(got[below], ref[below])
        worst = min(worst, (p, float(el)))
        worst_ground = min(worst_ground, (pg, float(el)))
    print(f"fitted bake between slices ({desc['elevation_axis']['step_deg']:g} deg): worst "
          f"PSNR {worst[0]:.1f} dB at sun {worst[1]:g} deg, ground alone "
          f"{worst_ground[0]:.1f} dB at {worst_ground[1]:g} deg")
    assert worst[0] >= PSNR_FLOOR_DB, worst
    assert worst_ground[0] >= PSNR_FLOOR_DB, worst_ground


def test_sun_between_the_steps_against_the_cpu_model(baked):
    """The sun's mean disc radiance (visible fraction included) halfway between the sun
    texture's steps, densely near the horizon where the transmittance bends most, against the
    CPU model's sun_radiance in XYZ: within 0.5 % in X, Y and Z where Y is above 1e-4 of
    its value at 45 deg (below, the disc is all but set: within 1e-4 of that value)."""
    desc, sky, sun = baked
    f = glsl.struct_from_desc(desc)
    se = desc["sun_elevation_axis"]
    # ... and every fourth step from -2 to +3 deg: the disc through the horizon (at -1.0
    # deg) and the transmittance's steepest part above it
    ks = list(range(0, 60, 3)) + [100] + list(range(200, 300, 4)) + [400, se["count"] - 2]
    y45 = _cpu_sun_xyz(_cpu(45.0))[1]
    worst = (0.0, None)
    for k in ks:
        el = se["first_deg"] + (k + 0.5) * se["step_deg"]
        cpu = _cpu(el)
        s = np.asarray(cpu.sun.direction, dtype=np.float64)
        sref = _cpu_sun_xyz(cpu)
        sgot = glsl.sun_mean_radiance(sun, f, s) * cpu.sun.irradiance_scale
        if sref[1] > 1e-4 * y45:
            worst = max(worst, (float(np.max(np.abs(sgot / sref - 1.0))), el))
        else:
            assert np.all(np.abs(sgot - sref) <= 1e-4 * y45), (el, sgot, sref)
    print(f"fitted bake, sun between steps ({se['step_deg']:g} deg): max |d|/XYZ "
          f"{worst[0]:.2e} at {worst[1]:.2f} deg")
    assert worst[0] <= 0.005, worst


def _disc_grid(s, n=801):
    """Directions (n, n, 3) on a tangent-plane grid around the sun's direction s, 1.2
    disc radii across at most, and each one's solid angle [sr]."""
    from skydome.imaging.sun_disc import _tangent_frame

    e1, e2 = _tangent_frame(s)
    h = np.tan(np.radians(0.2666 * 1.25))
    x = np.linspace(-h, h, n)
    X, Y = np.meshgrid(x, x)
    v = s + X[..., None] * e1 + Y[..., None] * e2
    norm = np.linalg.norm(v, axis=-1)
    dx = x[1] - x[0]
    return v / norm[..., None], dx * dx / norm ** 3         # dOmega = dA cos / r^2


@pytest.mark.parametrize("elevation", [45.0, 5.0])
def test_sun_disc_flux_and_profile(baked, elevation):
    """skydomeFittedSunDisc (transcribed) over a fine grid around the sun: its integral
    equals the CPU model's sun_radiance in XYZ x the disc's solid angle within 1 % (the
    grid's own error: 0.01 %), and its profile is [Nec05]'s centre-to-limb law as
    skydome.imaging.sun_disc gives it at the X, Y, Z channels' wavelengths (600, 555,
    450 nm), the CPU renders' disc, within 1e-6; 0 outside the disc."""
    from skydome.imaging import sun_disc as sd

    desc, _, sun = baked
    f = glsl.struct_from_desc(desc)
    cpu = _cpu(elevation)
    s = np.asarray(cpu.sun.direction, dtype=np.float64)
    d, omega = _disc_grid(s)
    got = glsl.sun_disc(sun, f, d, s) * cpu.sun.irradiance_scale
    flux = np.sum(got * omega[..., None], axis=(0, 1))
    ref = _cpu_sun_xyz(cpu) * cpu.sun.solid_angle_sr
    print(f"fitted.glsl disc, sun {elevation:g} deg: flux / (sun_radiance Omega) - 1 = "
          f"{np.array2string(flux / ref - 1.0, precision=5)}")
    np.testing.assert_allclose(flux, ref, rtol=0.01)
    r = np.radians(cpu.sun.angular_radius_deg)
    ang = np.arccos(np.clip(d @ s, -1.0, 1.0))
    inside = ang < r
    ch = np.asarray(sd.XYZ_CHANNEL_WAVELENGTHS_NM)
    mu = np.sqrt(np.clip(1.0 - (np.sin(ang[inside]) / np.sin(r)) ** 2, 0.0, 1.0))
    law = _cpu_sun_xyz(cpu) * sd.limb_darkening(mu, ch) / sd.limb_darkening_mean(ch)
    np.testing.assert_allclose(got[inside], law, rtol=1e-6)
    assert np.all(got[~inside] == 0.0)


def test_sun_disc_at_the_horizon(baked):
    """The disc straddling the horizon (observer at 1 km: the horizon 1.0 deg below eye
    level), its centre 0.6 radii below it, on it and 0.5 radii above it:
    skydomeFittedSunDisc is the limb-darkened radiance of the transmitted sun above the
    horizon alone (skydomeFittedSkyWithSun the sky below it). Its integral equals that of
    [Nec05]'s law (skydome.imaging.sun_disc) over the visible part, scaled to the bake's
    transmitted sun at the disc's centre, within 1 %; against that sun x the visible
    fraction x the disc's solid angle (the model's sun_radiance counts the visible area as
    uniform), the same within 1 % with the horizon through the centre (by symmetry), and
    otherwise the difference the limb darkening makes (the rim that stays up is darker),
    printed. The bake's transmitted sun itself against the model's (the 0.05-deg layers
    across the transmittance's kink at the horizon, where it is below 1e-13 of the
    extraterrestrial sun here) is printed; tested where it matters in
    test_sun_between_the_steps_against_the_cpu_model."""
    from skydome.imaging import sun_disc as sd

    desc, sky, sun = baked
    f = glsl.struct_from_desc(desc)
    dip = np.degrees(f["thetaH"]) - 90.0
    ch = np.asarray(sd.XYZ_CHANNEL_WAVELENGTHS_NM)
    lines = []
    for u in (-0.6, 0.0, 0.5):
        el = -dip + u * 0.2666
        cpu = _cpu(el)
        s = np.asarray(cpu.sun.direction, dtype=np.float64)
        d, omega = _disc_grid(s)
        got = glsl.sun_disc(sun, f, d, s) * cpu.sun.irradiance_scale
        flux = np.sum(got * omega[..., None], axis=(0, 1))
        th = 0.5 * glsl.PI - np.arctan2(d[..., 2], np.hypot(d[..., 0], d[..., 1]))
        below = th >= f["thetaH"]
        assert np.any(below) and np.any(got[~below] > 0.0)
        assert np.all(got[below] == 0.0)                          # nothing below
        drawn = glsl.sky_with_sun(sky, sun, f, d, s)
        assert np.array_equal(drawn[below], glsl.fitted_sky(sky, f, d, s)[below])
        vis = cpu.sun_visible_fraction()
        # the bake's transmitted sun at the disc's centre (XYZ radiance, no visible fraction)
        trans = glsl.sun_radiance(sun, f, s) * cpu.sun.irradiance_scale
        cpu_trans = _cpu_sun_xyz(cpu) / vis
        r = np.radians(cpu.sun.angular_radius_deg)
        ang = np.arccos(np.clip(d @ s, -1.0, 1.0))
        up = (ang < r) & ~below
        mu = np.sqrt(np.clip(1.0 - (np.sin(ang[up]) / np.sin(r)) ** 2, 0.0, 1.0))
        law = np.sum(sd.limb_darkening(mu, ch) / sd.limb_darkening_mean(ch)
                     * omega[up][:, None], axis=0)
        ref = trans * law
        model = trans * vis * cpu.sun.solid_angle_sr
        np.testing.assert_allclose(flux, ref, rtol=0.01)
        if u == 0.0:
            np.testing.assert_allclose(flux, model, rtol=0.01)
        lines.append(f"centre {u:+.1f} radii from the horizon: visible area {vis:.3f}, "
                     f"flux / law - 1 = {flux[1] / ref[1] - 1:+.1e}, flux / (sun_radiance "
                     f"Omega) - 1 = {flux[1] / model[1] - 1:+.3f} (Y); bake's / model's "
                     f"transmitted sun {trans[1] / cpu_trans[1]:.3f} (Y)")
    print("fitted.glsl disc at the horizon:\n  " + "\n  ".join(lines))


def test_bad_input_refused_before_work(tmp_path):
    """A value outside the model's range: one line naming it, exit 2, nothing on disk."""
    from typer.testing import CliRunner

    from skydome.cli import app

    runner = CliRunner()
    for args, msg in ((["--aerosol-optical-depth", "2"], "--aerosol-optical-depth"),
                      (["--observer-altitude-m", "-5"], "--observer-altitude-m")):
        bad = tmp_path / "bad"
        res = runner.invoke(app, ["export", "luts", "--model", "fitted", *args,
                                  "--out", str(bad)])
        assert res.exit_code == 2, (args, res.output)
        assert msg in res.output, (args, res.output)
        assert not bad.exists()


_PAGE_JS = """
async ([frag, sky, sun, dims, f, sunDir, w, h]) => {
  const canvas = document.createElement("canvas");
  const gl = canvas.getContext("webgl2");
  if (!gl || !gl.getExtension("EXT_color_buffer_float")) return "no WebGL2 float target";
  const f32 = (b64) => { const s = atob(b64), u = new Uint8Array(s.length);
                         for (let i = 0; i < s.length; ++i) u[i] = s.charCodeAt(i);
                         return new Float32Array(u.buffer); };
  const sh = (type, text) => { const x = gl.createShader(type); gl.shaderSource(x, text);
    gl.compileShader(x); if (!gl.getShaderParameter(x, gl.COMPILE_STATUS))
      throw new Error(gl.getShaderInfoLog(x)); return x; };
  const p = gl.createProgram();
  gl.attachShader(p, sh(gl.VERTEX_SHADER, "#version 300 es\\nin vec2 a;\\n" +
                        "void main() { gl_Position = vec4(a, 0.0, 1.0); }"));
  gl.attachShader(p, sh(gl.FRAGMENT_SHADER, frag));
  gl.bindAttribLocation(p, 0, "a");
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
  gl.useProgram(p);
  const [nl, rows, cols, ns] = dims;
  const t0 = gl.createTexture();
  gl.activeTexture(gl.TEXTURE0);
  gl.bindTexture(gl.TEXTURE_2D_ARRAY, t0);
  gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, gl.RGBA32F, cols, rows, nl);
  gl.texSubImage3D(gl.TEXTURE_2D_ARRAY, 0, 0, 0, 0, cols, rows, nl, gl.RGBA, gl.FLOAT, f32(sky));
  const t1 = gl.createTexture();
  gl.activeTexture(gl.TEXTURE1);
  gl.bindTexture(gl.TEXTURE_2D, t1);
  gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, ns, 1);
  gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, ns, 1, gl.RGBA, gl.FLOAT, f32(sun));
  for (const t of [gl.TEXTURE_2D_ARRAY, gl.TEXTURE_2D]) {
    gl.activeTexture(t === gl.TEXTURE_2D ? gl.TEXTURE1 : gl.TEXTURE0);
    gl.texParameteri(t, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(t, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  }
  gl.uniform1i(gl.getUniformLocation(p, "skyTex"), 0);
  gl.uniform1i(gl.getUniformLocation(p, "sunTex"), 1);
  for (const [k, v] of Object.entries(f)) {
    const loc = gl.getUniformLocation(p, "fit." + k + (k === "limb" ? "[0]" : ""));
    if (k === "limb") gl.uniform3fv(loc, v.flat());
    else if (["nSky", "nGround", "nPhi", "elevationCount", "sunElevationCount"].includes(k))
      gl.uniform1i(loc, v); else gl.uniform1f(loc, v);
  }
  gl.uniform3fv(gl.getUniformLocation(p, "sunDir"), sunDir);
  gl.uniform2f(gl.getUniformLocation(p, "size"), w, h);
  const tex = gl.createTexture();
  gl.activeTexture(gl.TEXTURE2);
  gl.bindTexture(gl.TEXTURE_2D, tex);
  gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, w, h);
  const fb = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
  const buf = gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, buf);
  gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
  gl.enableVertexAttribArray(0);
  gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
  gl.viewport(0, 0, w, h);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  const out = new Float32Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, out);
  return Array.from(out);
}
"""

_FRAG_MAIN = """
uniform sampler2DArray skyTex; uniform sampler2D sunTex; uniform SkydomeFitted fit;
uniform vec3 sunDir; uniform vec2 size;
out vec4 o;
void main() {
    // skydome.imaging.projections.Equirect(w, h) at the pixel centre (gl_FragCoord rows
    // count from the bottom): elevation 90 deg - 180 deg row / h, azimuth 360 deg col / w
    float row = size.y - gl_FragCoord.y;
    float el = 0.5 * SKYDOME_FITTED_PI - SKYDOME_FITTED_PI * row / size.y;
    float az = 2.0 * SKYDOME_FITTED_PI * gl_FragCoord.x / size.x;
    vec3 d = vec3(cos(el) * sin(az), cos(el) * cos(az), sin(el));
    // the sun's function compiled and linked too (its value is checked by the
    // transcription; 0 x it leaves the sky alone)
    o = vec4(skydomeFittedSky(skyTex, fit, d, sunDir) + 0.0 * skydomeFittedSunMeanRadiance(
        sunTex, fit, sunDir), 1.0);
}
"""


def test_glsl_in_chromium_against_the_cpu_model(baked):
    """fitted.glsl itself in WebGL2 (headless Chromium, SwiftShader, float32), on the two
    layers of the bake around the sun (the struct's axis set to them), over the whole
    sphere (equirect 128 x 64) against the CPU model at that sun: PSNR >= 40 dB at
    elevations between the layers."""
    import base64

    from _viewer import CHROMIUM, CHROMIUM_ARGS, have_browser

    if not have_browser():
        pytest.skip("headless Chromium or Playwright missing")
    from playwright.sync_api import sync_playwright

    desc, sky, sun = baked
    e, se = desc["elevation_axis"], desc["sun_elevation_axis"]
    frag = ("#version 300 es\nprecision highp float;\nprecision highp int;\n"
            "precision highp sampler2DArray;\n" + GLSL.read_text() + _FRAG_MAIN)
    d = _directions()
    w, h = d.shape[1], d.shape[0]

    def b64(a):
        return base64.b64encode(np.ascontiguousarray(a, dtype="<f4").tobytes()).decode()

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        page = browser.new_page()
        for el in (45.5, 3.5, e["first_deg"] + 0.5 * e["step_deg"]):
            k = int((el - e["first_deg"]) // e["step_deg"])
            ks = int((el - se["first_deg"]) // se["step_deg"])
            f = glsl.struct_from_desc(desc)
            f.update({"elevationFirstDeg": e["first_deg"] + k * e["step_deg"],
                      "elevationCount": 2, "sunElevationCount": 2,
                      "sunElevationFirstDeg": se["first_deg"] + ks * se["step_deg"]})
            cpu = _cpu(el)
            s = np.asarray(cpu.sun.direction, dtype=np.float64)
            layers = sky[k:k + 2]
            out = page.evaluate(_PAGE_JS, [frag, b64(layers), b64(sun[ks:ks + 2]),
                                           list(layers.shape[:3]) + [2], f, s.tolist(), w, h])
            assert not isinstance(out, str), out
            gpu = np.asarray(out, dtype=np.float64).reshape(h, w, 4)[::-1, :, :3]
            gpu = gpu * cpu.sun.irradiance_scale
            ref = np.asarray(cpu.xyz(d))
            value = psnr_db(gpu, ref)
            # the shader against its numpy transcription on the same two layers: the
            # same arithmetic in float32 and float64 (the interpolation's weights included)
            tr = glsl.fitted_sky(layers, f, d, s) * cpu.sun.irradiance_scale
            own = psnr_db(gpu, tr)
            print(f"fitted.glsl in Chromium, sun {el:g} deg: PSNR {value:.1f} dB against the "
                  f"CPU model, {own:.1f} dB against the transcription")
            assert np.all(np.isfinite(gpu)) and value >= PSNR_FLOOR_DB
            assert own >= MIRROR_FLOOR_DB
        browser.close()
