"""The effects gallery (docs/gallery/effects.png, made by ./scripts/demo as
out/effects/effects_gallery.png) is a clean grid: equal cells, each filled by its picture,
no empty cell."""

from pathlib import Path

import numpy as np
import pytest

from skydome.apps.demo import EFFECTS_CAPTION, EFFECTS_CELL, EFFECTS_COLS

GALLERY = Path(__file__).resolve().parents[1] / "docs" / "gallery" / "effects.png"
BACKGROUND = (24, 24, 24)   # the demo's sheet colour


def _cells(a):
    w, h = EFFECTS_CELL
    rows = a.shape[0] // (h + EFFECTS_CAPTION)
    return [a[r * (h + EFFECTS_CAPTION): r * (h + EFFECTS_CAPTION) + h, c * w:(c + 1) * w]
            for r in range(rows) for c in range(EFFECTS_COLS)]


def test_effects_gallery_is_a_grid_of_equal_filled_cells():
    from PIL import Image

    a = np.asarray(Image.open(GALLERY).convert("RGB")).astype(int)
    w, h = EFFECTS_CELL
    # the sheet is exactly whole rows of equal cells with their caption bands
    assert a.shape[1] == EFFECTS_COLS * w
    assert a.shape[0] % (h + EFFECTS_CAPTION) == 0
    cells = _cells(a)
    assert len(cells) == 8 and len(cells) % EFFECTS_COLS == 0
    for k, cell in enumerate(cells):
        bg = np.abs(cell - np.array(BACKGROUND)).max(axis=-1) <= 2
        # letterbox margins (rows or columns entirely background) at most 5 % of the cell
        assert bg.all(axis=0).mean() <= 0.05, (k, bg.all(axis=0).mean())
        assert bg.all(axis=1).mean() <= 0.05, (k, bg.all(axis=1).mean())
        # and at most 5 % of the cell is background in all (no empty cell)
        assert bg.mean() <= 0.05, (k, bg.mean())


def test_letterbox_check_catches_an_unfilled_cell(tmp_path):
    # the bounds above fail on a sheet such as the old one (a square picture in a 2:1 cell)
    from skydome.apps.demo import _contact_sheet
    from PIL import Image

    tiles = [(np.full((100, 100, 3), 0.6), "square"), (np.full((100, 205, 3), 0.6), "2:1")]
    out = tmp_path / "s.png"
    _contact_sheet(tiles, out, tile=EFFECTS_CELL, cols=2, line_height=EFFECTS_CAPTION, font_size=18)
    a = np.asarray(Image.open(out).convert("RGB")).astype(int)
    fractions = [(np.abs(c - np.array(BACKGROUND)).max(axis=-1) <= 2).mean() for c in _cells(a)]
    assert fractions[0] > 0.4 and fractions[1] < 0.05, fractions


@pytest.mark.parametrize("size,height", [(17, 9), (16, 8)])
def test_wide_closeup_keeps_the_square_closeups_pixels(size, height):
    # a 2:1 close-up is the middle of the square one at the same horizontal field: same
    # rays, so the same radiance (the aspect is layout only); pixels stay square
    from skydome.apps.aureole import render_closeup
    from skydome.effects.aureole import bishops_ring_atmosphere

    wl = np.array([450.0, 650.0])
    kw = dict(fov_deg=40.0, size=size, view_samples=8)
    sq = render_closeup(bishops_ring_atmosphere(), 30.0, wl, **kw).data
    wide = render_closeup(bishops_ring_atmosphere(), 30.0, wl, height=height, **kw).data
    assert wide.shape[:2] == (height, size)
    if size % 2 and height % 2:   # odd sizes: the middle rows are the same directions
        np.testing.assert_allclose(wide[height // 2], sq[size // 2], rtol=1e-12)
    assert np.all(np.isfinite(wide)) and np.all(wide >= 0)
    with pytest.raises(ValueError, match="height"):
        render_closeup(bishops_ring_atmosphere(), 30.0, wl, fov_deg=40.0, size=size, height=4)
