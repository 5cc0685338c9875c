// skydome's precomputed sky in a three.js scene.
//
// Draws the sky, the ground behind the air and the sun's disc from the files that
// `skydome export luts --model precomputed --format bin --out DIR` writes (luts.json and
// the raw float32 .bin textures), with skydome's own shader, precomputed.glsl (fetched at
// run time: the one source of the shader, shipped next to this module by
// `skydome.export.integrations.threejs.write_threejs`). Only dependency: three (imported
// as the bare specifier 'three', resolved by the page's import map).
//
//   import { loadSkydomeSky } from './skydome-sky.js';
//   const sky = await loadSkydomeSky('luts/');      // a THREE.Mesh
//   sky.setSun(20, 180);                             // elevation, azimuth [deg]
//   sky.exposure = 1 / (1.2 * 2 ** 14);              // [m^2 cd^-1], EV100 14
//   scene.add(sky);
//
// Frame: three.js +x = east, +y = up, -z = north (skydome's East-North-Up frame
// (x east, y north, z up) as (x, z, -y)); azimuth from north towards east. Output: linear
// sRGB (or CIE XYZ with sky.output = 'xyz') in cd m^-2 times sky.exposure, then the
// renderer's tone mapping and output colour space (three's shader chunks). Values are for
// a sun at 1 au (sky.sunScale multiplies them, e.g. skydome's Sun.irradiance_scale).
// The sun's disc has the uniform radiance of the model's sun seen through the air
// (no limb darkening), drawn where a pixel's centre lies inside the disc.

import * as THREE from 'three';

const DEG = Math.PI / 180;

async function fetchOk(url, what) {
  const res = await fetch(url);
  if (!res.ok) throw new Error(`skydome-sky: ${what} ${url}: HTTP ${res.status}`);
  return res;
}

// one texture of the bake, as its luts.json entry describes it (float32 RGBA, C order)
async function loadTexture(base, name, entry) {
  const buf = await (await fetchOk(new URL(entry.file, base), `texture ${name}`)).arrayBuffer();
  const data = new Float32Array(buf);
  const shape = entry.shape;
  const count = shape.reduce((a, b) => a * b, 1);
  if (shape[shape.length - 1] !== 4 || data.length !== count) {
    throw new Error(`skydome-sky: texture ${name}: ${data.length} floats, luts.json says ` +
                    `shape ${JSON.stringify(shape)} (RGBA expected)`);
  }
  let tex;
  if (shape.length === 3) {
    tex = new THREE.DataTexture(data, shape[1], shape[0], THREE.RGBAFormat, THREE.FloatType);
  } else if (name === 'irradiance_spectral') {
    tex = new THREE.DataArrayTexture(data, shape[2], shape[1], shape[0]);
  } else {
    tex = new THREE.Data3DTexture(data, shape[2], shape[1], shape[0]);
    tex.wrapR = THREE.ClampToEdgeWrapping;
  }
  tex.format = THREE.RGBAFormat;
  tex.type = THREE.FloatType;
  tex.minFilter = THREE.LinearFilter;
  tex.magFilter = THREE.LinearFilter;
  tex.wrapS = THREE.ClampToEdgeWrapping;
  tex.wrapT = THREE.ClampToEdgeWrapping;
  tex.generateMipmaps = false;
  tex.unpackAlignment = 1;
  tex.colorSpace = THREE.NoColorSpace;
  tex.needsUpdate = true;
  return tex;
}

// the GLSL struct SkydomeAtmosphere filled from luts.json (the keys its fields name)
function atmosphereUniform(desc) {
  const MAX = 32;
  const ext = [];
  const weights = [];
  const albedo = [];
  for (let j = 0; j < MAX; ++j) {
    const e = [0, 0, 0, 0];
    desc.extinction_per_km.forEach((row, c) => { if (j < row.length) e[c] = row[j]; });
    ext.push(new THREE.Vector4(...e));
    const k = j < desc.n_wavelengths ? desc.xyz_weights[j] : [0, 0, 0];
    weights.push(new THREE.Vector3(...k));
    albedo.push(j < desc.n_wavelengths ? desc.ground_albedo[j] : 0);
  }
  return {
    bottomRadius: desc.bottom_radius_m, topRadius: desc.top_radius_m, muSMin: desc.mu_s_min,
    sunAngularRadius: desc.sun.angular_radius_rad, sunSolidAngle: desc.sun.solid_angle_sr,
    solarIrradiance: new THREE.Vector3(...desc.sun.solar_irradiance_xyz),
    rayleighGamma: desc.rayleigh.gamma, miePhaseCode: desc.mie.phase_code, mieG: desc.mie.g,
    nuSize: desc.sizes.nu, nWavelengths: desc.n_wavelengths,
    extinction: ext, xyzWeights: weights, groundAlbedo: albedo,
  };
}

/** Fetch a precomputed bake (luts.json + .bin textures) and the shader.
 * @param {string|URL} lutsUrl folder of `skydome export luts --model precomputed`
 * @param {{shaderUrl?: string|URL}} options shaderUrl: precomputed.glsl (default: next to
 *   this module)
 * @returns {Promise<{desc: object, textures: object, glsl: string}>} */
export async function loadSkydomeLuts(lutsUrl, options = {}) {
  const base = new URL(String(lutsUrl).endsWith('/') ? String(lutsUrl) : `${lutsUrl}/`,
                       document.baseURI);
  const shaderUrl = options.shaderUrl ?? new URL('precomputed.glsl', import.meta.url);
  const [desc, glsl] = await Promise.all([
    fetchOk(new URL('luts.json', base), 'description').then((r) => r.json()),
    fetchOk(shaderUrl, 'shader').then((r) => r.text()),
  ]);
  if (desc.model !== 'precomputed') {
    throw new Error(`skydome-sky: luts.json model = ${JSON.stringify(desc.model)}; only ` +
                    "'precomputed' bakes are drawn (skydome export luts --model precomputed)");
  }
  const names = ['scattering', 'single_mie_scattering', 'multiple_scattering',
                 'transmittance', 'optical_depth', 'irradiance_spectral'];
  for (const n of names) {
    const files = (desc.files ?? {})[n];
    if (!desc.textures[n] || (files && !files.includes(`${n}.bin`))) {
      throw new Error(`skydome-sky: ${n}.bin missing from the bake (export with --format bin)`);
    }
  }
  const list = await Promise.all(names.map((n) => loadTexture(base, n, desc.textures[n])));
  const textures = Object.fromEntries(names.map((n, i) => [n, list[i]]));
  return { desc, textures, glsl };
}

const VERTEX_SKY = /* glsl */ `
varying vec3 vDirection;
void main() {
  vDirection = (modelMatrix * vec4(position, 0.0)).xyz;
  vec4 p = projectionMatrix * vec4((viewMatrix * vec4(vDirection, 0.0)).xyz, 1.0);
  gl_Position = p.xyww;                       // on the far plane, around the camera
}
`;

const VERTEX_QUAD = /* glsl */ `
void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }
`;

// the host code around precomputed.glsl: uniforms, the view direction, the sun's disc
function fragmentShader(glsl, equirect) {
  return `${glsl}
uniform sampler3D scatteringTex;
uniform sampler3D singleMieTex;
uniform sampler3D multipleTex;
uniform sampler2D transmittanceTex;
uniform sampler2D opticalDepthTex;
uniform sampler2DArray irradianceSpectralTex;
uniform SkydomeAtmosphere atm;
uniform vec3 skyCamera;        // from the planet's centre, East-North-Up [m]
uniform vec3 skySunDir;        // East-North-Up
uniform float skyExposure;
uniform float skySunScale;
uniform float skyCosDisc;      // cos of the disc's angular radius; 2 = no disc
uniform bool skyOutputXYZ;
uniform mat3 skyXyzToRgb;
${equirect ? 'uniform vec2 skySize; uniform float skySpan;' : 'varying vec3 vDirection;'}
void main() {
${equirect ? `
  // skydome's Equirect: row from the top, azimuth = 360 deg col / W from north
  float row = skySize.y - gl_FragCoord.y;
  float el = 0.5 * SKYDOME_PC_PI - skySpan * row / skySize.y;
  float az = 2.0 * SKYDOME_PC_PI * gl_FragCoord.x / skySize.x;
  vec3 v = vec3(cos(el) * sin(az), cos(el) * cos(az), sin(el));` : `
  vec3 d = normalize(vDirection);
  vec3 v = vec3(d.x, -d.z, d.y);              // three.js (east, up, south) -> ENU`}
  vec3 L = skydomeRadiance(scatteringTex, singleMieTex, multipleTex, transmittanceTex,
                           opticalDepthTex, irradianceSpectralTex, atm, skyCamera, v,
                           skySunDir);
  float r = length(skyCamera);
  if (dot(v, skySunDir) >= skyCosDisc
      && !skydomePcHitsGround(r, dot(skyCamera, v) / r, atm.bottomRadius)) {
    L += skydomeSunRadiance(opticalDepthTex, atm, r, dot(skyCamera, skySunDir) / r);
  }
  L *= skySunScale;
  vec3 c = skyOutputXYZ ? L : skyXyzToRgb * L;
  gl_FragColor = vec4(c * skyExposure, 1.0);
  #include <tonemapping_fragment>
  #include <colorspace_fragment>
}
`;
}

/** The sky as a THREE.Mesh (a box drawn around the camera on the far plane). */
export class SkydomeSky extends THREE.Mesh {
  /** @param {{desc: object, textures: object, glsl: string}} luts from loadSkydomeLuts */
  constructor(luts) {
    const { desc, textures, glsl } = luts;
    const m = desc.xyz_to_linear_srgb;
    const uniforms = {
      scatteringTex: { value: textures.scattering },
      singleMieTex: { value: textures.single_mie_scattering },
      multipleTex: { value: textures.multiple_scattering },
      transmittanceTex: { value: textures.transmittance },
      opticalDepthTex: { value: textures.optical_depth },
      irradianceSpectralTex: { value: textures.irradiance_spectral },
      atm: { value: atmosphereUniform(desc) },
      skyCamera: { value: new THREE.Vector3(0, 0, desc.bottom_radius_m) },
      skySunDir: { value: new THREE.Vector3(0, 0, 1) },
      skyExposure: { value: 1.0 },
      skySunScale: { value: 1.0 },
      skyCosDisc: { value: Math.cos(desc.sun.disc_angular_radius_deg * DEG) },
      skyOutputXYZ: { value: false },
      // luts.json's matrix is row-major; Matrix3.set takes rows
      skyXyzToRgb: { value: new THREE.Matrix3().set(...m[0], ...m[1], ...m[2]) },
    };
    const material = new THREE.ShaderMaterial({
      name: 'SkydomeSky', uniforms, vertexShader: VERTEX_SKY,
      fragmentShader: fragmentShader(glsl, false), side: THREE.BackSide,
      depthWrite: false,
    });
    super(new THREE.BoxGeometry(1, 1, 1), material);
    this.name = 'SkydomeSky';
    this.frustumCulled = false;
    this.renderOrder = -1;
    this.desc = desc;
    this.glsl = glsl;
    this._discCos = uniforms.skyCosDisc.value;
    this.setSun(30, 180);
  }

  /** Sun elevation above the horizon and azimuth from north towards east [deg]. */
  setSun(elevationDeg, azimuthDeg) {
    const el = Number(elevationDeg);
    const az = Number(azimuthDeg);
    if (!Number.isFinite(el) || el < -90 || el > 90) {
      throw new RangeError(`sun elevation = ${elevationDeg}: valid range -90..90 deg`);
    }
    if (!Number.isFinite(az)) throw new RangeError(`sun azimuth = ${azimuthDeg}: not a number`);
    const ce = Math.cos(el * DEG);
    this.material.uniforms.skySunDir.value.set(ce * Math.sin(az * DEG),
                                              ce * Math.cos(az * DEG), Math.sin(el * DEG));
    this.sunElevationDeg = el;
    this.sunAzimuthDeg = az;
  }

  /** The sun's direction in three.js' frame (x east, y up, -z north), unit. */
  sunDirection(target = new THREE.Vector3()) {
    const s = this.material.uniforms.skySunDir.value;
    return target.set(s.x, s.z, -s.y);
  }

  /** Observer altitude above the ground [m], 0..top of the atmosphere. */
  set altitude(m) {
    const top = this.desc.top_radius_m - this.desc.bottom_radius_m;
    if (!(m >= 0 && m <= top)) throw new RangeError(`altitude = ${m}: valid range 0..${top} m`);
    this.material.uniforms.skyCamera.value.set(0, 0, this.desc.bottom_radius_m + m);
  }

  get altitude() { return this.material.uniforms.skyCamera.value.z - this.desc.bottom_radius_m; }

  /** Multiplier from cd m^-2 to the renderer's linear values [m^2 cd^-1]. */
  set exposure(k) { this.material.uniforms.skyExposure.value = k; }

  get exposure() { return this.material.uniforms.skyExposure.value; }

  /** Sun's 1/d^2 factor (skydome's Sun.irradiance_scale), 1 = 1 au. */
  set sunScale(s) { this.material.uniforms.skySunScale.value = s; }

  get sunScale() { return this.material.uniforms.skySunScale.value; }

  /** Draw the sun's disc (default true). */
  set sunDisc(on) { this.material.uniforms.skyCosDisc.value = on ? this._discCos : 2.0; }

  get sunDisc() { return this.material.uniforms.skyCosDisc.value <= 1.0; }

  /** 'rgb' (linear sRGB, default) or 'xyz' (CIE 1931 XYZ). */
  set output(o) {
    if (o !== 'rgb' && o !== 'xyz') throw new RangeError(`output = ${o}: 'rgb' or 'xyz'`);
    this.material.uniforms.skyOutputXYZ.value = o === 'xyz';
  }

  get output() { return this.material.uniforms.skyOutputXYZ.value ? 'xyz' : 'rgb'; }

  /** Render the sky into a float render target in skydome's equirectangular layout
   * (skydome.imaging.Equirect: row 0 at the zenith, the left edge north, azimuth
   * increasing to the right; the full sphere or the upper hemisphere). Its values are
   * linear (no tone mapping), in the sky's output and exposure; read them with
   * renderer.readRenderTargetPixels (rows bottom to top). */
  renderEquirect(renderer, width, height, { hemisphere = false, target = null } = {}) {
    const rt = target ?? new THREE.WebGLRenderTarget(width, height, {
      type: THREE.FloatType, format: THREE.RGBAFormat, depthBuffer: false,
      minFilter: THREE.LinearFilter, magFilter: THREE.LinearFilter,
    });
    if (!this._equirect) {
      const mat = new THREE.ShaderMaterial({
        name: 'SkydomeSkyEquirect',
        uniforms: { ...this.material.uniforms, skySize: { value: new THREE.Vector2() },
                    skySpan: { value: Math.PI } },
        vertexShader: VERTEX_QUAD, fragmentShader: fragmentShader(this.glsl, true),
        depthTest: false, depthWrite: false, toneMapped: false,
      });
      const quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), mat);
      quad.frustumCulled = false;
      const scene = new THREE.Scene();
      scene.add(quad);
      this._equirect = { scene, camera: new THREE.Camera(), mat };
    }
    const { scene, camera, mat } = this._equirect;
    mat.uniforms.skySize.value.set(width, height);
    mat.uniforms.skySpan.value = hemisphere ? 0.5 * Math.PI : Math.PI;
    const previous = renderer.getRenderTarget();
    renderer.setRenderTarget(rt);
    renderer.render(scene, camera);
    renderer.setRenderTarget(previous);
    return rt;
  }
}

/** loadSkydomeLuts + new SkydomeSky. */
export async function loadSkydomeSky(lutsUrl, options = {}) {
  return new SkydomeSky(await loadSkydomeLuts(lutsUrl, options));
}
