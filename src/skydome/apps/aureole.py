"""The aureole, Bishop's ring and the blue sun (survey 5.4-5.6) as files: the radiance
profile against the angle from the sun, a close-up image and the sun's transmittance
(``skydome aureole``). The physics is in
:mod:`skydome.effects.aureole`."""

from __future__ import annotations

import numpy as np

from skydome._io import atomic_folder, check_output_folder
from skydome._validate import as_wavelengths, check_choice, check_int, check_number
from skydome.effects.aureole import (bishops_ring_atmosphere, radiance_profile,
                                     single_scattering_true_phase, sun_disc_radiance)

__all__ = ["AEROSOLS", "render_closeup", "run_aureole"]

AEROSOLS = ("earth", "volcanic_ash", "forest_fire_smoke", "bishops_ring")


def render_closeup(atmosphere, sun, wavelengths_nm=None, *, fov_deg: float = 50.0, size: int = 161,
                   height: int | None = None, with_sun: bool = True, **kwargs):
    """A narrow-field (gnomonic) image centred on the sun: SkyImage of spectral radiance,
    ``size`` pixels wide over the horizontal field ``fov_deg`` (in (1, 120) deg) and
    ``height`` pixels high (default ``size``: square), with square pixels (the vertical
    field follows from the aspect). The sun disc is drawn with :func:`sun_disc_radiance`
    where ``with_sun``."""
    from skydome.effects.aureole import _sun
    from skydome.imaging.image import SkyImage

    sun = _sun(sun)
    fov = check_number("fov_deg", fov_deg, 1.0, 120.0, "deg", low_open=True, high_open=True)
    n = check_int("size", size, 8, 2048)
    h = n if height is None else check_int("height", height, 8, 2048)
    wl = np.linspace(380.0, 780.0, 21) if wavelengths_nm is None else as_wavelengths(wavelengths_nm)
    f = sun.direction
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(f, up)
    if np.linalg.norm(right) < 1e-9:
        right = np.array([1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    upv = np.cross(right, f)
    t = np.tan(np.radians(fov / 2.0)) * np.linspace(-1.0, 1.0, n)
    tv = np.tan(np.radians(fov / 2.0)) * (h - 1) / (n - 1) * np.linspace(-1.0, 1.0, h)
    u, v = np.meshgrid(t, -tv)
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
    from skydome.imaging.plots import plot_radiance_profiles
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
