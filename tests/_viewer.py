"""Shared fixtures of the viewer tests: the server in a thread and headless Chromium.

The browser is Debian's ``chromium`` (installed by scripts/_setup), driven by Playwright
for Python with SwiftShader's software WebGL2; nothing is downloaded.
"""

from __future__ import annotations

import os
import shutil
import threading

import pytest

CHROMIUM = os.environ.get("SKYDOME_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader",
                 "--enable-unsafe-swiftshader", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run",
                 "--disable-quic"]


def psnr_db(test, ref) -> float:
    """10 log10(peak^2 / MSE), peak = max |ref| over all pixels and channels (the PSNR of
    every shader test against its CPU model)."""
    import numpy as np

    mse = float(np.mean((np.asarray(test) - np.asarray(ref)) ** 2))
    peak = float(np.max(np.abs(ref)))
    return float("inf") if mse == 0.0 else 10.0 * np.log10(peak * peak / mse)


def have_browser() -> bool:
    try:
        import playwright  # noqa: F401
    except ImportError:
        return False
    return shutil.which(CHROMIUM) is not None or os.path.exists(CHROMIUM)


def wait_ready(page, timeout_s: float = 60.0) -> None:
    """Poll until the page's renderer is up (Playwright's wait_for_function would need
    eval, which the page's Content-Security-Policy forbids, as it should)."""
    import time

    t0 = time.monotonic()
    while not page.evaluate("() => !!(window.skydomeViewer && window.skydomeViewer.ready)"):
        err = page.evaluate("() => document.getElementById('error')?.textContent || ''")
        if err or time.monotonic() - t0 > timeout_s:
            raise AssertionError(f"viewer not ready: {err or 'timeout'}")
        time.sleep(0.1)


def warm_precomputed() -> None:
    """Build the viewer's precomputed tables and their bake in this process (the server
    thread shares the caches of skydome.viewer.scene), with no time limit, so that a page
    that switches to the precomputed model does not wait for a table build (minutes on a
    loaded machine) inside a test's drawing timeout."""
    from skydome.viewer.scene import shader_scene

    shader_scene({"model": "precomputed", "sun_elevation": "40", "sun_azimuth": "180"})


@pytest.fixture(scope="module")
def viewer_url():
    from skydome.viewer.server import make_server

    srv = make_server("127.0.0.1", 0)
    t = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    t.start()
    yield srv.url
    srv.shutdown()
    t.join()
    srv.server_close()


@pytest.fixture(scope="module")
def browser_page(viewer_url):
    """(page, console messages): the viewer loaded in headless Chromium, ready."""
    if not have_browser():
        pytest.skip("headless Chromium or Playwright missing (scripts/_setup test installs them)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 1360, "height": 800})
        messages = []
        page.on("console", lambda m: messages.append((m.type, m.text)))
        page.on("pageerror", lambda e: messages.append(("pageerror", str(e))))
        warm_precomputed()          # the page opens on precomputed: its first draw bakes
        page.goto(viewer_url)
        wait_ready(page)
        yield page, messages
        browser.close()
