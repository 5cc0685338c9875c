"""The scanner's response to polarised light: the test of docs/validation_measured.md,
"The scanner's response to polarised light".

A radiometer whose optics transmit one linear polarisation better than the other reads
a partially polarised sky as

    measured = true * (1 + m P cos 2 chi + n P sin 2 chi)                       (1)

with P the sky's degree of linear polarisation, chi the angle of its E-vector in the
instrument's frame and sqrt(m^2 + n^2) the instrument's diattenuation (its polarisation
sensitivity, (T_max - T_min) / (T_max + T_min)); the orientation of the most transmitted
axis in the instrument's frame is 0.5 atan2(n, m).

**The frame.** The scanner is a pan-tilt (alt-azimuth) head: whatever its optics, they
turn with the head, so the instrument's reference axis keeps a fixed angle to the local
vertical of the view direction. :func:`scan_frame` takes that vertical as the reference:
e_v, the direction of increasing elevation at the sample's own azimuth, and
e_h = k x e_v with k = -d the direction the light travels (the frame of
:func:`skydome.effects.polarisation.local_frame` and of ``montecarlo``'s ``stokes_frame``;
at the zenith sample the head's azimuth as written in the scan, so e_v points away from
that azimuth). Any fixed orientation of the instrument's axis in that frame (in or
perpendicular to the vertical plane of the view, or between) and either sign of the
sensitivity are then one pair (m, n) of (1): both are unknowns of the fit.

**chi** is the E-vector of single Rayleigh scattering, perpendicular to the scattering
plane (Chandrasekhar 1950, sec. 18; Coulson 1988, ch. 5): :func:`single_scattering_angle`.
**P** is the polarised Monte Carlo reference's (``montecarlo``, ``polarised=True``) at the
capture's own aerosol: :func:`degree_montecarlo`. Multiple scattering, the aerosol (whose
scattering that model treats as depolarising) and the ground lower P below the
single-scattering value; the E-vector's angle moves little outside the neutral points.

:func:`fit_response` fits (m, n) with one constant per capture (the level, which the
aerosol fit leaves free) to ``ln(measured / model)``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["scan_frame", "single_scattering_angle", "single_scattering_degree",
           "degree_montecarlo", "response_terms", "fit_response", "ResponseFit"]


def scan_frame(azimuth_deg, elevation_deg) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(d, e_v, e_h), each (..., 3) in East-North-Up, for a view at ``azimuth_deg`` (from
    north towards east) and ``elevation_deg``: the view direction, the direction of
    increasing elevation (d d / d elevation, defined at the zenith too, by the azimuth)
    and e_h = k x e_v with k = -d (towards decreasing azimuth: west for a view due north)."""
    a = np.radians(np.asarray(azimuth_deg, dtype=np.float64))
    e = np.radians(np.asarray(elevation_deg, dtype=np.float64))
    if a.shape != e.shape:
        raise ValueError(f"azimuth_deg and elevation_deg must have one shape, got {a.shape} "
                         f"and {e.shape}")
    if np.any(np.abs(e) > 0.5 * np.pi + 1e-9):
        raise ValueError("elevation_deg must lie in [-90, 90] deg, got "
                         f"{np.degrees(e[np.abs(e) > 0.5 * np.pi + 1e-9]).tolist()}")
    d = np.stack([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)], axis=-1)
    ev = np.stack([-np.sin(e) * np.sin(a), -np.sin(e) * np.cos(a), np.cos(e)], axis=-1)
    eh = np.cross(-d, ev)
    return d, ev, eh


def single_scattering_angle(azimuth_deg, elevation_deg, sun_direction) -> np.ndarray:
    """Angle chi [rad] of the E-vector of singly Rayleigh-scattered sunlight in the frame of
    :func:`scan_frame`, from e_v towards e_h, in (-pi/2, pi/2]: the E-vector is along
    d x s, perpendicular to the scattering plane (the plane of the sun s, the observer and
    the view d). NaN where d is parallel to s (no scattering plane)."""
    d, ev, eh = scan_frame(azimuth_deg, elevation_deg)
    s = np.asarray(sun_direction, dtype=np.float64).reshape(3)
    s = s / np.linalg.norm(s)
    e = np.cross(d, s)
    n = np.linalg.norm(e, axis=-1)
    chi = np.arctan2(np.sum(e * eh, axis=-1), np.sum(e * ev, axis=-1))
    chi = np.where(chi <= -0.5 * np.pi, chi + np.pi, chi)
    chi = np.where(chi > 0.5 * np.pi, chi - np.pi, chi)
    return np.where(n > 1e-12, chi, np.nan)


def single_scattering_degree(azimuth_deg, elevation_deg, sun_direction,
                             depolarisation: float = 0.0) -> np.ndarray:
    """Degree of linear polarisation of single Rayleigh scattering in each view
    (:func:`skydome.effects.polarisation.rayleigh_degree_of_polarisation`)."""
    from skydome.effects.polarisation import rayleigh_degree_of_polarisation

    d, _, _ = scan_frame(azimuth_deg, elevation_deg)
    s = np.asarray(sun_direction, dtype=np.float64).reshape(3)
    return rayleigh_degree_of_polarisation(d @ (s / np.linalg.norm(s)), depolarisation)


def degree_montecarlo(capture, atmosphere, wavelengths_nm, *, samples: int = 20000,
                      seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(P, its standard error), each (81, n_wavelengths): the degree of linear polarisation
    sqrt(Q^2 + U^2) / I of the polarised ``montecarlo`` model in the capture's 81
    directions, sun at the capture's mean time (the standard error from those of I, Q, U to
    first order)."""
    import skydome as sd

    wl = np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64))
    m = sd.model("montecarlo", sun=capture.sun, atmosphere=atmosphere, samples=int(samples),
                 seed=int(seed), polarised=True)
    S, E = m.stokes_with_error(capture.directions, wl)
    I, Q, U = S[..., 0], S[..., 1], S[..., 2]
    lin = np.hypot(Q, U)
    P = np.where(I > 0, lin / np.where(I > 0, I, 1.0), 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        dq = np.where(lin > 0, Q / np.where(lin > 0, lin, 1.0), 0.0)
        du = np.where(lin > 0, U / np.where(lin > 0, lin, 1.0), 0.0)
        err = np.sqrt((dq * E[..., 1]) ** 2 + (du * E[..., 2]) ** 2 + (P * E[..., 0]) ** 2) \
            / np.where(I > 0, I, 1.0)
    return P, err


def response_terms(P, chi) -> tuple[np.ndarray, np.ndarray]:
    """(P cos 2 chi, P sin 2 chi): the two regressors of (1); 0 where chi is NaN."""
    P = np.asarray(P, dtype=np.float64)
    chi = np.asarray(chi, dtype=np.float64)
    ok = np.isfinite(chi)
    c = np.where(ok, np.cos(2 * np.where(ok, chi, 0.0)), 0.0)
    s = np.where(ok, np.sin(2 * np.where(ok, chi, 0.0)), 0.0)
    return P * c, P * s


class ResponseFit:
    """Result of :func:`fit_response`: ``m``, ``n``, their standard errors ``sm``, ``sn``
    (from the residual's variance), the constants per group ``const``, ``rms_before`` (RMS of
    y about the group constants alone) and ``rms_after`` (about the full fit)."""

    def __init__(self, m, n, sm, sn, const, rms_before, rms_after, count):
        self.m, self.n, self.sm, self.sn = float(m), float(n), float(sm), float(sn)
        self.const = np.asarray(const)
        self.rms_before, self.rms_after, self.count = float(rms_before), float(rms_after), int(count)

    @property
    def diattenuation(self) -> float:
        """sqrt(m^2 + n^2): the polarisation sensitivity the fit asks of the instrument."""
        return float(np.hypot(self.m, self.n))

    @property
    def axis_deg(self) -> float:
        """Most transmitted axis [deg] in the frame of :func:`scan_frame`, from e_v towards
        e_h: 0.5 atan2(n, m), in (-90, 90]."""
        a = 0.5 * np.degrees(np.arctan2(self.n, self.m))
        return float(a + 180.0 if a <= -90.0 else a)


def fit_response(groups) -> ResponseFit:
    """Least-squares fit of ``y = c_k + m X + n Y`` over groups k (captures), each group a
    tuple ``(y, X, Y)`` of 1-d arrays of one length (y = ln(measured / model) in the kept
    directions; X, Y from :func:`response_terms`): (1) with ln(1 + x) ~ x."""
    groups = list(groups)
    if not groups:
        raise ValueError("groups must hold at least one (y, X, Y) group, got none")
    ys, rows, Xs, Ys = [], [], [], []
    for k, (y, X, Y) in enumerate(groups):
        y, X, Y = (np.asarray(v, dtype=np.float64).ravel() for v in (y, X, Y))
        if not (y.size == X.size == Y.size) or y.size == 0:
            raise ValueError(f"group {k}: y, X and Y must be non-empty and of one length, got "
                             f"{y.size}, {X.size}, {Y.size}")
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
            raise ValueError(f"group {k}: y, X and Y must be finite")
        ys.append(y)
        Xs.append(X)
        Ys.append(Y)
        rows.append(np.full(y.size, k))
    y = np.concatenate(ys)
    rows = np.concatenate(rows)
    nk = len(groups)
    A = np.zeros((y.size, nk + 2))
    A[np.arange(y.size), rows] = 1.0
    A[:, nk] = np.concatenate(Xs)
    A[:, nk + 1] = np.concatenate(Ys)
    x, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ x
    dof = max(y.size - A.shape[1], 1)
    cov = np.linalg.pinv(A.T @ A) * float(r @ r) / dof
    before = y - np.array([ys[k].mean() for k in range(nk)])[rows]
    return ResponseFit(x[nk], x[nk + 1], np.sqrt(cov[nk, nk]), np.sqrt(cov[nk + 1, nk + 1]),
                       x[:nk], np.sqrt(np.mean(before ** 2)), np.sqrt(np.mean(r ** 2)), y.size)
