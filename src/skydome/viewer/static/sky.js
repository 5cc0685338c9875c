// WebGL2 sky renderer: compiles each model's shader (common.glsl + <model>.glsl), renders
// linear XYZ into a float render target and shows it (display.glsl). No framework.

const VERT = `#version 300 es
in vec2 a_pos;
void main() { gl_Position = vec4(a_pos, 0.0, 1.0); }`;

const sources = new Map();
async function source(name) {
  if (!sources.has(name)) {
    const r = await fetch(`shaders/${name}.glsl`);
    if (!r.ok) throw new Error(`shader ${name}: HTTP ${r.status}`);
    sources.set(name, await r.text());
  }
  return sources.get(name);
}

// uniforms of each model, from the server's scene JSON (skydome.viewer.scene)
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
      const text = `#version 300 es\n#define NW ${nw}\n${await source("common")}\n${await source(model)}\n`;
      this.programs.set(key, this._link(text, model));
    }
    return this.programs.get(key);
  }

  async displayProgram() {
    if (!this.display) this.display = this._link(`#version 300 es\n${await source("display")}`, "display");
    return this.display;
  }

  // float RGBA32F render target of the given size
  _ensureTarget(w, h) {
    const gl = this.gl;
    if (this.target && this.target.w === w && this.target.h === h) return this.target;
    if (this.target) { gl.deleteTexture(this.target.tex); gl.deleteFramebuffer(this.target.fb); }
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
    this.target = { tex, fb, w, h };
    return this.target;
  }

  // Draw the views into the float target. views: [{scene, x0, w}] side by side (split view);
  // camera: {projection, fwd, right, up, tanHalfFov}.
  async renderXYZ(views, camera, w, h) {
    const gl = this.gl, t = this._ensureTarget(w, h);
    const progs = [];
    for (const v of views) progs.push(await this.program(v.scene.model, v.scene.wavelengths_nm?.length ?? 1));
    gl.bindFramebuffer(gl.FRAMEBUFFER, t.fb);
    gl.viewport(0, 0, w, h);
    gl.enable(gl.SCISSOR_TEST);
    gl.bindVertexArray(this.vao);
    views.forEach((v, k) => {
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
      SETTERS[v.scene.model](gl, u, v.scene);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    });
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
  async show(display) {
    const gl = this.gl, { tex, w, h } = this.target, { program, u } = await this.displayProgram();
    if (this.canvas.width !== w || this.canvas.height !== h) { this.canvas.width = w; this.canvas.height = h; }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, w, h);
    gl.useProgram(program);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.uniform1i(u("u_xyz"), 0);
    gl.uniform1i(u("u_mode"), display.mode);
    gl.uniform1f(u("u_white"), display.white);
    gl.uniform2f(u("u_log_range"), display.logLo, display.logHi);
    gl.bindVertexArray(this.vao);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
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
