"""The aureole, Bishop's ring and the blue sun (survey 5.4-5.6) as files: the radiance
profile against the angle from the sun, a close-up image and the sun's transmittance
(``skydome aureole``), and the documentation figures. The physics is in
:mod:`skydome.effects.aureole`."""

from __future__ import annotations

import numpy as np

from skydome._io import atomic_folder, check_output_folder
from skydome._validate import as_wavelengths, check_choice, check_int, check_number
from skydome.effects.aureole import (bishops_ring_atmosphere, diffraction_ring_radius_deg,
                                     radiance_profile, ring_analysis, single_scattering_true_phase,
                                     sun_disc_radiance)

__all__ = ["AEROSOLS", "render_closeup", "run_aureole", "doc_figures"]

AEROSOLS = ("earth", "volcanic_ash", "forest_fire_smoke", "bishops_ring")


def render_closeup(atmosphere, sun, wavelengths_nm=None, *, fov_deg: float = 50.0, size: int = 161,
                   with_sun: bool = True, **kwargs):
    """A narrow-field (gnomonic) image centred on the sun: SkyImage of spectral radiance,
    ``size`` x ``size`` pixels over ``fov_deg`` (in (1, 120) deg). The sun disc is drawn
    with :func:`sun_disc_radiance` where ``with_sun``."""
    from skydome.effects.aureole import _sun
    from skydome.render.image import SkyImage

    sun = _sun(sun)
    fov = check_number("fov_deg", fov_deg, 1.0, 120.0, "deg", low_open=True, high_open=True)
    n = check_int("size", size, 8, 2048)
    wl = np.linspace(380.0, 780.0, 21) if wavelengths_nm is None else as_wavelengths(wavelengths_nm)
    f = sun.direction
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(f, up)
    if np.linalg.norm(right) < 1e-9:
        right = np.array([1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    upv = np.cross(right, f)
    t = np.tan(np.radians(fov / 2.0)) * np.linspace(-1.0, 1.0, n)
    u, v = np.meshgrid(t, -t)
    dirs = f + u[..., None] * right + v[..., None] * upv
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    L = single_scattering_true_phase(atmosphere, dirs, sun, wl, **kwargs)
    if with_sun:
        inside = (dirs @ f) >= np.cos(np.radians(sun.angular_radius_deg))
        if np.any(inside):
            L[inside] = sun_disc_radiance(atmosphere, sun, wl)
    return SkyImage(L, "spectral", wl, metadata={"atmosphere": atmosphere.describe(),
                                                  "sun_elevation_deg": sun.elevation_deg,
                                                  "fov_deg": fov, "projection": "gnomonic"})


def check_aureole_args(aerosol: str, sun_elevation_deg: float, fov_deg: float, size: int, out) -> float:
    """Validate the arguments of :func:`run_aureole` (before any work); return the elevation."""
    check_choice("aerosol", aerosol, AEROSOLS)
    elev = check_number("sun_elevation", sun_elevation_deg, 1.0, 90.0, "deg")
    check_number("fov", fov_deg, 2.0, 120.0, "deg")
    check_int("size", size, 16, 1024)
    check_output_folder(out)
    return elev


def run_aureole(out, aerosol: str = "earth", sun_elevation_deg: float = 30.0, fov_deg: float = 50.0,
                size: int = 161) -> list[str]:
    """Write ``profile.png`` (radiance at 550 nm against the angle from the sun),
    ``closeup.png`` and ``sun.txt`` (the sun's transmittance at 450 and 650 nm) into the
    folder ``out`` (atomically); return the lines of ``sun.txt``."""
    from skydome.atmosphere import Atmosphere
    from skydome.render.plots import plot_radiance_profiles
    from skydome.sun import Sun

    elev = check_aureole_args(aerosol, sun_elevation_deg, fov_deg, size, out)
    sun = Sun(elevation_deg=elev, azimuth_deg=180.0)
    if aerosol == "earth":
        atms = [Atmosphere.earth(turbidity=t) for t in (2.0, 4.0, 8.0)]
        labels = ["turbidity 2", "turbidity 4", "turbidity 8"]
    elif aerosol == "bishops_ring":
        atms, labels = [Atmosphere.earth(turbidity=2.0), bishops_ring_atmosphere()], ["clear", "1 um layer"]
    else:
        make = getattr(Atmosphere, aerosol)
        atms, labels = [Atmosphere.earth(turbidity=2.0), make()], ["clear", aerosol.replace("_", " ")]
    ang = np.concatenate([np.linspace(1.0, 10.0, 19), np.linspace(11.0, 60.0, 25)])
    wl = np.array([450.0, 550.0, 650.0])
    prof = radiance_profile(atms, elev, ang, wl)
    lines = []
    for a, lab in zip(atms, labels):
        t = sun_disc_radiance(a, sun, wl) / sun_disc_radiance(Atmosphere.custom(rayleigh_scattering=0.0), sun, wl)
        lines.append(f"{lab}: sun transmittance T(450) = {t[0]:.4f}, T(650) = {t[2]:.4f}, "
                     f"T(450)/T(650) = {t[0] / t[2]:.3f}" + (" (blue sun)" if t[0] > t[2] else ""))
    with atomic_folder(out) as tmp:
        plot_radiance_profiles(ang, [p[:, 1] for p in prof], labels, tmp / "profile.png",
                               title=f"radiance at 550 nm against the angle from the sun (sun {elev:g} deg)")
        render_closeup(atms[-1], sun, fov_deg=fov_deg, size=size).save(tmp / "closeup.png")
        (tmp / "sun.txt").write_text("\n".join(lines) + "\n")
    return lines


def doc_figures(directory) -> dict:
    """Write the documentation figures of docs/sections/effects_mie.md into ``directory``
    and return the measured figures (python -c "from skydome.apps.aureole import
    doc_figures; print(doc_figures('docs/figures'))")."""
    from pathlib import Path

    from skydome.atmosphere import Atmosphere
    from skydome.render.plots import _pyplot, _save, plot_radiance_profiles
    from skydome.sun import Sun

    out = Path(directory)
    plt = _pyplot()
    res = {}
    # 1. blue sun: transmittance of the sun at 30 deg elevation through ash / smoke
    wl = np.arange(380.0, 781.0, 10.0)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for label, atm in (("clear (T = 2)", Atmosphere.earth(turbidity=2.0)),
                       ("volcanic ash, tau550 = 1", Atmosphere.volcanic_ash(1.0)),
                       ("forest-fire smoke, tau550 = 1", Atmosphere.forest_fire_smoke(1.0))):
        t = sun_disc_radiance(atm, Sun(elevation_deg=30.0, azimuth_deg=180.0), wl)
        t0 = sun_disc_radiance(Atmosphere(()), Sun(elevation_deg=30.0, azimuth_deg=180.0), wl)
        trans = t / t0
        res[f"T450/T650 {label}"] = float(np.interp(450, wl, trans) / np.interp(650, wl, trans))
        ax.plot(wl, trans, label=label)
    ax.set_xlabel("wavelength [nm]")
    ax.set_ylabel("direct-sun transmittance, sun at 30 deg")
    ax.set_title("Blue sun: Mie extinction of narrow 0.45-0.5 um particles")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    _save(fig, out / "mie_blue_sun_transmittance.png")
    # 2. Bishop's ring profile
    atm = bishops_ring_atmosphere()
    r = ring_analysis(atm, 30.0, np.arange(1.0, 40.01, 0.5), np.linspace(380.0, 780.0, 21))
    res.update({k: r[k] for k in ("bluish_disc_deg", "red_border_deg", "red_border_outer_deg")})
    res["airy_450_550_650_deg"] = [diffraction_ring_radius_deg(1.0, w) for w in (450, 550, 650)]
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True)
    i = [int(np.argmin(np.abs(r["wavelengths_nm"] - w))) for w in (460, 540, 640)]
    for j, c in zip(i, ("tab:blue", "tab:green", "tab:red")):
        a1.plot(r["angles_deg"], r["radiance"][:, j], color=c, label=f"{r['wavelengths_nm'][j]:.0f} nm")
    a1.set_yscale("log")
    a1.set_ylabel("radiance [W m$^{-2}$ sr$^{-1}$ nm$^{-1}$]")
    a1.legend(fontsize=8)
    a1.set_title("Bishop's ring: r_m = 1 um, sigma_g = 1.1, tau550 = 0.3, sun at 30 deg")
    a2.plot(r["angles_deg"], r["red_blue"], color="k")
    a2.axhline(1.0, color="0.5", lw=0.8)
    for w, c in zip((450, 550, 650), ("tab:blue", "tab:green", "tab:red")):
        a2.axvline(diffraction_ring_radius_deg(1.0, w), color=c, ls="--", lw=0.8)
    a2.set_ylabel("L(650)/L(450) relative to the sun")
    a2.set_xlabel("angle from the sun along the almucantar [deg]")
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
    _save(fig, out / "mie_bishops_ring_profile.png")
    # 3. rendered close-up of Bishop's ring
    img = render_closeup(atm, Sun(elevation_deg=45.0, azimuth_deg=180.0), fov_deg=60.0, size=241,
                         view_samples=32)
    img.save(out / "mie_bishops_ring_closeup.png", exposure=0.35 / float(np.percentile(img.luminance(), 90)))
    # 4. aureole profiles: loads and sizes
    ang = np.concatenate([np.arange(1.0, 10.0, 0.5), np.arange(10.0, 60.01, 2.0)])
    cases = [(f"tau550 = {t}, r_m = 0.3 um", Atmosphere.volcanic_ash(t, median_radius_um=0.3, geometric_std=1.5))
             for t in (0.05, 0.2, 0.5)]
    cases += [(f"tau550 = 0.2, r_m = {rm} um", Atmosphere.volcanic_ash(0.2, median_radius_um=rm, geometric_std=1.5))
              for rm in (0.1, 1.0)]
    cases.append(("no aerosol (Rayleigh only)", Atmosphere.earth(aerosol_optical_depth=0.0)))
    L = radiance_profile([c[1] for c in cases], 40.0, ang, [550.0], view_samples=48)
    res["aureole_L3deg_550"] = {c[0]: float(L[k, 2, 0]) for k, c in enumerate(cases)}
    plot_radiance_profiles(ang, [L[k, :, 0] for k in range(len(cases))], [c[0] for c in cases],
                           out / "mie_aureole_profiles.png",
                           title="Aureole at 550 nm, sun at 40 deg (almucantar), single scattering")
    return res
