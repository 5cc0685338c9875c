"""The precomputed LUT bake and its shader (src/skydome/export/glsl/precomputed.glsl).

The shader is transcribed function by function into numpy (tests/_glsl_precomputed.py,
with GLSL ``texture()`` emulated); the transcription, fed the baked textures and luts.json,
is compared with the CPU model: its radiance (sky and ground), its sun, its irradiance and
its own look-up of the same tables (skydome.models.simulated.precomputed._render, numba).
The reference values are the model's, computed by its own kernels; the shader and its
transcription are an independent implementation of the look-ups."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import _glsl_precomputed as G  # noqa: E402

GLSL = Path(__file__).parents[1] / "src/skydome/export/glsl/precomputed.glsl"
SUN_ELEVATIONS = (60.0, 20.0, 5.0)


def test_the_transcription_follows_the_glsl_file():
    """The entry points transcribed in _glsl_precomputed.py exist in the GLSL file."""
    src = GLSL.read_text()
    for sig in ("vec3 skydomeSkyRadiance(sampler3D scattering, sampler3D singleMie, "
                "sampler3D multiple,",
                "vec3 skydomeRadiance(sampler3D scattering, sampler3D singleMie, "
                "sampler3D multiple,",
                "vec3 skydomeGroundRadiance(sampler2D opticalDepth, sampler2DArray "
                "irradianceSpectral,",
                "vec3 skydomeSunRadiance(sampler2D opticalDepth, SkydomeAtmosphere atm, "
                "float r, float muS)",
                "vec3 skydomeSunAndSkyIrradiance(sampler2D transmittance, sampler2D "
                "irradiance,",
                "vec3 skydomeSkyRadianceToPoint(sampler3D scattering, sampler3D singleMie,",
                "vec4 skydomeScatteringUvwz(float r, float mu, float muS, float nu, "
                "bool ground,",
                "vec3 skydomeLookup4D(sampler3D tex, vec4 uvwz, float nNu)",
                "vec3 skydomeMultipleScatteringAlong(sampler3D density, sampler2D "
                "opticalDepth,",
                "vec3 skydomeSkyMapTexel(sampler3D density, sampler2D opticalDepth, "
                "SkydomeAtmosphere atm,",
                "vec3 skydomeSkyMapLookup(sampler2D skyMap, SkydomeAtmosphere atm,",
                "vec3 skydomeRadianceMapped(sampler3D scattering, sampler3D singleMie, "
                "sampler2D skyMap,",
                "vec3 skydomeSkyRadianceToPointMapped(sampler3D scattering, sampler3D "
                "singleMie,"):
        assert sig in src, sig
    assert src.count("{") == src.count("}")
    assert not re.search(r"\bdouble\b", src)


MAIN = """
uniform sampler3D scatteringTex; uniform sampler3D mieTex; uniform sampler3D msTex;
uniform sampler2D transTex; uniform sampler2D odTex; uniform sampler2D irrTex;
uniform sampler2DArray irrSpec; uniform SkydomeAtmosphere atm;
uniform sampler3D densTex; uniform sampler2D skyMap; uniform SkydomeScatteringDensity dens;
uniform vec3 camera; uniform vec3 dir; uniform vec3 sunDir;
out vec4 colour;
void main() {
    vec3 t; vec3 sky;
    vec3 L = skydomeRadiance(scatteringTex, mieTex, msTex, transTex, odTex, irrSpec, atm,
                             camera, dir, sunDir);
    float r = length(camera);
    vec3 sun = skydomeSunRadiance(odTex, atm, r, dot(camera, sunDir) / r);
    vec3 sun3 = skydomeSunRadianceXYZ(transTex, atm, r, dot(camera, sunDir) / r);
    vec3 ap = skydomeSkyRadianceToPoint(scatteringTex, mieTex, msTex, odTex, atm, camera,
                                        camera + 1e4 * dir, sunDir, t);
    vec3 e = skydomeSunAndSkyIrradiance(transTex, irrTex, atm, camera, normalize(camera),
                                        sunDir, sky);
    vec3 map = skydomeSkyMapTexel(densTex, odTex, atm, dens, r, dot(camera, sunDir) / r,
                                  ivec2(gl_FragCoord.xy));
    vec3 Lm = skydomeRadianceMapped(scatteringTex, mieTex, skyMap, odTex, irrSpec, atm, dens,
                                    camera, dir, sunDir);
    vec3 t2;
    vec3 apm = skydomeSkyRadianceToPointMapped(scatteringTex, mieTex, msTex, skyMap, odTex,
                                               atm, dens, camera, camera + 1e4 * dir, sunDir,
                                               t2);
    colour = vec4(L + sun + sun3 + ap * t + e + sky + map + Lm + apm * t2, 1.0);
}
"""


@pytest.mark.skipif(not Path("/usr/bin/glslangValidator").exists(),
                    reason="glslangValidator (Debian glslang-tools, installed by "
                           "scripts/_setup) missing")
@pytest.mark.parametrize("version", ["#version 300 es\nprecision highp float;\n"
                                     "precision highp sampler3D;\n"
                                     "precision highp sampler2DArray;\n", "#version 330 core\n"])
def test_glsl_compiles(tmp_path, version):
    """The shader compiles as GLSL ES 3.00 (WebGL2) and GLSL 3.30 with the Khronos reference
    compiler, called from a fragment shader that uses every entry point."""
    src = tmp_path / "precomputed.frag"
    src.write_text(version + GLSL.read_text() + MAIN)
    res = subprocess.run(["/usr/bin/glslangValidator", str(src)], capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr


@pytest.fixture(scope="module")
def baked():
    """The default precomputed sky (the on-disk cache makes it quick after the first run),
    baked with its scattering density, textures in float64 for the transcription (the
    scattering density, 545 MB, kept in float32: the transcription reads its texels and
    computes in float64). The shader reads single scattering from the 4-D table with the
    sun below the horizon too, so the model it is compared with does
    (``twilight_single_scattering=False``). The default integrates it at the observer:
    against that default the shader's mapped sky at sun -2 deg is 0.7 / 1.0 / 3.9 % RMS
    and at most 3.0 / 6.6 / 25.9 % off at 0 / 1 / 10 km (docs/performance.md, "Twilight:
    the observer's single scattering made the default")."""
    import skydome
    from skydome.export.luts import bake_precomputed

    sky = skydome.model("precomputed", sun=skydome.Sun(elevation_deg=20.0, azimuth_deg=180.0),
                        twilight_single_scattering=False)
    tex, desc = bake_precomputed(sky, density=True)
    return sky, {k: (v if k == "scattering_density" else v.astype(np.float64))
                 for k, v in tex.items()}, desc


def _grid():
    """View directions: elevation -60..89 deg, azimuth 0..180 deg (the sky is symmetric
    about the sun's vertical), 150 x 37."""
    el, az = np.meshgrid(np.radians(np.linspace(-60.0, 89.0, 150)),
                         np.radians(np.linspace(0.0, 180.0, 37)))
    return np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)],
                    -1).reshape(-1, 3)


def _render(tex, desc, sky):
    R = desc["bottom_radius_m"]
    cam = np.array([0.0, 0.0, R + sky.observer_altitude_m])
    sun = np.asarray(sky.sun.direction)
    d = _grid()
    gpu = G.radiance(tex["scattering"], tex["single_mie_scattering"],
                     tex["multiple_scattering"], tex["transmittance"], tex["optical_depth"],
                     tex["irradiance_spectral"], G.atmosphere_from_desc(desc), cam, d, sun)
    return d, cam, sun, gpu


def _cpu_xyz(sky, d):
    from skydome.spectra import default_wavelengths, spectrum_to_xyz

    wl = default_wavelengths()
    return spectrum_to_xyz(sky.radiance(d, wl), wl) / sky.sun.irradiance_scale


@pytest.mark.parametrize("altitude_m", [0.0, 5000.0])
def test_shader_equals_the_models_lookup_of_its_tables(baked, altitude_m):
    """Sky and ground (everything but the sun's disc) through the shader = the model's own
    numba look-up of the same 4-D tables (render_observer on the tables' slices) with the
    model's Lambertian ground, to float32: every index, mapping, filter and the spectral
    ground term agree, at 60, 20, 5 and -4 deg sun, from the ground and from 5 km."""
    import skydome
    from skydome.models.simulated.precomputed import _render as K

    sky0, tex, desc = baked
    Kx = np.asarray(desc["xyz_weights"])
    for elev in (*SUN_ELEVATIONS, -4.0):
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=30.0),
                            observer_altitude_m=altitude_m)
        d, cam, sun, gpu = _render(tex, desc, sky)
        t = sky._t
        ss, ms = sky._observer_slices(table_only=True)
        out = np.empty((d.shape[0], t.table_wavelengths_nm.size))
        K.render_observer(np.ascontiguousarray(d), sky._r0, np.ascontiguousarray(sun), ss,
                          t.phase_code, t.phase_param, t.kernel_phase_table, ms, t.columns,
                          t.beta_e, t.ground_albedo, t.irradiance, np.ones(out.shape[1]),
                          sky._R, sky._Rt, sky._mu_s_min, sky._alpha, sky._slice_geometry(table=True), out)
        cpu = out @ Kx
        assert cpu[:, 1].min() > 0.0
        np.testing.assert_allclose(gpu, cpu, rtol=1e-5, atol=1e-6 * cpu[:, 1].max())


def test_ground_within_one_percent_of_the_model(baked):
    """The ground (the surface lit by the transmitted sun and the sky irradiance, spectral)
    for an observer standing on it, as the model renders it below the horizon (which
    imaging/ground.py keeps for this model): within 1 % of the model's luminance (measured
    within 1e-4), sun at 60, 20 and 5 deg, every direction below the horizon."""
    import skydome

    sky0, tex, desc = baked
    for elev in SUN_ELEVATIONS:
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=0.0))
        d, cam, sun, gpu = _render(tex, desc, sky)
        g = G.hits_ground(cam[2], d[:, 2], desc["bottom_radius_m"])
        cpu = _cpu_xyz(sky, d[g])
        rel = gpu[g, 1] / cpu[:, 1] - 1.0
        assert np.abs(rel).max() < 1e-4, (elev, np.abs(rel).max())


def test_ground_from_above_against_the_model(baked):
    """From 5 km the ground is seen through 5-100 km of air, whose in-scattering the model
    takes from its observer's sky map of orders 2..N and the shader from the stored table
    (see test_sky_against_the_model): measured max 0.9 / 3.6 / 4.2 %, RMS 0.18 / 0.53 /
    0.70 % at 60 / 20 / 5 deg sun (the surface term itself is exact, see
    test_shader_equals_the_models_lookup_of_its_tables); the bounds are those rounded up,
    the 1 % goal holds for the RMS."""
    import skydome

    sky0, tex, desc = baked
    bounds = {60.0: (0.012, 0.002), 20.0: (0.04, 0.006), 5.0: (0.045, 0.008)}
    for elev in SUN_ELEVATIONS:
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=0.0),
                            observer_altitude_m=5000.0)
        d, cam, sun, gpu = _render(tex, desc, sky)
        g = G.hits_ground(cam[2], d[:, 2], desc["bottom_radius_m"])
        cpu = _cpu_xyz(sky, d[g])
        rel = gpu[g, 1] / cpu[:, 1] - 1.0
        mx, rms = bounds[elev]
        assert np.abs(rel).max() < mx and np.sqrt(np.mean(rel ** 2)) < rms, (elev, rel)


def test_sky_against_the_model(baked):
    """The sky (view elevation >= 0, more than 1 deg from the sun's centre) against the
    model's radiance, luminance, sun at 60, 20 and 5 deg.

    The model's radiance integrates orders 2..N at the observer (its sky map of 192 x 96
    directions, exact in mu_s); the shader reads the stored 4-D table of orders 2..N
    (16 nu, 48 mu_s nodes), which the test above shows it reads exactly. The table's
    interpolation makes the difference, largest at the horizon 15-30 deg from a low sun
    (measured on this grid: max 2.4 / 6.0 / 8.4 %, RMS 0.56 / 0.65 / 0.86 % at 60 / 20 /
    5 deg; 91.0 / 91.4 / 91.7 % of the directions within 1 %; a table with 32 nu nodes
    halves the largest). The model's sky map takes its rays' columns along the rays
    themselves (``observer_columns``, the default), the table the differences of two
    columns to the top, up to 0.9 % off in the transmittance of the first kilometres of a
    ray 1 deg above the horizon: that moved the largest at 60 deg from 1.9 % (both with
    the differences) to 2.4 %, near the horizon. The asserted bounds are those measurements rounded up: the 1 %
    goal holds for the RMS, not for every direction, on this fast path; the sky-map path
    (skydomeRadianceMapped) integrates orders 2..N as the model does and meets it
    everywhere (test_sky_and_ground_mapped_equal_the_model)."""
    import skydome

    sky0, tex, desc = baked
    bounds = {60.0: (0.025, 0.006, 0.905), 20.0: (0.062, 0.007, 0.91),
              5.0: (0.09, 0.0095, 0.915)}
    for elev in SUN_ELEVATIONS:
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=0.0))
        d, cam, sun, gpu = _render(tex, desc, sky)
        ang = np.degrees(np.arccos(np.clip(d @ sun, -1.0, 1.0)))
        m = (d[:, 2] >= 0.0) & (ang > 1.0)
        cpu = _cpu_xyz(sky, d[m])
        rel = gpu[m, 1] / cpu[:, 1] - 1.0
        mx, rms, within = bounds[elev]
        assert np.abs(rel).max() < mx, (elev, np.abs(rel).max())
        assert np.sqrt(np.mean(rel ** 2)) < rms, (elev, np.sqrt(np.mean(rel ** 2)))
        assert np.mean(np.abs(rel) < 0.01) > within, (elev, np.mean(np.abs(rel) < 0.01))


def test_sun_within_one_percent_of_the_model(baked):
    """The sun's disc through the air (skydomeSunRadiance, spectral from the optical
    depths, and skydomeSunRadianceXYZ, from the XYZ transmittance texture) = the model's
    sun_radiance reduced to XYZ, within 1 % (measured: 1e-6 and 1e-4), sun at 60, 20 and
    5 deg; at 0.1 deg (the disc's penumbra) the spectral one still within 1e-4, the XYZ one
    1.6 % off in Y (its transmittance interpolated in value, not in optical depth)."""
    import skydome
    from skydome.spectra import default_wavelengths, spectrum_to_xyz

    sky0, tex, desc = baked
    atm = G.atmosphere_from_desc(desc)
    wl = default_wavelengths()
    for elev in (*SUN_ELEVATIONS, 0.1):
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=0.0))
        cpu = spectrum_to_xyz(sky.sun_radiance(wl), wl) / sky.sun.irradiance_scale
        r = np.array([sky._r0])
        mu_s = np.array([sky.sun.direction[2]])
        assert cpu[1] > 0.0
        np.testing.assert_allclose(G.sun_radiance(tex["optical_depth"], atm, r, mu_s)[0], cpu,
                                   rtol=1e-4)
        np.testing.assert_allclose(G.sun_radiance_xyz(tex["transmittance"], atm, r, mu_s)[0],
                                   cpu, rtol=0.01 if elev > 1.0 else 0.03)


def test_sun_and_sky_irradiance_equal_the_model(baked):
    """skydomeSunAndSkyIrradiance on a horizontal surface at the observer = the model's
    irradiance_components (direct, diffuse) reduced to XYZ (measured within 2e-4 for the
    sun, where the model averages the cosine over the disc, and 1e-7 for the sky)."""
    import skydome
    from skydome.spectra import default_wavelengths, spectrum_to_xyz

    sky0, tex, desc = baked
    atm = G.atmosphere_from_desc(desc)
    wl = default_wavelengths()
    for elev in SUN_ELEVATIONS:
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=0.0))
        direct, diffuse = sky.irradiance_components(wl)
        cam = np.array([0.0, 0.0, sky._r0])
        e_sun, e_sky = G.sun_and_sky_irradiance(tex["transmittance"], tex["irradiance"], atm,
                                                cam, np.array([0.0, 0.0, 1.0]),
                                                np.asarray(sky.sun.direction))
        s = sky.sun.irradiance_scale
        np.testing.assert_allclose(e_sun, spectrum_to_xyz(direct, wl) / s, rtol=1e-3)
        np.testing.assert_allclose(e_sky, spectrum_to_xyz(diffuse, wl) / s, rtol=1e-5)


def test_aerial_perspective_against_the_model(baked):
    """skydomeSkyRadianceToPoint: its transmittance = the model's (the sun-weighted mean of
    the spectral transmittance of the model's aerial-perspective kernel) to float32; its
    in-scattering, S(camera) - T S(point) in XYZ, against the model's aerial_perspective
    (which multiplies T S spectrally and adds its observer-slice correction), error
    relative to the sky's luminance in that direction (measured, 1-60 km, view elevation
    >= -3 deg: RMS 0.58 / 0.61 / 0.99 %, max 1.6 / 2.5 / 7.1 % at 60 / 20 / 5 deg sun,
    with the model's sky map integrating its rays' columns along the rays, the default;
    0.54 / 0.70 / 1.04 and 1.7 / 4.0 / 9.2 % with the column table's differences; the
    bounds below are the latter rounded up)."""
    import skydome
    from skydome.models.simulated.precomputed import _render as K
    from skydome.spectra import default_wavelengths, spectrum_to_xyz

    sky0, tex, desc = baked
    atm = G.atmosphere_from_desc(desc)
    wl = default_wavelengths()
    Kx = np.asarray(desc["xyz_weights"])
    rng = np.random.default_rng(11)
    d = rng.normal(size=(2000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = np.ascontiguousarray(d[d[:, 2] > -0.05][:500])
    dist = rng.uniform(1e3, 60e3, d.shape[0])
    bounds = {60.0: (0.008, 0.025), 20.0: (0.010, 0.05), 5.0: (0.014, 0.10)}
    for elev in SUN_ELEVATIONS:
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=30.0))
        sun = np.asarray(sky.sun.direction)
        t = sky._t
        tr = np.empty((d.shape[0], Kx.shape[0]))
        ins = np.zeros_like(tr)
        K.aerial_perspective(d, dist, sky._r0, np.ascontiguousarray(sun), t.single_scattering,
                             t.phase_code, t.phase_param, t.kernel_phase_table,
                             t.multiple_scattering, t.columns, t.beta_e, sky._R, sky._Rt,
                             sky._mu_s_min, tr, ins)
        gl, gt = G.sky_radiance_to_point(tex["scattering"], tex["single_mie_scattering"],
                                         tex["multiple_scattering"], tex["optical_depth"], atm,
                                         np.array([0.0, 0.0, sky._r0]), d, dist, sun)
        np.testing.assert_allclose(gt, tr @ (Kx / Kx.sum(axis=0)), rtol=1e-5, atol=1e-6)
        _, L = sky.aerial_perspective(d, dist, wl)
        cpu = spectrum_to_xyz(L, wl) / sky.sun.irradiance_scale
        y_sky = _cpu_xyz(sky, d)[:, 1]
        err = np.abs(gl[:, 1] - cpu[:, 1]) / y_sky
        rms, mx = bounds[elev]
        assert np.sqrt(np.mean(err ** 2)) < rms and err.max() < mx, (elev, err.max())


def test_description_holds_the_constants(baked):
    """luts.json holds the parametrisation and the atmosphere's constants an engine needs:
    radii, mu_s_min, sizes, the sun, the Rayleigh and Mie coefficients and phase functions,
    the luminance conversion; the extraterrestrial sun's Y is the luminous solar constant
    (133 334 lx, Darula, Kittler & Gueymard 2005, within 1 %)."""
    sky, tex, desc = baked
    t = sky._t
    assert desc["bottom_radius_m"] == t.planet_radius_m and desc["top_radius_m"] == t.top_radius_m
    assert desc["mu_s_min"] == t.mu_s_min
    assert desc["sizes"] == {"r": 32, "mu": 128, "mu_s": 48, "nu": 16}
    assert desc["transmittance_size"] == {"r": 64, "mu": 256}
    assert desc["irradiance_size"] == {"r": 16, "mu_s": 64}
    assert desc["n_wavelengths"] == 20
    assert desc["sun"]["solar_irradiance_xyz"][1] == pytest.approx(133_334.0, rel=0.01)
    assert desc["mie"]["g"] == 0.76 and desc["mie"]["phase"] == "Cornette-Shanks"
    assert desc["rayleigh"]["gamma"] == pytest.approx(float(t.phase_param[0]))
    # the coefficients are the atmosphere's own (its constituents' functions of wavelength)
    wl = np.asarray(desc["table_wavelengths_nm"])
    atm = sky.atmosphere
    np.testing.assert_allclose(desc["rayleigh"]["scattering_per_m"],
                               atm.constituent("rayleigh").scattering(wl), rtol=1e-12)
    np.testing.assert_allclose(desc["mie"]["scattering_per_m"],
                               atm.constituent("aerosol").scattering(wl), rtol=1e-12)
    assert desc["constituents"][:2] == ["rayleigh", "aerosol"]
    assert len(desc["extinction_per_km"]) == len(desc["constituents"]) <= 4
    assert tex["scattering"].shape == (32, 128, 16 * 48, 4)
    assert tex["irradiance_spectral"].shape == (5, 16, 64, 4)
    for name in ("scattering", "single_mie_scattering", "multiple_scattering", "transmittance",
                 "irradiance"):
        assert desc["textures"][name]["channels"] == ["X", "Y", "Z"]
        assert np.all(tex[name][..., 3] == 0.0) and np.all(tex[name] >= 0.0)


def test_half_float_exr(baked, tmp_path):
    """`write_luts(..., ("exr",), half=True)`: the textures beyond the half-float range
    (65504 cd m^-2) are written in kcd m^-2 (exr_scale 1e-3 in luts.json), channels X, Y,
    Z; the sky rendered
    from the half-float values is within 0.1 % of the float32 one (measured 0.034 % max at
    sun 20 deg; 0.2 % at -10 deg)."""
    import OpenEXR

    from skydome.export.luts import write_luts
    from skydome.imaging.image import read_exr

    sky, tex, desc = baked
    out = tmp_path / "half"
    write_luts(sky, out, ("exr",), half=True)
    d = __import__("json").loads((out / "luts.json").read_text())
    half = {}
    for name in ("scattering", "single_mie_scattering", "multiple_scattering", "transmittance",
                 "optical_depth", "irradiance"):
        with OpenEXR.File(str(out / f"{name}.exr")) as f:
            names = [c.name for c in f.header()["channels"]]
        assert set(names) == set(d["textures"][name]["channels"]), name
        ch = read_exr(out / f"{name}.exr")
        scale = d["textures"][name].get("exr_scale", 1.0)
        img = np.stack([ch[c].astype(np.float64) for c in d["textures"][name]["channels"]], -1)
        full = np.zeros(img.shape[:-1] + (4,))
        full[..., :img.shape[-1]] = img / scale
        half[name] = full.reshape(tex[name].shape)
    assert d["textures"]["scattering"]["exr_scale"] == 1e-3
    assert "exr_scale" not in d["textures"]["transmittance"]
    assert "exr_scale" not in d["textures"]["multiple_scattering"]     # max 21 010 cd m^-2
    half["irradiance_spectral"] = tex["irradiance_spectral"]       # not in EXR
    d_, cam, sun, ref = _render(tex, desc, sky)
    _, _, _, got = _render(half, desc, sky)
    np.testing.assert_allclose(got[:, 1], ref[:, 1], rtol=1e-3)


# -- orders 2..N integrated along the view ray (the scattering density), as the model does ----
#: the sun elevations [deg] and observer altitudes [m] of the sky-map tests
MAP_SUN_ELEVATIONS = (60.0, 20.0, 5.0, 0.0, -2.0)
MAP_ALTITUDES = (0.0, 1000.0, 10000.0)


@pytest.fixture(scope="module")
def sky_maps(baked):
    """The shader's sky maps of orders 2..N (skydomeSkyMapTexel at every texel, through the
    transcription), by (sun elevation, observer altitude): a map depends on the observer's
    radius and the sun's zenith angle only (its azimuth axis is measured from the sun's)."""
    sky0, tex, desc = baked
    atm = G.atmosphere_from_desc(desc)
    dens = G.density_from_desc(desc)
    R = desc["bottom_radius_m"]
    maps = {}
    for elev in MAP_SUN_ELEVATIONS:
        mu_s = np.sin(np.radians(elev))
        for alt in MAP_ALTITUDES:
            maps[elev, alt] = G.sky_map(tex["scattering_density"], tex["optical_depth"], atm,
                                        dens, R + alt, mu_s)
    return maps


def test_sky_map_equals_the_models_observer_map(baked, sky_maps):
    """Every texel of the shader's sky map (the scattering density integrated along the
    texel's view ray: skydomeMultipleScatteringAlong) = the model's own sky map of orders
    2..N for that observer (multiple_scattering_slice, numba, float64), reduced to XYZ
    with the bake's weights, to float32 (measured max 1.5e-8 of the map's largest
    value with the columns integrated along the rays, 1.9e-6 with the differences of the
    float32 optical-depth texture's columns)."""
    import skydome

    sky0, tex, desc = baked
    Kx = np.asarray(desc["xyz_weights"])
    for (elev, alt), smap in sky_maps.items():
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=0.0),
                            observer_altitude_m=alt)
        ref = sky._observer_slices()[1] @ Kx
        assert ref.shape == smap[..., :3].shape
        np.testing.assert_allclose(smap[..., :3], ref, rtol=1e-5, atol=1e-6 * ref.max(),
                                   err_msg=f"sun {elev} deg, observer {alt} m")


def test_sky_map_with_the_column_tables_differences(baked):
    """A sky made with ``observer_columns=False`` bakes ``column_nodes: 0``, and the
    shader's sky map then takes the difference of two columns to the top from the column
    table, as that model's map does: every texel equal to float32 (sun 20 deg, observer
    1 km), while the two ways' maps differ by far more than that (checked here: more than
    0.3 % of the largest texel)."""
    import skydome
    from skydome.export.luts import _density_description

    sky0, tex, desc = baked
    sky = skydome.model("precomputed", sun=skydome.Sun(elevation_deg=20.0, azimuth_deg=0.0),
                        observer_altitude_m=1000.0, twilight_single_scattering=False,
                        observer_columns=False)
    # luts.json's scattering_density of this sky (the same tables: only the entry differs)
    off = _density_description(sky, sky._t)
    assert off["column_nodes"] == 0
    dens = G.density_from_desc({"scattering_density": off})
    Kx = np.asarray(desc["xyz_weights"])
    mu_s = np.sin(np.radians(20.0))
    smap = G.sky_map(tex["scattering_density"], tex["optical_depth"],
                     G.atmosphere_from_desc(desc), dens, desc["bottom_radius_m"] + 1000.0,
                     mu_s)[..., :3]
    ref = sky._observer_slices()[1] @ Kx
    np.testing.assert_allclose(smap, ref, rtol=1e-5, atol=1e-6 * ref.max())
    on = sky0.with_sun(skydome.Sun(elevation_deg=20.0, azimuth_deg=0.0),
                       observer_altitude_m=1000.0)._observer_slices()[1] @ Kx
    assert np.abs(on - ref).max() > 3e-3 * ref.max()


def test_sky_and_ground_mapped_equal_the_model(baked, sky_maps):
    """skydomeRadianceMapped (single scattering from the 4-D tables, orders 2..N from the
    sky map, the Lambertian ground): the sky and the ground as the model's radiance() gives
    them, every direction of the grid (elevation -60..89 deg, the sun's disc is not in
    either), sun at 60, 20, 5, 0 and -2 deg, observer at 0, 1 and 10 km. The goal is 1 %;
    measured max 8.0e-8 in X, Y and Z (1.4e-6 with the column table's differences; the
    bound asserted: 1e-4)."""
    import skydome

    sky0, tex, desc = baked
    atm = G.atmosphere_from_desc(desc)
    dens = G.density_from_desc(desc)
    R = desc["bottom_radius_m"]
    d = _grid()
    for (elev, alt), smap in sky_maps.items():
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=0.0),
                            observer_altitude_m=alt)
        cam = np.array([0.0, 0.0, R + alt])
        sun = np.asarray(sky.sun.direction)
        gpu = G.radiance_mapped(tex["scattering"], tex["single_mie_scattering"], smap,
                                tex["optical_depth"], tex["irradiance_spectral"], atm, dens,
                                cam, d, sun)
        cpu = _cpu_xyz(sky, d)
        assert cpu[:, 1].min() > 0.0
        g = G.hits_ground(cam[2], d[:, 2], R)
        assert g.sum() > 1000 and (~g).sum() > 1000
        rel = np.abs(gpu / cpu - 1.0)
        assert rel.max() < 1e-4, (elev, alt, rel.max())


def test_aerial_perspective_mapped_against_the_model(baked, sky_maps):
    """skydomeSkyRadianceToPointMapped (the model's correction at the observer's end: the
    sky map's orders 2..N in place of the table's, in proportion to the segment's share of
    the ray's extinction) against the model's aerial_perspective, error relative to the
    sky's luminance in that direction, 1-60 km, view elevation >= -3 deg, observer at 0, 1
    and 10 km. The remaining error comes from the three-channel products T S(point) and
    share x correction (the model forms them per wavelength): measured max 1.0-1.5 % (RMS 0.4-0.6 %) with the sun at 60-5
    deg, 3.8 % / 2.7 % (RMS 0.9 / 1.0 %) at 0 / -2 deg; the bounds are those rounded up.
    Its transmittance is the table path's (test_aerial_perspective_against_the_model)."""
    import skydome
    from skydome.spectra import default_wavelengths, spectrum_to_xyz

    sky0, tex, desc = baked
    atm = G.atmosphere_from_desc(desc)
    dens = G.density_from_desc(desc)
    R = desc["bottom_radius_m"]
    wl = default_wavelengths()
    rng = np.random.default_rng(11)
    d = rng.normal(size=(2000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = np.ascontiguousarray(d[d[:, 2] > -0.05][:500])
    dist = rng.uniform(1e3, 60e3, d.shape[0])
    bounds = {60.0: (0.005, 0.013), 20.0: (0.005, 0.014), 5.0: (0.006, 0.016),
              0.0: (0.009, 0.038), -2.0: (0.011, 0.028)}
    for (elev, alt), smap in sky_maps.items():
        sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=30.0),
                            observer_altitude_m=alt)
        sun = np.asarray(sky.sun.direction)
        cam = np.array([0.0, 0.0, R + alt])
        gl, _ = G.sky_radiance_to_point_mapped(tex["scattering"], tex["single_mie_scattering"],
                                               tex["multiple_scattering"], smap,
                                               tex["optical_depth"], atm, dens, cam, d, dist,
                                               sun)
        _, L = sky.aerial_perspective(d, dist, wl)
        cpu = spectrum_to_xyz(L, wl) / sky.sun.irradiance_scale
        err = np.abs(gl[:, 1] - cpu[:, 1]) / _cpu_xyz(sky, d)[:, 1]
        rms, mx = bounds[elev]
        assert np.sqrt(np.mean(err ** 2)) < rms and err.max() < mx, (elev, alt, err.max())


def test_density_description_and_packing(baked):
    """luts.json's scattering_density: J's axes, the constituents' density profiles (the
    atmosphere's own: Rayleigh 7994 m and aerosol 1200 m scale heights, ozone's tent at
    25 km), the quadrature and the sky map; every texel of the packed texture is the
    model's J at the node its layout names (checked at 2000 random nodes)."""
    sky, tex, desc = baked
    t = sky._t
    s = desc["scattering_density"]
    J = t.scattering_density
    assert (s["scatterers"], s["theta"], s["phi"], s["r"], s["mu_s"]) == J.shape[:5]
    assert s["layers"] == 5 and s["scatterer_constituent"] == [0, 1]
    assert desc["constituents"][:3] == ["rayleigh", "aerosol", "ozone"]
    assert s["profile_code"][:3] == [0, 0, 1]
    assert s["profile_p0_m"][:3] == [7994.0, 1200.0, 25000.0]
    assert s["profile_p1_m"][2] == 15000.0
    assert s["quadrature"] == {"samples": 20, "scale_m": 500.0}
    # the model's observer_columns (the default): the rays' columns integrated along them
    assert s["column_nodes"] == 6 and s["constituents"] == len(desc["constituents"])
    assert s["sky_map"] == {"ground": 64, "sky": 192, "phi": 96, "ground_linear": 0.15,
                            "sky_linear": 0.15}
    D = tex["scattering_density"]
    assert max(D.shape[:3]) <= 2048 and desc["textures"]["scattering_density"]["channels"] is None
    rng = np.random.default_rng(3)
    for _ in range(2000):
        k, it, ip, ir, im, j = (int(rng.integers(n)) for n in J.shape)
        b = (it * s["scatterers"] + k) * s["layers"] + j // 4
        z = (b // s["block_columns"]) * s["phi"] + ip
        x = (b % s["block_columns"]) * s["mu_s"] + im
        assert D[z, ir, x, j % 4] == J[k, it, ip, ir, im, j]


def test_sky_map_path_in_any_frame(baked, sky_maps):
    """The sky-map functions take the camera anywhere on its sphere (the planet's centre at
    the origin, any orientation): the camera, the view rays and the sun turned by one
    rotation give the same radiance through the map (float64 rounding, amplified by the
    arc cosines near the sun's vertical and the horizon: measured 2.6e-8; asserted 1e-6)."""
    import skydome

    sky0, tex, desc = baked
    atm = G.atmosphere_from_desc(desc)
    dens = G.density_from_desc(desc)
    R = desc["bottom_radius_m"]
    rng = np.random.default_rng(5)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    d = _grid()
    elev, alt = 5.0, 1000.0
    sky = sky0.with_sun(skydome.Sun(elevation_deg=elev, azimuth_deg=70.0),
                        observer_altitude_m=alt)
    cam = np.array([0.0, 0.0, R + alt])
    sun = np.asarray(sky.sun.direction)
    smap = sky_maps[elev, alt]
    args = (tex["scattering"], tex["single_mie_scattering"], smap, tex["optical_depth"],
            tex["irradiance_spectral"], atm, dens)
    a = G.radiance_mapped(*args, cam, d, sun)
    b = G.radiance_mapped(*args, q @ cam, d @ q.T, q @ sun)
    assert a[:, 1].min() > 0.0
    np.testing.assert_allclose(b, a, rtol=1e-6)
