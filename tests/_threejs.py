"""Shared parts of the three.js tests (tests/test_threejs.py, tests/test_threejs_fitted.py):
npm's three as the set-up vendors it, the harness page that drives
src/skydome/export/integrations/threejs/skydome-sky.js in headless Chromium, a local
static server, and the directions of three's PerspectiveCamera pixels.

The served folder holds ``threejs/`` (``write_threejs`` and ``harness.html``), ``three/``
(npm's package) and ``luts/`` (a bake in ``.bin``)."""

from __future__ import annotations

import contextlib
import functools
import http.server
import os
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).parents[1]
THREE = Path(os.environ.get("SKYDOME_THREE_DIR",
                            ROOT / ".vendor" / "npm" / "node_modules" / "three"))

HARNESS = """<!DOCTYPE html><html><head><meta charset="utf-8"><link rel="icon" href="data:,">
<script type="importmap">{ "imports": { "three": "../three/build/three.module.js" } }</script>
</head><body><script type="module">
import * as THREE from 'three';
import { loadSkydomeSky } from './skydome-sky.js';
const renderer = new THREE.WebGLRenderer();
const h = { ready: false };
window.harness = h;
function read(rt, w, hh) {
  const px = new Float32Array(w * hh * 4);
  renderer.readRenderTargetPixels(rt, 0, 0, w, hh, px);
  const out = new Array(w * hh * 3);                 // rows top to bottom, RGB
  for (let j = 0; j < hh; ++j) for (let i = 0; i < w; ++i) for (let c = 0; c < 3; ++c)
    out[3 * (j * w + i) + c] = px[4 * ((hh - 1 - j) * w + i) + c];
  return out;
}
h.equirect = (el, az, w, hh, scale, output = 'xyz') => {
  h.sky.setSun(el, az); h.sky.sunScale = scale; h.sky.sunDisc = false; h.sky.output = output;
  const rt = h.sky.renderEquirect(renderer, w, hh);
  const out = read(rt, w, hh); rt.dispose(); h.sky.output = 'xyz'; return out;
};
h.pinhole = (el, az, w, hh, fov, look, scale, disc) => {
  h.sky.setSun(el, az); h.sky.sunScale = scale; h.sky.sunDisc = disc;
  const camera = new THREE.PerspectiveCamera(fov, w / hh, 0.1, 100);
  camera.position.set(1, 2, 3);                       // anywhere: the sky is at infinity
  camera.lookAt(camera.position.clone().add(new THREE.Vector3(...look)));
  camera.updateMatrixWorld();
  const scene = new THREE.Scene(); scene.add(h.sky);
  const rt = new THREE.WebGLRenderTarget(w, hh, { type: THREE.FloatType });
  renderer.setRenderTarget(rt); renderer.render(scene, camera); renderer.setRenderTarget(null);
  const out = read(rt, w, hh); rt.dispose();
  return { pixels: out, matrixWorld: camera.matrixWorld.elements };
};
h.tryCall = (what) => {
  try {
    if (what === 'low') h.sky.setSun(-30, 0);
    else if (what === 'altitude') h.sky.altitude = 5;
    return '';
  } catch (e) { return `${e.name}: ${e.message}`; }
};
try {
  h.sky = await loadSkydomeSky('../luts/');
  h.sky.output = 'xyz'; h.sky.exposure = 1.0;
  h.ready = true;
} catch (e) { h.error = String(e); }
</script></body></html>
"""


def missing() -> str | None:
    """Why the browser tests cannot run here, or None."""
    from _viewer import have_browser

    if not have_browser():
        return "headless Chromium or Playwright missing (scripts/_setup test installs them)"
    if not (THREE / "build" / "three.module.js").exists():
        return f"npm's three missing ({THREE}; scripts/_setup test installs it with npm)"
    return None


def write_site(root: Path) -> None:
    """The module, its example and the harness into ``root/threejs``, three as
    ``root/three`` (a link); the bake goes to ``root/luts`` (the caller's)."""
    from skydome.export.integrations.threejs import write_threejs

    write_threejs(root / "threejs")
    (root / "threejs" / "harness.html").write_text(HARNESS)
    (root / "three").symlink_to(THREE.resolve(), target_is_directory=True)


@contextlib.contextmanager
def static_server(root: Path):
    """A static server of ``root`` on 127.0.0.1 in a thread; yields its URL."""
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):
            pass

    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0),
                                          functools.partial(Quiet, directory=str(root)))
    t = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    t.start()
    try:
        yield f"http://127.0.0.1:{srv.server_address[1]}"
    finally:
        srv.shutdown()
        t.join()
        srv.server_close()


def wait(page, expr: str, timeout_s: float = 120.0) -> None:
    """Poll until ``expr`` (a page global) is ready, or raise with its error."""
    t0 = time.monotonic()
    while not page.evaluate(f"() => !!({expr} && {expr}.ready)"):
        err = page.evaluate(f"() => ({expr} && {expr}.error) || ''")
        if err or time.monotonic() - t0 > timeout_s:
            raise AssertionError(f"page not ready: {err or 'timeout'}")
        time.sleep(0.2)


def pinhole_dirs(matrix_world, w, h, fov_deg):
    """ENU directions through the pixel centres of three's PerspectiveCamera (vertical
    fov, aspect w / h, looking down its -z), rows top to bottom."""
    m = np.asarray(matrix_world, dtype=np.float64).reshape(4, 4).T     # column-major
    t = np.tan(np.radians(fov_deg) / 2.0)
    x = ((np.arange(w) + 0.5) / w * 2.0 - 1.0) * t * w / h
    y = (1.0 - (np.arange(h) + 0.5) / h * 2.0) * t
    cam = np.stack(np.broadcast_arrays(x[None, :], y[:, None], -1.0), -1)
    world = cam @ m[:3, :3].T
    world /= np.linalg.norm(world, axis=-1, keepdims=True)
    return np.stack([world[..., 0], -world[..., 2], world[..., 1]], -1)
