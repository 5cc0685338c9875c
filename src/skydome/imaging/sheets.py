"""Contact sheets: one labelled grid of images, written atomically as PNG (Pillow).

Every sheet skydome writes (the timelapse and twilight sheets, the comparison grid, the
airlight before/after strip, the demo gallery) is made by :func:`contact_sheet`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

__all__ = ["contact_sheet", "to_uint8"]


def to_uint8(rgb) -> np.ndarray:
    """Display values in [0, 1] (clipped; NaN as 0) -> (H, W, 3) uint8."""
    a = np.nan_to_num(np.asarray(rgb, dtype=np.float64), nan=0.0)
    return (np.clip(a, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def _as_pil(image):
    from PIL import Image

    if isinstance(image, (str, Path)):
        with Image.open(image) as im:
            return im.convert("RGB")
    a = np.asarray(image)
    if a.dtype != np.uint8:
        a = to_uint8(a)
    return Image.fromarray(a[..., :3] if a.ndim == 3 else a).convert("RGB")


def contact_sheet(tiles: Sequence, path, *, cols: int | None = None, tile=128, labels_above: bool = False,
                  line_height: int = 14, upscale: bool = False, background=(16, 16, 16),
                  column_labels: Sequence[str] | None = None, row_labels: Sequence[str] | None = None,
                  row_label_width: int = 150, text_colours=((220, 220, 220), (170, 170, 170)),
                  letterbox: bool = False, font_size: int | None = None) -> Path:
    """Write a grid of images with text lines under (or above) each one to ``path`` (PNG).

    Parameters
    ----------
    tiles : sequence of (image, lines)
        ``image``: a PNG path, an (H, W, 3) array of display values in [0, 1] (sRGB encoded)
        or uint8, or None for a missing entry (drawn as "n/a"). ``lines``: a string or a
        sequence of strings drawn in the tile's label band (first line in the first text
        colour, the others in the second).
    cols : int, optional
        Tiles per row (default: all in one row, at most 8).
    tile : int or (int, int)
        The box (width, height) [pixels] each image is fitted into, keeping its aspect
        ratio; images are only shrunk unless ``upscale``. A row is as high as its tallest
        image plus the label band.
    letterbox : bool
        Every cell is exactly the box: each image is scaled (up or down) to fit it, keeping
        its aspect ratio, and centred on the background; the caption band is under the
        box; a last row with fewer images is centred. For galleries of unlike images.
    labels_above : bool
        Draw the label band above each image instead of below.
    line_height : int
        Height of one label line [pixels]; the band holds the most lines of any tile.
    background : (int, int, int)
        Sheet colour.
    font_size : int, optional
        Height of the label font [pixels] (default: Pillow's default font, about 10 px);
        keep ``line_height`` a few pixels above it.
    column_labels, row_labels : sequence of str, optional
        A header row above the grid (one text per column) and a label column on its left
        (one text per row, ``row_label_width`` pixels wide).
    """
    from PIL import Image, ImageDraw

    from skydome._io import atomic_file

    tiles = list(tiles)
    if not tiles:
        raise ValueError("tiles is empty: a contact sheet needs at least one image")
    n = len(tiles)
    cols = min(8, n) if cols is None else max(1, min(int(cols), n))
    rows = (n + cols - 1) // cols
    tw, th = (tile, tile) if np.isscalar(tile) else (int(tile[0]), int(tile[1]))
    ims, texts = [], []
    for image, lines in tiles:
        texts.append([lines] if isinstance(lines, str) else list(lines or ()))
        if image is None:
            ims.append(None)
            continue
        im = _as_pil(image)
        scale = min(tw / im.width, th / im.height)
        if scale < 1.0 or ((upscale or letterbox) and scale > 1.0):
            im = im.resize((max(1, round(im.width * scale)), max(1, round(im.height * scale))),
                           Image.LANCZOS)
        ims.append(im)
    band = line_height * max((len(t) for t in texts), default=0)
    cell_h = th if letterbox else max((im.height for im in ims if im is not None), default=th)
    left = row_label_width if row_labels is not None else 0
    top = line_height + 4 if column_labels is not None else 0
    sheet = Image.new("RGB", (left + cols * tw, top + rows * (cell_h + band)), tuple(background))
    draw = ImageDraw.Draw(sheet)
    if font_size is not None:
        from PIL import ImageFont

        draw.font = ImageFont.load_default(size=int(font_size))
    if column_labels is not None:
        for j, text in enumerate(column_labels):
            draw.text((left + j * tw + 4, 3), str(text), fill=text_colours[0])
    if row_labels is not None:
        for i, text in enumerate(row_labels):
            draw.text((4, top + i * (cell_h + band) + cell_h // 2), str(text)[:24], fill=text_colours[0])
    last = n - (rows - 1) * cols   # images in the last row
    for k, (im, lines) in enumerate(zip(ims, texts)):
        x = left + (k % cols) * tw
        if letterbox and k // cols == rows - 1:
            x += (cols - last) * tw // 2
        y = top + (k // cols) * (cell_h + band)
        y_img, y_txt = (y + band, y) if labels_above else (y, y + cell_h)
        if im is None:
            draw.text((x + 10, y_img + cell_h // 2), "n/a", fill=(200, 120, 120))
        else:
            sheet.paste(im, (x + (tw - im.width) // 2, y_img + (cell_h - im.height) // 2))
        for m, text in enumerate(lines):
            draw.text((x + 3, y_txt + 1 + m * line_height), text,
                      fill=text_colours[0] if m == 0 else text_colours[-1])
    path = Path(path)
    with atomic_file(path) as tmp:
        sheet.save(tmp, format="PNG")
    return path
