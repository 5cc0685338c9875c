"""What the scans themselves say: the aerosol fitted to a scan, and the scanner's clock.

* :func:`fit_aerosol` fits the aerosol optical depth at 440 nm and its Angstrom exponent
  (``tau(lambda) = tau440 (lambda / 440)^-alpha``, Angstrom 1929) to one scan's own spectral
  radiance, 400-700 nm, in the directions at least 10 deg from the sun (sample 0 left out):
  least squares on ``ln(model / measured)`` with ``hillaire2020`` (its tables take about
  1 s per atmosphere; the multiple-scattering solvers agree within 1-2 points,
  docs/validation_measured.md). Everything else is the AERONET retrieval's (phase
  function, surface albedo; single scattering albedo 0.95 assumed), for a day without
  AERONET (2013-09-24) the Egbert 2013-05-27 14:19 UTC retrieval's.
  The fitted level absorbs whatever else is off in level (the scanner's absolute
  calibration, the ground albedo, the single scattering albedo), so a model's level and
  colour on a fitted atmosphere are fits, not predictions.
* :func:`skydome.validation.compare.clock_scan` measures, per scan, how well a model's luminance shape follows the
  measured one when the sun is taken at the label time plus each of a range of offsets,
  with the model sampled at the labelled directions or as the mean along each of the
  scanner's moves (:func:`skydome.validation.compare.arc_directions`): the test of whether
  the scanner's apparent clock shift is its motion.
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["FIT_WAVELENGTHS", "fit_aerosol", "fit_aerosol_phase", "base_retrieval"]

#: wavelengths of the aerosol fit [nm]
FIT_WAVELENGTHS = np.arange(400.0, 701.0, 50.0)
#: bounds of the fit: tau440 and the Angstrom exponent
TAU440_RANGE = (0.01, 1.5)
ALPHA_RANGE = (-0.5, 3.0)
#: bounds of the Henyey-Greenstein asymmetry factor in :func:`fit_aerosol_phase`
G_RANGE = (0.3, 0.9)

_FIT_CACHE: dict = {}


def base_retrieval(capture):
    """The AERONET retrieval a capture's aerosol starts from: the Egbert retrieval nearest
    in time on 2013-05-27; on another day (no AERONET retrieval shipped), the 14:19 UTC
    one (its phase function and surface albedo; tau440 and alpha are then fitted)."""
    from skydome.validation.aeronet import egbert_20130527, nearest_retrieval

    rets = egbert_20130527()
    if capture.mean_time.date() == rets[0].time.date():
        return nearest_retrieval(rets, capture.mean_time)
    return max(rets, key=lambda r: r.time)


def _fit_mask(capture):
    from skydome.validation.kider2014 import EXCLUDED_SAMPLES

    keep = capture.sun_angle_deg >= 10.0
    keep[list(EXCLUDED_SAMPLES)] = False
    return keep


def fit_aerosol(capture, *, model: str = "hillaire2020", phase: str = "tabulated",
                atmosphere_kw: dict | None = None, model_kw: dict | None = None):
    """The aerosol (tau440, alpha) that best reproduces the scan's 400-700 nm radiance.

    Returns an :class:`~skydome.validation.aeronet.AeronetRetrieval` (the base retrieval of
    :func:`base_retrieval` with tau440 and alpha replaced) and caches it per capture.
    ``atmosphere_kw`` (e.g. ``aerosol_scale_height_m``, ``ground_albedo``) goes to
    :func:`~skydome.validation.aeronet.aerosol_atmosphere` and ``model_kw`` (e.g.
    ``observer_altitude_m``) to the model: the sensitivity runs of
    docs/validation_measured.md refit the aerosol with them.
    """
    from scipy.optimize import least_squares

    import skydome as sd
    from skydome._validate import check_choice
    from skydome.validation.aeronet import aerosol_atmosphere

    check_choice("model", model, ("hillaire2020", "precomputed"))
    atmosphere_kw, model_kw = dict(atmosphere_kw or {}), dict(model_kw or {})
    key = (capture.day, capture.label, capture.mean_time, model, phase,
           repr(sorted(atmosphere_kw.items())), repr(sorted(model_kw.items())))
    if key in _FIT_CACHE:
        return _FIT_CACHE[key]
    base, wl, d, meas = _fit_data(capture)

    def resid(p):
        r = dataclasses.replace(base, tau440=float(np.exp(p[0])), alpha=float(p[1]))
        m = sd.model(model, sun=capture.sun,
                     atmosphere=aerosol_atmosphere(r, phase=phase, **atmosphere_kw),
                     n_wavelengths=wl.size, **model_kw)
        S = np.maximum(m.radiance(d, wl), 1e-30)
        return (np.log(S) - meas).ravel()

    lo = [np.log(TAU440_RANGE[0]), ALPHA_RANGE[0]]
    hi = [np.log(TAU440_RANGE[1]), ALPHA_RANGE[1]]
    p0 = [np.log(np.clip(base.tau440, *TAU440_RANGE)), float(np.clip(base.alpha, *ALPHA_RANGE))]
    sol = least_squares(resid, p0, bounds=(lo, hi), diff_step=2e-3, x_scale=[0.3, 0.3],
                        xtol=1e-3, ftol=1e-4, max_nfev=40)
    out = dataclasses.replace(base, tau440=float(np.exp(sol.x[0])), alpha=float(sol.x[1]))
    _FIT_CACHE[key] = out
    return out


def _fit_data(capture):
    """(the base retrieval, the fit's wavelengths, the kept directions, ln of the measured
    radiance there at those wavelengths): what :func:`fit_aerosol` and
    :func:`fit_aerosol_phase` fit to."""
    keep = _fit_mask(capture)
    wl = FIT_WAVELENGTHS
    idx = [int(np.argmin(np.abs(capture.wavelengths_nm - w))) for w in wl]
    return (base_retrieval(capture), wl, capture.directions[keep],
            np.log(capture.radiance[keep][:, idx]))


def fit_aerosol_phase(capture, *, model: str = "hillaire2020"):
    """The aerosol (tau440, alpha) and a Henyey-Greenstein asymmetry factor g fitted together
    to the scan's 400-700 nm radiance (the same residual, directions and wavelengths as
    :func:`fit_aerosol`; g in :data:`G_RANGE`, the same g at every wavelength).

    The test of whether the aerosol's phase function explains the angular error left after
    :func:`fit_aerosol` (docs/validation_measured.md, "The goal, per day"): if it did, a
    fitted g would remove the pattern by angle from the sun. Returns ``(retrieval, g)``, the
    base retrieval with tau440 and alpha replaced and the fitted g (use with
    ``aerosol_atmosphere(retrieval, phase="henyey_greenstein", asymmetry=g)``); cached per
    capture.
    """
    from scipy.optimize import least_squares

    import skydome as sd
    from skydome._validate import check_choice
    from skydome.validation.aeronet import aerosol_atmosphere

    check_choice("model", model, ("hillaire2020", "precomputed"))
    key = (capture.day, capture.label, capture.mean_time, model, "henyey_greenstein", "g")
    if key in _FIT_CACHE:
        return _FIT_CACHE[key]
    base, wl, d, meas = _fit_data(capture)

    def resid(p):
        r = dataclasses.replace(base, tau440=float(np.exp(p[0])), alpha=float(p[1]))
        atm = aerosol_atmosphere(r, phase="henyey_greenstein", asymmetry=float(p[2]))
        m = sd.model(model, sun=capture.sun, atmosphere=atm, n_wavelengths=wl.size)
        S = np.maximum(m.radiance(d, wl), 1e-30)
        return (np.log(S) - meas).ravel()

    g0 = float(np.clip(base.asymmetry()[1], *G_RANGE))
    lo = [np.log(TAU440_RANGE[0]), ALPHA_RANGE[0], G_RANGE[0]]
    hi = [np.log(TAU440_RANGE[1]), ALPHA_RANGE[1], G_RANGE[1]]
    p0 = [np.log(np.clip(base.tau440, *TAU440_RANGE)), float(np.clip(base.alpha, *ALPHA_RANGE)), g0]
    sol = least_squares(resid, p0, bounds=(lo, hi), diff_step=2e-3, x_scale=[0.3, 0.3, 0.05],
                        xtol=1e-3, ftol=1e-4, max_nfev=60)
    out = (dataclasses.replace(base, tau440=float(np.exp(sol.x[0])), alpha=float(sol.x[1])),
           float(sol.x[2]))
    _FIT_CACHE[key] = out
    return out
