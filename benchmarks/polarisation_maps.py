"""Polarisation of the sky: maps for the documentation and neutral-point positions.

Prints the maximum degree of polarisation on the solar meridian and its angle from the
sun, and the Arago / Babinet / Brewster positions, for sun elevations 5, 20 and 40 deg
(polarised Monte Carlo, turbidity 2.5, HG aerosols, rho = 0.0279, 550 nm), and writes
docs/figures/polarisation_*.png. Usage: python benchmarks/polarisation_maps.py [--no-figures]
"""

import sys
import time
from pathlib import Path

import numpy as np

from skydome.effects.polarisation_maps import find_neutral_points, meridian_profile, polarisation_maps
from skydome.imaging.plots import plot_polarisation_maps
from skydome.imaging.projections import Fisheye
from skydome.sun import Sun

FIG = Path(__file__).resolve().parent.parent / "docs" / "figures"


def profiles(samples=20000, seeds=(0, 1, 2)):
    print(f"solar meridian, 550 nm, turbidity 2.5, {samples} paths per direction, 1 deg steps")
    print("sun_el  method           maxDoP  at[deg from sun]  babinet[above sun]  brewster[below sun]  "
          "arago[above antisun]")
    for el in (5.0, 20.0, 40.0):
        sun = Sun(el, 180.0)
        an = meridian_profile("rayleigh_single", sun, step_deg=1.0, turbidity=2.5)
        i = int(np.argmax(an.dop))
        print(f"{el:5.0f}   rayleigh_single  {an.dop[i]:.3f}   {an.scattering_deg[i]:6.1f}            "
              f"{find_neutral_points(an) or 'none'}")
        res = []
        for seed in seeds:
            t = time.perf_counter()
            mc = meridian_profile("montecarlo", sun, step_deg=1.0, samples=samples, seed=seed, turbidity=2.5)
            dt = time.perf_counter() - t
            i = int(np.argmax(mc.dop))
            f = find_neutral_points(mc)
            res.append((mc.dop[i], mc.scattering_deg[i], f.get("babinet", np.nan) - el,
                        el - f.get("brewster", np.nan), 180.0 + el - f.get("arago", np.nan), dt))
        r = np.array(res)
        with np.errstate(all="ignore"), __import__("warnings").catch_warnings():
            __import__("warnings").simplefilter("ignore")
            m, s = np.nanmean(r, axis=0), np.nanstd(r, axis=0)
        fmt = lambda k: "absent" if np.isnan(m[k]) else f"{m[k]:5.1f} +- {s[k]:.1f}"
        print(f"{el:5.0f}   montecarlo       {m[0]:.3f}   {m[1]:6.1f} +- {s[1]:.1f}     {fmt(2):18s}  "
              f"{fmt(3):19s}  {fmt(4)}   ({m[5]:.1f} s per profile)")


def figures(size=48, samples=3000):
    FIG.mkdir(parents=True, exist_ok=True)
    for el in (5.0, 20.0, 40.0):
        sun = Sun(el, 180.0)
        grid = Fisheye(size).directions()
        plot_polarisation_maps(polarisation_maps("rayleigh_single", sun, *grid, turbidity=2.5),
                               FIG / f"polarisation_single_{int(el)}.png")
        t = time.perf_counter()
        pm = polarisation_maps("montecarlo", sun, *grid, samples=samples, seed=1, turbidity=2.5)
        print(f"montecarlo map {size}x{size}, {samples} paths/pixel, sun {el:g} deg: "
              f"{time.perf_counter() - t:.1f} s; max DoP {np.nanmax(pm.dop):.3f}")
        plot_polarisation_maps(pm, FIG / f"polarisation_montecarlo_{int(el)}.png")
    _profile_figure()


def _profile_figure(samples=20000):
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
    for ax, el in zip(axes, (5.0, 20.0, 40.0)):
        sun = Sun(el, 180.0)
        an = meridian_profile("rayleigh_single", sun, step_deg=1.0, turbidity=2.5)
        mc = meridian_profile("montecarlo", sun, step_deg=1.0, samples=samples, seed=0, turbidity=2.5)
        err = mc.stderr[:, 1] / np.maximum(mc.stokes[:, 0], 1e-30)
        ax.plot(an.angle_deg, an.signed, "k--", lw=1, label="single Rayleigh (analytic)")
        ax.fill_between(mc.angle_deg, mc.signed - 2 * err, mc.signed + 2 * err, color="C0", alpha=0.3)
        ax.plot(mc.angle_deg, mc.signed, "C0", lw=1.2, label="Monte Carlo, all orders, T = 2.5")
        ax.axhline(0, color="0.5", lw=0.6)
        ax.axvline(el, color="orange", lw=1, label="sun")
        for name, x in find_neutral_points(mc).items():
            ax.plot(x, 0, "rv", ms=7)
            ax.annotate(name, (x, 0), (x, {"brewster": -0.07, "babinet": -0.14, "arago": -0.07}[name]),
                        ha="center", fontsize=8, color="r")
        ax.set_title(f"sun elevation {el:g} deg")
        ax.set_xlabel("angle along solar meridian [deg]: 0 horizon below sun, 90 zenith", fontsize=8)
        ax.set_xlim(0, 180)
    axes[0].set_ylabel("signed degree of polarisation -Q/I")
    axes[0].set_ylim(-0.2, 1.0)
    axes[0].legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(FIG / "polarisation_meridian.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    profiles()
    if "--no-figures" not in sys.argv:
        figures()
