"""Stokes parameters, polarisation maps and neutral points of the whole sky (survey 5.7).

One entry point, :func:`sky_stokes`, returns the Stokes vectors (I, Q, U, V) of skylight for
any polarisation-capable method:

``"rayleigh_single"``
    the analytic single-scattering Rayleigh field of :mod:`skydome.effects.polarisation`
    (Chandrasekhar 1950, sec. 18; Hansen & Travis 1974, eq. 2.15), with I from the
    ``single_scattering`` model's radiance (``intensity="model"``) or 1 (``"unit"``);
``"montecarlo"``
    the polarised Monte Carlo model (every order of scattering, aerosols, ground), with
    standard errors.

Both give the Stokes vectors in the same frame: the reference axis e_par is the direction
of increasing elevation (in the vertical plane through the viewing direction) and the
second axis is e_perp = k x e_par, with k = -d the direction the light travels. Q > 0 means
the E-vector lies preferentially in the vertical plane; the angle of polarisation is
0.5 atan2(U, Q), measured from e_par towards e_perp, i.e. counter-clockwise as seen by an
observer facing the sky (for a view due north, e_perp points west). The two modules build
this frame in the same way; at the zenith they pick opposite reference axes (north and
south), which leaves Q and U unchanged (a rotation by 180 deg). ``test_polarisation_maps``
checks both.

:func:`polarisation_maps` samples a grid of directions (a fisheye's pixels, say: north
up, east left, looking up),
:func:`skydome.imaging.plots.plot_polarisation_maps` draws the degree (perceptual colour map, 0..1) and angle
(cyclic colour map, with E-vector segments) of polarisation, and :func:`meridian_profile`
with :func:`find_neutral_points` locate the Arago, Babinet and Brewster neutral points
along the solar meridian.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_choice, check_number
from skydome.effects.polarisation import (angle_of_polarisation, degree_of_polarisation,
                                          neutral_points_from_sign, neutral_points_on_meridian,
                                          rayleigh_single_scattering_stokes)

__all__ = ["METHODS", "DEPOLARISATION_550", "SkyStokes", "polarisation_atmosphere", "sky_stokes",
           "e_vectors", "PolarisationMap", "polarisation_maps", "MeridianProfile", "meridian_profile",
           "find_neutral_points"]

METHODS = ("rayleigh_single", "montecarlo")

#: Depolarisation factor of air at 550 nm (Bates 1984, Planet. Space Sci. 32, 785; Young
#: 1980, Appl. Opt. 19, 3427: 0.0279 with a weak wavelength dependence).
DEPOLARISATION_550 = 0.0279


class SkyStokes(NamedTuple):
    """Stokes vectors and their standard errors, each (..., n_wavelengths, 4)
    [W m^-2 sr^-1 nm^-1] (or relative units with ``intensity="unit"``). The standard error
    is 0 for the analytic method."""
    stokes: np.ndarray
    stderr: np.ndarray


def polarisation_atmosphere(turbidity: float = 2.5, *, depolarisation: float = DEPOLARISATION_550,
                            aerosol_phase: str = "henyey_greenstein", ground_albedo: float = 0.1):
    """The default atmosphere for polarisation: ``Atmosphere.earth(turbidity)`` with the
    Rayleigh depolarisation of air (0.0279) and depolarising Henyey-Greenstein aerosols.

    ``Atmosphere.earth`` defaults to rho = 0 and Cornette-Shanks aerosols, whose scattering
    matrix in the Monte Carlo model polarises like Rayleigh scattering and so overstates the
    polarisation by aerosols (see docs/sections/montecarlo.md); real continental aerosols
    polarise weakly (tens of per cent at most), closer to the depolarising HG choice.
    """
    from skydome.atmosphere import Atmosphere

    t = check_number("turbidity", turbidity, 1.0, 32.0)
    return Atmosphere.earth(turbidity=t, depolarisation=depolarisation, aerosol_phase=aerosol_phase,
                            ground_albedo=ground_albedo)


def _rayleigh_depolarisation(atmosphere) -> float:
    props = atmosphere.optical_properties(np.array([550.0]))
    ray = np.flatnonzero(props.phase_code == 0)
    if ray.size == 0:
        return 0.0
    pp = float(props.phase_param[ray[0]])          # rho / (2 - rho)
    return 2.0 * pp / (1.0 + pp)


def sky_stokes(method: str, sun, directions, wavelengths_nm, *, atmosphere=None,
               turbidity: float | None = None, depolarisation: float | None = None,
               intensity: str = "model", samples: int = 1000, seed: int = 0,
               max_order: int | None = None, observer_altitude_m: float = 0.0) -> SkyStokes:
    """Stokes parameters of skylight arriving from ``directions``.

    Parameters
    ----------
    method : {"rayleigh_single", "montecarlo"}
        Analytic single Rayleigh scattering, or the polarised Monte Carlo model.
    sun : skydome.Sun
        Sun position.
    directions : array_like, (..., 3)
        Unit vectors (East-North-Up) towards where the light comes from.
    wavelengths_nm : array_like, (n,)
        Wavelengths [nm].
    atmosphere : skydome.Atmosphere, optional
        The medium (default :func:`polarisation_atmosphere` (turbidity)).
    turbidity : float, optional
        Turbidity [1, 32] of the default atmosphere (default 2.5); not with ``atmosphere``.
    depolarisation : float, optional
        ``rayleigh_single`` only: depolarisation factor rho [0, 0.5]; default the
        atmosphere's Rayleigh value, so that both methods use the same rho.
    intensity : {"model", "unit"}
        ``rayleigh_single`` only: I from the ``single_scattering`` model's radiance in the
        same atmosphere, or I = 1.
    samples, seed, max_order, observer_altitude_m
        ``montecarlo`` only (see the ``montecarlo`` model); ``observer_altitude_m`` [m] is
        also passed to ``single_scattering`` for ``intensity="model"``.

    Returns
    -------
    SkyStokes
        (stokes, stderr), each (..., n_wavelengths, 4), in the frame described in the module
        docstring. V = 0 for ``rayleigh_single``.

    Notes
    -----
    Directions below the horizon: ``montecarlo`` returns the light from the ground and the
    air in front of it; ``rayleigh_single`` returns the single-scattering polarisation of the
    scattering geometry with I from the model (which sees the air in front of the ground).
    With the sun below the horizon both stay finite and non-negative in I.
    """
    from skydome.sun import Sun

    check_choice("method", method, METHODS)
    if not isinstance(sun, Sun):
        raise TypeError(f"sun must be a skydome.Sun, not {type(sun).__name__}")
    d = as_directions(directions)
    wl = as_wavelengths(wavelengths_nm)
    check_choice("intensity", intensity, ("model", "unit"))
    if atmosphere is not None and turbidity is not None:
        raise ValueError("give either atmosphere or turbidity, not both")
    if atmosphere is None:
        atmosphere = polarisation_atmosphere(2.5 if turbidity is None else turbidity)
    if method == "montecarlo":
        if depolarisation is not None:
            raise ValueError("depolarisation is a property of the atmosphere for method = 'montecarlo'")
        from skydome.models.simulated.montecarlo import MonteCarloSky

        m = MonteCarloSky(sun=sun, atmosphere=atmosphere, observer_altitude_m=observer_altitude_m,
                          samples=samples, seed=seed, polarised=True, max_order=max_order)
        st, err = m.stokes_with_error(d, wl)
        return SkyStokes(st, err)
    # analytic single scattering
    rho = _rayleigh_depolarisation(atmosphere) if depolarisation is None else \
        check_number("depolarisation", depolarisation, 0.0, 0.5)
    if intensity == "model":
        from skydome.models.simulated.single_scattering import SingleScatteringSky

        I = SingleScatteringSky(sun=sun, atmosphere=atmosphere,
                                observer_altitude_m=observer_altitude_m).radiance(d, wl)
        I = np.maximum(np.nan_to_num(I, nan=0.0), 0.0)
    else:
        I = np.ones(d.shape[:-1] + (wl.size,))
    unit = rayleigh_single_scattering_stokes(d, sun.direction, 1.0, rho)     # (..., 4)
    st = I[..., None] * unit[..., None, :]
    return SkyStokes(st, np.zeros_like(st))


def e_vectors(directions, stokes) -> np.ndarray:
    """Unit E-vectors (..., 3) in East-North-Up of the linear polarisation described by
    Stokes vectors (..., 4) in the common frame (0 where the light is unpolarised).

    The E-vector is cos(chi) e_par + sin(chi) e_perp with chi the angle of polarisation;
    its sign is arbitrary (a line, not an arrow)."""
    from skydome.effects.polarisation import local_frame

    d = as_directions(directions)
    v, h = local_frame(d)       # e_par and e_perp (= k x e_par)
    chi = np.radians(angle_of_polarisation(stokes))
    e = np.cos(chi)[..., None] * v + np.sin(chi)[..., None] * h
    pol = degree_of_polarisation(stokes) > 0
    return np.where(pol[..., None], e, 0.0)


# ---------------------------------------------------------------------------------------
# Maps
# ---------------------------------------------------------------------------------------

class PolarisationMap(NamedTuple):
    """A map of polarisation on a grid of viewing directions (a fisheye, say: north up,
    east left, looking up).

    dirs (H, W, 3); mask (H, W) True where computed (the sky disc of a fisheye); stokes,
    stderr (H, W, 4) at one wavelength; dop (H, W) in [0, 1] and aop (H, W) [deg] in
    (-90, 90] (NaN where not computed); plus the method, sun and wavelength [nm]."""
    dirs: np.ndarray
    mask: np.ndarray
    stokes: np.ndarray
    stderr: np.ndarray
    dop: np.ndarray
    aop: np.ndarray
    method: str
    sun: Any
    wavelength_nm: float


def polarisation_maps(method: str, sun, directions, mask=None, wavelength_nm: float = 550.0,
                      **kw) -> PolarisationMap:
    """Degree and angle of polarisation at one wavelength [nm] on a grid of viewing
    directions (H, W, 3) (unit vectors, East-North-Up), e.g. the pixels of a projection:
    ``polarisation_maps(method, sun, *skydome.Fisheye(48).directions())`` gives the
    fisheye map (north up, east left, zenith at the centre, horizon on the inscribed
    circle). ``mask`` (H, W) marks the directions to compute (default: every finite one);
    the others hold 0 (Stokes) and NaN (degree, angle). ``kw`` go to :func:`sky_stokes`."""
    d = np.asarray(directions, dtype=np.float64)
    if d.ndim != 3 or d.shape[-1] != 3:
        raise ValueError(f"directions has shape {d.shape}; expected (height, width, 3)")
    if mask is None:
        mask = np.all(np.isfinite(d), axis=-1)
    mask = np.asarray(mask)
    if mask.shape != d.shape[:2] or mask.dtype != bool:
        raise ValueError(f"mask has shape {mask.shape} and dtype {mask.dtype}; expected "
                         f"booleans of shape {d.shape[:2]} (the directions')")
    wl = float(check_number("wavelength_nm", wavelength_nm, 200.0, 4000.0, "nm"))
    st = np.zeros(d.shape[:2] + (4,))
    er = np.zeros(d.shape[:2] + (4,))
    r = sky_stokes(method, sun, d[mask], [wl], **kw)
    st[mask] = r.stokes[:, 0, :]
    er[mask] = r.stderr[:, 0, :]
    dop = np.where(mask, degree_of_polarisation(st), np.nan)
    aop = np.where(mask, angle_of_polarisation(st), np.nan)
    return PolarisationMap(d, mask, st, er, dop, aop, method, sun, wl)


class MeridianProfile(NamedTuple):
    """Polarisation along the solar meridian.

    angle_deg: position as the angle above the horizon on the sun's side (0..180: 90 is the
    zenith, 180 the horizon opposite the sun), as :func:`neutral_points_on_meridian`;
    scattering_deg: angle from the sun; stokes, stderr (n, 4); dop (n,); signed (n,) the
    signed degree -Q/I: > 0 for the normal polarisation perpendicular to the meridian
    (the scattering plane), < 0 for the "negative" polarisation parallel to it."""
    angle_deg: np.ndarray
    scattering_deg: np.ndarray
    stokes: np.ndarray
    stderr: np.ndarray
    dop: np.ndarray
    signed: np.ndarray
    sun_elevation_deg: float


def meridian_profile(method: str, sun, step_deg: float = 2.0, wavelength_nm: float = 550.0,
                     **kw) -> MeridianProfile:
    """Stokes vectors along the solar meridian, from ``step_deg / 2`` above the horizon
    under the sun, through the zenith, to the horizon opposite. ``kw`` go to
    :func:`sky_stokes`."""
    from skydome.transport.geometry import direction_from_angles

    step = check_number("step_deg", step_deg, 0.1, 30.0, "deg")
    a = np.arange(0.5 * step, 180.0, step)
    el = np.where(a <= 90.0, a, 180.0 - a)
    az = np.where(a <= 90.0, sun.azimuth_deg, sun.azimuth_deg + 180.0) % 360.0
    d = direction_from_angles(el, az)
    r = sky_stokes(method, sun, d, [wavelength_nm], **kw)
    st, er = r.stokes[:, 0, :], r.stderr[:, 0, :]
    I = st[:, 0]
    signed = np.where(I > 0, -st[:, 1] / np.where(I > 0, I, 1.0), 0.0)
    scat = np.degrees(np.arccos(np.clip(d @ sun.direction, -1.0, 1.0)))
    return MeridianProfile(a, scat, st, er, degree_of_polarisation(st), signed, sun.elevation_deg)


def find_neutral_points(profile: MeridianProfile, exclude_deg: float = 4.0,
                        method: str = "sign") -> dict[str, float]:
    """Arago, Babinet and Brewster points of a :class:`MeridianProfile`.

    ``method="sign"`` (default): the zero crossings of the signed degree -Q/I (where the
    polarisation turns from perpendicular to parallel to the meridian), linearly
    interpolated, ignoring crossings within ``exclude_deg`` of the sun and the antisolar
    point (see :func:`skydome.effects.polarisation.neutral_points_from_sign`).
    ``method="minimum"``: local minima of |Q|/I below 0.05 by
    :func:`skydome.effects.polarisation.neutral_points_on_meridian`, with the points
    within ``exclude_deg`` of the sun and antisolar point left out (the degree vanishes
    there for every sky). Returns {name: angle [deg] on the scale of ``profile.angle_deg``}.
    """
    check_choice("method", method, ("sign", "minimum"))
    if method == "sign":
        return neutral_points_from_sign(profile.angle_deg, profile.signed, profile.sun_elevation_deg,
                                        exclude_deg=exclude_deg)
    keep = (profile.scattering_deg > exclude_deg) & (profile.scattering_deg < 180.0 - exclude_deg)
    return neutral_points_on_meridian(profile.angle_deg[keep], np.abs(profile.signed[keep]),
                                      profile.sun_elevation_deg)
