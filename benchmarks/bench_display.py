"""Display path: SkyImage.to_srgb() per display transform, with and without the Hunt-effect
chroma gain, on a synthetic sky-coloured XYZ image (no model: the display step alone), and
the chroma gain by itself in process CPU time (run it from another tree's root with that
tree's src on PYTHONPATH to compare).

    PYTHONPATH=src python benchmarks/bench_display.py [WIDTH]     # default 2048 (x WIDTH/2)
"""

from __future__ import annotations

import sys
import time

import numpy as np

from skydome.imaging import SkyImage
from skydome.imaging.display import DISPLAY_TRANSFORMS


def _cpu(f) -> float:
    t0 = time.process_time()
    f()
    return time.process_time() - t0


def main(width: int = 2048) -> None:
    h = width // 2
    rng = np.random.default_rng(1)
    # luminance over four decades around a day sky's, blue-to-orange chromaticities
    Y = 10.0 ** rng.uniform(2.0, 6.0, size=(h, width))
    x = rng.uniform(0.24, 0.45, size=(h, width))
    y = rng.uniform(0.25, 0.40, size=(h, width))
    xyz = np.stack([x / y * Y, Y, (1.0 - x - y) / y * Y], axis=-1)
    im = SkyImage(xyz, "xyz")
    k = im.auto_exposure()
    # the Hunt-effect chroma gain alone: process CPU time, best of 5 (after a first call)
    from skydome.imaging.display import scale_chroma

    rgb = im.linear_srgb() * k
    scale_chroma(rgb, 1.5)
    best = min(_cpu(lambda: scale_chroma(rgb, 1.5)) for _ in range(5))
    print(f"scale_chroma (gain 1.5) of a {width} x {h} image: {best:.3f} s CPU (best of 5)")
    print(f"to_srgb of a {width} x {h} image (time of the second of two calls)")
    for tm in DISPLAY_TRANSFORMS:
        for hunt in (False, True):
            im.to_srgb(k, tm, hunt=hunt)
            t0 = time.perf_counter()
            im.to_srgb(k, tm, hunt=hunt)
            print(f"  {tm:15s} hunt={hunt!s:5s} {time.perf_counter() - t0:6.2f} s")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2048)
