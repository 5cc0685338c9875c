"""The hillaire2020 LUT bake in Hillaire's layout and its GLSL look-ups
(src/skydome/export/glsl/hillaire2020.glsl).

The GLSL functions are transcribed line by line into numpy below (``_glsl_*``), with a
numpy emulation of GLSL ``texture()`` (LINEAR filtering, CLAMP_TO_EDGE, texel centres at
(i + 0.5) / n, OpenGL 4.6 section 8.14.2); the look-up of the baked textures must give the
model's own CPU values (its numba look-ups of the same tables) in the same directions."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

GLSL = Path(__file__).parents[1] / "src/skydome/export/glsl/hillaire2020.glsl"


# GLSL texture() with LINEAR filtering and CLAMP_TO_EDGE (GL 4.6 section 8.14.2): the one
# transcription of tests/_glsl_precomputed.py
from _glsl_precomputed import texture2d, texture3d  # noqa: E402


# -- numpy transcription of hillaire2020.glsl ------------------------------------------
def _unit_to_texel(x, n):
    return (np.clip(x, 0.0, 1.0) * (n - 1.0) + 0.5) / n


def _hits_ground(r, mu, R):
    return (mu < 0.0) & (r * r * (mu * mu - 1.0) + R * R >= 0.0)


def _rel_az_cos(d, sun):
    nd = np.hypot(d[..., 0], d[..., 1])
    ns = np.hypot(sun[0], sun[1])
    c = (d[..., 0] * sun[0] + d[..., 1] * sun[1]) / np.maximum(nd * ns, 1e-300)
    return np.where((nd < 1e-12) | (ns < 1e-12), 1.0, np.clip(c, -1.0, 1.0))


def _glsl_transmittance_uv(r, mu, R, Rt, size):
    H = np.sqrt(Rt * Rt - R * R)
    rho = np.sqrt(np.maximum(r * r - R * R, 0.0))
    d = -r * mu + np.sqrt(np.maximum(r * r * (mu * mu - 1.0) + Rt * Rt, 0.0))
    d_min, d_max = Rt - r, rho + H
    x_mu = np.where(d_max <= d_min, 0.0, np.clip((d - d_min) / (d_max - d_min), 0.0, 1.0))
    return np.stack([_unit_to_texel(x_mu, size[0]), _unit_to_texel(rho / H, size[1])], -1)


def _glsl_transmittance_to_top(lut, r, mu, R, Rt):
    v = texture2d(lut, _glsl_transmittance_uv(r, mu, R, Rt, (lut.shape[1], lut.shape[0])))
    return np.where(_hits_ground(r, mu, R)[..., None], 0.0, v)


def _glsl_ms_uv(r, mu_s, R, Rt, size):
    return np.stack([_unit_to_texel(0.5 * (mu_s + 1.0), size[0]),
                     _unit_to_texel((r - R) / (Rt - R), size[1])], -1)


def _glsl_sky_view_uv(d, sun, r0, R, size):
    hh = np.floor(size[1] * 0.5)
    beta = np.arccos(min(np.sqrt(max(r0 * r0 - R * R, 0.0)) / r0, 1.0))
    zh = np.pi - beta
    mu = np.clip(d[..., 2], -1.0, 1.0)
    theta = np.arccos(mu)
    g = _hits_ground(r0, mu, R)
    c_sky = 1.0 - np.sqrt(np.maximum(1.0 - theta / zh, 0.0))
    c_gnd = np.sqrt(np.maximum((theta - zh) / beta, 0.0)) if beta > 0 else np.zeros_like(mu)
    c = np.where(g, c_gnd, c_sky)
    base = np.where(g, hh, 0.0)
    fr = np.clip(c, 0.0, 1.0) * (hh - 1.0)
    fx = np.sqrt(np.maximum(0.5 - 0.5 * _rel_az_cos(d, sun), 0.0)) * (size[0] - 1.0)
    return np.stack([(fx + 0.5) / size[0], (base + fr + 0.5) / size[1]], -1)


def _glsl_aerial_uvw(d, dist, sun, km, size):
    s = np.arcsin(np.clip(d[..., 2], -1.0, 1.0)) / (0.5 * np.pi)
    ss = np.where(s < 0.0, -np.sqrt(np.abs(s)), np.sqrt(np.abs(s)))
    fr = (0.5 * ss + 0.5) * (size[1] - 1.0)
    fx = np.sqrt(np.maximum(0.5 - 0.5 * _rel_az_cos(d, sun), 0.0)) * (size[0] - 1.0)
    sl = dist / (km * 1000.0)
    weight = np.where(sl < 0.5, np.maximum(2.0 * sl, 0.0), 1.0)
    sl = np.where(sl < 0.5, 0.5, sl)
    fz = np.clip(np.sqrt(sl / size[2]) * size[2] - 0.5, 0.0, size[2] - 1.0)
    return np.stack([(fx + 0.5) / size[0], (fr + 0.5) / size[1], (fz + 0.5) / size[2]], -1), weight


def _glsl_aerial(vol, d, dist, sun, km):
    uvw, w = _glsl_aerial_uvw(d, dist, sun, km, (vol.shape[2], vol.shape[1], vol.shape[0]))
    v = texture3d(vol, uvw)
    return w[..., None] * v[..., :3], 1.0 - w * (1.0 - v[..., 3])


def test_the_transcription_follows_the_glsl_file():
    """The functions transcribed here exist in the GLSL file with these signatures."""
    src = GLSL.read_text()
    for sig in ("vec2 transmittanceUv(float r, float mu, float R, float Rt, vec2 size)",
                "vec2 multipleScatteringUv(float r, float muS, float R, float Rt, vec2 size)",
                "vec2 skyViewUv(vec3 dir, vec3 sun, float r0, float R, vec2 size)",
                "vec4 aerialPerspectiveUvw(vec3 dir, float distanceM, vec3 sun, float "
                "kmPerSlice, vec3 size)",
                "vec4 aerialPerspective(sampler3D vol,", "vec3 skyViewXYZ(sampler2D lut,",
                "vec3 transmittanceToTop(sampler2D lut,"):
        assert sig in src, sig
    assert src.count("{") == src.count("}")
    assert not re.search(r"\bdouble\b", src)


@pytest.fixture(scope="module")
def baked():
    import skydome
    from skydome.export.luts import bake_hillaire2020

    sky = skydome.model("hillaire2020", sun=skydome.Sun(elevation_deg=20.0, azimuth_deg=135.0),
                        n_wavelengths=6, ms_directions=16, view_samples=8, ap_samples=4)
    tex, desc = bake_hillaire2020(sky)
    return sky, tex, desc


def _dirs(n, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def test_layout_sizes_are_hillaires(baked):
    """[Hil20]: transmittance 256 x 64, multiple scattering 32 x 32, sky view 192 x 108,
    aerial perspective 32^3 (texture shapes are (height, width, 4) / (depth, height, width, 4))."""
    _, tex, desc = baked
    assert tex["transmittance"].shape == (64, 256, 4)
    assert tex["multiple_scattering"].shape == (32, 32, 4)
    assert tex["sky_view"].shape == (108, 192, 4)
    assert tex["aerial_perspective"].shape == (32, 32, 32, 4)
    for name, t in tex.items():
        assert t.dtype == np.float32 and np.all(np.isfinite(t)) and np.all(t >= 0.0), name
        assert desc["textures"][name]["shape"] == list(t.shape)


def test_glsl_sky_view_reproduces_the_cpu_sky(baked):
    """The GLSL sky-view look-up of the baked XYZ texture = sky.xyz (the model's CPU
    look-up of its spectral table, then the CIE integration), sky and ground, to float32."""
    sky, tex, desc = baked
    d = _dirs(400, 1)
    cpu = sky.xyz(d) / sky.sun.irradiance_scale
    uv = _glsl_sky_view_uv(d, np.asarray(sky.sun.direction), desc["observer_radius_m"],
                           desc["planet_radius_m"], (192, 108))
    gpu = texture2d(tex["sky_view"].astype(np.float64), uv)[..., :3]
    np.testing.assert_allclose(gpu, cpu, rtol=2e-5, atol=1e-6 * cpu[:, 1].max())
    assert cpu[:, 1].min() > 0.0


def test_glsl_transmittance_reproduces_the_cpu_lookup(baked):
    """Per wavelength (the spectral texture) the GLSL look-up = sky.transmittance; the
    XYZ texture = the sun-weighted mean of the spectral values."""
    sky, tex, desc = baked
    grid = np.asarray(desc["grid_wavelengths_nm"])
    d = _dirs(300, 2)
    R, Rt, r0 = desc["planet_radius_m"], desc["top_radius_m"], desc["observer_radius_m"]
    cpu = sky.transmittance(d, grid)
    r = np.full(d.shape[0], r0)
    gpu = _glsl_transmittance_to_top(tex["transmittance_spectral"].astype(float), r, d[:, 2], R, Rt)
    np.testing.assert_allclose(gpu, cpu, rtol=1e-5, atol=1e-7)
    Kn = np.asarray(desc["xyz_weights_transmittance"])
    gpu3 = _glsl_transmittance_to_top(tex["transmittance"].astype(float), r, d[:, 2], R, Rt)[:, :3]
    np.testing.assert_allclose(gpu3, cpu @ Kn, rtol=1e-5, atol=1e-7)
    # a point above the observer, looking sideways: other r than the observer's
    r2 = np.full(50, R + 20e3)
    mu2 = np.linspace(-0.3, 1.0, 50)
    from skydome.models.simulated import _kernels_hillaire2020 as K

    out = np.empty((50, grid.size))
    tb = sky.tables(np.asarray(desc["output_wavelengths_nm"]))
    K.lookup_transmittance(r2, mu2, tb.tlut, R, Rt, out)
    gpu2 = _glsl_transmittance_to_top(tex["transmittance_spectral"].astype(float), r2, mu2, R, Rt)
    np.testing.assert_allclose(gpu2, out, rtol=1e-5, atol=1e-7)


def test_glsl_multiple_scattering_uv_reproduces_the_cpu_cell(baked):
    """multipleScatteringUv + texture() = the ray march's Psi_ms look-up (irradiance_cell +
    bilerp_last of skydome.transport._tables)."""
    from skydome.transport._tables import bilerp_last, irradiance_cell

    sky, tex, desc = baked
    R, Rt = desc["planet_radius_m"], desc["top_radius_m"]
    ms = tex["multiple_scattering_spectral"].astype(np.float64)
    rng = np.random.default_rng(3)
    r = R + rng.uniform(0.0, Rt - R, 200)
    mu_s = rng.uniform(-1.0, 1.0, 200)
    gpu = texture2d(ms, _glsl_ms_uv(r, mu_s, R, Rt, (ms.shape[1], ms.shape[0])))
    cpu = np.empty_like(gpu)
    for k in range(r.size):
        i, j, a, b = irradiance_cell(r[k], mu_s[k], R, Rt, ms.shape[0], ms.shape[1])
        cpu[k] = [bilerp_last(ms, i, j, a, b, l) for l in range(ms.shape[2])]
    np.testing.assert_allclose(gpu, cpu, rtol=1e-9, atol=1e-12 * np.abs(ms).max())


def test_glsl_aerial_perspective_reproduces_the_cpu_volume(baked):
    """aerialPerspective of the baked volume = sky.aerial_perspective (the CPU trilinear
    look-up of the same volume): in-scatter XYZ exact to float32, transmittance (the
    sun-luminance-weighted one in A) likewise."""
    from skydome.spectra import spectrum_to_xyz

    sky, tex, desc = baked
    wl = np.asarray(desc["output_wavelengths_nm"])
    d = _dirs(300, 4)
    d[:, 2] = np.abs(d[:, 2]) * 0.5 - 0.1
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    dist = np.random.default_rng(5).uniform(0.0, 150e3, d.shape[0])
    dist[:10] = np.linspace(0.0, 2500.0, 10)                  # the fade below half a slice
    T, L = sky.aerial_perspective(d, dist, wl)
    cpu_l = spectrum_to_xyz(L, wl) / sky.sun.irradiance_scale
    gl, gt = _glsl_aerial(tex["aerial_perspective"].astype(np.float64), d, dist,
                          np.asarray(sky.sun.direction), desc["ap_km_per_slice"])
    np.testing.assert_allclose(gl, cpu_l, rtol=2e-5, atol=1e-6 * cpu_l[:, 1].max())
    grid = np.asarray(desc["grid_wavelengths_nm"])
    T_grid, _ = sky.aerial_perspective(d, dist, grid)
    Ky = np.asarray(desc["xyz_weights_transmittance"])[:, 1]
    np.testing.assert_allclose(gt, T_grid @ Ky, rtol=1e-5, atol=1e-6)


def test_write_luts_folder_and_cli(tmp_path):
    """`skydome export luts --model hillaire2020`: .npy, .bin, half EXR and luts.json in a
    folder that appears complete; bad input exits 2 with nothing on disk."""
    from typer.testing import CliRunner

    from skydome.cli import app
    from skydome.imaging.image import read_exr

    runner = CliRunner()
    out = tmp_path / "luts"
    small = ["--n-wavelengths", "3", "--ms-directions", "4", "--ms-size", "8",
             "--transmittance-width", "16", "--transmittance-height", "8", "--skyview-width",
             "16", "--skyview-height", "8", "--ap-size", "4", "--view-samples", "4"]
    res = runner.invoke(app, ["export", "luts", "--model", "hillaire2020", "--format",
                              "exr,npy,bin", "--half", "--out", str(out), *small])
    assert res.exit_code == 0, res.output
    desc = json.loads((out / "luts.json").read_text())
    assert desc["format"] == "skydome.luts.hillaire-xyz/2"
    assert desc["exr"]["dtype"] == "float16"
    sv = np.load(out / "sky_view.npy")
    assert sv.shape == (8, 16, 4)
    np.testing.assert_array_equal(np.fromfile(out / "sky_view.bin", "<f4").reshape(sv.shape), sv)
    ch = read_exr(out / "sky_view.exr")
    assert ch["X"].dtype == np.float16
    np.testing.assert_allclose(ch["Y"].astype(float), sv[..., 1], rtol=1e-3)
    ap = read_exr(out / "aerial_perspective.exr")
    assert ap["X"].shape == (4 * 4, 4)                     # slices stacked top to bottom
    # the channels are named for what they hold (CIE XYZ; A = transmittance in the volume),
    # as the OpenEXR reader lists them in the header
    import OpenEXR

    for name, want in (("sky_view", {"X", "Y", "Z"}), ("transmittance", {"X", "Y", "Z"}),
                       ("aerial_perspective", {"X", "Y", "Z", "A"})):
        with OpenEXR.File(str(out / f"{name}.exr")) as f:
            assert {c.name for c in f.header()["channels"]} == want, name
    assert not (out / "sky_view_spectral.exr").exists()      # spectral only as npy / bin
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    for args, msg in ((["--model", "preetham1999"], "has no LUT bake"),
                      (["--model", "hillaire2020", "--format", "png"], "formats"),
                      (["--model", "hillaire2020", "--half"], "exr"),
                      (["--model", "hillaire2020", "--ap-size", "1"], "--ap-size")):
        bad = tmp_path / "bad"
        res = runner.invoke(app, ["export", "luts", *args, "--out", str(bad)])
        assert res.exit_code == 2, (args, res.output)
        assert msg in res.output, (args, res.output)
        assert not bad.exists()


@pytest.mark.skipif(not Path("/usr/bin/glslangValidator").exists(),
                    reason="glslangValidator (Debian glslang-tools, installed by scripts/_setup) missing")
@pytest.mark.parametrize("version", ["#version 300 es\nprecision highp float;\n"
                                     "precision highp sampler3D;\n", "#version 330 core\n"])
def test_glsl_compiles(tmp_path, version):
    """The GLSL file compiles as GLSL ES 3.00 (WebGL2) and GLSL 3.30 with the Khronos
    reference compiler, called from a fragment shader that uses every look-up."""
    import subprocess

    main = """
uniform sampler2D transLut; uniform sampler2D skyLut; uniform sampler3D apVol;
uniform vec3 dir; uniform vec3 sunDir; uniform float dist;
out vec4 colour;
void main() {
    vec3 t = transmittanceToTop(transLut, 6.361e6, dir.z, 6.36e6, 6.46e6);
    vec2 ms = multipleScatteringUv(6.362e6, sunDir.z, 6.36e6, 6.46e6, vec2(32.0));
    vec3 sky = skyViewXYZ(skyLut, dir, sunDir, 6.3600001e6, 6.36e6);
    vec4 ap = aerialPerspective(apVol, dir, dist, sunDir, 4.0);
    colour = vec4(t * sky + ap.rgb * ap.a + vec3(ms, 0.0), 1.0);
}
"""
    src = tmp_path / "lut.frag"
    src.write_text(version + GLSL.read_text() + main)
    res = subprocess.run(["/usr/bin/glslangValidator", str(src)], capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr


def test_bake_holds_the_atmosphere_that_rebuilds_the_model(baked):
    """luts.json's atmosphere (coefficients, density profiles, phase functions, radii,
    ground albedo) and model parameters alone rebuild the model: a hillaire2020 sky built
    from the JSON (after a JSON round trip) gives the original's radiance within 1e-6, for
    the baked sun and another one (an engine rebuilding its per-frame tables)."""
    import skydome
    from skydome.export.luts import atmosphere_from_luts

    sky, _, desc = baked
    desc = json.loads(json.dumps(desc))
    atm = atmosphere_from_luts(desc)
    params = {k: v for k, v in desc["model_parameters"].items()}
    wl = np.asarray(desc["output_wavelengths_nm"])
    d = _dirs(200, 7)
    for sun in (sky.sun, skydome.Sun(elevation_deg=3.0, azimuth_deg=250.0)):
        orig = skydome.model("hillaire2020", sun=sun, atmosphere=sky.atmosphere,
                             **params).radiance(d, wl)
        again = skydome.model("hillaire2020", sun=sun, atmosphere=atm, **params).radiance(d, wl)
        assert orig.max() > 0.0
        np.testing.assert_allclose(again, orig, rtol=1e-6, atol=1e-9 * orig.max())
    names = [c["name"] for c in desc["atmosphere"]["constituents"]]
    assert names[:2] == ["rayleigh", "aerosol"]
    assert desc["atmosphere"]["constituents"][1]["g"] == sky.atmosphere.constituent("aerosol").g
    with pytest.raises(ValueError, match="atmosphere"):
        atmosphere_from_luts({"format": "skydome.luts.hillaire-xyz/1"})


def test_bake_holds_the_sun_disc(baked):
    """sun_disc: above the atmosphere the disc's luminance is the luminous solar constant
    over the disc's solid angle (133 334 lx, Darula, Kittler & Gueymard 2005, within 1 %:
    their spectrum differs from ASTM G173's); through the air it is that radiance times the
    transmittance texture at (observer, sun), per XYZ channel, and equals the model's
    sun_radiance reduced to XYZ."""
    from skydome.spectra import spectrum_to_xyz

    sky, tex, desc = baked
    disc = desc["sun_disc"]
    assert disc["angular_radius_deg"] == sky.sun.angular_radius_deg
    top = np.asarray(disc["radiance_top_of_atmosphere_xyz"])
    assert top[1] * disc["solid_angle_sr"] == pytest.approx(133_334.0, rel=0.01)
    wl = np.asarray(desc["output_wavelengths_nm"])
    cpu = spectrum_to_xyz(sky.sun_radiance(wl), wl) / sky.sun.irradiance_scale
    np.testing.assert_allclose(disc["radiance_xyz"], cpu, rtol=1e-9)
    R, Rt, r0 = desc["planet_radius_m"], desc["top_radius_m"], desc["observer_radius_m"]
    t = _glsl_transmittance_to_top(tex["transmittance"].astype(float), np.array([r0]),
                                   np.array([sky.sun.direction[2]]), R, Rt)[0, :3]
    np.testing.assert_allclose(top * t, cpu, rtol=1e-5)
