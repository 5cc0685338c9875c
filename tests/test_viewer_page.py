"""The viewer page driven through its controls in headless Chromium (SwiftShader WebGL2).

Moving the sun towards the horizon must redden the horizon under the sun (R/B of linear
sRGB up) and darken the zenith, for every model, as in any photograph of a clear sky at
sunset; the split view, the false-colour mode and "save this view" must work; no console
errors at any point.
"""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from _viewer import browser_page, viewer_url, warm_precomputed  # noqa: F401 - fixtures

MODELS = ["preetham1999", "hoffman_preetham2002", "oneil2005", "hillaire2020", "precomputed",
          "fitted"]


def _wait_idle(page, timeout_s=60.0):
    t0 = time.monotonic()
    time.sleep(0.05)
    while not page.evaluate("() => window.skydomeViewer.idle()"):
        assert time.monotonic() - t0 < timeout_s, "page did not finish drawing"
        time.sleep(0.05)
    err = page.evaluate("() => document.getElementById('error').textContent")
    assert not err, err


def _set(page, selector, value):
    page.evaluate("([s, v]) => { const e = document.querySelector(s); e.value = v; "
                  "e.dispatchEvent(new Event(e.tagName === 'SELECT' ? 'change' : 'input')); "
                  "e.dispatchEvent(new Event('input')); }", [selector, str(value)])
    _wait_idle(page)


def _linear_srgb(xyz):
    from skydome.spectra import xyz_to_linear_srgb

    return xyz_to_linear_srgb(np.asarray(xyz, dtype=np.float64))


def _save_view(page):
    """Click "save this view"; return the two downloads (PNG, JSON)."""
    downloads = []

    def handler(d):
        downloads.append(d)

    page.on("download", handler)
    page.click("#save")
    t0 = time.monotonic()
    while len(downloads) < 2 and time.monotonic() - t0 < 20:
        page.wait_for_timeout(100)
    page.remove_listener("download", handler)
    return downloads


@pytest.fixture(scope="module")
def page(browser_page):  # noqa: F811
    page, messages = browser_page
    warm_precomputed()
    page.evaluate("() => { const c = document.getElementById('sky'); c.width = 256; c.height = 128; }")
    _set(page, "#model-b", "")
    _set(page, "#projection", "1")            # equirect hemisphere: zenith row 0, horizon last
    _set(page, "#sun-az", "180")
    # the sky alone: these checks are about the sky's colours (the sun's disc has its own
    # tests in test_viewer_layout.py)
    page.evaluate("() => { const e = document.getElementById('sun-disc'); e.checked = false; "
                  "e.dispatchEvent(new Event('change')); }")
    _wait_idle(page)
    return page, messages


@pytest.mark.parametrize("model", MODELS)
def test_low_sun_reddens_horizon_darkens_zenith(page, model):
    page, messages = page
    _set(page, "#model", model)
    # horizon under the sun (azimuth 180 deg: centre column, last row) and the zenith
    pts = [[0.5, 0.97], [0.5, 0.0]]
    out = {}
    for el in (40, 3):
        _set(page, "#sun-el", el)
        out[el] = np.asarray(page.evaluate("(p) => window.skydomeViewer.sample(p)", pts))
    rgb_hi, rgb_lo = _linear_srgb(out[40][0]), _linear_srgb(out[3][0])
    rb_hi, rb_lo = rgb_hi[0] / rgb_hi[2], rgb_lo[0] / rgb_lo[2]
    assert rb_lo > rb_hi, (model, rb_hi, rb_lo)
    assert out[3][1][1] < out[40][1][1], (model, out[40][1][1], out[3][1][1])
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]], messages


def test_split_view_and_false_colour(page, tmp_path):
    page, messages = page
    _set(page, "#model", "preetham1999")
    _set(page, "#sun-el", "30")
    _set(page, "#model-b", "oneil2005")
    labels = page.evaluate("() => [document.getElementById('label-a').textContent, "
                           "document.getElementById('label-b').textContent]")
    assert labels == ["preetham1999", "oneil2005"]
    # the two halves hold the two models: compare with each model's own full render
    left = page.evaluate("() => window.skydomeViewer.sample([[0.1, 0.5], [0.9, 0.5]])")
    _set(page, "#model-b", "")
    full_a = page.evaluate("() => window.skydomeViewer.sample([[0.1, 0.5], [0.9, 0.5]])")
    assert left[0] == pytest.approx(full_a[0], rel=1e-6)
    assert left[1] != pytest.approx(full_a[1], rel=1e-2)
    _set(page, "#mode", "1")
    assert page.evaluate("() => document.getElementById('scale').classList.contains('on')")
    _set(page, "#mode", "0")
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]], messages


def test_save_this_view(page, tmp_path):
    page, messages = page
    _set(page, "#model", "hoffman_preetham2002")
    _set(page, "#sun-el", "12.5")
    downloads = _save_view(page)
    names = sorted(d.suggested_filename for d in downloads)
    assert len(names) == 2 and names[0].endswith(".json") and names[1].endswith(".png")
    js = next(d for d in downloads if d.suggested_filename.endswith(".json"))
    path = tmp_path / "view.json"
    js.save_as(path)
    view = json.loads(path.read_text())
    assert view["sun"]["elevation_deg"] == pytest.approx(12.5)
    assert view["models"][0]["model"] == "hoffman_preetham2002"
    assert "--model hoffman_preetham2002 --sun-elevation 12.5" in view["render_command"]
    png = next(d for d in downloads if d.suggested_filename.endswith(".png"))
    png.save_as(tmp_path / "view.png")
    assert (tmp_path / "view.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]], messages


def test_saved_view_reproduces_on_the_cpu(page, tmp_path):
    """The JSON of "save this view" carries a `skydome render` command; run it and compare
    its EXR (linear sRGB, cd/m^2 scale) with the page's own float frame of the same view."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    from skydome.imaging.image import read_exr
    from skydome.spectra import xyz_to_linear_srgb

    page, messages = page
    page.evaluate("() => { const c = document.getElementById('sky'); c.width = 128; c.height = 32; }")
    _set(page, "#model", "preetham1999")
    _set(page, "#model-b", "")
    _set(page, "#projection", "1")
    _set(page, "#sun-el", "25")
    _set(page, "#sun-az", "150")
    downloads = _save_view(page)
    js = next(d for d in downloads if d.suggested_filename.endswith(".json"))
    js.save_as(tmp_path / "view.json")
    cmd = json.loads((tmp_path / "view.json").read_text())["render_command"].split()
    assert cmd[:2] == ["skydome", "render"] and "--no-sun" in cmd
    assert "--projection equirect-hemisphere --size 128x32" in " ".join(cmd)
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root / "src"))
    r = subprocess.run([sys.executable, "-m", "skydome.cli", *cmd[1:]], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    ch = read_exr(tmp_path / "view.exr")
    cpu = np.stack([ch["R"], ch["G"], ch["B"]], axis=-1).astype(np.float64)
    pts = [[(c + 0.5) / 128, (rr + 0.5) / 32] for rr in range(0, 32, 4) for c in range(0, 128, 8)]
    gpu = _linear_srgb(page.evaluate("(p) => window.skydomeViewer.sample(p)", pts))
    want = np.array([cpu[rr, c] for rr in range(0, 32, 4) for c in range(0, 128, 8)])
    assert np.max(np.abs(gpu - want)) <= 1e-3 * np.max(want)
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]], messages
