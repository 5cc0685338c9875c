// The viewer page: controls -> /api/scene (skydome computes the shader's numbers) ->
// SkyRenderer (WebGL2) -> canvas. window.skydomeViewer exposes the same renderer to tests
// and to the benchmark (renderFloat, benchmark).
import { SkyRenderer, apiFetch, cameraAxes } from "./sky.js";

// false-colour stops, the same as ramp() in shaders/display.glsl
const RAMP = [[0, 0, 0], [0.1, 0.1, 0.8], [0, 0.7, 0.9], [0.1, 0.8, 0.2], [0.95, 0.9, 0.1],
              [0.9, 0.15, 0.1], [1, 1, 1]];

const $ = (id) => document.getElementById(id);
let renderer = null, models = {}, lastScenes = [], chromaGain = 1;
// the sky pass's times of the model (or pair) on screen, reset when it changes
let frameTimes = [], frameKey = "";
// the model the page opens on: skydome's default model
const DEFAULT_MODEL = "precomputed";

// A refused value: its message over the picture, and no picture under it (the canvas is
// cleared and dimmed while the error stands).
function showError(msg) {
  $("error").textContent = msg || "";
  if (msg) { renderer?.clearCanvas(); $("sky").classList.add("stale"); }
}

// The baking state: shown over a cleared canvas when the server takes longer than a
// moment to answer (a precomputed turbidity bakes tables for seconds); the controls stay
// usable, and the newest values are drawn when the answer comes.
let busyTimer = null, busyTick = null;
function startBusy(text) {
  stopBusy();
  busyTimer = setTimeout(() => {
    const t0 = performance.now();
    renderer?.clearCanvas();
    $("sky").classList.add("stale");
    $("busy").hidden = false;
    const tick = () => {
      $("busy-text").textContent = `${text} ${((performance.now() - t0) / 1000).toFixed(0)} s`;
    };
    tick();
    busyTick = setInterval(tick, 500);
  }, 300);
}
function stopBusy() {
  clearTimeout(busyTimer);
  clearInterval(busyTick);
  busyTimer = busyTick = null;
  $("busy").hidden = true;
}

// the precomputed turbidities this page has had drawn (the server keeps the last two)
const bakedTurbidity = new Set();
const defaultOf = (model, name) => models[model].parameters.find((p) => p.name === name)?.default;
function busyText(a, b, own) {
  for (const m of [a, b]) {
    if (m === "precomputed") {
      const T = m === a ? own.turbidity : defaultOf(m, "turbidity");
      if (!bakedTurbidity.has(String(T)))
        return `baking the precomputed model's tables for turbidity ${T} (about 10 s)...`;
    }
  }
  return `computing the scene (${[a, b].filter(Boolean).join(", ")})...`;
}

async function getJSON(url) {
  const r = await apiFetch(url);
  const body = await r.json();
  if (!r.ok) throw new Error(body.error || `HTTP ${r.status}`);
  return body;
}

export function sceneQuery(model, values) {
  const q = new URLSearchParams({ model });
  for (const [k, v] of Object.entries(values)) if (v !== undefined && v !== "") q.set(k, String(v));
  return q;
}

async function fetchScene(model, values) {
  return getJSON(`/api/scene?${sceneQuery(model, values)}`);
}

// -- the controls ----------------------------------------------------------------------
function paramControls(model) {
  const box = $("params");
  box.replaceChildren();
  for (const p of models[model].parameters) {
    const label = document.createElement("label");
    label.textContent = `${p.name}${p.unit ? ` [${p.unit}]` : ""} `;
    label.title = p.doc;
    let input;
    if (p.kind === "choice" || p.kind === "bool") {
      input = document.createElement("select");
      const choices = p.kind === "bool" ? [true, false] : p.choices;
      for (const c of choices) input.append(new Option(String(c), String(c), c === p.default, c === p.default));
    } else {
      input = document.createElement("input");
      input.type = "number";
      input.step = p.kind === "int" ? "1" : "any";
      if (p.low !== null) input.min = p.low;
      if (p.high !== null) input.max = p.high;
      input.value = p.default;
    }
    input.dataset.param = p.name;
    input.addEventListener("input", schedule);
    label.append(input);
    box.append(label);
  }
}

function modelValues() {
  const out = {};
  for (const el of $("params").querySelectorAll("[data-param]")) out[el.dataset.param] = el.value;
  return out;
}

function sunValues() {
  if (document.querySelector("input[name=sunmode]:checked").value === "place")
    return { lat: $("lat").value, lon: $("lon").value, time: $("time").value };
  return { sun_elevation: $("sun-el").value, sun_azimuth: $("sun-az").value };
}

function camera() {
  return cameraAxes(+$("view-az").value, +$("view-el").value, +$("fov").value, +$("projection").value);
}

function display() {
  // imaging.display.ev100_to_exposure: k = 1 / (1.2 x 2^EV100) [LdR14]
  const ev = Math.min(30, Math.max(-20, +$("ev100").value));
  return { mode: +$("mode").value, ev100: ev, k: 1 / (1.2 * 2 ** ev), transform: +$("transform").value,
           gain: $("hunt").checked ? chromaGain : 1,
           logLo: Math.log10(Math.max(+$("fc-lo").value, 1e-6)),
           logHi: Math.log10(Math.max(+$("fc-hi").value, 2e-6)) };
}

function updateOutputs() {
  for (const id of ["sun-el", "sun-az", "view-az", "view-el", "fov"]) $(`${id}-v`).textContent = $(id).value;
}

// -- drawing ---------------------------------------------------------------------------
let pending = false, busy = false;
function schedule() { pending = true; if (!busy) draw(); }

async function draw() {
  busy = true;
  while (pending) {
    pending = false;
    updateOutputs();
    try {
      const a = $("model").value, b = $("model-b").value;
      const own = modelValues(), sun = sunValues();
      startBusy(busyText(a, b, own));
      let scenes;
      try {
        scenes = [await fetchScene(a, { ...sun, ...own })];
        if (b) scenes.push(await fetchScene(b, { ...sun, ...(b === a ? own : {}) }));
      } finally {
        stopBusy();
      }
      if (a === "precomputed") bakedTurbidity.add(String(own.turbidity));
      if (b === "precomputed") bakedTurbidity.add(String(b === a ? own.turbidity : defaultOf(b, "turbidity")));
      if (pending) continue;            // newer values came in meanwhile: draw those
      lastScenes = scenes;
      const c = $("sky"), w = c.width, h = c.height, half = Math.floor(w / 2);
      const disc = $("sun-disc").checked;
      const views = scenes.length === 1 ? [{ scene: scenes[0], x0: 0, w, disc }]
        : [{ scene: scenes[0], x0: 0, w: half, disc }, { scene: scenes[1], x0: half, w: w - half, disc }];
      const t0 = performance.now();
      await renderer.renderXYZ(views, camera(), w, h);
      renderer.sync();
      const ms1 = performance.now() - t0;
      const la = adaptingLuminance(renderer.readXYZ());
      if ($("auto-exp").checked && la !== null) $("ev100").value = Math.log2(1 / (1.2 * 0.18 / la)).toFixed(2);
      chromaGain = la === null ? 1 : huntChromaGain(la);
      $("gain-v").textContent = $("hunt").checked ? chromaGain.toFixed(2) : "off";
      await renderer.show(display());
      $("sky").classList.remove("stale");
      const key = `${scenes.map((s) => s.model).join(" | ")} ${w}x${h}`;
      if (key !== frameKey) { frameTimes = []; frameKey = key; }
      frameTimes.push(ms1);
      if (frameTimes.length > 20) frameTimes.shift();
      const ms = frameTimes.reduce((s, v) => s + v, 0) / frameTimes.length;
      $("readout").textContent = `${scenes.map((s) => s.model).join(" | ")}: ${ms.toFixed(1)} ms/frame `
        + `sky pass (${w}x${h}, synced, mean of ${frameTimes.length})`;
      $("label-a").textContent = scenes.length > 1 ? scenes[0].model : "";
      $("label-b").textContent = scenes.length > 1 ? scenes[1].model : "";
      drawScale();
      showError("");
    } catch (e) {
      showError(e.message);
    }
  }
  busy = false;
}

function rampColour(t) {
  const x = Math.min(Math.max(t, 0), 1) * 6, k = Math.min(Math.floor(x), 5), f = x - k;
  return RAMP[k].map((v, i) => Math.round(255 * (v + (RAMP[k + 1][i] - v) * f)));
}

function drawScale() {
  const c = $("scale"), d = display();
  c.classList.toggle("on", d.mode === 1);
  if (d.mode !== 1) return;
  const g = c.getContext("2d"), w = c.width;
  g.clearRect(0, 0, w, c.height);
  for (let x = 0; x < w; ++x) {
    const [r, gg, b] = rampColour(x / (w - 1));
    g.fillStyle = `rgb(${r},${gg},${b})`;
    g.fillRect(x, 0, 1, 18);
  }
  g.fillStyle = "#ddd";
  g.font = "11px monospace";
  const n = Math.max(1, Math.round(d.logHi - d.logLo));
  for (let i = 0; i <= n; ++i) {
    const lg = d.logLo + (d.logHi - d.logLo) * i / n, x = (w - 1) * i / n;
    g.fillRect(x, 18, 1, 5);
    g.textAlign = i === 0 ? "left" : i === n ? "right" : "center";
    g.fillText(Number(10 ** lg).toPrecision(2), x, 34);
  }
  g.textAlign = "right";
  g.fillText("cd/m^2", w, 44);
}

// SkyImage.adapting_luminance: the log-average luminance of the sky pixels above the
// horizon (alpha 1), 0 < Y <= 1e5 cd/m^2, delta 1e-6 [Rei02] eq. 1; every rendered pixel
// if none is above the horizon; null if no pixel qualifies. It keys the auto exposure
// (SkyImage.auto_exposure: k = 0.18 / L, shown as its EV100, imaging.display.exposure_to_ev100)
// and the chroma gain.
function adaptingLuminance(xyz) {
  let s = 0, n = 0, below = 0, nb = 0;
  for (let i = 0; i < xyz.length; i += 4) {
    const Y = xyz[i + 1];
    if (!(Y > 0 && Y <= 1e5)) continue;
    if (xyz[i + 3] === 1) { s += Math.log(1e-6 + Y); n += 1; } else if (xyz[i + 3] > 0) { below += Math.log(1e-6 + Y); nb += 1; }
  }
  if (!n) { s = below; n = nb; }        // no sky above the horizon in view: every rendered pixel
  return n ? Math.exp(s / n) : null;
}

// imaging.display.luminance_adaptation_factor: F_L of [CIE159] eq. 7
function luminanceAdaptationFactor(la) {
  la = Math.max(la, 0);
  const k = 1 / (5 * la + 1), k4 = k ** 4;
  return 0.2 * k4 * (5 * la) + 0.1 * (1 - k4) ** 2 * Math.cbrt(5 * la);
}

// imaging.display.hunt_chroma_gain: (F_L(scene) / F_L(display))^(1/4), never below 1, with
// the display's adapting luminance a fifth of its 80 cd/m^2 white (DISPLAY_WHITE_CD_M2)
function huntChromaGain(la, displayWhite = 80) {
  return Math.max(1, (luminanceAdaptationFactor(la) / luminanceAdaptationFactor(displayWhite / 5)) ** 0.25);
}

function saveView() {
  const scenes = lastScenes, sun = scenes[0]?.sun;
  if (!sun) return;
  const cam = { projection: ["camera", "equirect-hemisphere", "fisheye", "equirect"][+$("projection").value],
                view_azimuth_deg: +$("view-az").value, view_elevation_deg: +$("view-el").value,
                fov_deg: +$("fov").value, width: $("sky").width, height: $("sky").height };
  const params = modelValues();
  const cli = ["skydome", "render", "--model", scenes[0].model,
               "--sun-elevation", String(sun.elevation_deg), "--sun-azimuth", String(sun.azimuth_deg)];
  for (const [k, v] of Object.entries(params)) cli.push(`--${k.replaceAll("_", "-")}`, String(v));
  // the CLI has no ground pinhole camera: a camera view is reproduced as the whole dome
  const proj = cam.projection === "camera" ? "fisheye" : cam.projection;
  const size = proj === "fisheye" ? String(Math.min(cam.width, cam.height)) : `${cam.width}x${cam.height}`;
  if (scenes[0].wavelengths_nm) cli.push("--wavelengths", String(scenes[0].wavelengths_nm.length));
  cli.push("--projection", proj, "--size", size);
  if (!$("sun-disc").checked) cli.push("--no-sun");
  cli.push("--out", "view.exr");
  if (scenes[0].model === "dobashi2002") {
    // the effect over the same synthetic scene on the CPU (`skydome airlight`; without shafts)
    cli.length = 0;
    cli.push("skydome", "airlight", "--synthetic", "--method", "dobashi2002",
             "--sun-elevation", String(sun.elevation_deg), "--sun-azimuth", String(sun.azimuth_deg),
             "--turbidity", String(params.turbidity), "--fov", String(cam.fov_deg),
             "--view-azimuth", String(cam.view_azimuth_deg), "--out", "view.png");
  }
  const json = { skydome_view: 1, models: scenes.map((s) => s.describe), sun, camera: cam,
                 display: display(), split: scenes.length > 1,
                 render_command: cli.join(" ") };
  const stamp = new Date().toISOString().replace(/[:.]/g, "-");
  const link = (href, name) => { const a = document.createElement("a"); a.href = href; a.download = name; a.click(); };
  $("sky").toBlob((blob) => {
    link(URL.createObjectURL(blob), `skydome-view-${stamp}.png`);
    link(URL.createObjectURL(new Blob([JSON.stringify(json, null, 2)], { type: "application/json" })),
         `skydome-view-${stamp}.json`);
  }, "image/png");
}

// drag: look around; shift-drag: put the sun in the pointed direction
function pointerDirection(ev) {
  const c = $("sky"), r = c.getBoundingClientRect();
  const px = (ev.clientX - r.left) * c.width / r.width, py = (r.bottom - ev.clientY) * c.height / r.height;
  const cam = camera();
  if (cam.projection !== 0) return null;
  const nx = 2 * px / c.width - 1, ny = 2 * py / c.height - 1, asp = c.height / c.width;
  const d = cam.fwd.map((f, i) => f + nx * cam.tanHalfFov * cam.right[i] + ny * cam.tanHalfFov * asp * cam.up[i]);
  const n = Math.hypot(...d);
  return d.map((v) => v / n);
}

function wireDrag() {
  const c = $("sky");
  let last = null;
  c.addEventListener("pointerdown", (ev) => { last = [ev.clientX, ev.clientY, ev.shiftKey]; c.setPointerCapture(ev.pointerId); });
  c.addEventListener("pointerup", () => { last = null; });
  c.addEventListener("pointermove", (ev) => {
    if (!last) return;
    if (last[2]) {
      const d = pointerDirection(ev);
      if (!d) return;
      $("sun-el").value = (Math.asin(d[2]) * 180 / Math.PI).toFixed(1);
      $("sun-az").value = ((Math.atan2(d[0], d[1]) * 180 / Math.PI + 360) % 360).toFixed(1);
      document.querySelector("input[name=sunmode][value=angles]").checked = true;
    } else {
      const k = +$("fov").value / c.getBoundingClientRect().width;
      $("view-az").value = ((+$("view-az").value - (ev.clientX - last[0]) * k + 360) % 360).toFixed(1);
      $("view-el").value = Math.min(90, Math.max(-30, +$("view-el").value + (ev.clientY - last[1]) * k)).toFixed(1);
      last = [ev.clientX, ev.clientY, false];
    }
    schedule();
  });
}

// -- the test and benchmark interface ----------------------------------------------------
// renderFloat(model, values, w, h, projection): XYZ per pixel, row 0 at the top, as a plain
// array of w*h*3 numbers (Y in cd/m^2); projection 1 = skydome's equirect-hemisphere.
// opts.camera: [view azimuth, elevation, field of view] of a camera view (projection 0);
// opts.output: dobashi2002's quantity (0 the scene, 1 in-scattered light, 2 transmittance
// as the XYZ of a white surface facing the sun, 3 the surface's distance [m] in X);
// opts.crop: [col0, row0, cols, rows] of the frame to return (default all);
// hillaire2020's aerial perspective to opts.distance [m] (1 in-scattered light, 2 the
// XYZ of sunlight through the transmittance); opts.disc: with the sun's disc (off by
// default: the model's sky alone, as the CPU model's xyz()).
async function renderFloat(model, values, w, h, projection = 1, opts = {}) {
  const scene = await fetchScene(model, values), [az, el, fov] = opts.camera || [180, 15, 90];
  await renderer.renderXYZ([{ scene, x0: 0, w, output: opts.output || 0, distance: opts.distance || 0,
                             disc: !!opts.disc }],
                          cameraAxes(az, el, fov, projection), w, h);
  const a = renderer.readXYZ();
  // opts.crop [col0, row0, cols, rows]: only that rectangle (row 0 at the top)
  const [c0, r0, cw, ch] = opts.crop || [0, 0, w, h], out = new Array(cw * ch * 3);
  for (let r = 0, j = 0; r < ch; ++r)
    for (let c = 0; c < cw; ++c, j += 3) {
      const i = 4 * ((r0 + r) * w + c0 + c);
      out[j] = a[i]; out[j + 1] = a[i + 1]; out[j + 2] = a[i + 2];
    }
  return out;
}

// benchmark(model, values, n, w, h, camera): mean ms per frame over n synced frames after
// one warm-up; camera [view azimuth, elevation, field of view] (default south, 15 deg up, 90 deg).
async function benchmark(model, values, n = 20, w = 1920, h = 1080, camera = [180, 15, 90]) {
  const scene = await fetchScene(model, values), cam = cameraAxes(...camera, 0);
  await renderer.renderXYZ([{ scene, x0: 0, w }], cam, w, h);
  renderer.sync();
  const t0 = performance.now();
  for (let i = 0; i < n; ++i) { await renderer.renderXYZ([{ scene, x0: 0, w }], cam, w, h); renderer.sync(); }
  return (performance.now() - t0) / n;
}

// sample([[u, v], ...]): XYZ of the shown frame at fractions (u across, v down) of the view.
function sample(points) {
  const xyz = renderer.readXYZ(), { w, h } = renderer.target;
  return points.map(([u, v]) => {
    const c = Math.min(w - 1, Math.floor(u * w)), r = Math.min(h - 1, Math.floor(v * h)), i = 4 * (r * w + c);
    return [xyz[i], xyz[i + 1], xyz[i + 2]];
  });
}

const idle = () => !busy && !pending;

// displayColours(xyz, ev100, transform, hunt): the display pass on linear XYZ colours, 8-bit
// RGB; with hunt, the chroma gain of the colours' own adapting luminance (as SkyImage.save
// computes it for a picture of these colours). Returns { rgb, gain }.
async function displayColours(xyz, ev100, transform = 0, hunt = true) {
  const flat = new Float32Array(4 * xyz.length);
  xyz.forEach((c, i) => flat.set([c[0], c[1], c[2], 1], 4 * i));
  const la = adaptingLuminance(flat), gain = hunt && la !== null ? huntChromaGain(la) : 1;
  const rgb = await renderer.displayColours(xyz, { mode: 0, k: 1 / (1.2 * 2 ** ev100), transform, gain, logLo: 0, logHi: 1 });
  return { rgb, gain };
}

async function main() {
  try {
    renderer = new SkyRenderer($("sky"));
  } catch (e) {
    showError(e.message);
    return;
  }
  window.skydomeViewer = { renderFloat, benchmark, sample, idle, displayColours, ready: false };
  try {
    models = await getJSON("/api/models");
  } catch (e) {
    showError(e.message);
    return;
  }
  for (const name of Object.keys(models)) {
    $("model").append(new Option(name, name, name === DEFAULT_MODEL, name === DEFAULT_MODEL));
    $("model-b").append(new Option(name, name));
  }
  paramControls($("model").value);
  $("model").addEventListener("change", () => { paramControls($("model").value); schedule(); });
  for (const id of ["model-b", "sun-el", "sun-az", "lat", "lon", "time", "projection", "view-az",
                    "view-el", "fov", "mode", "transform", "hunt", "ev100", "fc-lo", "fc-hi"])
    $(id).addEventListener("input", schedule);
  // a slider's value shows at once, also while the server is still busy with a bake
  for (const id of ["sun-el", "sun-az", "view-az", "view-el", "fov"]) $(id).addEventListener("input", updateOutputs);
  for (const el of document.querySelectorAll("input[name=sunmode]")) el.addEventListener("change", schedule);
  $("auto-exp").addEventListener("change", schedule);
  $("sun-disc").addEventListener("change", schedule);
  $("save").addEventListener("click", saveView);
  wireDrag();
  pending = true;
  await draw();
  window.skydomeViewer.ready = true;
}

main();
