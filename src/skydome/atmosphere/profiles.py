"""Density profiles of the atmosphere's constituents (survey eq. 7 and the ozone layer).

A profile gives the density relative to its reference density (1 at sea level for the
exponential profile, 1 at the peak for the tent and Gaussian layers) as a function of
altitude above the ground. Each profile also has a kernel encoding (code, p0, p1) that
the numba kernels evaluate with :func:`skydome.transport._kernels.profile_density`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skydome._validate import check_number

__all__ = ["DensityProfile", "ExponentialProfile", "TentProfile", "UniformProfile",
           "GaussianLayerProfile", "PROFILE_CODES"]

# kernel codes (mirrored in transport/_kernels.py)
PROFILE_CODES = {"exponential": 0, "tent": 1, "uniform": 2, "gaussian": 3}


class DensityProfile:
    """Base class; subclasses implement :meth:`density` and :meth:`kernel_params`."""

    kind: str = ""

    def density(self, altitude_m) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def kernel_params(self) -> tuple[int, float, float]:  # pragma: no cover - abstract
        raise NotImplementedError

    def column(self, top_altitude_m: float) -> float:
        """Vertical column integral of the relative density from 0 to ``top_altitude_m`` [m]
        (the equivalent thickness of the layer at reference density)."""
        raise NotImplementedError


@dataclass(frozen=True)
class ExponentialProfile(DensityProfile):
    """rho(h) = exp(-h / H) (survey eq. 7, [NSTN93]); H = 7994 m for air, 1200 m for aerosols."""

    scale_height_m: float
    kind = "exponential"

    def __post_init__(self):
        check_number("scale_height_m", self.scale_height_m, 1.0, 1e6, "m")

    def density(self, altitude_m):
        return np.exp(-np.asarray(altitude_m, dtype=np.float64) / self.scale_height_m)  # [KRZ06] eq. 7

    def kernel_params(self):
        return PROFILE_CODES["exponential"], float(self.scale_height_m), 0.0

    def column(self, top_altitude_m):
        return self.scale_height_m * (1.0 - np.exp(-top_altitude_m / self.scale_height_m))


@dataclass(frozen=True)
class TentProfile(DensityProfile):
    """Piecewise-linear layer: rho = max(0, 1 - |h - center| / half_width), the ozone
    profile of Bruneton (2017) (10-25-40 km: center 25 km, half width 15 km)."""

    center_m: float = 25e3
    half_width_m: float = 15e3
    kind = "tent"

    def __post_init__(self):
        check_number("center_m", self.center_m, 0.0, 1e6, "m")
        check_number("half_width_m", self.half_width_m, 0.0, 1e6, "m", low_open=True)

    def density(self, altitude_m):
        h = np.asarray(altitude_m, dtype=np.float64)
        return np.maximum(0.0, 1.0 - np.abs(h - self.center_m) / self.half_width_m)

    def kernel_params(self):
        return PROFILE_CODES["tent"], float(self.center_m), float(self.half_width_m)

    def column(self, top_altitude_m):
        h = np.linspace(0.0, top_altitude_m, 20001)
        return float(np.trapezoid(self.density(h), h))


@dataclass(frozen=True)
class UniformProfile(DensityProfile):
    """rho = 1 below ``thickness_m``, 0 above: a homogeneous layer (Klassen 1987; the
    closed-form Beer-Lambert test case)."""

    thickness_m: float
    kind = "uniform"

    def __post_init__(self):
        check_number("thickness_m", self.thickness_m, 0.0, 1e6, "m", low_open=True)

    def density(self, altitude_m):
        h = np.asarray(altitude_m, dtype=np.float64)
        return np.where(h < self.thickness_m, 1.0, 0.0)

    def kernel_params(self):
        return PROFILE_CODES["uniform"], float(self.thickness_m), 0.0

    def column(self, top_altitude_m):
        return float(min(self.thickness_m, top_altitude_m))


@dataclass(frozen=True)
class GaussianLayerProfile(DensityProfile):
    """rho = exp(-(h - center)^2 / (2 width^2)): an elevated layer (stratospheric volcanic
    aerosol, a smoke plume)."""

    center_m: float
    width_m: float
    kind = "gaussian"

    def __post_init__(self):
        check_number("center_m", self.center_m, 0.0, 1e6, "m")
        check_number("width_m", self.width_m, 0.0, 1e6, "m", low_open=True)

    def density(self, altitude_m):
        h = np.asarray(altitude_m, dtype=np.float64)
        return np.exp(-0.5 * ((h - self.center_m) / self.width_m) ** 2)

    def kernel_params(self):
        return PROFILE_CODES["gaussian"], float(self.center_m), float(self.width_m)

    def column(self, top_altitude_m):
        from math import erf, sqrt

        s = self.width_m * sqrt(2.0)
        return float(self.width_m * sqrt(np.pi / 2.0)
                     * (erf((top_altitude_m - self.center_m) / s) - erf(-self.center_m / s)))
