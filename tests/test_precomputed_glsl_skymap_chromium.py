"""The sky-map path of src/skydome/export/glsl/precomputed.glsl run in real headless Chromium.

``skydomeSkyMapTexel`` (one texel of the observer's sky map of orders 2..N: the scattering
density integrated along the texel's view ray, ``skydomeMultipleScatteringAlong``) renders
every texel of the map into an RGBA32F render target of a minimal WebGL2 page (Chromium,
SwiftShader, the launch settings of tests/_viewer.py), read back as floats; then
``skydomeRadianceMapped`` (single scattering from the 4-D tables, orders 2..N read from that
GLSL-made map by ``skydomeSkyMapLookup``, the Lambertian ground) renders a grid of view
directions. The page concatenates the shader file's text, read from the package, verbatim
with a main() of a few lines; the textures are the default precomputed sky's bake
(``bake_precomputed(sky, density=True)``), uploaded with the formats and sampler state
luts.json names (RGBA32F, LINEAR, CLAMP_TO_EDGE, the 4-D tables and the scattering density
as sampler3D), the structs SkydomeAtmosphere and SkydomeScatteringDensity filled from
luts.json as tests/_glsl_precomputed.py fills them.

The reference is the shader's numpy transcription (tests/_glsl_precomputed.py, float64,
itself checked against the model in tests/test_export_precomputed_luts.py) on the same
textures: ``G.sky_map`` for the map and ``G.radiance_mapped`` on the transcription's own map
for the radiance, never numbers made by the GLSL. PSNR on linear XYZ, peak = the
reference's largest value (tests/_viewer.py's psnr_db); floor 40 dB, the project's floor for
GPU-vs-CPU shader checks.

Measured on this machine (Debian's Chromium 156, SwiftShader, 2 busy cores; about 40 s
for the file): the sky map (256 rows x 96 azimuths, the bake's size) at sun 20 deg / 0 m,
0 deg / 1000 m, -2 deg / 10000 m: PSNR 77.9 / 68.7 / 80.8 dB (largest texel difference
0.18 / 0.28 / 0.14 % of the map's largest value); radiance through the map (60 x 19
directions, elevation -60..89 deg, azimuth 0..180 deg from the sun's): 97.2 / 73.8 /
100.4 dB. The lower figures at sun 0 deg come from the GPU's acos, not from the shader's
logic: SwiftShader's acos is a polynomial (Abramowitz & Stegun 4.4.45, error up to
6.8e-5 rad, -6.75e-5 just above 0 and +6.77e-5 just below), and the mu_s axis
(skydomePcMuSUnit) takes acos of a sun cosine near 0 there, where J varies steeply with the
sun's zenith angle: the GLSL map is 0.17-0.30 % high where nu > 0 and 0.14-0.20 % low where
nu < 0, a step at 90 deg from the sun's azimuth; the transcription with that acos in its
mu_s axis meets the GLSL map to a median 1.3e-4 in Y instead of 1.8e-3 (PSNR 81.4 dB).
"""

from __future__ import annotations

import json
import re
import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import _glsl_precomputed as G  # noqa: E402
from _threejs import static_server, wait  # noqa: E402
from _viewer import CHROMIUM, CHROMIUM_ARGS, have_browser, psnr_db  # noqa: E402

PSNR_FLOOR_DB = 40.0
#: (sun elevation [deg], observer altitude [m])
CASES = [(20.0, 0.0), (0.0, 1000.0), (-2.0, 10000.0)]
#: rows of the sky map drawn per draw call (each a short GPU task for SwiftShader)
BAND_ROWS = 32
#: the view directions of the radiance check: elevation x azimuth from the sun's
ELEVATIONS_DEG = np.linspace(-60.0, 89.0, 60)
AZIMUTHS_DEG = np.linspace(0.0, 180.0, 19)

#: the GLSL structs' fields and how the page sets each (WebGL's uniform<kind>)
ATM_UNIFORMS = {"bottomRadius": "1f", "topRadius": "1f", "muSMin": "1f",
                "sunAngularRadius": "1f", "sunSolidAngle": "1f", "solarIrradiance": "3fv",
                "rayleighGamma": "1f", "miePhaseCode": "1i", "mieG": "1f", "nuSize": "1i",
                "nWavelengths": "1i", "extinction": "4fv", "xyzWeights": "3fv",
                "groundAlbedo": "1fv"}
DENS_UNIFORMS = {"nTheta": "1i", "nPhi": "1i", "nR": "1i", "nMuS": "1i", "nScatterers": "1i",
                 "blockColumns": "1i", "scatterer": "1iv", "profileCode": "1iv",
                 "profileP0": "1fv", "profileP1": "1fv", "nConstituents": "1i",
                 "columnNodes": "1i", "samples": "1i", "scale": "1f", "mapGround": "1i",
                 "mapSky": "1i", "mapPhi": "1i", "mapGroundLinear": "1f",
                 "mapSkyLinear": "1f"}

#: textures the page uploads: name -> (GL target, the sampler uniform)
TEXTURES = {"scattering_density": ("3d", "densTex"), "optical_depth": ("2d", "odTex"),
            "scattering": ("3d", "scatteringTex"), "single_mie_scattering": ("3d", "mieTex"),
            "irradiance_spectral": ("2darray", "irrSpecTex")}

MAP_MAIN = """
uniform sampler3D densTex;
uniform sampler2D odTex;
uniform SkydomeAtmosphere atm;
uniform SkydomeScatteringDensity dens;
uniform float observerRadius;
uniform float sunMuS;
out vec4 colour;
void main() {
    colour = vec4(skydomeSkyMapTexel(densTex, odTex, atm, dens, observerRadius, sunMuS,
                                     ivec2(gl_FragCoord.xy)), 0.0);
}
"""

RADIANCE_MAIN = """
uniform sampler3D scatteringTex;
uniform sampler3D mieTex;
uniform sampler2D skyMap;
uniform sampler2D odTex;
uniform sampler2DArray irrSpecTex;
uniform sampler2D dirTex;
uniform SkydomeAtmosphere atm;
uniform SkydomeScatteringDensity dens;
uniform vec3 camera;
uniform vec3 sunDir;
out vec4 colour;
void main() {
    vec3 dir = texelFetch(dirTex, ivec2(gl_FragCoord.xy), 0).xyz;
    colour = vec4(skydomeRadianceMapped(scatteringTex, mieTex, skyMap, odTex, irrSpecTex, atm,
                                        dens, camera, dir, sunDir), 0.0);
}
"""

PAGE = """<!DOCTYPE html><html><head><meta charset="utf-8"><link rel="icon" href="data:,">
</head><body><script type="module">
const h = { ready: false };
window.h = h;
const gl = document.createElement('canvas').getContext('webgl2');
const HEADER = '#version 300 es\\nprecision highp float;\\nprecision highp int;\\n'
  + 'precision highp sampler2D;\\nprecision highp sampler3D;\\n'
  + 'precision highp sampler2DArray;\\n';
const VERTEX = '#version 300 es\\nvoid main() {\\n'
  + '  gl_Position = vec4(float((gl_VertexID & 1) << 2) - 1.0,\\n'
  + '                     float((gl_VertexID & 2) << 1) - 1.0, 0.0, 1.0);\\n}\\n';

function shader(type, src) {
  const s = gl.createShader(type);
  gl.shaderSource(s, src);
  gl.compileShader(s);
  if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
  return s;
}

function program(fragment) {
  const p = gl.createProgram();
  gl.attachShader(p, shader(gl.VERTEX_SHADER, VERTEX));
  gl.attachShader(p, shader(gl.FRAGMENT_SHADER, HEADER + fragment));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
  return p;
}

// sampler state of luts.json's texel convention: LINEAR, CLAMP_TO_EDGE, no mip maps
function samplerState(target) {
  gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
  gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
  for (const w of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T, gl.TEXTURE_WRAP_R])
    gl.texParameteri(target, w, gl.CLAMP_TO_EDGE);
}

// a float32 RGBA texture of shape (height, width, 4) or (depth / layers, height, width, 4)
function texture(kind, shape, data) {
  const t = gl.createTexture();
  const target = { '2d': gl.TEXTURE_2D, '3d': gl.TEXTURE_3D,
                   '2darray': gl.TEXTURE_2D_ARRAY }[kind];
  gl.bindTexture(target, t);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  if (kind === '2d')
    gl.texImage2D(target, 0, gl.RGBA32F, shape[1], shape[0], 0, gl.RGBA, gl.FLOAT, data);
  else
    gl.texImage3D(target, 0, gl.RGBA32F, shape[2], shape[1], shape[0], 0, gl.RGBA, gl.FLOAT,
                  data);
  samplerState(target);
  return { target, t };
}

function target(w, hh, data) {
  const tex = texture('2d', [hh, w], data);
  const fb = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex.t, 0);
  if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) !== gl.FRAMEBUFFER_COMPLETE)
    throw new Error('the RGBA32F render target is not complete');
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  return { w, h: hh, tex, fb };
}

function setUniforms(p, list) {
  gl.useProgram(p);
  for (const [name, kind, value] of list) {
    const loc = gl.getUniformLocation(p, name);
    if (loc === null) continue;                  // not used by this program's main()
    if (kind.endsWith('v')) gl['uniform' + kind](loc, value);
    else gl['uniform' + kind](loc, ...value);
  }
}

function bindTextures(p, units) {
  gl.useProgram(p);
  units.forEach(([name, tex], i) => {
    gl.activeTexture(gl.TEXTURE0 + i);
    gl.bindTexture(tex.target, tex.t);
    gl.uniform1i(gl.getUniformLocation(p, name), i);
  });
}

// draw rows y0 .. y1 - 1 of target rt with program p, read them back (rows bottom up)
function draw(p, rt, y0, y1) {
  gl.useProgram(p);
  gl.bindFramebuffer(gl.FRAMEBUFFER, rt.fb);
  gl.viewport(0, 0, rt.w, rt.h);
  gl.enable(gl.SCISSOR_TEST);
  gl.scissor(0, y0, rt.w, y1 - y0);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  const px = new Float32Array(rt.w * (y1 - y0) * 4);
  gl.readPixels(0, y0, rt.w, y1 - y0, gl.RGBA, gl.FLOAT, px);
  gl.disable(gl.SCISSOR_TEST);
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  return Array.from(px);
}

async function load() {
  for (const ext of ['EXT_color_buffer_float', 'OES_texture_float_linear'])
    if (!gl.getExtension(ext)) throw new Error(`WebGL2 extension ${ext} missing`);
  const setup = await (await fetch('setup.json')).json();
  const glsl = await (await fetch('precomputed.glsl')).text();
  h.mapProgram = program(glsl + setup.mapMain);
  h.radianceProgram = program(glsl + setup.radianceMain);
  const tex = {};
  for (const [name, [kind, shape]] of Object.entries(setup.textures)) {
    const res = await fetch(`${name}.bin`);
    if (!res.ok) throw new Error(`${name}.bin: HTTP ${res.status}`);
    tex[name] = texture(kind, shape, new Float32Array(await res.arrayBuffer()));
  }
  const d = setup.directions;
  h.map = target(setup.mapWidth, setup.mapHeight, null);
  h.radiance = target(d.width, d.height, null);
  const dirs = texture('2d', [d.height, d.width], new Float32Array(d.xyzw));
  gl.bindTexture(gl.TEXTURE_2D, dirs.t);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  for (const p of [h.mapProgram, h.radianceProgram]) {
    setUniforms(p, setup.uniforms);
    bindTextures(p, [...Object.entries(setup.samplers).map(([n, s]) => [s, tex[n]]),
                     ['skyMap', h.map.tex], ['dirTex', dirs]]);
  }
  gl.bindVertexArray(gl.createVertexArray());
  if (gl.getError() !== gl.NO_ERROR) throw new Error('WebGL error while loading');
  h.ready = true;
}

// rows y0 .. y1 - 1 of the sky map for an observer at radius r, the sun at zenith cosine muS
h.mapRows = (r, muS, y0, y1) => {
  setUniforms(h.mapProgram, [['observerRadius', '1f', [r]], ['sunMuS', '1f', [muS]]]);
  const out = draw(h.mapProgram, h.map, y0, y1);
  if (gl.getError() !== gl.NO_ERROR) throw new Error('WebGL error while drawing the map');
  return out;
};

// skydomeRadianceMapped in the uploaded directions, from the sky map drawn last
h.radianceMapped = (camera, sunDir) => {
  setUniforms(h.radianceProgram, [['camera', '3f', camera], ['sunDir', '3f', sunDir]]);
  const out = draw(h.radianceProgram, h.radiance, 0, h.radiance.h);
  if (gl.getError() !== gl.NO_ERROR) throw new Error('WebGL error while drawing radiance');
  return out;
};

load().catch((e) => { h.error = String(e); });
</script></body></html>
"""


def _glsl_text() -> str:
    return (resources.files("skydome.export") / "glsl" / "precomputed.glsl").read_text()


def _struct_fields(src: str, name: str) -> set[str]:
    """The field names of GLSL struct ``name`` in ``src``."""
    body = re.search(r"struct " + name + r" \{(.*?)\};", src, re.S).group(1)
    body = re.sub(r"//[^\n]*", "", body)
    return {m.group(1) for m in re.finditer(r"\b\w+\s+(\w+)\s*(?:\[[^\]]*\])?\s*;", body)}


def _uniforms(atm: dict, dens: dict) -> list:
    """(name, uniform kind, values) of every field of the two structs."""
    out = []
    for prefix, struct, kinds in (("atm", atm, ATM_UNIFORMS), ("dens", dens, DENS_UNIFORMS)):
        for field, kind in kinds.items():
            # an array's own name locates its first element (OpenGL ES 3.0,
            # GetUniformLocation): uniform<kind>v fills the array from there
            out.append([f"{prefix}.{field}", kind,
                        [float(x) if kind[1] == "f" else int(x)
                         for x in np.asarray(struct[field]).ravel()]])
    return out


def _directions() -> np.ndarray:
    """(len(AZIMUTHS_DEG), len(ELEVATIONS_DEG), 3) unit view directions, the sun's azimuth
    along +y (its vertical plane y-z), rounded to the float32 the page reads."""
    el, az = np.meshgrid(np.radians(ELEVATIONS_DEG), np.radians(AZIMUTHS_DEG))
    d = np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], -1)
    return d.astype(np.float32).astype(np.float64)


def _sun(elevation_deg: float) -> np.ndarray:
    e = np.radians(elevation_deg)
    return np.array([0.0, np.cos(e), np.sin(e)]).astype(np.float32).astype(np.float64)


def test_struct_uniforms_name_every_field():
    """The page fills every field of SkydomeAtmosphere and SkydomeScatteringDensity (a field
    left out would stay 0 in the shader)."""
    src = _glsl_text()
    assert _struct_fields(src, "SkydomeAtmosphere") == set(ATM_UNIFORMS)
    assert _struct_fields(src, "SkydomeScatteringDensity") == set(DENS_UNIFORMS)
    assert "vec3 skydomeSkyMapTexel(sampler3D density, sampler2D opticalDepth," in src
    assert "vec3 skydomeRadianceMapped(sampler3D scattering, sampler3D singleMie," in src


@pytest.fixture(scope="module")
def baked():
    """(textures, description): the default precomputed sky baked with its scattering
    density (float32, as the page uploads them), as tests/test_export_precomputed_luts.py
    bakes it (single scattering from the 4-D table with the sun below the horizon too)."""
    if not have_browser():
        pytest.skip("headless Chromium or Playwright missing (scripts/_setup test installs them)")
    import skydome
    from skydome.export.luts import bake_precomputed

    sky = skydome.model("precomputed", sun=skydome.Sun(elevation_deg=20.0, azimuth_deg=0.0),
                        twilight_single_scattering=False)
    tex, desc = bake_precomputed(sky, density=True)
    return {k: tex[k] for k in TEXTURES}, desc


@pytest.fixture(scope="module")
def page(baked, tmp_path_factory):
    """The page loaded in headless Chromium with the bake's textures and both programs."""
    from playwright.sync_api import sync_playwright

    tex, desc = baked
    atm = G.atmosphere_from_desc(desc)
    dens = G.density_from_desc(desc)
    root = tmp_path_factory.mktemp("glsl_skymap")
    d = _directions()
    xyzw = np.zeros(d.shape[:-1] + (4,), dtype=np.float32)
    xyzw[..., :3] = d
    setup = {"mapMain": MAP_MAIN, "radianceMain": RADIANCE_MAIN,
             "textures": {n: [TEXTURES[n][0], list(tex[n].shape)] for n in TEXTURES},
             "samplers": {n: TEXTURES[n][1] for n in TEXTURES},
             "uniforms": _uniforms(atm, dens),
             "mapWidth": dens["mapPhi"], "mapHeight": dens["mapGround"] + dens["mapSky"],
             "directions": {"width": d.shape[1], "height": d.shape[0],
                            "xyzw": xyzw.ravel().tolist()}}
    (root / "index.html").write_text(PAGE)
    (root / "precomputed.glsl").write_text(_glsl_text())
    (root / "setup.json").write_text(json.dumps(setup))
    for name in TEXTURES:
        np.ascontiguousarray(tex[name], dtype="<f4").tofile(root / f"{name}.bin")
    with static_server(root) as url, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        pg = browser.new_page(viewport={"width": 64, "height": 64})
        messages = []
        pg.on("console", lambda m: messages.append((m.type, m.text)))
        pg.on("pageerror", lambda e: messages.append(("pageerror", str(e))))
        pg.goto(f"{url}/index.html")
        wait(pg, "window.h", timeout_s=300.0)
        for name in TEXTURES:              # uploaded: the 0.5 GB of files are not needed
            (root / f"{name}.bin").unlink()
        yield pg
        browser.close()
    assert not [m for m in messages if m[0] in ("error", "pageerror")], messages


@pytest.fixture(scope="module")
def results(baked, page):
    """case -> {"map": (GLSL, transcription), "radiance": (GLSL, transcription)}, each
    case drawn once (the radiance right after its map, which it reads)."""
    tex, desc = baked
    atm = G.atmosphere_from_desc(desc)
    dens = G.density_from_desc(desc)
    od = tex["optical_depth"].astype(np.float64)
    R = desc["bottom_radius_m"]
    n_phi, n_rows = dens["mapPhi"], dens["mapGround"] + dens["mapSky"]
    d = _directions()
    cache: dict = {}

    def get(case):
        if case in cache:
            return cache[case]
        elevation, altitude = case
        r = float(np.float32(R + altitude))
        sun = _sun(elevation)
        mu_s = float(sun[2])
        rows = [page.evaluate("([r, m, y0, y1]) => window.h.mapRows(r, m, y0, y1)",
                              [r, mu_s, y0, min(y0 + BAND_ROWS, n_rows)])
                for y0 in range(0, n_rows, BAND_ROWS)]
        gl_map = np.concatenate([np.asarray(b, dtype=np.float64) for b in rows])
        gl_map = gl_map.reshape(n_rows, n_phi, 4)[..., :3]
        gl_rad = np.asarray(page.evaluate("([c, s]) => window.h.radianceMapped(c, s)",
                                          [[0.0, 0.0, r], sun.tolist()]),
                            dtype=np.float64).reshape(d.shape[:-1] + (4,))[..., :3]
        ref_map = G.sky_map(tex["scattering_density"], od, atm, dens, r, mu_s)
        ref_rad = G.radiance_mapped(tex["scattering"].astype(np.float64),
                                    tex["single_mie_scattering"].astype(np.float64), ref_map,
                                    od, tex["irradiance_spectral"].astype(np.float64), atm,
                                    dens, np.array([0.0, 0.0, r]), d.reshape(-1, 3), sun)
        cache[case] = {"map": (gl_map, ref_map[..., :3]),
                       "radiance": (gl_rad, ref_rad.reshape(d.shape))}
        return cache[case]

    return get


@pytest.mark.parametrize("case", CASES, ids=[f"sun{e:g}-alt{a:g}" for e, a in CASES])
def test_sky_map_texels(results, case):
    """Every texel of skydomeSkyMapTexel's map drawn in Chromium against the transcription's
    G.sky_map on the same textures: PSNR >= 40 dB on linear XYZ."""
    gl_map, ref = results(case)["map"]
    assert np.isfinite(gl_map).all() and ref[..., 1].max() > 0.0
    p = psnr_db(gl_map, ref)
    err = np.abs(gl_map - ref).max(axis=-1)
    y, x = np.unravel_index(np.argmax(err), err.shape)
    print(f"sky map sun {case[0]:g} deg, observer {case[1]:g} m: PSNR {p:.1f} dB; largest "
          f"difference {err[y, x]:.4g} at texel (phi {x}, row {y}): GLSL {gl_map[y, x]}, "
          f"transcription {ref[y, x]} (map max {ref.max():.6g})")
    assert p >= PSNR_FLOOR_DB


@pytest.mark.parametrize("case", CASES, ids=[f"sun{e:g}-alt{a:g}" for e, a in CASES])
def test_radiance_through_the_sky_map(results, case):
    """skydomeRadianceMapped reading the map Chromium drew (sky and ground, elevation
    -60..89 deg, azimuth 0..180 deg from the sun's) against G.radiance_mapped on the
    transcription's map: PSNR >= 40 dB on linear XYZ."""
    gl_rad, ref = results(case)["radiance"]
    assert np.isfinite(gl_rad).all() and ref[..., 1].min() > 0.0
    p = psnr_db(gl_rad, ref)
    print(f"radiance through the sky map, sun {case[0]:g} deg, observer {case[1]:g} m: "
          f"PSNR {p:.1f} dB; max |GLSL / transcription - 1| in Y "
          f"{np.abs(gl_rad[..., 1] / ref[..., 1] - 1.0).max():.3g}")
    assert p >= PSNR_FLOOR_DB
