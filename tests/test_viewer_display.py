"""The page's display pass against skydome.imaging.display (what `skydome render` writes).

A few linear colours (XYZ, cd/m^2) go through the page's display shader into an 8-bit
target; the same colours as a one-row SkyImage written by SkyImage.save to a PNG (linear
sRGB x the EV100 exposure k = 1 / (1.2 x 2^EV100), the Hunt-effect chroma gain of the
colours' adapting luminance, imaging.display.display_transform, spectra.srgb_encode, 8-bit
quantisation) must give the same bytes within 1/255. The reference is the Python pipeline
that writes `skydome render`'s PNGs, independent of the GLSL code.
"""

from __future__ import annotations

import numpy as np
import pytest

from _viewer import browser_page, viewer_url  # noqa: F401 - fixtures

EV100 = 13.0
# linear sRGB colours in units of the exposure's display white, then scaled to cd/m^2
COLOURS_RGB = [
    (0.0, 0.0, 0.0),            # black
    (0.18, 0.18, 0.18),         # mid grey
    (0.05, 0.12, 0.45),         # noon zenith blue
    (1.0, 0.31, 0.05),          # orange-red horizon under a 2 deg sun (imaging/display.py)
    (2.5, 0.9, 0.2),            # over-exposed orange (compressed, hue kept)
    (12.0, 10.0, 8.0),          # path to white (4 < max < 64)
    (200.0, 180.0, 150.0),      # the sun's disc: white
    (-0.05, 0.3, 0.6),          # out of gamut (a negative component)
    (0.002, 0.0025, 0.003),     # the linear part of the sRGB curve
]


def _reference(xyz, ev100, transform):
    from skydome.imaging.display import display_transform, ev100_to_exposure
    from skydome.spectra import srgb_encode, xyz_to_linear_srgb

    rgb = xyz_to_linear_srgb(xyz) * ev100_to_exposure(ev100)
    if transform in ("filmic", "reinhard", "clamp"):
        rgb = np.maximum(rgb, 0.0)
    return 255.0 * np.clip(srgb_encode(display_transform(rgb, transform)), 0.0, 1.0)


def _page_transforms(page) -> dict[str, int]:
    """The page's display transforms: name -> the shader's number (the options of #transform)."""
    return {o[0]: int(o[1]) for o in page.evaluate(
        "() => [...document.getElementById('transform').options].map((o) => [o.text, o.value])")}


def test_page_default_is_render_default(browser_page):  # noqa: F811
    """The page offers transforms of imaging.display only, and starts with its default."""
    from skydome.imaging.display import DEFAULT_TRANSFORM, DISPLAY_TRANSFORMS

    page, _ = browser_page
    names = _page_transforms(page)
    assert set(names) <= set(DISPLAY_TRANSFORMS)
    selected = page.evaluate("() => { const e = document.getElementById('transform'); "
                             "return e.options[e.selectedIndex].text; }")
    assert selected == DEFAULT_TRANSFORM


def _saved_png(xyz, ev100, transform, hunt, tmp_path):
    """The colours as SkyImage.save writes them to an 8-bit PNG: (N, 3) bytes, and the
    chroma gain save applies (SkyImage.chroma_gain)."""
    from PIL import Image

    from skydome.imaging.image import SkyImage

    img = SkyImage(np.asarray(xyz, dtype=np.float64)[None], "xyz")
    path = img.save(tmp_path / f"c-{transform}-{hunt}.png", ev100=ev100, tonemap=transform, hunt=hunt)
    with Image.open(path) as im:
        rgb = np.asarray(im.convert("RGB"), dtype=np.float64)[0]
    return rgb, img.chroma_gain(hunt)


def _page_colours(page, xyz, ev100, code, hunt):
    r = page.evaluate("([c, ev, t, h]) => window.skydomeViewer.displayColours(c, ev, t, h)",
                      [np.asarray(xyz).tolist(), ev100, code, hunt])
    return np.asarray(r["rgb"], dtype=np.float64), float(r["gain"])


@pytest.mark.parametrize("transform", ["hue-preserving", "agx", "aces-hill", "filmic", "reinhard", "clamp"])
def test_display_pass_matches_saved_png(browser_page, transform, tmp_path):  # noqa: F811
    """The page's display pass (with its Hunt-effect chroma gain, which is on by default as
    in SkyImage.save) gives the bytes of the PNG that SkyImage.save writes, within 1/255."""
    from skydome.imaging.display import ev100_to_exposure
    from skydome.spectra import linear_srgb_to_xyz

    page, messages = browser_page
    code = _page_transforms(page)[transform]
    xyz = linear_srgb_to_xyz(np.array(COLOURS_RGB)) / ev100_to_exposure(EV100)
    gpu, gpu_gain = _page_colours(page, xyz, EV100, code, True)
    want, gain = _saved_png(xyz, EV100, transform, True, tmp_path)
    assert gain > 1.2   # a daylight scene: the gain is in play
    assert abs(gpu_gain - gain) <= 1e-3, (gpu_gain, gain)
    assert np.max(np.abs(gpu - want)) <= 1.0, np.c_[gpu, want]
    assert not [m for m in messages if m[0] in ("error", "pageerror") or "GL_" in m[1]]


@pytest.mark.parametrize("transform", ["hue-preserving", "agx", "filmic", "clamp"])
def test_display_pass_without_hunt_gain(browser_page, transform, tmp_path):  # noqa: F811
    """With the gain switched off (`skydome render --no-hunt`, the page's checkbox) both
    show the chromaticities as they are; the steps equal imaging.display's functions."""
    from skydome.imaging.display import ev100_to_exposure
    from skydome.spectra import linear_srgb_to_xyz

    page, _ = browser_page
    code = _page_transforms(page)[transform]
    xyz = linear_srgb_to_xyz(np.array(COLOURS_RGB)) / ev100_to_exposure(EV100)
    gpu, gpu_gain = _page_colours(page, xyz, EV100, code, False)
    want, gain = _saved_png(xyz, EV100, transform, False, tmp_path)
    assert gpu_gain == 1.0 and gain == 1.0
    assert np.max(np.abs(gpu - want)) <= 1.0, np.c_[gpu, want]
    assert np.max(np.abs(want - np.round(_reference(xyz, EV100, transform)))) <= 1.0


def test_hue_preserving_keeps_the_sunset_orange(browser_page):  # noqa: F811
    """The default transform on the page keeps an over-exposed sunset orange (R > G > B)
    where filmic turns it towards yellow (G/R at least 0.1 higher)."""
    from skydome.imaging.display import ev100_to_exposure
    from skydome.spectra import linear_srgb_to_xyz

    page, _ = browser_page
    xyz = linear_srgb_to_xyz(np.array([[2.5, 0.9, 0.2]])) / ev100_to_exposure(EV100)
    codes = _page_transforms(page)
    hp, fm = (_page_colours(page, xyz, EV100, codes[t], False)[0][0] for t in ("hue-preserving", "filmic"))
    assert hp[0] > hp[1] > hp[2]
    assert fm[1] / fm[0] > hp[1] / hp[0] + 0.1
