"""Frame time of the viewer's sky shaders: N frames at 1920x1080 per model, in the
browser the machine has (headless Debian chromium; SwiftShader unless a GPU is exposed).

    PYTHONPATH=src python benchmarks/bench_viewer.py [--frames 5] [--gpu]

``--gpu`` drops SwiftShader (``--use-angle=swiftshader``) so that Chromium uses the
machine's GPU; ``--angle vulkan`` (or ``gl``, ``gl-egl``, ``d3d11``, ``metal``) picks ANGLE's
back end, ``--headed`` runs with a window (a display is needed) where headless Chromium
falls back to software. The first line printed names the WebGL renderer: it must name the
GPU, not SwiftShader, for the figures to be GPU figures (docs/viewer.md).
Prints ms/frame of the sky pass (render into the float target, synced by a one-pixel
read), averaged over the frames after one warm-up frame.
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from _viewer import CHROMIUM, CHROMIUM_ARGS, wait_ready  # noqa: E402

MODELS = {"preetham1999": {"turbidity": 2.5}, "hoffman_preetham2002": {"turbidity": 2.5},
          "oneil2005": {}, "hillaire2020": {"turbidity": 2.5}, "precomputed": {"turbidity": 2.5},
          "dobashi2002": {"turbidity": 2.5, "shafts": "true"}}
# the camera of each frame: [view azimuth, elevation, field of view] [deg]; dobashi2002 looks
# at its mountains (dobashi2002.DEFAULT_CAMERA), the others south, 15 deg up
CAMERAS = {"dobashi2002": [0, 2, 60]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--width", type=int, default=1920)
    ap.add_argument("--height", type=int, default=1080)
    ap.add_argument("--gpu", action="store_true")
    ap.add_argument("--models", default=",".join(MODELS), help="comma-separated subset")
    ap.add_argument("--chromium", default=CHROMIUM, help="browser executable (Chromium or Chrome)")
    ap.add_argument("--angle", default=None, help="ANGLE back end with --gpu (vulkan, gl, gl-egl, ...)")
    ap.add_argument("--headed", action="store_true", help="run with a window instead of headless")
    a = ap.parse_args()
    from playwright.sync_api import sync_playwright

    from skydome.viewer.server import make_server

    srv = make_server()
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    args = [x for x in CHROMIUM_ARGS if not (a.gpu and "swiftshader" in x)
            and not (a.headed and x.startswith("--headless"))]
    if a.gpu:
        args += ["--ignore-gpu-blocklist", "--enable-gpu-rasterization"]
        if a.angle:
            args.append(f"--use-angle={a.angle}")
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=a.chromium, args=args, headless=not a.headed)
        page = b.new_page()
        page.goto(srv.url)
        wait_ready(page)
        gl = page.evaluate("() => { const g = document.createElement('canvas').getContext('webgl2');"
                           " const e = g.getExtension('WEBGL_debug_renderer_info');"
                           " return e ? g.getParameter(e.UNMASKED_RENDERER_WEBGL) : g.getParameter(g.RENDERER); }")
        print(f"renderer: {gl}")
        for model in a.models.split(","):
            values = MODELS[model]
            t0 = time.perf_counter()
            ms = page.evaluate("([m, v, n, w, h, c]) => window.skydomeViewer.benchmark(m, v, n, w, h, c)",
                               [model, {"sun_elevation": 20, **values}, a.frames, a.width, a.height,
                                CAMERAS.get(model, [180, 15, 90])])
            print(f"{model:22s} {ms:9.1f} ms/frame at {a.width}x{a.height} "
                  f"({a.frames} frames, {time.perf_counter() - t0:.1f} s)")
        b.close()
    srv.shutdown()


if __name__ == "__main__":
    main()
