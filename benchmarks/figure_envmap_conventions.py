"""One panel per environment-map convention: the same sky (hosek_wilkie2012, sun at
elevation 25 deg, azimuth 120 deg) in each tool's layout, with the compass points on the
horizon and the sun marked where skydome's convention code puts them.

Writes docs/figures/envmap_conventions.png.

Run:  .venv/bin/python benchmarks/figure_envmap_conventions.py [--out FIGURE.png]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import skydome as sd
from skydome.export.conventions import CONVENTIONS
from skydome.export.envmap import K_M, render_envmap
from skydome.spectra import srgb_encode


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "docs" / "figures"
                                         / "envmap_conventions.png"))
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sun = sd.Sun(elevation_deg=25.0, azimuth_deg=120.0)
    sky = sd.model("hosek_wilkie2012", sun=sun, turbidity=3.0, albedo=0.3)
    names = list(CONVENTIONS)
    fig, axes = plt.subplots(2, 4, figsize=(16, 6.4))
    marks = {"N": 0.0, "E": 90.0, "S": 180.0, "W": 270.0}
    for ax, name in zip(axes.ravel(), names):
        env = render_envmap(sky, name, size=256)
        im = env.assembled() * K_M                       # cd m^-2 scale
        proj = env.projections["map"]
        disp = srgb_encode(np.clip(im / np.percentile(im, 99.0) * 0.9, 0.0, 1.0))
        ax.imshow(disp, extent=(0, proj.width, proj.height, 0))
        for label, az in marks.items():
            a = np.radians(az)
            d = np.array([np.sin(a), np.cos(a), 0.02])
            r, c = proj.pixel_from_direction(d / np.linalg.norm(d))
            if np.isfinite(r):
                ax.text(float(c), float(r), label, color="red", ha="center", va="center",
                        fontsize=11, fontweight="bold")
        r, c = proj.pixel_from_direction(sun.direction)
        ax.plot(float(c), float(r), "o", mfc="none", mec="yellow", ms=12, mew=1.5)
        conv = CONVENTIONS[name]
        ax.set_title(f"{name}: {conv.up} up, {conv.handedness}-handed, north {conv.north}",
                     fontsize=9)
        ax.set_xticks([]); ax.set_yticks([])
    fig.suptitle("The same sky in each convention (sun: az 120 deg, el 25 deg, yellow ring; "
                 "N E S W on the horizon)")
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=80)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
