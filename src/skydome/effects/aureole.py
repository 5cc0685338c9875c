"""The aureole and Bishop's ring: single-scattered sky radiance near the sun with the true
Lorenz-Mie phase function (survey sections 5.4, 5.5).

Single scattering of a distant sun has one scattering angle per view ray (the angle between
the view direction and the sun), so the single-scattering integral ([KRZ06] eqs. 15-16)
factors per constituent c:

    L(d, lambda) = E_sun(lambda) sum_c P_c(theta, lambda) beta_s,c(lambda)
                   integral rho_c(t) exp(-tau(O, P_t) - tau(P_t, sun)) dt.

The transport kernel (:mod:`skydome.transport._kernels`) evaluates each constituent's own
phase function inside the integral: the tabulated Lorenz-Mie phase
(:class:`skydome.atmosphere.mie.MieAerosol`, as a
:class:`~skydome.atmosphere.TabulatedPhase`) for
:class:`~skydome.atmosphere.mie.MieConstituent` s, whatever analytic stand-in they were
built with, and the constituent's phase (Rayleigh / Henyey-Greenstein / Cornette-Shanks,
[KRZ06] eqs. 3, 10, 11, or tabulated) for the others. This is exact for single
scattering; multiple scattering is left
out (it adds a smooth background of a few per cent of the aureole within 10 deg of the
sun for the optical depths used here), and the sun is a point (valid beyond ~1 deg from
the centre of the disc: the disc's 0.27 deg radius smooths the phase function only
inside that).

Directions below the horizon see the air in front of a black ground (no ground
reflection); a sun below the horizon gives only what the kernel's earth shadow lets
through (no refraction).

References
----------
[KRZ06] Kment, Rauter & Zotti, Modelling of Daylight for Computer Graphics (the survey),
    sections 5.4 (aureole), 5.5 (Bishop's ring), eqs. 15-16.
[Min93] Minnaert, M. (1993), *Light and Color in the Outdoors*, Springer (Bishop's ring:
    a bluish-white disc about 10 deg in radius with a reddish-brown border out to about
    20 deg, seen after Krakatoa 1883).
[BH83] Bohren & Huffman (1983), section 4.4.3 (the forward diffraction peak; first
    minimum of the Airy pattern at sin theta = 1.22 lambda / d for a disc of diameter d).
"""

from __future__ import annotations

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_int, check_number

__all__ = ["single_scattering_true_phase", "almucantar_directions", "radiance_profile",
           "sun_disc_radiance", "bishops_ring_atmosphere", "ring_analysis",
           "diffraction_ring_radius_deg"]

def _sun(sun_or_elevation):
    from skydome.sun import Sun

    if isinstance(sun_or_elevation, Sun):
        return sun_or_elevation
    e = check_number("sun_elevation_deg", sun_or_elevation, -90.0, 90.0, "deg")
    return Sun(elevation_deg=e, azimuth_deg=180.0)


def single_scattering_true_phase(atmosphere, directions, sun, wavelengths_nm, *,
                                 observer_altitude_m: float = 0.0, view_samples: int = 64,
                                 light_samples: int = 64, quadrature_scale_m: float = 5000.0,
                                 table_size=(128, 256), constituents=None) -> np.ndarray:
    """Single-scattered spectral radiance [W m^-2 sr^-1 nm^-1] with each constituent's own
    phase function (the tabulated Mie phase for Mie constituents), shape (..., nl).

    Parameters
    ----------
    atmosphere : skydome.Atmosphere
    directions : array_like (..., 3)
        Unit vectors the light arrives from (East-North-Up).
    sun : skydome.Sun or float
        The sun, or its elevation [deg] in [-90, 90] (azimuth 180 deg).
    wavelengths_nm : array_like (nl,)
    observer_altitude_m : float
        Observer altitude [m], in [0, top of the atmosphere).
    view_samples, light_samples : int
        Quadrature nodes per view-ray piece and per light-path column (>= 2).
    quadrature_scale_m : float
        Scale of the geometric node spacing along rays [m] (5 km resolves stratospheric
        layers 20 km up with 64 nodes; see tests/test_effects_mie.py for convergence).
    table_size : (int, int)
        Size of the light-path column table.
    constituents : sequence of str, optional
        Names of the constituents whose scattering is counted (all by default); the
        extinction of every constituent is always applied.
    """
    from skydome.atmosphere import PHASE_CODES, PHASE_TABLE_ANGLES, fold_absorbers
    from skydome.atmosphere.mie import MieConstituent, mie_phase_table
    from skydome.spectra import solar_irradiance
    from skydome.transport import _kernels as K
    from skydome.transport._medium import medium_from_properties
    from skydome.transport.optical_depth import ColumnTable
    from skydome.transport.single import SingleScattering

    sun = _sun(sun)
    d = as_directions(directions)
    wl = as_wavelengths(wavelengths_nm)
    ss = SingleScattering(atmosphere, wl, observer_altitude_m, check_int("view_samples", view_samples, 2, 4096),
                          check_int("light_samples", light_samples, 2, 4096), False,
                          tuple(table_size), check_number("quadrature_scale_m", quadrature_scale_m, 1.0, 1e6, "m"))
    p = atmosphere.optical_properties(wl)      # one row per constituent, to choose from
    names = [c.name for c in atmosphere.constituents]
    if constituents is not None:
        for n in constituents:
            if n not in names:
                raise ValueError(f"constituents: no constituent named {n!r}; have {names}")
    # only the chosen constituents scatter; every Mie constituent with its Lorenz-Mie phase
    # table; a black ground
    beta_s = p.scattering.copy()
    codes = p.phase_code.copy()
    table = (np.zeros((len(names), PHASE_TABLE_ANGLES, wl.size)) if p.phase_table is None
             else p.phase_table.copy())
    for ci, c in enumerate(atmosphere.constituents):
        if constituents is not None and c.name not in constituents:
            beta_s[ci] = 0.0
        if isinstance(c, MieConstituent) and c.aerosol is not None and c.phase != "tabulated":
            codes[ci] = PHASE_CODES["tabulated"]
            table[ci] = mie_phase_table(c.aerosol).on_grid(wl, PHASE_TABLE_ANGLES)
    # the constituents left without scattering are folded as the kernels' media are (exact)
    p = fold_absorbers(p._replace(scattering=beta_s, phase_code=codes, phase_table=table,
                                  ground_albedo=np.zeros(wl.size)))[0]
    medium = medium_from_properties(p)
    columns = ColumnTable.cached(p, ss.table.n_r, ss.table.n_mu, ss.light_samples, ss.scale_m)
    e_sun = np.ascontiguousarray(solar_irradiance(wl) * sun.irradiance_scale)
    flat = np.ascontiguousarray(d.reshape(-1, 3))
    total = np.empty((flat.shape[0], wl.size))
    K.single_scattering(flat, ss.r0, sun.direction, medium, e_sun, columns.table,
                        ss.view_samples, ss.scale_m, False, ss.light_samples, total)
    np.maximum(total, 0.0, out=total)
    return total.reshape(d.shape[:-1] + (wl.size,))


def almucantar_directions(sun_elevation_deg: float, angles_deg, sun_azimuth_deg: float = 180.0):
    """Directions on the sun's almucantar (same elevation) at angular distances
    ``angles_deg`` from the sun, towards increasing azimuth; shape (na, 3).

    On the almucantar cos psi = sin^2 h + cos^2 h cos(delta az), so psi reaches at most
    180 - 2 h deg; larger angles raise ValueError.
    """
    from skydome.transport.geometry import direction_from_angles

    h = check_number("sun_elevation_deg", sun_elevation_deg, 0.0, 89.0, "deg")
    psi = np.atleast_1d(np.asarray(angles_deg, dtype=np.float64))
    limit = 180.0 - 2.0 * h
    if np.any(~np.isfinite(psi)) or np.any(psi < 0) or np.any(psi > limit):
        raise ValueError(f"angles_deg must lie in [0, {limit:g}] deg on the almucantar of a sun "
                         f"at {h:g} deg elevation")
    sh, ch = np.sin(np.radians(h)), np.cos(np.radians(h))
    cos_daz = np.clip((np.cos(np.radians(psi)) - sh * sh) / (ch * ch), -1.0, 1.0)
    daz = np.degrees(np.arccos(cos_daz))
    return direction_from_angles(np.full_like(psi, h), sun_azimuth_deg + daz)


def radiance_profile(atmospheres, sun_elevation_deg: float, angles_deg, wavelengths_nm,
                     **kwargs) -> np.ndarray:
    """Sky radiance [W m^-2 sr^-1 nm^-1] along the sun's almucantar against the angle from
    the sun, for one atmosphere (shape (na, nl)) or a sequence of them (shape (n_atm, na,
    nl)). Keywords go to :func:`single_scattering_true_phase`."""
    from skydome.atmosphere import Atmosphere

    single = isinstance(atmospheres, Atmosphere)
    atms = [atmospheres] if single else list(atmospheres)
    for a in atms:
        if not isinstance(a, Atmosphere):
            raise TypeError(f"atmospheres must be Atmosphere objects, got {type(a).__name__}")
    dirs = almucantar_directions(sun_elevation_deg, angles_deg)
    out = np.stack([single_scattering_true_phase(a, dirs, sun_elevation_deg, wavelengths_nm, **kwargs)
                    for a in atms])
    return out[0] if single else out


def sun_disc_radiance(atmosphere, sun, wavelengths_nm, observer_altitude_m: float = 0.0) -> np.ndarray:
    """Radiance of the (uniform) sun disc seen through the atmosphere [W m^-2 sr^-1 nm^-1]:
    E_sun / Omega_sun T(observer -> top); 0 where the planet hides the sun."""
    from skydome.spectra import solar_irradiance
    from skydome.transport.single import SingleScattering

    sun = _sun(sun)
    wl = as_wavelengths(wavelengths_nm)
    t = SingleScattering(atmosphere, wl, observer_altitude_m, light_samples=64,
                         table_size=(128, 256), quadrature_scale_m=5000.0).transmittance(sun.direction)
    return solar_irradiance(wl) * sun.irradiance_scale / sun.solid_angle_sr * t


# ---------------------------------------------------------------------------------------------
def bishops_ring_atmosphere(optical_depth_550: float = 0.3, median_radius_um: float = 1.0,
                            geometric_std: float = 1.1, **kwargs):
    """Earth plus a stratospheric (20 km) layer of narrow ~1 um-radius volcanic particles
    (survey section 5.5): the Bishop's ring configuration. Keywords go to
    :meth:`skydome.Atmosphere.volcanic_ash`."""
    from skydome.atmosphere import Atmosphere

    return Atmosphere.volcanic_ash(optical_depth_550, median_radius_um=median_radius_um,
                                   geometric_std=geometric_std, **kwargs)


def diffraction_ring_radius_deg(radius_um: float, wavelength_nm: float) -> float:
    """First minimum of the Fraunhofer (Airy) diffraction pattern of a disc of radius r:
    sin theta = 1.2197 lambda / (2 r) [deg] ([BH83] 4.4.3)."""
    r = check_number("radius_um", radius_um, 1e-3, 1e3, "um")
    lam = check_number("wavelength_nm", wavelength_nm, 100.0, 1e5, "nm")
    s = 1.2197 * lam * 1e-3 / (2.0 * r)
    return float(np.degrees(np.arcsin(min(s, 1.0))))


def ring_analysis(atmosphere, sun_elevation_deg: float = 30.0, angles_deg=None,
                  wavelengths_nm=None, **kwargs) -> dict:
    """Colour of the single-scattered sky around the sun against the angle from the sun.

    Returns a dict with ``angles_deg``, ``radiance`` (na, nl), ``xy`` chromaticity (na, 2),
    ``red_blue``: the ratio L(650)/L(450) divided by the same ratio of the transmitted sun
    (1 = the sun's own colour, < 1 bluer, > 1 redder), ``red_border_deg``: the angle of
    the maximum of ``red_blue`` beyond 3 deg (the reddish border), ``bluish_disc_deg``: the
    last angle inside it where the sky is bluer than the sun (the radius of the
    bluish-white disc), ``red_border_outer_deg``: the first angle outside it where the sky
    is bluer than the sun again (NaN where there is none).
    """
    from skydome.spectra import spectrum_to_xyz, xyz_to_xy

    h = check_number("sun_elevation_deg", sun_elevation_deg, 1.0, 89.0, "deg")
    if angles_deg is None:
        angles_deg = np.arange(1.0, min(60.0, 180.0 - 2.0 * h) + 1e-9, 0.5)
    ang = np.asarray(angles_deg, dtype=np.float64)
    wl = np.linspace(380.0, 780.0, 21) if wavelengths_nm is None else as_wavelengths(wavelengths_nm)
    wl_all = np.unique(np.concatenate([wl, [450.0, 650.0]]))
    L = radiance_profile(atmosphere, h, ang, wl_all, **kwargs)
    sun_l = sun_disc_radiance(atmosphere, h, [450.0, 650.0])
    i450, i650 = np.searchsorted(wl_all, 450.0), np.searchsorted(wl_all, 650.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        rb = (L[:, i650] / L[:, i450]) / (sun_l[1] / sun_l[0])
    keep = np.isin(wl_all, wl)
    xy = xyz_to_xy(spectrum_to_xyz(L[:, keep], wl_all[keep]))
    sel = np.where(ang >= 3.0)[0]
    i_red = sel[np.argmax(rb[sel])]
    # edges of the reddish border: where red_blue crosses 1 inside and outside its maximum
    inner = np.where((ang < ang[i_red]) & (rb < 1.0))[0]
    outer = np.where((ang > ang[i_red]) & (rb < 1.0))[0]
    inner_deg = float(ang[inner[-1]]) if inner.size else float("nan")
    outer_deg = float(ang[outer[0]]) if outer.size else float("nan")
    return {"angles_deg": ang, "wavelengths_nm": wl_all[keep], "radiance": L[:, keep], "xy": xy,
            "red_blue": rb, "bluish_disc_deg": inner_deg, "red_border_deg": float(ang[i_red]),
            "red_border_outer_deg": outer_deg}
