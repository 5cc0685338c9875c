// skydome's skies in a three.js scene: the precomputed model and the fitted model.
//
// Draws the sky, the ground and the sun's disc from the files that
// `skydome export luts --model precomputed --format bin --out DIR` or
// `skydome export luts --model fitted --format bin --out DIR` writes (luts.json and the raw
// float32 .bin textures), with skydome's own shader for the bake (luts.json's model and
// format pick it): precomputed.glsl or fitted.glsl, fetched at run time (the one source of
// each shader, shipped next to this module by
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
// The sun's disc: precomputed, the uniform radiance of the model's sun seen through the
// air, added to the sky where a pixel's centre lies inside the disc; fitted, the disc
// limb-darkened as skydome.render draws it (Neckel 2005 at 600, 555, 450 nm for X, Y, Z),
// in place of the sky it covers, over each pixel's footprint (energy-true at any size).

import * as THREE from 'three';

const DEG = Math.PI / 180;

async function fetchOk(url, what) {
  const res = await fetch(url);
  if (!res.ok) throw new Error(`skydome-sky: ${what} ${url}: HTTP ${res.status}`);
  return res;
}

// one texture of the bake, as its luts.json entry describes it (float32 RGBA, C order);
// layered: a 4-D entry is a 2-D array texture (else a 3-D texture); nearest: NEAREST
// filters (a shader that reads it with texelFetch; float32 LINEAR needs an extension)
async function loadTexture(base, name, entry, { layered = false, nearest = false } = {}) {
  const buf = await (await fetchOk(new URL(entry.file, base), `texture ${name}`)).arrayBuffer();
  const data = new Float32Array(buf);
  const shape = entry.shape;
  const count = shape.reduce((a, b) => a * b, 1);
  if (shape[shape.length - 1] !== 4 || data.length !== count) {
    throw new Error(`skydome-sky: texture ${name}: ${data.length} floats, luts.json says ` +
                    `shape ${JSON.stringify(shape)} (RGBA expected)`);
  }
  let tex;
  if (shape.length === 2) {
    tex = new THREE.DataTexture(data, shape[0], 1, THREE.RGBAFormat, THREE.FloatType);
  } else if (shape.length === 3) {
    tex = new THREE.DataTexture(data, shape[1], shape[0], THREE.RGBAFormat, THREE.FloatType);
  } else if (layered || name === 'irradiance_spectral') {
    tex = new THREE.DataArrayTexture(data, shape[2], shape[1], shape[0]);
  } else {
    tex = new THREE.Data3DTexture(data, shape[2], shape[1], shape[0]);
    tex.wrapR = THREE.ClampToEdgeWrapping;
  }
  tex.format = THREE.RGBAFormat;
  tex.type = THREE.FloatType;
  tex.minFilter = nearest ? THREE.NearestFilter : THREE.LinearFilter;
  tex.magFilter = nearest ? THREE.NearestFilter : THREE.LinearFilter;
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

// the GLSL struct SkydomeFitted filled from luts.json (export/glsl/fitted.glsl); the sun's
// distance is applied by the host code (skySunScale), so irradianceScale = 1
function fittedUniform(desc) {
  const g = desc.view_grid;
  const e = desc.elevation_axis;
  const se = desc.sun_elevation_axis;
  return {
    nSky: g.n_sky, nGround: g.n_ground, nPhi: g.n_phi, thetaH: g.theta_h_rad,
    invSky: g.inv_sky, invGround: g.inv_ground, eps: g.eps_rad, aPhi: g.a_phi,
    elevationFirstDeg: e.first_deg, elevationStepDeg: e.step_deg, elevationCount: e.count,
    sunElevationFirstDeg: se.first_deg, sunElevationStepDeg: se.step_deg,
    sunElevationCount: se.count, sunAngularRadius: desc.sun.angular_radius_rad,
    irradianceScale: 1.0,
    limb: desc.sun.limb_darkening.coefficients_xyz.map((c) => new THREE.Vector3(...c)),
  };
}

const FITTED_FORMAT = 'skydome.luts.fitted-xyz/1';

// 'precomputed' or 'fitted': the shader that draws the bake luts.json describes
function bakeKind(desc) {
  if (desc.format === FITTED_FORMAT) return 'fitted';
  if (desc.model === 'precomputed') return 'precomputed';
  throw new Error(`skydome-sky: luts.json model = ${JSON.stringify(desc.model)}, format = ` +
                  `${JSON.stringify(desc.format)}; drawn: 'precomputed' bakes and ` +
                  `'${FITTED_FORMAT}' bakes (skydome export luts --model precomputed or ` +
                  '--model fitted, --format bin)');
}

/** Fetch a bake (luts.json + .bin textures) and the shader that draws it.
 * @param {string|URL} lutsUrl folder of `skydome export luts --model precomputed` or
 *   `--model fitted` (with --format bin)
 * @param {{shaderUrl?: string|URL}} options shaderUrl: the shader (default: next to this
 *   module, precomputed.glsl or fitted.glsl as luts.json says)
 * @returns {Promise<{desc: object, textures: object, glsl: string, kind: string}>} */
export async function loadSkydomeLuts(lutsUrl, options = {}) {
  const base = new URL(String(lutsUrl).endsWith('/') ? String(lutsUrl) : `${lutsUrl}/`,
                       document.baseURI);
  const desc = await fetchOk(new URL('luts.json', base), 'description').then((r) => r.json());
  const kind = bakeKind(desc);
  if (kind === 'fitted' && !(desc.sun?.limb_darkening && desc.xyz_to_linear_srgb)) {
    throw new Error('skydome-sky: luts.json has no sun.limb_darkening or ' +
                    'xyz_to_linear_srgb (a fitted bake of an older skydome): export it again');
  }
  const shaderUrl = options.shaderUrl ?? new URL(`${kind}.glsl`, import.meta.url);
  const names = kind === 'fitted' ? ['sky', 'sun']
    : ['scattering', 'single_mie_scattering', 'multiple_scattering', 'transmittance',
       'optical_depth', 'irradiance_spectral'];
  for (const n of names) {
    const files = (desc.files ?? {})[n];
    if (!desc.textures[n] || (files && !files.includes(`${n}.bin`))) {
      throw new Error(`skydome-sky: ${n}.bin missing from the bake (export with --format bin)`);
    }
  }
  const how = kind === 'fitted' ? { layered: true, nearest: true } : {};
  const [glsl, ...list] = await Promise.all([
    fetchOk(shaderUrl, 'shader').then((r) => r.text()),
    ...names.map((n) => loadTexture(base, n, desc.textures[n], how))]);
  const textures = Object.fromEntries(names.map((n, i) => [n, list[i]]));
  return { desc, textures, glsl, kind };
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

// the host code around the shader: uniforms, the view direction, the sun's disc
const HOST_UNIFORMS = {
  precomputed: `
uniform sampler3D scatteringTex;
uniform sampler3D singleMieTex;
uniform sampler3D multipleTex;
uniform sampler2D transmittanceTex;
uniform sampler2D opticalDepthTex;
uniform sampler2DArray irradianceSpectralTex;
uniform SkydomeAtmosphere atm;
uniform vec3 skyCamera;        // from the planet's centre, East-North-Up [m]
uniform float skyCosDisc;      // cos of the disc's angular radius; 2 = no disc`,
  fitted: `
uniform sampler2DArray skyTex;
uniform sampler2D sunTex;
uniform SkydomeFitted fit;
uniform bool skyDisc;          // draw the sun's disc`,
};

// the radiance L (XYZ, cd m^-2 at 1 au) in direction v (East-North-Up)
const HOST_RADIANCE = {
  precomputed: `
  vec3 L = skydomeRadiance(scatteringTex, singleMieTex, multipleTex, transmittanceTex,
                           opticalDepthTex, irradianceSpectralTex, atm, skyCamera, v,
                           skySunDir);
  float r = length(skyCamera);
  if (dot(v, skySunDir) >= skyCosDisc
      && !skydomePcHitsGround(r, dot(skyCamera, v) / r, atm.bottomRadius)) {
    L += skydomeSunRadiance(opticalDepthTex, atm, r, dot(skyCamera, skySunDir) / r);
  }`,
  fitted: `
  vec3 vdx = dFdx(v);                         // the pixel's footprint, for the disc
  vec3 vdy = dFdy(v);
  vec3 L = skyDisc ? skydomeFittedSkyWithSunPixel(skyTex, sunTex, fit, v, vdx, vdy, skySunDir)
                   : skydomeFittedSky(skyTex, fit, v, skySunDir);`,
};

function fragmentShader(kind, glsl, equirect) {
  return `${glsl}
${HOST_UNIFORMS[kind]}
uniform vec3 skySunDir;        // East-North-Up
uniform float skyExposure;
uniform float skySunScale;
uniform bool skyOutputXYZ;
uniform mat3 skyXyzToRgb;
${equirect ? 'uniform vec2 skySize; uniform float skySpan;' : 'varying vec3 vDirection;'}
void main() {
${equirect ? `
  // skydome's Equirect: row from the top, azimuth = 360 deg col / W from north
  const float PI_ = 3.14159265358979;
  float row = skySize.y - gl_FragCoord.y;
  float el = 0.5 * PI_ - skySpan * row / skySize.y;
  float az = 2.0 * PI_ * gl_FragCoord.x / skySize.x;
  vec3 v = vec3(cos(el) * sin(az), cos(el) * cos(az), sin(el));` : `
  vec3 d = normalize(vDirection);
  vec3 v = vec3(d.x, -d.z, d.y);              // three.js (east, up, south) -> ENU`}
${HOST_RADIANCE[kind]}
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
  /** @param {{desc: object, textures: object, glsl: string, kind?: string}} luts from
   *   loadSkydomeLuts */
  constructor(luts) {
    const { desc, textures, glsl } = luts;
    const kind = luts.kind ?? bakeKind(desc);
    const m = desc.xyz_to_linear_srgb;
    const common = {
      skySunDir: { value: new THREE.Vector3(0, 0, 1) },
      skyExposure: { value: 1.0 },
      skySunScale: { value: 1.0 },
      skyOutputXYZ: { value: false },
      // luts.json's matrix is row-major; Matrix3.set takes rows
      skyXyzToRgb: { value: new THREE.Matrix3().set(...m[0], ...m[1], ...m[2]) },
    };
    const own = kind === 'fitted' ? {
      skyTex: { value: textures.sky },
      sunTex: { value: textures.sun },
      fit: { value: fittedUniform(desc) },
      skyDisc: { value: true },
    } : {
      scatteringTex: { value: textures.scattering },
      singleMieTex: { value: textures.single_mie_scattering },
      multipleTex: { value: textures.multiple_scattering },
      transmittanceTex: { value: textures.transmittance },
      opticalDepthTex: { value: textures.optical_depth },
      irradianceSpectralTex: { value: textures.irradiance_spectral },
      atm: { value: atmosphereUniform(desc) },
      skyCamera: { value: new THREE.Vector3(0, 0, desc.bottom_radius_m) },
      skyCosDisc: { value: Math.cos(desc.sun.disc_angular_radius_deg * DEG) },
    };
    const uniforms = { ...own, ...common };
    const material = new THREE.ShaderMaterial({
      name: 'SkydomeSky', uniforms, vertexShader: VERTEX_SKY,
      fragmentShader: fragmentShader(kind, glsl, false), side: THREE.BackSide,
      depthWrite: false,
    });
    super(new THREE.BoxGeometry(1, 1, 1), material);
    this.name = 'SkydomeSky';
    this.frustumCulled = false;
    this.renderOrder = -1;
    this.desc = desc;
    this.glsl = glsl;
    /** 'precomputed' or 'fitted': the bake's model */
    this.kind = kind;
    if (kind === 'fitted') {
      const e = desc.elevation_axis;
      this._elevationRange = [e.first_deg, e.first_deg + (e.count - 1) * e.step_deg];
    } else {
      this._elevationRange = [-90, 90];
      this._discCos = uniforms.skyCosDisc.value;
    }
    this.setSun(30, 180);
  }

  /** Sun elevation above the horizon and azimuth from north towards east [deg] (a fitted
   * bake: within its elevation axis, the model's range). */
  setSun(elevationDeg, azimuthDeg) {
    const el = Number(elevationDeg);
    const az = Number(azimuthDeg);
    const [lo, hi] = this._elevationRange;
    if (!Number.isFinite(el) || el < lo - 1e-9 || el > hi + 1e-9) {
      throw new RangeError(`sun elevation = ${elevationDeg}: valid range ${lo}..${hi} deg` +
                           (this.kind === 'fitted' ? ' (the fitted bake\'s range)' : ''));
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

  /** Observer altitude above the ground [m], 0..top of the atmosphere (a fitted bake:
   * the altitude it was baked for, model_parameters.observer_altitude_m, alone). */
  set altitude(m) {
    if (this.kind === 'fitted') {
      const h = this.altitude;
      if (m !== h) {
        throw new RangeError(`altitude = ${m}: this fitted bake is for ${h} m (export ` +
                             'another with skydome export luts --model fitted ' +
                             '--observer-altitude-m)');
      }
      return;
    }
    const top = this.desc.top_radius_m - this.desc.bottom_radius_m;
    if (!(m >= 0 && m <= top)) throw new RangeError(`altitude = ${m}: valid range 0..${top} m`);
    this.material.uniforms.skyCamera.value.set(0, 0, this.desc.bottom_radius_m + m);
  }

  get altitude() {
    if (this.kind === 'fitted') return this.desc.model_parameters.observer_altitude_m;
    return this.material.uniforms.skyCamera.value.z - this.desc.bottom_radius_m;
  }

  /** Multiplier from cd m^-2 to the renderer's linear values [m^2 cd^-1]. */
  set exposure(k) { this.material.uniforms.skyExposure.value = k; }

  get exposure() { return this.material.uniforms.skyExposure.value; }

  /** Sun's 1/d^2 factor (skydome's Sun.irradiance_scale), 1 = 1 au. */
  set sunScale(s) { this.material.uniforms.skySunScale.value = s; }

  get sunScale() { return this.material.uniforms.skySunScale.value; }

  /** Draw the sun's disc (default true). */
  set sunDisc(on) {
    const u = this.material.uniforms;
    if (this.kind === 'fitted') u.skyDisc.value = !!on;
    else u.skyCosDisc.value = on ? this._discCos : 2.0;
  }

  get sunDisc() {
    const u = this.material.uniforms;
    return this.kind === 'fitted' ? u.skyDisc.value : u.skyCosDisc.value <= 1.0;
  }

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
        vertexShader: VERTEX_QUAD, fragmentShader: fragmentShader(this.kind, this.glsl, true),
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
