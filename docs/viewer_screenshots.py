"""Retake the viewer's screenshots in docs/images/ (headless Debian chromium, SwiftShader).

    PYTHONPATH=src python docs/viewer_screenshots.py [NAME ...]

Each view is set through the page's own controls, drawn at the canvas's 960 x 540 and
saved from the canvas (photographic mode, the default hue-preserving display, auto exposure
unless an EV100 is given, the sun's disc on). ``viewer_page_1280x720`` is the whole page
in a 1280 x 720 window as it opens (the default model, precomputed).
"""

from __future__ import annotations

import base64
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from _viewer import CHROMIUM, CHROMIUM_ARGS, wait_ready, warm_precomputed  # noqa: E402

# name: controls (element id -> value), in the order they are set
VIEWS = {
    "viewer_preetham_camera": {"model": "preetham1999", "sun-el": 35, "sun-az": 200, "projection": 0,
                               "view-az": 180, "view-el": 15, "fov": 90},
    "viewer_oneil_sunset": {"model": "oneil2005", "sun-el": 2, "sun-az": 270, "projection": 0,
                            "view-az": 270, "view-el": 10, "fov": 90},
    "viewer_split_fisheye": {"model": "preetham1999", "model-b": "hoffman_preetham2002", "sun-el": 35,
                             "sun-az": 200, "projection": 2},
    "viewer_false_colour": {"model": "preetham1999", "sun-el": 35, "sun-az": 135, "projection": 1,
                            "mode": 1, "fc-lo": 1000, "fc-hi": 100000},
    "viewer_precomputed_sunset": {"model": "precomputed", "sun-el": 2, "sun-az": 270, "projection": 0,
                                  "view-az": 270, "view-el": 10, "fov": 90},
    # auto exposure would expose for black space (the sky above the horizon): a fixed EV100
    "viewer_precomputed_99km": {"model": "precomputed", "observer_altitude_m": 99000, "sun-el": 20,
                                "sun-az": 135, "projection": 3, "auto-exp": False, "ev100": 12},
    # the ground below the horizon from 10 km: Bruneton's ground radiance through the air
    "viewer_precomputed_ground_10km": {"model": "precomputed", "observer_altitude_m": 10000, "sun-el": 20,
                                       "sun-az": 135, "projection": 0, "view-az": 135, "view-el": -5,
                                       "fov": 100},
    "viewer_hillaire_sunset": {"model": "hillaire2020", "sun-el": 3, "sun-az": 270, "projection": 0,
                               "view-az": 270, "view-el": 5, "fov": 90},
    "viewer_hillaire_10km": {"model": "hillaire2020", "observer_altitude_m": 10000, "sun-el": 25,
                             "sun-az": 200, "projection": 0, "view-az": 180, "view-el": 5, "fov": 90},
    # the model last: each of its frames takes a while on SwiftShader
    "viewer_dobashi_shafts": {"sun-el": 6, "sun-az": 15, "projection": 0, "view-az": 0, "view-el": 2,
                              "fov": 60, "model": "dobashi2002"},
}


def _set(page, key, value):
    sel = f"#{key}" if not key.endswith("_m") else f"[data-param={key}]"
    page.evaluate("([s, v]) => { const e = document.querySelector(s); "
                  "if (e.type === 'checkbox') e.checked = v === 'True'; else e.value = v; "
                  "e.dispatchEvent(new Event('change')); e.dispatchEvent(new Event('input')); }",
                  [sel, str(value)])
    time.sleep(0.05)
    t0 = time.monotonic()
    while not page.evaluate("() => window.skydomeViewer.idle()"):
        if time.monotonic() - t0 > 600:
            raise RuntimeError("page did not finish drawing")
        time.sleep(0.1)
    err = page.evaluate("() => document.getElementById('error').textContent")
    if err:
        raise RuntimeError(err)


def main(names) -> None:
    from playwright.sync_api import sync_playwright

    from skydome._io import atomic_write
    from skydome.viewer.server import make_server

    warm_precomputed()                  # the page opens on precomputed: its first draw bakes
    srv = make_server()
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        if not names or "viewer_page_1280x720" in names:
            page = b.new_page(viewport={"width": 1280, "height": 720})
            page.goto(srv.url)
            wait_ready(page, 120)
            out = ROOT / "docs" / "images" / "viewer_page_1280x720.png"
            data = page.screenshot()
            atomic_write(out, lambda path, d=data: Path(path).write_bytes(d), suffix=".png")
            print(out.relative_to(ROOT))
            page.close()
        for name in [n for n in names if n in VIEWS] or (VIEWS if not names else []):
            page = b.new_page(viewport={"width": 1500, "height": 900})
            page.goto(srv.url)
            wait_ready(page)
            for key, value in VIEWS[name].items():
                _set(page, key, value)
            url = page.evaluate("() => document.getElementById('sky').toDataURL('image/png')")
            data = base64.b64decode(url.split(",", 1)[1])
            out = ROOT / "docs" / "images" / f"{name}.png"
            atomic_write(out, lambda path, d=data: Path(path).write_bytes(d), suffix=".png")
            ev = page.evaluate("() => document.getElementById('ev100').value")
            print(out.relative_to(ROOT), ev, "EV100")
            page.close()
        b.close()
    srv.shutdown()


if __name__ == "__main__":
    main(sys.argv[1:])
