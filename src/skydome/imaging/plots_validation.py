"""Figures of the measured-sky comparison (matplotlib, Agg, written atomically).

* :func:`plot_luminance_vs_scattering_angle`: measured and model luminance in the scanner's
  81 directions against the angle from the sun, one panel per capture.
* :func:`plot_spectra`: measured and model spectral radiance at a few directions.
* :func:`plot_error_maps`: the shape error (model / measured, each normalised by its own
  mean, minus 1) on the scanner's sky grid, one polar panel per model.
"""

from __future__ import annotations

import numpy as np

from skydome.imaging.plots import _pyplot, _save

__all__ = ["plot_luminance_vs_scattering_angle", "plot_spectra", "plot_error_maps", "plot_scan_order"]

_STYLE = {"precomputed": ("C0", "o"), "hillaire2020": ("C1", "s"), "nishita1996": ("C2", "^"),
          "single_scattering": ("C3", "v"), "montecarlo": ("C4", "D"), "preetham1999": ("C5", "P"),
          "perez1993": ("C6", "X"), "cie2003": ("C7", "*"), "precomputed_accurate": ("C8", "h"),
          "fitted": ("C9", "d"), "hosek_wilkie2012": ("saddlebrown", "p")}


def _keep(n, excluded):
    k = np.ones(n, bool)
    k[list(excluded)] = False
    return k


def plot_luminance_vs_scattering_angle(panels, path, *, excluded=(0,), title=None) -> None:
    """``panels``: list of (capture, measured luminance (81,), {model: luminance (81,)})."""
    plt = _pyplot()
    n = len(panels)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, 3.8 * rows), squeeze=False)
    for ax, (cap, meas, models) in zip(axes.flat, panels):
        k = _keep(meas.size, excluded)
        g = cap.sun_angle_deg
        ax.semilogy(g[k], meas[k], "ko", ms=5, label="measured", zorder=5)
        for m, L in models.items():
            c, mk = _STYLE.get(m, ("0.5", "."))
            ax.semilogy(g[k], L[k], mk, color=c, ms=3.5, alpha=0.8, label=m)
        ax.semilogy(g[~k], meas[~k], "kx", ms=7, label="sample 0 (excluded)")
        ax.set_xlabel("angle from the sun [deg]")
        ax.set_ylabel("luminance [cd m$^{-2}$]")
        ax.set_title(f"{cap.label} EDT label, sun elevation {cap.sun.elevation_deg:.1f} deg")
        ax.grid(True, which="both", alpha=0.3)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7, loc="upper right")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def plot_spectra(capture, wavelengths_nm, models, path, *, samples=(80, 24, 44, 16), title=None) -> None:
    """Measured spectra (350-1000 nm) and model spectra (``models``: {name: (81, nw)} at
    ``wavelengths_nm``) at the given samples."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(samples), figsize=(4.2 * len(samples), 3.6), squeeze=False)
    for ax, i in zip(axes.flat, samples):
        ax.plot(capture.wavelengths_nm, capture.radiance[i], "k-", lw=1.5, label="measured")
        for m, S in models.items():
            c, _ = _STYLE.get(m, ("0.5", "."))
            ax.plot(wavelengths_nm, S[i], "-", color=c, lw=1.0, label=m)
        ax.set_xlim(350, 1000)
        ax.set_xlabel("wavelength [nm]")
        ax.set_ylabel("radiance [W m$^{-2}$ sr$^{-1}$ nm$^{-1}$]")
        ax.set_title(f"sample {i}: elev {capture.elevation_deg[i]:.0f}, az {capture.azimuth_deg[i]:.0f}, "
                     f"{capture.sun_angle_deg[i]:.0f} deg from sun", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes.flat[0].legend(fontsize=7)
    fig.suptitle(title or f"capture {capture.label}")
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def plot_error_maps(capture, measured, models, path, *, excluded=(0,), limit=0.5, title=None) -> None:
    """Shape error of each model (``models``: {name: luminance (81,)}) on the sky grid:
    polar panels in map view (north up, east right), radius = zenith angle."""
    plt = _pyplot()
    n = len(models)
    cols = min(n, 4)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.3 * cols + 1.2, 3.6 * rows), squeeze=False,
                             subplot_kw={"projection": "polar"})
    fig.subplots_adjust(left=0.03, right=0.86, wspace=0.35, hspace=0.55, top=0.86)
    k = _keep(measured.size, excluded)
    theta = np.radians(capture.azimuth_deg)
    r = 90.0 - capture.elevation_deg
    sc = None
    for ax, (m, L) in zip(axes.flat, models.items()):
        err = (L / L[k].mean()) / (measured / measured[k].mean()) - 1.0
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)  # azimuth clockwise from north, east at 90 deg
        sc = ax.scatter(theta[k], r[k], c=err[k], cmap="RdBu_r", vmin=-limit, vmax=limit, s=60,
                        edgecolors="k", linewidths=0.3)
        ax.scatter(theta[~k], r[~k], marker="x", c="k", s=30)
        ax.plot(np.radians(capture.sun.azimuth_deg), capture.sun.zenith_deg, "*", color="gold",
                ms=14, mec="k")
        ax.set_rlim(0, 90)
        ax.set_rticks([30, 60, 90])
        ax.set_yticklabels([])
        ax.set_xticks(np.radians([0, 90, 180, 270]))
        ax.set_xticklabels(["N", "E", "S", "W"])
        rms = float(np.sqrt(np.mean(err[k] ** 2)))
        ax.set_title(f"{m}\nshape RMS {100 * rms:.0f} %", fontsize=9)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    cax = fig.add_axes([0.89, 0.2, 0.015, 0.6])
    fig.colorbar(sc, cax=cax, label="model / measured - 1 (each / own mean)")
    fig.suptitle(title or f"capture {capture.label}: luminance shape error (sun: star)")
    _save(fig, path)
    plt.close(fig)


def plot_scan_order(capture, measured, models, path, *, title=None) -> None:
    """Luminance against the sample index (the scanner's order): the measurement and
    ``models`` ({label: luminance (81,)}), e.g. a model sampled at the labelled directions
    and averaged along each move. Ring boundaries are marked."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(11, 3.8))
    i = np.arange(measured.size)
    ax.semilogy(i, measured, "ko-", ms=4, lw=0.8, label="measured")
    for k, (lab, L) in enumerate(models.items()):
        ax.semilogy(i, L, ".-", color=f"C{k}", ms=5, lw=0.8, label=lab)
    for b in np.flatnonzero(np.diff(capture.elevation_deg) != 0) + 0.5:
        ax.axvline(b, color="0.6", lw=0.8, ls=":")
    ax.annotate("sample 0", (0, measured[0]), xytext=(3, measured[0] * 0.8), fontsize=8,
                arrowprops={"arrowstyle": "->"})
    ax.set_xlabel("sample (scan order; dotted: next ring)")
    ax.set_ylabel("luminance [cd m$^{-2}$]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or f"capture {capture.label}")
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)
