// WebGL2 sky renderer: compiles each model's shader (common.glsl + <model>.glsl), renders
// linear XYZ into a float render target and shows it (display.glsl). No framework.

const VERT = `#version 300 es
in vec2 a_pos;
void main() { gl_Position = vec4(a_pos, 0.0, 1.0); }`;

// apiFetch(url): GET an /api/ URL with the page's token (written into the page by the
// server at each start); the server refuses /api/ requests without it (403).
export function apiFetch(url) {
  const meta = document.querySelector('meta[name="skydome-token"]');
  return fetch(url, { headers: { "X-Skydome-Token": meta ? meta.content : "" },
                      credentials: "same-origin", cache: "no-store" });
}

const sources = new Map();
async function source(name) {
  if (!sources.has(name)) {
    const r = await fetch(`shaders/${name}.glsl`);
    if (!r.ok) throw new Error(`shader ${name}: HTTP ${r.status}`);
    sources.set(name, await r.text());
  }
  return sources.get(name);
}

// uniforms of each shader (the scene's "shader", a model's viewer_shader), from the server's
// scene JSON (skydome.viewer.scene)
const SETTERS = {
  preetham1999(gl, u, s) {
    gl.uniform1fv(u("u_coef"), s.coef.flat());
    gl.uniform3fv(u("u_zen"), s.zenith);
    gl.uniform1f(u("u_cos_floor"), s.cos_floor);
  },
  hoffman_preetham2002(gl, u, s) {
    const n = s.wavelengths_nm.length, spec = new Float32Array(4 * n);
    for (let i = 0; i < n; ++i) spec.set([s.beta_r[i], s.beta_m[i], s.e_sun[i], 0], 4 * i);
    gl.uniform4fv(u("u_spec"), spec);
    gl.uniform3fv(u("u_cmf"), s.xyz_weights.flat());
    gl.uniform1f(u("u_g"), s.g);
    gl.uniform1i(u("u_hp_phase"), s.hp_phase);
    gl.uniform1f(u("u_shell_m"), s.shell_m);
    gl.uniform1f(u("u_earth_radius_m"), s.earth_radius_m);
  },
  oneil2005(gl, u, s) {
    const n = s.wavelengths_nm.length, spec = new Float32Array(4 * n);
    for (let i = 0; i < n; ++i) spec.set([s.inv_wl4[i], s.e_sun[i], 0, 0], 4 * i);
    gl.uniform4fv(u("u_spec"), spec);
    gl.uniform3fv(u("u_cmf"), s.xyz_weights.flat());
    for (const k of ["kr", "km", "g", "scale_depth", "outer_ratio"]) gl.uniform1f(u(`u_${k}`), s[k]);
    gl.uniform1i(u("u_samples"), s.samples);
  },
};
SETTERS.hillaire2020 = (gl, u, s) => {
  gl.uniform1i(u("u_skyview"), 3);
  gl.uniform1i(u("u_ap_l"), 9);
  gl.uniform1i(u("u_ap_t"), 10);
  gl.uniform1i(u("u_ap_size"), s.ap_size);
  gl.uniform1f(u("u_ap_km_per_slice"), s.ap_km_per_slice);
  gl.uniform3fv(u("u_sun_xyz"), s.sun_xyz);
  gl.uniform2i(u("u_sv_size"), ...s.sv_size);
  gl.uniform1f(u("u_R"), s.R);
  gl.uniform1f(u("u_h0"), s.h0);
};

SETTERS.precomputed = (gl, u, s) => {
  gl.uniform1i(u("u_ms"), 4);
  gl.uniform1i(u("u_ss0"), 5);
  gl.uniform1i(u("u_ss1"), s.nsc > 1 ? 6 : 5);
  gl.uniform4i(u("u_sizes"), ...s.sizes);
  for (const k of ["R", "Rt", "mu_s_min", "h0", "irradiance_scale"]) gl.uniform1f(u(`u_${k}`), s[k]);
  gl.uniform1i(u("u_nsc"), s.nsc);
  gl.uniform2i(u("u_pc"), ...s.pc);
  gl.uniform2f(u("u_pp"), ...s.pp);
  gl.uniform1i(u("u_tr"), 11);
  gl.uniform1i(u("u_irr"), 12);
  gl.uniform3i(u("u_ground_sizes"), s.textures.transmittance_spectral[1], s.textures.transmittance_spectral[2],
               s.textures.irradiance_spectral[2]);
  gl.uniform1i(u("u_nl"), s.nl);
  gl.uniform1fv(u("u_albedo"), new Float32Array(16).fill(0).map((_, i) => s.albedo[i] ?? 0));
  gl.uniform3fv(u("u_K"), new Float32Array(48).fill(0).map((_, i) => s.K[i] ?? 0));
  gl.uniform1f(u("u_sun_alpha"), s.sun_alpha);
};

SETTERS.dobashi2002 = (gl, u, s) => {
  gl.uniform1i(u("u_tables"), 7);
  gl.uniform1i(u("u_grid"), 8);
  gl.uniform2i(u("u_table_size"), ...s.table_size);
  gl.uniform2f(u("u_mu_range"), ...s.mu_range);
  gl.uniform1f(u("u_extent"), s.extent_m);
  gl.uniform2i(u("u_grid_size"), ...s.grid_size);
  gl.uniform2f(u("u_grid_origin"), ...s.grid_origin);
  gl.uniform2f(u("u_grid_step"), ...s.grid_step);
  gl.uniform1f(u("u_hmax"), s.hmax);
  gl.uniform3fv(u("u_eye"), s.eye);
  gl.uniform1f(u("u_planet_radius"), s.planet_radius_m);
  gl.uniform1f(u("u_datum_radius"), s.datum_radius_m);
  for (const k of ["march_steps", "nc", "shafts", "n_planes"]) gl.uniform1i(u(`u_${k}`), s[k]);
  gl.uniform4iv(u("u_phase_codes"), s.phase_codes);
  gl.uniform4fv(u("u_phase_params"), s.phase_params);
  gl.uniform4fv(u("u_ext"), s.ext);
  gl.uniform3fv(u("u_tw"), s.t_weights.flat());
  gl.uniform3fv(u("u_albedo"), s.albedo);
  gl.uniform1f(u("u_fill"), s.fill);
  gl.uniformMatrix3fv(u("u_srgb_to_xyz"), false, s.srgb_to_xyz);
  gl.uniformMatrix3fv(u("u_xyz_to_srgb"), false, s.xyz_to_srgb);
};

SETTERS.fitted = (gl, u, s) => {
  gl.uniform1i(u("u_fitted"), 13);
  gl.uniform3i(u("u_fitted_n"), ...s.n);
  for (const k of ["theta_h", "inv_sky", "inv_ground", "eps", "a_phi"]) gl.uniform1f(u(`u_${k}`), s[k]);
  gl.uniform2f(u("u_sun_az"), ...s.sun_az);
};

// extra shader sources a model's program includes between common.glsl and its own
const INCLUDES = { precomputed: ["transport"], dobashi2002: ["transport"] };

function f32FromBase64(b64) {
  const bin = atob(b64), bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
  return new Float32Array(bytes.buffer);
}

// Per-frame passes that a model needs before its sky pass: hillaire2020 renders its
// sky-view LUT ([Hil20] 5.3) from the transmittance and multiple-scattering LUTs.
const PREPASSES = {
  // precomputed: upload the baked tables (once per bake) as RGBA32F 3-D textures
  async precomputed(r, s) {
    const gl = r.gl;
    if (r.precomputed?.key !== s.lut_key) {
      if (r.precomputed) for (const [, t] of r.precomputed.tex) gl.deleteTexture(t);
      // texture units: scattering tables 4-6, the ground's spectral tables 11-12 (hillaire2020 has 1-3 and 9-10, dobashi2002 7-8)
      const units = { multiple_scattering: 4, single_scattering_0: 5, single_scattering_1: 6,
                      transmittance_spectral: 11, irradiance_spectral: 12 };
      const tex = [];
      for (const name of Object.keys(units).filter((n) => n in s.textures)) {
        const resp = await apiFetch(`/api/lut?${new URLSearchParams({ key: s.lut_key, name })}`);
        if (!resp.ok) throw new Error(`table ${name}: ${(await resp.json()).error}`);
        const data = new Float32Array(await resp.arrayBuffer());
        const [d, h, w] = s.textures[name];
        const t = gl.createTexture();
        gl.activeTexture(gl.TEXTURE0 + units[name]);
        gl.bindTexture(gl.TEXTURE_3D, t);
        gl.texStorage3D(gl.TEXTURE_3D, 1, gl.RGBA32F, w, h, d);
        gl.texSubImage3D(gl.TEXTURE_3D, 0, 0, 0, 0, w, h, d, gl.RGBA, gl.FLOAT, data);
        for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_3D, p, gl.NEAREST);
        tex.push([units[name], t]);
      }
      r.precomputed = { key: s.lut_key, tex };
    }
    r.precomputed.tex.forEach(([unit, t]) => { gl.activeTexture(gl.TEXTURE0 + unit); gl.bindTexture(gl.TEXTURE_3D, t); });
    gl.activeTexture(gl.TEXTURE0);
  },

  // fitted: upload the configuration's XYZ table (once per scene) as an RGBA32F texture
  // on unit 13, read with texelFetch (the shader interpolates as the CPU kernel does)
  async fitted(r, s) {
    const gl = r.gl;
    if (r.fitted?.scene !== s) {
      if (r.fitted) gl.deleteTexture(r.fitted.tex);
      const [ns, ng, np] = s.n, tex = gl.createTexture();
      gl.activeTexture(gl.TEXTURE13);
      gl.bindTexture(gl.TEXTURE_2D, tex);
      gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, np, ns + ng);
      gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, np, ns + ng, gl.RGBA, gl.FLOAT, f32FromBase64(s.table_b64));
      for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
      r.fitted = { scene: s, tex };
    }
    gl.activeTexture(gl.TEXTURE13); gl.bindTexture(gl.TEXTURE_2D, r.fitted.tex);
    gl.activeTexture(gl.TEXTURE0);
  },

  // dobashi2002: upload the [DYN02] tables and the heightmap grid (once per turbidity and sun)
  async dobashi2002(r, s) {
    const gl = r.gl;
    if (r.dobashi?.key !== s.lut_key) {
      if (r.dobashi) { gl.deleteTexture(r.dobashi.tables); gl.deleteTexture(r.dobashi.grid); }
      const nearest = (target) => {
        for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(target, p, gl.NEAREST);
      };
      const tables = gl.createTexture();
      gl.activeTexture(gl.TEXTURE7);
      gl.bindTexture(gl.TEXTURE_2D_ARRAY, tables);
      const [na, nd] = s.table_size;
      gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, gl.RGBA32F, na, nd, s.nc);
      gl.texSubImage3D(gl.TEXTURE_2D_ARRAY, 0, 0, 0, 0, na, nd, s.nc, gl.RGBA, gl.FLOAT, f32FromBase64(s.tables_b64));
      nearest(gl.TEXTURE_2D_ARRAY);
      const grid = gl.createTexture();
      gl.activeTexture(gl.TEXTURE8);
      gl.bindTexture(gl.TEXTURE_2D, grid);
      const [nx, ny] = s.grid_size;
      gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, nx, ny);
      gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, nx, ny, gl.RGBA, gl.FLOAT, f32FromBase64(s.grid_b64));
      nearest(gl.TEXTURE_2D);
      r.dobashi = { key: s.lut_key, tables, grid };
    }
    gl.activeTexture(gl.TEXTURE7); gl.bindTexture(gl.TEXTURE_2D_ARRAY, r.dobashi.tables);
    gl.activeTexture(gl.TEXTURE8); gl.bindTexture(gl.TEXTURE_2D, r.dobashi.grid);
    gl.activeTexture(gl.TEXTURE0);
  },

  async hillaire2020(r, s) {
    const gl = r.gl;
    if (r.hillaire?.key !== s.lut_key) {
      const up = (b64, [w, h], unit) => {
        const tex = gl.createTexture();
        gl.activeTexture(gl.TEXTURE0 + unit);
        gl.bindTexture(gl.TEXTURE_2D_ARRAY, tex);
        gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, gl.RGBA32F, w, h, s.ng);
        gl.texSubImage3D(gl.TEXTURE_2D_ARRAY, 0, 0, 0, 0, w, h, s.ng, gl.RGBA, gl.FLOAT, f32FromBase64(b64));
        for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D_ARRAY, p, gl.NEAREST);
        return tex;
      };
      if (r.hillaire) { gl.deleteTexture(r.hillaire.tlut); gl.deleteTexture(r.hillaire.mslut); }
      r.hillaire = { key: s.lut_key, tlut: up(s.tlut_b64, s.tlut_size, 1), mslut: up(s.mslut_b64, s.mslut_size, 2) };
    }
    const [w, h] = s.sv_size;
    const key = `hillaire2020_lut/${s.ng}`;
    if (!r.programs.has(key)) {
      const text = `#version 300 es\n#define NG ${s.ng}\nprecision highp float;\nprecision highp int;\nconst float PI = 3.14159265358979;\n${await source("transport")}\n${await source("hillaire2020_lut")}`;
      r.programs.set(key, r._link(text, "hillaire2020_lut"));
    }
    const { program, u } = r.programs.get(key);
    const t = r._ensureAux("skyview", w, h);
    gl.bindFramebuffer(gl.FRAMEBUFFER, t.fb);
    gl.viewport(0, 0, w, h);
    gl.disable(gl.SCISSOR_TEST);
    gl.useProgram(program);
    gl.activeTexture(gl.TEXTURE1); gl.bindTexture(gl.TEXTURE_2D_ARRAY, r.hillaire.tlut);
    gl.activeTexture(gl.TEXTURE2); gl.bindTexture(gl.TEXTURE_2D_ARRAY, r.hillaire.mslut);
    gl.uniform1i(u("u_tlut"), 1);
    gl.uniform1i(u("u_mslut"), 2);
    gl.uniform2i(u("u_tlut_size"), ...s.tlut_size);
    gl.uniform2i(u("u_mslut_size"), ...s.mslut_size);
    gl.uniform2i(u("u_sv_size"), w, h);
    for (const k of ["R", "Rt", "h0", "ts"]) gl.uniform1f(u(`u_${k}`), s[k]);
    gl.uniform1f(u("u_sz"), s.sun.direction[2]);
    gl.uniform1i(u("u_n_steps"), s.n_steps);
    gl.uniform1i(u("u_use_ms"), s.use_ms);
    gl.uniform1i(u("u_nc"), s.nc);
    gl.uniform4iv(u("u_codes"), s.codes);
    gl.uniform4fv(u("u_p0"), s.p0);
    gl.uniform4fv(u("u_p1"), s.p1);
    gl.uniform4iv(u("u_phase_codes"), s.phase_codes);
    gl.uniform4fv(u("u_phase_params"), s.phase_params);
    gl.uniform4fv(u("u_beta_s"), s.beta_s);
    gl.uniform4fv(u("u_beta_e"), s.beta_e);
    gl.uniform4fv(u("u_albedo"), s.albedo);
    gl.uniform3fv(u("u_K"), s.K.flat());
    gl.bindVertexArray(r.vao);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    // the aerial-perspective volume ([Hil20] 5.4): n^3 froxels as an (n n) x n 2-D
    // target pair (in-scattering, transmittance), the same march per froxel
    const n = s.ap_size, apKey = `hillaire2020_ap/${s.ng}`;
    if (!r.programs.has(apKey)) {
      const text = `#version 300 es\n#define NG ${s.ng}\n#define AP_VOLUME 1\nprecision highp float;\nprecision highp int;\nconst float PI = 3.14159265358979;\n${await source("transport")}\n${await source("hillaire2020_lut")}`;
      r.programs.set(apKey, r._link(text, "hillaire2020_ap"));
    }
    const ap = r._ensureAuxMRT("aerial", n * n, n);
    const pa = r.programs.get(apKey);
    gl.bindFramebuffer(gl.FRAMEBUFFER, ap.fb);
    gl.viewport(0, 0, n * n, n);
    gl.useProgram(pa.program);
    for (const [name, fn] of [["u_tlut", 1], ["u_mslut", 2]]) gl.uniform1i(pa.u(name), fn);
    gl.uniform2i(pa.u("u_tlut_size"), ...s.tlut_size);
    gl.uniform2i(pa.u("u_mslut_size"), ...s.mslut_size);
    for (const k of ["R", "Rt", "h0", "ts"]) gl.uniform1f(pa.u(`u_${k}`), s[k]);
    gl.uniform1f(pa.u("u_sz"), s.sun.direction[2]);
    gl.uniform1i(pa.u("u_n_steps"), s.ap_samples);
    gl.uniform1i(pa.u("u_use_ms"), s.use_ms);
    gl.uniform1i(pa.u("u_nc"), s.nc);
    gl.uniform4iv(pa.u("u_codes"), s.codes);
    gl.uniform4fv(pa.u("u_p0"), s.p0);
    gl.uniform4fv(pa.u("u_p1"), s.p1);
    gl.uniform4iv(pa.u("u_phase_codes"), s.phase_codes);
    gl.uniform4fv(pa.u("u_phase_params"), s.phase_params);
    gl.uniform4fv(pa.u("u_beta_s"), s.beta_s);
    gl.uniform4fv(pa.u("u_beta_e"), s.beta_e);
    gl.uniform4fv(pa.u("u_albedo"), s.albedo);
    gl.uniform3fv(pa.u("u_K"), s.K.flat());
    gl.uniform3fv(pa.u("u_KT"), s.KT.flat());
    gl.uniform1i(pa.u("u_ap_size"), n);
    gl.uniform1f(pa.u("u_ap_km_per_slice"), s.ap_km_per_slice);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    gl.activeTexture(gl.TEXTURE3);
    gl.bindTexture(gl.TEXTURE_2D, t.tex);
    gl.activeTexture(gl.TEXTURE9);
    gl.bindTexture(gl.TEXTURE_2D, ap.tex[0]);
    gl.activeTexture(gl.TEXTURE10);
    gl.bindTexture(gl.TEXTURE_2D, ap.tex[1]);
    gl.activeTexture(gl.TEXTURE0);
  },
};

export const MODELS = Object.keys(SETTERS);

export class SkyRenderer {
  constructor(canvas) {
    const gl = canvas.getContext("webgl2", { antialias: false, preserveDrawingBuffer: true });
    if (!gl) throw new Error("WebGL2 is not available in this browser");
    if (!gl.getExtension("EXT_color_buffer_float"))
      throw new Error("EXT_color_buffer_float is not available: no float render targets");
    this.gl = gl;
    this.canvas = canvas;
    this.programs = new Map();
    this.timer = gl.getExtension("EXT_disjoint_timer_query_webgl2");
    const buf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, buf);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
    this.vao = gl.createVertexArray();
    gl.bindVertexArray(this.vao);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
    this.target = null;
  }

  _compile(type, text, label) {
    const gl = this.gl, sh = gl.createShader(type);
    gl.shaderSource(sh, text);
    gl.compileShader(sh);
    if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS))
      throw new Error(`${label}: ${gl.getShaderInfoLog(sh)}`);
    return sh;
  }

  _link(fragText, label) {
    const gl = this.gl, p = gl.createProgram();
    gl.attachShader(p, this._compile(gl.VERTEX_SHADER, VERT, "vertex"));
    gl.attachShader(p, this._compile(gl.FRAGMENT_SHADER, fragText, label));
    gl.bindAttribLocation(p, 0, "a_pos");
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(`${label}: ${gl.getProgramInfoLog(p)}`);
    const cache = new Map();
    const u = (name) => {
      if (!cache.has(name)) cache.set(name, gl.getUniformLocation(p, name));
      return cache.get(name);
    };
    return { program: p, u };
  }

  async program(model, nw) {
    const key = `${model}/${nw}`;
    if (!this.programs.has(key)) {
      let inc = "";
      for (const name of INCLUDES[model] || []) inc += `${await source(name)}\n`;
      const text = `#version 300 es\n#define NW ${nw}\n${await source("common")}\n${inc}${await source(model)}\n`;
      this.programs.set(key, this._link(text, model));
    }
    return this.programs.get(key);
  }

  async displayProgram() {
    if (!this.display) this.display = this._link(`#version 300 es\n${await source("display")}`, "display");
    return this.display;
  }

  // float RGBA32F render target of the given size
  _makeTarget(w, h) {
    const gl = this.gl;
    const tex = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, w, h);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    const fb = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
    const st = gl.checkFramebufferStatus(gl.FRAMEBUFFER);
    if (st !== gl.FRAMEBUFFER_COMPLETE) throw new Error(`float render target incomplete (0x${st.toString(16)})`);
    return { tex, fb, w, h };
  }

  _ensureTarget(w, h) {
    if (this.target && this.target.w === w && this.target.h === h) return this.target;
    if (this.target) { this.gl.deleteTexture(this.target.tex); this.gl.deleteFramebuffer(this.target.fb); }
    this.target = this._makeTarget(w, h);
    return this.target;
  }

  _ensureAux(name, w, h) {
    this.aux = this.aux || {};
    const t = this.aux[name];
    if (t && t.w === w && t.h === h) return t;
    if (t) { this.gl.deleteTexture(t.tex); this.gl.deleteFramebuffer(t.fb); }
    return (this.aux[name] = this._makeTarget(w, h));
  }

  // two float targets drawn by one pass (gl.drawBuffers)
  _ensureAuxMRT(name, w, h) {
    this.aux = this.aux || {};
    const t = this.aux[name], gl = this.gl;
    if (t && t.w === w && t.h === h) return t;
    const tex = [0, 1].map(() => {
      const x = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, x);
      gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, w, h);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      return x;
    });
    const fb = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    tex.forEach((x, i) => gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0 + i, gl.TEXTURE_2D, x, 0));
    gl.drawBuffers([gl.COLOR_ATTACHMENT0, gl.COLOR_ATTACHMENT1]);
    const st = gl.checkFramebufferStatus(gl.FRAMEBUFFER);
    if (st !== gl.FRAMEBUFFER_COMPLETE) throw new Error(`float render targets incomplete (0x${st.toString(16)})`);
    return (this.aux[name] = { tex, fb, w, h });
  }

  // Draw the views into the float target. views: [{scene, x0, w, disc}] side by side (split
  // view; disc: draw the sun's disc);
  // camera: {projection, fwd, right, up, tanHalfFov}.
  async renderXYZ(views, camera, w, h) {
    const gl = this.gl, t = this._ensureTarget(w, h);
    const progs = [];
    for (const v of views) progs.push(await this.program(v.scene.shader, v.scene.wavelengths_nm?.length ?? 1));
    gl.bindVertexArray(this.vao);
    for (let k = 0; k < views.length; ++k) {
      const v = views[k], pre = PREPASSES[v.scene.shader];
      if (pre) await pre(this, v.scene);
      gl.bindFramebuffer(gl.FRAMEBUFFER, t.fb);
      gl.viewport(0, 0, w, h);
      gl.enable(gl.SCISSOR_TEST);
      const { program, u } = progs[k];
      gl.useProgram(program);
      gl.scissor(v.x0, 0, v.w, h);
      gl.uniform4f(u("u_viewport"), 0, 0, w, h);
      gl.uniform1i(u("u_projection"), camera.projection);
      gl.uniform3fv(u("u_fwd"), camera.fwd);
      gl.uniform3fv(u("u_right"), camera.right);
      gl.uniform3fv(u("u_up"), camera.up);
      gl.uniform1f(u("u_tan_half_fov"), camera.tanHalfFov);
      gl.uniform3fv(u("u_sun"), v.scene.sun.direction);
      gl.uniform1i(u("u_shows_ground"), ["hillaire2020", "precomputed", "dobashi2002", "fitted"].includes(v.scene.shader) ? 1 : 0);
      gl.uniform1i(u("u_output"), v.output || 0);
      gl.uniform1f(u("u_ap_distance"), v.distance || 0);
      SETTERS[v.scene.shader](gl, u, v.scene);
      // the sun's disc (common.glsl: with_sun_disc): views that ask for it (v.disc), for
      // the sky itself (output 0), where the model has a sun above minus its radius
      const disc = v.disc && !v.output ? v.scene.sun_disc : null;
      gl.uniform1i(u("u_disc_on"), disc ? 1 : 0);
      if (disc) {
        gl.uniform3fv(u("u_disc_L"), disc.xyz);
        gl.uniform1f(u("u_disc_alpha"), disc.alpha);
        gl.uniform3fv(u("u_limb"), disc.limb);
      }
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    }
    gl.disable(gl.SCISSOR_TEST);
    return t;
  }

  // Read the float target back: Float32Array of w*h*4 (X, Y, Z, mask), row 0 at the top.
  readXYZ() {
    const gl = this.gl, { fb, w, h } = this.target;
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    const buf = new Float32Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, buf);
    const out = new Float32Array(w * h * 4);
    for (let r = 0; r < h; ++r) out.set(buf.subarray((h - 1 - r) * w * 4, (h - r) * w * 4), r * w * 4);
    return out;
  }

  // Show the float target on the canvas: mode 0 exposure + sRGB, 1 false colour.
  async show(display, source = this.target, fb = null) {
    const gl = this.gl, { tex, w, h } = source, { program, u } = await this.displayProgram();
    if (!fb && (this.canvas.width !== w || this.canvas.height !== h)) { this.canvas.width = w; this.canvas.height = h; }
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    gl.viewport(0, 0, w, h);
    gl.useProgram(program);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.uniform1i(u("u_xyz"), 0);
    gl.uniform1i(u("u_mode"), display.mode);
    gl.uniform1f(u("u_k"), display.k);
    gl.uniform1i(u("u_transform"), display.transform);
    gl.uniform1f(u("u_gain"), display.gain ?? 1);
    gl.uniform2f(u("u_log_range"), display.logLo, display.logHi);
    gl.bindVertexArray(this.vao);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  // The display pass applied to a list of linear XYZ colours: [[r, g, b] 0..255, ...] as
  // read back from an 8-bit target (for the test against imaging/display.py).
  async displayColours(xyz, display) {
    const gl = this.gl, n = xyz.length, src = this._ensureAux("colours", n, 1);
    const data = new Float32Array(4 * n);
    xyz.forEach((c, i) => data.set([c[0], c[1], c[2], 1], 4 * i));
    gl.bindTexture(gl.TEXTURE_2D, src.tex);
    gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, n, 1, gl.RGBA, gl.FLOAT, data);
    const tex = gl.createTexture(), fb = gl.createFramebuffer();
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA8, n, 1);
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
    await this.show(display, src, fb);
    const px = new Uint8Array(4 * n);
    gl.readPixels(0, 0, n, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    gl.deleteFramebuffer(fb);
    gl.deleteTexture(tex);
    return Array.from({ length: n }, (_, i) => [px[4 * i], px[4 * i + 1], px[4 * i + 2]]);
  }

  // Clear the canvas (no picture: while an error stands or tables bake).
  clearCanvas() {
    const gl = this.gl;
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.clearColor(0, 0, 0, 1);
    gl.clear(gl.COLOR_BUFFER_BIT);
  }

  // Block until the GPU has finished (a one-pixel read), for frame timing.
  sync() {
    const gl = this.gl, px = new Float32Array(4);
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.target.fb);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.FLOAT, px);
  }
}

// Camera axes from a view azimuth (from north towards east) and elevation [deg].
export function cameraAxes(azDeg, elDeg, fovDeg, projection = 0) {
  const a = azDeg * Math.PI / 180, e = elDeg * Math.PI / 180;
  const fwd = [Math.cos(e) * Math.sin(a), Math.cos(e) * Math.cos(a), Math.sin(e)];
  let right = [Math.cos(a), -Math.sin(a), 0];
  const up = [right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
              right[0] * fwd[1] - right[1] * fwd[0]];
  return { projection, fwd, right, up, tanHalfFov: Math.tan(0.5 * fovDeg * Math.PI / 180) };
}
