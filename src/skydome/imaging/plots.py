"""Figures: polar false-colour luminance maps and model comparisons (matplotlib).

matplotlib is imported inside the functions (with the non-interactive Agg backend), so
importing this module is cheap. Figures are written atomically.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_luminance_map", "plot_compare", "meridian_profiles", "plot_radiance_profiles",
           "plot_error_maps", "plot_day_colours", "plot_twilight", "plot_polarisation_maps"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` atomically (format from the suffix) and close it."""
    from skydome._io import atomic_file

    plt = _pyplot()
    try:
        with atomic_file(path) as tmp:
            fig.savefig(tmp, dpi=dpi)
    finally:
        plt.close(fig)


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


def plot_error_maps(path, spec, elevs, xyzs, ref_spec, weights) -> None:
    """log2(L / L_ref) fisheye maps of model ``spec`` against ``ref_spec``, one per sun
    elevation (``xyzs[(spec, elevation)]`` XYZ images, ``weights`` > 0 on the sky disc)."""
    plt = _pyplot()

    fig, axes = plt.subplots(1, len(elevs), figsize=(3.2 * len(elevs) + 1.0, 3.4), squeeze=False)
    im = None
    for j, e in enumerate(elevs):
        ax = axes[0, j]
        ax.set_axis_off()
        got, ref = xyzs.get((spec, e)), xyzs.get((ref_spec, e))
        if got is None or ref is None:
            ax.set_title(f"sun {e:g} deg: n/a", fontsize=9)
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(weights > 0, np.log2(got[..., 1] / ref[..., 1]), np.nan)
        im = ax.imshow(ratio, cmap="RdBu_r", vmin=-2, vmax=2)
        ax.set_title(f"sun {e:g} deg", fontsize=9)
    if im is not None:
        fig.colorbar(im, ax=axes.ravel().tolist(), label="log2(L / L_ref)", shrink=0.85)
    fig.suptitle(f"{spec} against {ref_spec} (fisheye, north up, east left)", fontsize=10)
    _save(fig, path, dpi=90)


def plot_day_colours(frames, path, display_colour) -> None:
    """The timelapse figure: colour strips (``display_colour(xyz)`` of the zenith, the horizon
    under the sun and the sun disc), their luminance, and the sun's elevation against time."""
    plt = _pyplot()

    ok = [f for f in frames if f.zenith_xyz is not None]
    hours = np.array([f.time.hour + f.time.minute / 60 + f.time.second / 3600 for f in ok])
    fig, axes = plt.subplots(3, 1, figsize=(9, 6.5), sharex=True,
                             gridspec_kw={"height_ratios": [1.2, 2, 1.2]})
    strip = axes[0]
    labels = [("zenith", "zenith_xyz"), ("horizon under the sun", "horizon_xyz"), ("sun disc", "sun_xyz")]
    dt = np.median(np.diff(hours)) if hours.size > 1 else 0.25
    for row, (label, attr) in enumerate(labels):
        for h, f in zip(hours, ok):
            strip.add_patch(plt.Rectangle((h - dt / 2, row), dt, 0.9, color=display_colour(getattr(f, attr))))
    strip.set_ylim(0, 3)
    strip.set_yticks([0.45, 1.45, 2.45], [lab for lab, _ in labels])
    strip.set_title("colour (chromaticity at constant brightness)")
    lum = axes[1]
    for label, attr in labels:
        y = [getattr(f, attr)[1] if getattr(f, attr) is not None else np.nan for f in ok]
        lum.semilogy(hours, y, label=label)
    lum.set_ylabel("luminance [cd/m$^2$]")
    lum.legend(fontsize=8)
    lum.grid(alpha=0.3, which="both")
    axes[2].plot(hours, [f.elevation_deg for f in ok], color="k")
    axes[2].axhline(0, color="0.6", lw=0.8)
    axes[2].set_ylabel("sun elevation [deg]")
    axes[2].set_xlabel(f"local time [h] (UTC{ok[0].time.strftime('%z')})" if ok else "local time [h]")
    axes[2].grid(alpha=0.3)
    fig.tight_layout()
    _save(fig, path, dpi=90)


def plot_twilight(rows, prof_el, path) -> None:
    """The twilight figure: zenith luminance and horizontal illuminance against the sun's
    elevation with published values, and the anti-solar R/B and luminance profiles
    (``rows``: (depression, zenith luminance, illuminance, luminance profile, R/B profile, _))."""
    plt = _pyplot()

    deps = np.array([r[0] for r in rows])
    fig, ax = plt.subplots(1, 3, figsize=(11, 5.4))   # about 2:1, like the demo's gallery cells
    ax[0].semilogy(-deps, [max(r[1], 1e-12) for r in rows], "o-", label="zenith luminance [cd/m$^2$]")
    ax[0].semilogy(-deps, [max(r[2], 1e-12) for r in rows], "s-", label="horizontal illuminance [lx]")
    # published clear-sky horizontal illuminance (AMS Glossary of Meteorology, "civil
    # twilight", "astronomical twilight") and the natural night sky's zenith luminance
    # (V = 21.6 mag/arcsec^2, Patat 2003, A&A 400, 1183: 10.8e4 * 10^(-0.4 V) = 2.5e-4 cd/m^2)
    for x, lo, hi in ((0.0, 410.0, 585.0), (-6.0, 2.0, 3.5)):
        ax[0].plot([x, x], [lo, hi], "k-", lw=3)
    ax[0].plot([-12.0, -18.0], [8e-3, 6e-4], "kx", ms=8, label="AMS glossary illuminance [lx]")
    ax[0].axhline(2.5e-4, color="k", ls=":", lw=1, label="night sky zenith (not modelled)")
    for x, name in ((-6, "civil"), (-12, "nautical"), (-18, "astronomical")):
        ax[0].axvline(x, color="0.7", lw=0.8)
        ax[0].text(x + 0.2, 1e2, name, rotation=90, fontsize=8, color="0.4")
    ax[0].set_xlabel("sun elevation [deg]")
    ax[0].legend(fontsize=8)
    ax[0].grid(alpha=0.3, which="both")
    for dep, _, _, lum, rb, _ in rows:
        if dep <= 6:
            ax[1].plot(prof_el, rb, label=f"sun {-dep + 0.0:g}")
            ax[2].semilogy(prof_el, np.maximum(lum, 1e-12), label=f"sun {-dep + 0.0:g}")
    ax[1].set_xlabel("elevation opposite the sun [deg]")
    ax[1].set_ylabel("R/B (linear sRGB)")
    ax[1].set_title("Belt of Venus (R/B peak) over the earth's shadow")
    ax[1].legend(fontsize=7)
    ax[1].grid(alpha=0.3)
    ax[2].set_xlabel("elevation opposite the sun [deg]")
    ax[2].set_ylabel("luminance [cd/m$^2$]")
    ax[2].grid(alpha=0.3, which="both")
    fig.tight_layout()
    _save(fig, path, dpi=90)


def plot_polarisation_maps(pmap, path, title: str | None = None,
                           segments: int = 16) -> None:
    """Figure with the degree (viridis, colour bar 0..1) and the angle (cyclic 'twilight',
    colour bar -90..90 deg) of polarisation of ``pmap``; the degree panel carries E-vector
    segments on a ``segments`` x ``segments`` grid, of length proportional to the degree.
    ``pmap`` holds the directions of a square fisheye (``Fisheye(n).directions()``): north
    up, east left; the sun is marked. Written atomically (.png, .pdf or .svg)."""
    from skydome.effects.polarisation_maps import e_vectors
    from skydome.imaging.projections import Fisheye

    plt = _pyplot()

    n = pmap.mask.shape[0]
    proj = Fisheye(n)
    fig, axes = plt.subplots(1, 2, figsize=(10.5, 5.0))
    ext = (0, n, n, 0)
    im0 = axes[0].imshow(np.ma.masked_invalid(pmap.dop), cmap="viridis", vmin=0.0, vmax=1.0,
                         extent=ext, interpolation="nearest")
    fig.colorbar(im0, ax=axes[0], fraction=0.046, pad=0.04, label="degree of linear polarisation")
    im1 = axes[1].imshow(np.ma.masked_invalid(pmap.aop), cmap="twilight", vmin=-90.0, vmax=90.0,
                         extent=ext, interpolation="nearest")
    fig.colorbar(im1, ax=axes[1], fraction=0.046, pad=0.04,
                 label="angle of polarisation [deg] from the local vertical")
    # E-vector segments: sample a coarser grid of directions through the projection
    k = max(1, n // segments)
    rows = np.arange(k // 2, n, k)
    for ax, col_, lw in ((axes[0], "white", 1.0), (axes[1], "black", 0.8)):
        for r in rows:
            for c in rows:
                if not pmap.mask[r, c]:
                    continue
                d = pmap.dirs[r, c]
                e = e_vectors(d, pmap.stokes[r, c])
                p = float(pmap.dop[r, c])
                if not np.any(e):
                    continue
                eps = 1e-3
                r1, c1 = proj.pixel_from_direction((d + eps * e) / np.linalg.norm(d + eps * e))
                r0, c0 = proj.pixel_from_direction((d - eps * e) / np.linalg.norm(d - eps * e))
                dr, dc = float(r1 - r0), float(c1 - c0)
                L = np.hypot(dr, dc)
                if not np.isfinite(L) or L == 0:
                    continue
                half = 0.45 * k * (p if ax is axes[0] else 1.0)
                yc, xc = r + 0.5, c + 0.5
                ax.plot([xc - half * dc / L, xc + half * dc / L], [yc - half * dr / L, yc + half * dr / L],
                        color=col_, lw=lw, solid_capstyle="round")
    sp = proj.sun_pixel(pmap.sun)
    for ax in axes:
        ax.add_patch(plt.Circle((n / 2, n / 2), n / 2, fill=False, color="0.4", lw=0.8))
        if sp is not None:
            ax.plot(sp[1], sp[0], marker="o", ms=9, mfc="yellow", mec="black")
        for lab, (x, y) in {"N": (n / 2, -0.04 * n), "S": (n / 2, 1.04 * n),
                            "E": (-0.04 * n, n / 2), "W": (1.04 * n, n / 2)}.items():
            ax.text(x, y, lab, ha="center", va="center", fontsize=10)
        ax.set_xlim(-0.08 * n, 1.08 * n)
        ax.set_ylim(1.08 * n, -0.08 * n)
        ax.set_aspect("equal")
        ax.axis("off")
    axes[0].set_title("degree of polarisation (E-vectors)")
    axes[1].set_title("angle of polarisation")
    if title is None:
        title = (f"{pmap.method}: sun elevation {pmap.sun.elevation_deg:g} deg, azimuth "
                 f"{pmap.sun.azimuth_deg:g} deg, {pmap.wavelength_nm:g} nm (north up, east left)")
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    _save(fig, path, dpi=110)
