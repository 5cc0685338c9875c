"""The medium record: one argument that carries an atmosphere to every kernel.

:class:`Medium` is a ``typing.NamedTuple`` of floats and arrays, so numba passes it to
``@njit(cache=True)`` functions in nopython mode as one value (a jitclass would not
cache). Kernels read its fields by name (``m.extinction[c, l]``) instead of taking a dozen
unpacked arrays. nc constituents, nl wavelengths, na nodes of the tabulated phase
functions (uniform in scattering angle over [0, pi], see :mod:`._phase`).

Build it with :func:`medium_from_properties` from an
:class:`skydome.atmosphere.OpticalProperties`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from skydome._kernel_cache import njit

# profile codes (mirror of skydome.atmosphere.profiles.PROFILE_CODES)
EXPONENTIAL, TENT, UNIFORM, GAUSSIAN = 0, 1, 2, 3


class Medium(NamedTuple):
    """An atmosphere on a wavelength grid, as the kernels see it.

    Lengths in metres, coefficients at reference density in m^-1.
    """

    R: float                     # planet (ground) radius [m]
    Rt: float                    # radius of the top of the atmosphere [m]
    profile_code: np.ndarray     # (nc,) int64, density profile kind
    profile_p0: np.ndarray       # (nc,) first profile parameter [m]
    profile_p1: np.ndarray       # (nc,) second profile parameter [m]
    scattering: np.ndarray       # (nc, nl) scattering coefficient beta_s [m^-1]
    extinction: np.ndarray       # (nc, nl) extinction coefficient beta_e [m^-1]
    phase_code: np.ndarray       # (nc,) int64, see _phase
    phase_param: np.ndarray      # (nc,) g (HG, CS) or gamma = rho / (2 - rho) (Rayleigh)
    phase_table: np.ndarray      # (nc, na, nl) tabulated phase function [sr^-1]
    phase_cdf: np.ndarray        # (nc, na, nl) its cumulative distribution in angle
    albedo: np.ndarray           # (nl,) Lambertian ground albedo


@njit(cache=True, fastmath=False)
def profile_density(code, p0, p1, h):
    """Density relative to the reference density at altitude h [m] ([KRZ06] eq. 7 for the
    exponential profile; tent, uniform slab and Gaussian layer as in
    :mod:`skydome.atmosphere.profiles`)."""
    if code == EXPONENTIAL:
        return math.exp(-max(h, 0.0) / p0)
    if code == TENT:
        return max(0.0, 1.0 - abs(h - p0) / p1)
    if code == UNIFORM:
        return 1.0 if h < p0 else 0.0
    if code == GAUSSIAN:
        x = (h - p0) / p1
        return math.exp(-0.5 * x * x)
    return 0.0


@njit(cache=True)
def density(m, c, h):
    """Relative density of constituent c of the medium at altitude h [m]."""
    return profile_density(m.profile_code[c], m.profile_p0[c], m.profile_p1[c], h)


@njit(cache=True)
def densities(m, h, out):
    """out[c] = relative density of every constituent at altitude h [m]."""
    for c in range(m.profile_code.shape[0]):
        out[c] = profile_density(m.profile_code[c], m.profile_p0[c], m.profile_p1[c], h)


@njit(cache=True)
def scatterer_indices(m):
    """Indices (int64) of the constituents of the medium that scatter at some wavelength
    (beta_s > 0): the only ones whose scattering terms a per-step loop needs (the others,
    such as ozone or water vapour, only add to the extinction)."""
    nc = m.scattering.shape[0]
    idx = np.empty(nc, dtype=np.int64)
    n = 0
    for c in range(nc):
        for l in range(m.scattering.shape[1]):
            if m.scattering[c, l] > 0.0:
                idx[n] = c
                n += 1
                break
    return idx[:n]


@njit(cache=True)
def n_constituents(m):
    return m.profile_code.shape[0]


@njit(cache=True)
def n_wavelengths(m):
    return m.extinction.shape[1]


def phase_cdf_table(table: np.ndarray) -> np.ndarray:
    """Cumulative distribution in scattering angle of tabulated phase functions
    (..., na, nl) on the uniform grid theta_k = pi k / (na - 1): C_k = integral from 0 to
    theta_k of 2 pi p(theta) sin(theta) d theta by the trapezoidal rule, divided by its
    last value (so it ends at 1 whatever the table's normalisation). Rows that are all zero
    give zeros."""
    t = np.asarray(table, dtype=np.float64)
    na = t.shape[-2]
    theta = np.linspace(0.0, math.pi, na)
    f = 2.0 * math.pi * t * np.sin(theta)[:, None]
    inc = 0.5 * (f[..., 1:, :] + f[..., :-1, :]) * (math.pi / (na - 1))
    cdf = np.concatenate([np.zeros(t.shape[:-2] + (1, t.shape[-1])), np.cumsum(inc, axis=-2)],
                         axis=-2)
    last = cdf[..., -1:, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(last > 0.0, cdf / np.where(last > 0.0, last, 1.0), 0.0)


def medium_from_properties(p) -> Medium:
    """The :class:`Medium` of an :class:`skydome.atmosphere.OpticalProperties` (contiguous
    float64/int64 copies; a 2-node zero phase table where no constituent is tabulated)."""
    nl = int(np.asarray(p.wavelengths_nm).size)
    nc = int(np.asarray(p.profile_code).size)
    table = getattr(p, "phase_table", None)
    if table is None or np.size(table) == 0:
        table = np.zeros((nc, 2, nl))
    table = np.ascontiguousarray(table, dtype=np.float64)
    return Medium(float(p.planet_radius_m), float(p.top_radius_m),
                  np.ascontiguousarray(p.profile_code, dtype=np.int64),
                  np.ascontiguousarray(p.profile_p0, dtype=np.float64),
                  np.ascontiguousarray(p.profile_p1, dtype=np.float64),
                  np.ascontiguousarray(p.scattering, dtype=np.float64),
                  np.ascontiguousarray(p.extinction, dtype=np.float64),
                  np.ascontiguousarray(p.phase_code, dtype=np.int64),
                  np.ascontiguousarray(p.phase_param, dtype=np.float64),
                  table, np.ascontiguousarray(phase_cdf_table(table)),
                  np.ascontiguousarray(p.ground_albedo, dtype=np.float64))
