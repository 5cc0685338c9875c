"""Figures: polar false-colour luminance maps and model comparisons (matplotlib).

matplotlib is imported inside the functions (with the non-interactive Agg backend), so
importing this module is cheap. Figures are written atomically.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_luminance_map", "plot_compare", "meridian_profiles", "plot_radiance_profiles"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path) -> None:
    from skydome._io import atomic_file

    with atomic_file(path) as tmp:
        fig.savefig(tmp, dpi=110)


def _polar_grid(n_zenith: int = 90, n_azimuth: int = 360):
    from skydome.transport.geometry import direction_from_angles

    zen = np.linspace(0.0, 90.0, n_zenith + 1)
    az = np.linspace(0.0, 360.0, n_azimuth + 1)
    zc = 0.5 * (zen[:-1] + zen[1:])
    ac = 0.5 * (az[:-1] + az[1:])
    A, Z = np.meshgrid(ac, zc)
    dirs = direction_from_angles(90.0 - Z, A)
    return zen, az, dirs


def plot_luminance_map(sky, path, *, title: str | None = None, log: bool = True) -> None:
    """Polar (upper-hemisphere) false-colour map of luminance [cd/m^2] with a colour bar
    and the sun marked. North is at the top and east to the right, as on a sun-path
    diagram (the view from above); the radius is the zenith angle (equidistant)."""
    plt = _pyplot()
    from matplotlib.colors import LogNorm, Normalize

    zen, az, dirs = _polar_grid()
    lum = np.asarray(sky.luminance(dirs), dtype=np.float64)
    fig = plt.figure(figsize=(6.4, 5.4))
    ax = fig.add_subplot(projection="polar")
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    positive = lum[lum > 0]
    if log and positive.size:
        norm = LogNorm(vmin=max(positive.min(), positive.max() * 1e-4), vmax=positive.max())
        data = np.maximum(lum, norm.vmin)
    else:
        norm, data = Normalize(vmin=0.0, vmax=max(lum.max(), 1e-12)), lum
    mesh = ax.pcolormesh(np.radians(az), zen, data, norm=norm, cmap="inferno", shading="flat")
    cb = fig.colorbar(mesh, ax=ax, pad=0.1)
    cb.set_label("luminance [cd/m$^2$]")
    sun = getattr(sky, "sun", None)
    if sun is not None and sun.elevation_deg > 0:
        ax.plot(np.radians(sun.azimuth_deg), sun.zenith_deg, marker="o", ms=10, mfc="none",
                mec="cyan", mew=2, label="sun")
        ax.legend(loc="lower left", bbox_to_anchor=(-0.15, -0.12))
    ax.set_ylim(0, 90)
    ax.set_yticks([30, 60, 90])
    ax.set_yticklabels(["60°", "30°", "0°"], color="0.6")
    ax.set_xticks(np.radians([0, 90, 180, 270]))
    ax.set_xticklabels(["N", "E", "S", "W"])
    ax.set_title(title or f"{sky.name}: luminance", pad=14)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def meridian_profiles(sky, n: int = 181):
    """Luminance [cd/m^2] along the solar meridian and along the sun's almucantar.

    Returns (meridian_angle_deg, meridian_luminance, almucantar_azimuth_deg,
    almucantar_luminance): the meridian angle runs from the horizon on the sun's side
    (-90) through the zenith (0) to the opposite horizon (+90); the almucantar azimuth is
    measured from the sun (0 = the sun).
    """
    from skydome.transport.geometry import direction_from_angles

    sun = sky.sun
    m = np.linspace(-89.5, 89.5, n)
    el = 90.0 - np.abs(m)
    az = np.where(m < 0, sun.azimuth_deg, sun.azimuth_deg + 180.0)
    lm = sky.luminance(direction_from_angles(el, az))
    rel = np.linspace(-180.0, 180.0, 2 * n - 1)
    alm_el = min(max(sun.elevation_deg, 0.5), 89.5)
    la = sky.luminance(direction_from_angles(np.full_like(rel, alm_el), sun.azimuth_deg + rel))
    return m, np.asarray(lm), rel, np.asarray(la)


def plot_compare(skies, labels, path, *, title: str | None = None, relative: bool = False) -> None:
    """One figure: luminance along the solar meridian (left) and the almucantar (right)
    for several models; ``relative`` divides each curve by its zenith luminance."""
    plt = _pyplot()
    from skydome.transport.geometry import direction_from_angles

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.4))
    for sky, label in zip(skies, labels):
        m, lm, rel, la = meridian_profiles(sky)
        if relative:
            lz = float(sky.luminance(direction_from_angles(90.0, 0.0)))
            lm, la = lm / lz, la / lz
        a1.plot(m, lm, label=label)
        a2.plot(rel, la, label=label)
    ylabel = "L / L$_z$" if relative else "luminance [cd/m$^2$]"
    a1.set_xlabel("angle from zenith along the solar meridian [deg] (sun side < 0)")
    a2.set_xlabel("azimuth from the sun along its almucantar [deg]")
    for a in (a1, a2):
        a.set_ylabel(ylabel)
        a.set_yscale("log")
        a.grid(True, which="both", alpha=0.3)
    a1.legend(fontsize=8)
    if skies:
        s = skies[0].sun
        fig.suptitle(title or f"sun elevation {s.elevation_deg:.1f} deg, azimuth {s.azimuth_deg:.1f} deg")
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def plot_radiance_profiles(angles_deg, profiles, labels, path, *, title: str | None = None,
                           ylabel: str = "radiance [W m$^{-2}$ sr$^{-1}$ nm$^{-1}$]",
                           log: bool = True) -> None:
    """Plot radiance (or any quantity) against the angle from the sun: ``profiles`` is a
    sequence of (na,) arrays, one per label; written to ``path`` (PNG/PDF/SVG)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for prof, lab in zip(profiles, labels):
        ax.plot(angles_deg, prof, label=lab)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("angle from the sun [deg]")
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    _save(fig, path)
