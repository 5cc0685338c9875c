"""The GGX-prefiltered mip chain of one sky: hosek_wilkie2012 (T 3, albedo 0.3, sun at
elevation 20 deg, azimuth 100 deg, the sun in the map), a 512 x 256 lat-long map in
skydome's convention and its 6 levels (roughness 0, 0.2, ..., 1), each shown at the same
size with the same exposure (Reinhard on the map's median sky radiance).

Writes docs/figures/envmap_mips.png.

Run:  .venv/bin/python benchmarks/figure_envmap_mips.py [--out FIGURE.png]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import skydome as sd
from skydome.export.envmap import render_envmap
from skydome.export.prefilter import prefiltered_mips
from skydome.spectra import srgb_encode


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "docs" / "figures"
                                         / "envmap_mips.png"))
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sky = sd.model("hosek_wilkie2012", sun=sd.Sun(elevation_deg=20.0, azimuth_deg=100.0),
                   turbidity=3.0, albedo=0.3)
    env = render_envmap(sky, "skydome", size="512x256", sun="map")
    mips = prefiltered_mips(env, 6)
    exposure = 1.0 / (2.0 * np.median(env.images["map"][:128]))
    fig, axes = plt.subplots(3, 2, figsize=(10, 5.6))
    for k, (ax, m) in enumerate(zip(axes.T.ravel(), mips)):
        im = m.images["map"] * exposure
        ax.imshow(srgb_encode(np.clip(im / (1.0 + im), 0.0, 1.0)), interpolation="nearest",
                  extent=(0, 2, 1, 0))
        r = m.metadata.get("roughness", 0.0)
        ax.set_title(f"level {k}: roughness {r:.1f}, {im.shape[1]} x {im.shape[0]}",
                     fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle("GGX-prefiltered mips (split sum, n = v = r), hosek_wilkie2012, sun in the map")
    fig.tight_layout()
    fig.savefig(args.out, dpi=80)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
