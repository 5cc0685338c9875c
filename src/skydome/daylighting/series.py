"""Hourly illuminance and irradiance on planes (horizontal, vertical, tilted) from a weather
file: sky, sun and ground-reflected parts separately, perez1993 for the sky.

For a plane with unit normal n (pointing away from its front face):

- sky: E_sky = integral over the sky hemisphere of L(d) max(0, n.d) dOmega, taken with the
  patch quadrature of :mod:`skydome.daylighting.patches` (every node weighted by its cosine to
  the plane; order 4 on Reinhart MF:4 by default), each hour's sky normalised as in the sky
  matrices (its horizontal illuminance is the diffuse horizontal illuminance);
- sun: E_sun = E_dn max(0, n.s) with the sun above the horizon;
- ground: a uniform (Lambertian) ground of reflectance rho lit by the global horizontal
  illuminance E_gh = E_dh + E_dn sin(a): E_ground = rho E_gh (1 - n_z) / 2 (the view factor
  of the lower hemisphere from a plane of tilt beta is (1 - cos beta) / 2).

Irradiances use the same distribution scaled to the diffuse horizontal irradiance (Perez
1993 fits luminance; applying its shape to radiance is an approximation, stated here) and the
direct normal irradiance.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

__all__ = ["Plane", "parse_plane", "plane_series"]


@dataclass(frozen=True)
class Plane:
    """A plane by its tilt from horizontal [deg] (0 = facing up, 90 = vertical) and the
    azimuth its front faces [deg from north towards east]."""

    name: str
    tilt_deg: float
    azimuth_deg: float

    @property
    def normal(self) -> np.ndarray:
        t, a = math.radians(self.tilt_deg), math.radians(self.azimuth_deg)
        return np.array([math.sin(t) * math.sin(a), math.sin(t) * math.cos(a), math.cos(t)])


def parse_plane(spec: str) -> Plane:
    """"horizontal", "vertical:AZ" or "tilted:TILT:AZ" (degrees; azimuth from north towards
    east, e.g. vertical:180 faces south)."""
    s = str(spec).strip().lower()
    if s == "horizontal":
        return Plane("horizontal", 0.0, 0.0)
    m = re.fullmatch(r"vertical:(-?[0-9.]+)", s)
    if m:
        az = float(m.group(1))
        if 0.0 <= az <= 360.0:
            return Plane(f"vertical_{az:g}", 90.0, az)
    m = re.fullmatch(r"tilted:(-?[0-9.]+):(-?[0-9.]+)", s)
    if m:
        tilt, az = float(m.group(1)), float(m.group(2))
        if 0.0 <= tilt <= 180.0 and 0.0 <= az <= 360.0:
            return Plane(f"tilted_{tilt:g}_{az:g}", tilt, az)
    raise ValueError(f"plane = {spec!r} is unknown; use 'horizontal', 'vertical:AZ' (AZ in "
                     "[0, 360] deg from north towards east) or 'tilted:TILT:AZ' (TILT in "
                     "[0, 180] deg)")


def plane_series(weather, planes, *, patches: str = "reinhart:4", order: int = 4,
                 sun_position: str = "spa", ground_reflectance=0.2) -> dict:
    """Hourly sky, sun and ground illuminance [lx] and irradiance [W m^-2] on planes.

    Parameters
    ----------
    weather : Weather
    planes : sequence of Plane or str
    patches, order : quadrature of the sky (see :mod:`skydome.daylighting.patches`)
    sun_position : {"spa", "radiance"}
    ground_reflectance : float or array_like per hour, in [0, 1]

    Returns
    -------
    dict
        ``{plane.name: {"sky_lx", "sun_lx", "ground_lx", "sky_wm2", "sun_wm2", "ground_wm2"}}``
        arrays (n_hours,), plus ``"time"``.
    """
    from skydome._validate import check_choice, check_int
    from skydome.daylighting.patches import patches as make_patches
    from skydome.models.analytic import _kernels_analytic as K
    from skydome.models.analytic.perez1993 import (COS_ZETA_MIN, perez1993_coefficients_many,
                                                    perez1993_sky_parameters)

    pl = [p if isinstance(p, Plane) else parse_plane(p) for p in planes]
    if not pl:
        raise ValueError("planes: give at least one plane")
    ps = make_patches(patches)
    order = check_int("order", order, 1, 16)
    check_choice("sun_position", sun_position, ("spa", "radiance"))
    n = len(weather)
    rho = np.broadcast_to(np.asarray(ground_reflectance, dtype=np.float64), (n,))
    if np.any(~np.isfinite(rho)) or np.any(rho < 0.0) or np.any(rho > 1.0):
        raise ValueError("ground_reflectance must be in [0, 1]")
    sd = weather.spa_sun_directions() if sun_position == "spa" else weather.radiance_sun_directions()
    td = 11.0 if weather.dew_point_c is None else np.where(
        np.isfinite(weather.dew_point_c), weather.dew_point_c, 11.0)
    alt = np.arcsin(np.clip(sd[:, 2], -1.0, 1.0))
    par = perez1993_sky_parameters(weather.dni, weather.dhi, np.degrees(0.5 * np.pi - alt),
                                   weather.day_of_year, td)
    zc = np.radians(par.sun_zenith_deg)
    azi = np.arctan2(sd[:, 0], sd[:, 1])
    s_dist = np.ascontiguousarray(np.stack([np.sin(zc) * np.sin(azi), np.sin(zc) * np.cos(azi),
                                            np.cos(zc)], axis=-1))
    coef = np.ascontiguousarray(perez1993_coefficients_many(zc, par.epsilon, par.delta))
    day = np.nonzero((weather.dni + weather.dhi) > 1e-4)[0]
    nodes, weights, offsets = ps.nodes(order)
    _, horiz = K.perez1993_patch_means(nodes, weights, offsets, s_dist[day], coef[day],
                                       COS_ZETA_MIN)
    horiz = np.where(horiz > 1e-6, horiz, np.nan)
    e_diff = np.maximum(par.diffuse_illuminance, 0.0)
    e_dir = np.maximum(par.direct_illuminance, 0.0)
    up = sd[:, 2] > 0.0
    out: dict = {"time": weather.time}
    for p in pl:
        nv = p.normal
        cw = weights * np.maximum(nodes @ nv, 0.0)
        # keep the patches the plane sees; one kernel call gives sum(w cos lv) per patch
        seen = np.add.reduceat(cw, offsets[:-1]) > 0.0
        keep = np.repeat(seen, np.diff(offsets))
        off = np.concatenate([[0], np.cumsum(np.diff(offsets)[seen])]).astype(np.int64)
        means, _ = K.perez1993_patch_means(np.ascontiguousarray(nodes[keep]),
                                           np.ascontiguousarray(cw[keep]), off, s_dist[day],
                                           coef[day], COS_ZETA_MIN)
        wsum = np.add.reduceat(cw[keep], off[:-1])
        rel = means @ wsum  # integral of lv max(0, n.d) dOmega per hour [sr]
        ratio = np.zeros(n)
        ok = np.isfinite(horiz)
        ratio[day[ok]] = rel[ok] / horiz[ok]
        # a sky that integrates to zero is uniform (as the sky matrices): ratio (1 + n_z) / 2
        ratio[day[~ok]] = (1.0 + nv[2]) / 2.0
        cos_sun = np.where(up, np.maximum(sd @ nv, 0.0), 0.0)
        ground_view = (1.0 - nv[2]) / 2.0
        e_gh = e_diff + np.where(up, e_dir * np.sin(alt), 0.0)
        g_h = weather.dhi + np.where(up, weather.dni * np.sin(alt), 0.0)
        out[p.name] = {
            "sky_lx": e_diff * ratio, "sun_lx": e_dir * cos_sun,
            "ground_lx": rho * e_gh * ground_view,
            "sky_wm2": weather.dhi * ratio, "sun_wm2": weather.dni * cos_sun,
            "ground_wm2": rho * g_h * ground_view,
        }
    return out


def write_series_csv(path, series: dict, overwrite: bool = False) -> None:
    """Write :func:`plane_series` output as CSV (one row per hour) atomically."""
    from pathlib import Path

    from skydome.daylighting.radiance_io import atomic_write_bytes

    path = Path(path)
    if path.exists() and not overwrite:
        raise ValueError(f"out = {str(path)!r} exists (use --overwrite)")
    names = [k for k in series if k != "time"]
    cols = ["sky_lx", "sun_lx", "ground_lx", "sky_wm2", "sun_wm2", "ground_wm2"]
    head = ["time_midpoint_local_standard"] + [f"{p}_{c}" for p in names for c in cols]
    lines = [",".join(head)]
    for i, t in enumerate(series["time"]):
        vals = [f"{series[p][c][i]:.6g}" for p in names for c in cols]
        lines.append(",".join([str(t)] + vals))
    atomic_write_bytes(path, ("\n".join(lines) + "\n").encode())
