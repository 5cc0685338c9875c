"""Atmospheric refraction near the horizon and the flattened sun disc.

Refraction lifts a celestial object by R (a few arcminutes near the horizon, half a degree
at it). Two standard empirical formulas, both for 10 degC and 101.0 kPa:

    Bennett (1982):      R = cot(h_a + 7.31 / (h_a + 4.4))  arcmin   (h_a apparent, deg)
    Saemundsson (1986):  R = 1.02 cot(h_t + 10.3 / (h_t + 5.11)) arcmin (h_t true, deg)

and for other air R is scaled by (P / 101 kPa) (283 K / T) (Meeus 1998, ch. 16, eqs.
16.3-16.4 and the pressure/temperature factor). Bennett's formula is accurate to 0.07'
for h_a in [0, 90] deg; Saemundsson's is its inverse to 0.1' (Meeus).

The sun disc near the horizon is flattened because its lower limb is lifted more than its
upper limb: the apparent vertical diameter is the difference of the apparent elevations
of the two limbs, while the horizontal diameter is (almost) unchanged. With standard
refraction the disc whose lower limb touches the horizon has a vertical/horizontal ratio
of about 0.85 (its vertical diameter is shortened by ~5').

Both formulas are fits for the standard atmosphere above about -1 deg; below a true
elevation of -1.9 deg (Saemundsson) or an apparent one of -1 deg (Bennett) this module
returns no refraction (the object is below the horizon; the formulas diverge at
h = -2.9 / -4.2 deg).

References
----------
[Ben82] Bennett, G. G. (1982), The calculation of astronomical refraction in marine
    navigation, Journal of Navigation 35, 255-259.
[Sae86] Saemundsson, T. (1986), Astronomical refraction, Sky and Telescope 72, 70.
[Mee98] Meeus, J. (1998), *Astronomical Algorithms*, 2nd ed., Willmann-Bell, ch. 16.
"""

from __future__ import annotations

import numpy as np

from skydome._validate import check_number
from skydome.constants import SUN_ANGULAR_RADIUS_DEG

__all__ = ["refraction_bennett_arcmin", "refraction_saemundsson_arcmin", "apparent_elevation",
           "true_elevation", "sun_disc_shape"]

P_REF_KPA = 101.0
T_REF_K = 283.0


def _factor(pressure_pa: float, temperature_c: float) -> float:
    p = check_number("pressure_pa", pressure_pa, 0.0, 2e5, "Pa")
    t = check_number("temperature_c", temperature_c, -90.0, 60.0, "degC")
    return (p / 1000.0 / P_REF_KPA) * (T_REF_K / (273.0 + t))   # [Mee98] ch. 16


def _cot_fit(name: str, elevation_deg, k: float, a: float, b: float, h_min: float,
             pressure_pa: float, temperature_c: float) -> np.ndarray:
    """R = k cot(h + a / (h + b)) [arcmin] at elevation h [deg] (the form of both fits),
    0 below h_min, scaled to the pressure and temperature."""
    h = np.asarray(elevation_deg, dtype=np.float64)
    if np.any(~np.isfinite(h)) or np.any(np.abs(h) > 90.0):
        raise ValueError(f"{name} must lie in [-90, 90] deg")
    hh = np.maximum(h, h_min)
    r = k / np.tan(np.radians(hh + a / (hh + b)))
    r = np.where(h >= h_min, r, 0.0)
    # at the zenith cot(90 + ...) is slightly negative: no refraction
    return np.maximum(r, 0.0) * _factor(pressure_pa, temperature_c)


def refraction_bennett_arcmin(apparent_elevation_deg, pressure_pa: float = 101000.0,
                              temperature_c: float = 10.0) -> np.ndarray:
    """Refraction R [arcmin] from the apparent elevation [deg] ([Ben82]); 0 below -1 deg."""
    # [Ben82]: R = cot(h_a + 7.31 / (h_a + 4.4))
    return _cot_fit("apparent_elevation_deg", apparent_elevation_deg, 1.0, 7.31, 4.4, -1.0,
                    pressure_pa, temperature_c)


def refraction_saemundsson_arcmin(true_elevation_deg, pressure_pa: float = 101000.0,
                                  temperature_c: float = 10.0) -> np.ndarray:
    """Refraction R [arcmin] from the true (airless) elevation [deg] ([Sae86], [Mee98]
    eq. 16.4); 0 below -1.9 deg."""
    # [Sae86]: R = 1.02 cot(h + 10.3 / (h + 5.11))
    return _cot_fit("true_elevation_deg", true_elevation_deg, 1.02, 10.3, 5.11, -1.9,
                    pressure_pa, temperature_c)


def apparent_elevation(true_elevation_deg, pressure_pa: float = 101000.0,
                       temperature_c: float = 10.0) -> np.ndarray:
    """Apparent elevation [deg] = true + R(Saemundsson)/60."""
    h = np.asarray(true_elevation_deg, dtype=np.float64)
    return h + refraction_saemundsson_arcmin(h, pressure_pa, temperature_c) / 60.0


def true_elevation(apparent_elevation_deg, pressure_pa: float = 101000.0,
                   temperature_c: float = 10.0) -> np.ndarray:
    """True elevation [deg] = apparent - R(Bennett)/60."""
    h = np.asarray(apparent_elevation_deg, dtype=np.float64)
    return h - refraction_bennett_arcmin(h, pressure_pa, temperature_c) / 60.0


def sun_disc_shape(true_elevation_deg: float, angular_radius_deg: float = SUN_ANGULAR_RADIUS_DEG,
                   pressure_pa: float = 101000.0, temperature_c: float = 10.0,
                   n_limb: int = 721) -> dict:
    """Apparent shape of the refracted sun disc.

    Each limb point (true elevation/azimuth offset on a small circle of radius
    ``angular_radius_deg`` around the true centre; default the mean apparent radius of
    :data:`skydome.constants.SUN_ANGULAR_RADIUS_DEG`, 0.2665 deg) is lifted by the Saemundsson
    refraction of its own true elevation; the apparent vertical diameter is the spread of
    apparent elevations, the horizontal one the spread of azimuth offsets times the cosine
    of the apparent centre elevation.

    Returns
    -------
    dict with ``vertical_deg``, ``horizontal_deg``, ``ratio`` (vertical / horizontal),
    ``apparent_centre_deg`` (mean of the apparent limb extremes).
    """
    h0 = check_number("true_elevation_deg", true_elevation_deg, -1.5, 89.0, "deg")
    a = check_number("angular_radius_deg", angular_radius_deg, 0.0, 2.0, "deg", low_open=True)
    phi = np.linspace(0.0, 2.0 * np.pi, n_limb)
    # limb points on the sphere around the true centre (small-circle geometry)
    h0r, ar = np.radians(h0), np.radians(a)
    sin_h = np.sin(h0r) * np.cos(ar) + np.cos(h0r) * np.sin(ar) * np.sin(phi)
    h = np.degrees(np.arcsin(np.clip(sin_h, -1.0, 1.0)))
    daz = np.arctan2(np.sin(ar) * np.cos(phi),
                     np.cos(ar) * np.cos(h0r) - np.sin(ar) * np.sin(h0r) * np.sin(phi))
    h_app = apparent_elevation(h, pressure_pa, temperature_c)
    vertical = float(h_app.max() - h_app.min())
    centre = 0.5 * float(h_app.max() + h_app.min())
    horizontal = float(np.degrees(daz.max() - daz.min()) * np.cos(np.radians(centre)))
    return {"vertical_deg": vertical, "horizontal_deg": horizontal,
            "ratio": vertical / horizontal, "apparent_centre_deg": centre}
