"""skydome's ``hosek_wilkie2012`` against Mitsuba 3's ``sunsky`` emitter (an independent C++
evaluation of the same authors' datasets), evaluated in the same directions.

For four (sun elevation, turbidity, albedo) cases, the radiance at 450, 550 and 650 nm
along the sun's vertical plane (from the horizon behind the observer over the zenith to the
horizon under the sun), in Mitsuba's ``scalar_spectral`` variant, and the RGB dataset in
``scalar_rgb`` on 2000 random upper-hemisphere directions. Prints the largest relative
difference per case and writes docs/figures/hosek_wilkie2012_vs_mitsuba.png.

Run:  .venv/bin/python benchmarks/validate_hosek_wilkie_mitsuba.py [--out FIGURE.png]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import skydome as sd

CASES = [(30.0, 3.0, 0.2), (5.0, 7.5, 0.6), (65.0, 1.5, 0.0), (1.0, 10.0, 1.0)]
WAVELENGTHS = (450.0, 550.0, 650.0, 700.0)


def _eval(mi, em, d, wl=None):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.ScalarVector3f(*(-np.asarray(d, float)))
    if wl is not None:
        si.wavelengths = mi.ScalarVector4f(*wl)
    return np.array(em.eval(si), dtype=float)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "docs" / "figures"
                                         / "hosek_wilkie2012_vs_mitsuba.png"))
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import mitsuba as mi

    # signed zenith angle in the sun's vertical plane, sun side positive
    t = np.radians(np.linspace(-89.5, 89.5, 359))
    az = np.radians(135.0)
    fig, axes = plt.subplots(2, len(CASES), figsize=(4.2 * len(CASES), 6.4), sharex=True,
                             gridspec_kw={"height_ratios": [2, 1]})
    rng = np.random.default_rng(3)
    rnd = rng.normal(size=(2000, 3))
    rnd[:, 2] = np.abs(rnd[:, 2])
    rnd /= np.linalg.norm(rnd, axis=1)[:, None]
    for col, (el, T, a) in enumerate(CASES):
        sun = sd.Sun(elevation_deg=el, azimuth_deg=135.0)
        sky = sd.model("hosek_wilkie2012", sun=sun, turbidity=T, albedo=a)
        d = np.stack([np.sin(t) * np.sin(az), np.sin(t) * np.cos(az), np.cos(t)], axis=-1)
        mi.set_variant("scalar_spectral")
        em = mi.load_dict({"type": "sunsky", "sun_direction": [float(x) for x in sun.direction],
                           "turbidity": T, "albedo": a, "sun_scale": 0.0})
        ref = np.array([_eval(mi, em, x, WAVELENGTHS) for x in d])
        mine = sky.radiance(d, np.array(WAVELENGTHS))
        rel = mine / ref - 1.0
        mi.set_variant("scalar_rgb")
        em = mi.load_dict({"type": "sunsky", "sun_direction": [float(x) for x in sun.direction],
                           "turbidity": T, "albedo": a, "sun_scale": 0.0})
        ref_rgb = np.array([_eval(mi, em, x) for x in rnd]) * 106.7502593994140625
        rel_rgb = sky.rgb(rnd) / 683.0 / ref_rgb - 1.0
        print(f"sun {el:4.1f} deg  T {T:4.1f}  albedo {a:.1f}:  spectral max |rel| "
              f"{np.abs(rel).max():.2e}   RGB max |rel| {np.abs(rel_rgb).max():.2e}")
        ax, ax2 = axes[0, col], axes[1, col]
        for j, (w, c) in enumerate(zip(WAVELENGTHS[:3], ("tab:blue", "tab:green", "tab:red"))):
            ax.plot(np.degrees(t), mine[:, j], color=c, lw=2.2, alpha=0.5,
                    label=f"skydome {w:.0f} nm")
            ax.plot(np.degrees(t), ref[:, j], color=c, lw=0.9, ls="--",
                    label=f"Mitsuba {w:.0f} nm")
            ax2.plot(np.degrees(t), 100 * rel[:, j], color=c, lw=1)
        ax.set_yscale("log")
        ax.set_title(f"sun {el:g} deg, T = {T:g}, albedo {a:g}")
        ax2.set_ylim(-0.01, 0.01)
        ax2.set_xlabel("zenith angle, sun side > 0 [deg]")
        if col == 0:
            ax.set_ylabel("radiance [W m$^{-2}$ sr$^{-1}$ nm$^{-1}$]")
            ax2.set_ylabel("skydome / Mitsuba - 1 [%]")
            ax.legend(fontsize=7)
    fig.suptitle("hosek_wilkie2012: skydome vs Mitsuba 3 sunsky (sky only)")
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=90)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
