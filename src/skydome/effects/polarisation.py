"""Polarisation of skylight (survey section 5.7).

Single Rayleigh scattering polarises sunlight perpendicular to the scattering plane (the
plane through the sun, the observer and the viewing direction) with the degree

    P(theta) = (1 - rho) sin^2 theta / (1 + rho + (1 - rho) cos^2 theta)

for scattering angle theta and depolarisation factor rho (Chandrasekhar 1950, sec. 18;
Hansen & Travis 1974, eq. 2.15): 1 at 90 deg from the sun for rho = 0, and
(1 - rho) / (1 + rho) with depolarisation (0.946 for rho = 0.0279, Bates 1984 at 550 nm).
This module gives the analytic single-scattering Rayleigh field; the polarised Monte Carlo
model (``montecarlo``, ``polarised=True``) adds multiple scattering and aerosols, which
lower the maximum and create the neutral points (Arago, Babinet, Brewster) that single
scattering lacks.

Stokes parameters are given in the local meridian frame of each viewing direction: the
reference axis is the direction of increasing elevation on the sky (towards the zenith
along the vertical circle through the point), Q > 0 means polarisation along that
vertical, and the angle of polarisation is measured from it towards the second axis
k x e_vertical (k = -d, the direction the light travels), in (-90, 90] deg: counter-clockwise
as seen by an observer facing the sky, i.e. towards decreasing azimuth (for a view due
north the second axis points west). At the zenith the reference axis is north. This is the
frame of the ``montecarlo`` model's ``stokes_frame`` (which takes south at the zenith, a
rotation by 180 deg that leaves Q and U unchanged).
"""

from __future__ import annotations

import numpy as np

from skydome._validate import as_directions, check_number

__all__ = ["rayleigh_degree_of_polarisation", "local_frame", "rayleigh_single_scattering_stokes",
           "degree_of_polarisation", "angle_of_polarisation", "neutral_points_on_meridian",
           "neutral_points_from_sign"]


def rayleigh_degree_of_polarisation(cos_theta, depolarisation: float = 0.0) -> np.ndarray:
    """Degree of linear polarisation of single Rayleigh scattering at scattering angle theta."""
    rho = check_number("depolarisation", depolarisation, 0.0, 0.5)
    c = np.asarray(cos_theta, dtype=np.float64)
    s2 = np.maximum(1.0 - c * c, 0.0)
    return (1.0 - rho) * s2 / (1.0 + rho + (1.0 - rho) * c * c)


def local_frame(directions) -> tuple[np.ndarray, np.ndarray]:
    """(e_vertical, e_horizontal) unit vectors perpendicular to each direction: the
    direction of increasing elevation, and e_horizontal = k x e_vertical with k = -d the
    direction the light travels (horizontal, towards decreasing azimuth: west for a view
    due north). At the zenith: north and east."""
    d = as_directions(directions)
    z = np.array([0.0, 0.0, 1.0])
    # azimuthal unit vector (east for a direction due north): z x d normalised; at the
    # zenith or nadir, use the frame in which the vertical axis points north
    h = np.cross(z, d)
    n = np.linalg.norm(h, axis=-1, keepdims=True)
    pole = n[..., 0] < 1e-12
    h = np.where(pole[..., None], np.array([1.0, 0.0, 0.0]), h / np.where(n > 0, n, 1.0))
    v = np.cross(d, h)
    return v, h


def rayleigh_single_scattering_stokes(directions, sun_direction, intensity=1.0,
                                      depolarisation: float = 0.0) -> np.ndarray:
    """Stokes vectors (I, Q, U, V) of singly Rayleigh-scattered light, shape (..., 4).

    ``intensity`` (broadcast against the directions' shape) is I; the E-vector is
    perpendicular to the scattering plane (along d x s). V = 0.
    """
    d = as_directions(directions)
    s = as_directions(sun_direction).reshape(3)
    I = np.broadcast_to(np.asarray(intensity, dtype=np.float64), d.shape[:-1])
    cos_t = d @ s
    p = rayleigh_degree_of_polarisation(cos_t, depolarisation)
    e = np.cross(d, s)
    en = np.linalg.norm(e, axis=-1, keepdims=True)
    e = e / np.where(en > 0, en, 1.0)
    v, h = local_frame(d)
    psi = np.arctan2(np.sum(e * h, axis=-1), np.sum(e * v, axis=-1))   # from vertical towards h
    out = np.zeros(d.shape[:-1] + (4,))
    out[..., 0] = I
    out[..., 1] = I * p * np.cos(2 * psi)
    out[..., 2] = I * p * np.sin(2 * psi)
    return out


def degree_of_polarisation(stokes) -> np.ndarray:
    """sqrt(Q^2 + U^2) / I (linear), 0 where I = 0."""
    s = np.asarray(stokes, dtype=np.float64)
    lin = np.hypot(s[..., 1], s[..., 2])
    return np.where(s[..., 0] > 0, lin / np.where(s[..., 0] > 0, s[..., 0], 1.0), 0.0)


def angle_of_polarisation(stokes) -> np.ndarray:
    """0.5 atan2(U, Q) [deg] in (-90, 90], from the local vertical towards increasing azimuth."""
    s = np.asarray(stokes, dtype=np.float64)
    a = 0.5 * np.degrees(np.arctan2(s[..., 2], s[..., 1]))
    return np.where(a <= -90.0 + 1e-9, a + 180.0, a)


def neutral_points_on_meridian(elevation_deg, dop, sun_elevation_deg: float,
                               threshold: float = 0.05) -> dict[str, float]:
    """Locate the neutral points along the solar meridian from a degree-of-polarisation
    profile.

    ``elevation_deg`` runs along the solar meridian as the angle above the horizon on the
    sun's side (0..180: 0 is the horizon under the sun, 90 the zenith, 180 the horizon
    opposite). Returns the position (same angle) of each local minimum of ``dop`` below
    ``threshold``, named by where it lies: "babinet" (above the sun), "brewster" (below the
    sun), "arago" (above the anti-sun point).
    """
    e = np.asarray(elevation_deg, dtype=np.float64)
    p = np.asarray(dop, dtype=np.float64)
    out: dict[str, float] = {}
    for i in range(1, len(p) - 1):
        if p[i] <= p[i - 1] and p[i] <= p[i + 1] and p[i] < threshold:
            if e[i] > 90.0:
                out.setdefault("arago", float(e[i]))
            elif e[i] > sun_elevation_deg:
                out.setdefault("babinet", float(e[i]))
            else:
                out.setdefault("brewster", float(e[i]))
    return out


def neutral_points_from_sign(elevation_deg, signed_dop, sun_elevation_deg: float,
                             exclude_deg: float = 4.0) -> dict[str, float]:
    """Neutral points along the solar meridian as the zero crossings of the signed degree
    of polarisation.

    ``elevation_deg`` is the angle along the solar meridian as in
    :func:`neutral_points_on_meridian` (0..180, 90 the zenith); ``signed_dop`` is -Q/I in
    the local meridian frame: > 0 where the E-vector is perpendicular to the meridian (the
    normal Rayleigh polarisation), < 0 where it is parallel ("negative" polarisation, between
    the Babinet and Brewster points and beyond the Arago point). Each sign change is
    located by linear interpolation; crossings within ``exclude_deg`` of the sun or the
    antisolar point are ignored, and when noise gives several crossings of one kind their
    median is returned. Names as in :func:`neutral_points_on_meridian`.
    """
    e = np.asarray(elevation_deg, dtype=np.float64)
    p = np.asarray(signed_dop, dtype=np.float64)
    sun_e = check_number("sun_elevation_deg", sun_elevation_deg, -90.0, 90.0, "deg")
    ex = check_number("exclude_deg", exclude_deg, 0.0, 45.0, "deg")
    anti = 180.0 + sun_e          # the antisolar point on the same scale
    found: dict[str, list[float]] = {}
    for i in range(len(p) - 1):
        if p[i] == 0.0 or np.sign(p[i]) == np.sign(p[i + 1]):
            continue
        x = e[i] + (e[i + 1] - e[i]) * p[i] / (p[i] - p[i + 1])
        if abs(x - sun_e) < ex or abs(x - anti) < ex:
            continue
        name = "arago" if x > 90.0 else ("babinet" if x > sun_e else "brewster")
        found.setdefault(name, []).append(float(x))
    return {k: float(np.median(v)) for k, v in found.items()}
