"""The figures of docs/sections/effects_mie.md (aureole, Bishop's ring, blue sun).

    PYTHONPATH=src python docs/mie_figures.py docs/figures
"""

import sys
from pathlib import Path

import numpy as np

from skydome.apps.aureole import render_closeup
from skydome.effects.aureole import (bishops_ring_atmosphere, diffraction_ring_radius_deg,
                                     radiance_profile, ring_analysis, sun_disc_radiance)
from skydome.imaging.plots import _pyplot, _save, plot_radiance_profiles


def doc_figures(directory) -> dict:
    """Write the documentation figures of docs/sections/effects_mie.md into ``directory``
    and return the measured figures."""
    from skydome.atmosphere import Atmosphere
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


if __name__ == "__main__":
    print(doc_figures(sys.argv[1] if len(sys.argv) > 1 else "docs/figures"))
