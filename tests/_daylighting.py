"""Helpers shared by the daylighting tests: the sample TMY3 file, a few days of it, Radiance's
own solar position (to feed skydome the same suns gendaymtx uses), and gendaymtx runs."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from _radiance import _env, _tool

#: Days of the sample year used by the fast tests (winter, spring, summer, autumn).
TEST_DAYS = (15, 100, 172, 290)


def radiance_sun_directions(lat_deg, lon_east_deg, utc_offset_h, day_of_year, hour):
    """Sun unit vectors (ENU) as Radiance's sun.c computes them (sdec, stadj, salt, sazi of
    Radiance 5.4: declination 0.4093 sin(2 pi (jd - 81) / 365), solar time from the
    standard time plus 0.170 sin(4 pi (jd - 80) / 373) - 0.129 sin(2 pi (jd - 8) / 355) +
    12 (meridian - longitude) / pi), with gendaymtx's azimuth = sazi + pi."""
    lat = np.radians(lat_deg)
    lon_w = np.radians(-np.asarray(lon_east_deg, dtype=float))
    mer_w = np.radians(-15.0 * utc_offset_h)
    jd = np.asarray(day_of_year, dtype=float)
    sd = 0.4093 * np.sin((2 * np.pi / 365.0) * (jd - 81.0))
    st = (np.asarray(hour, dtype=float) + 0.170 * np.sin((4 * np.pi / 373.0) * (jd - 80.0))
          - 0.129 * np.sin((2 * np.pi / 355.0) * (jd - 8.0)) + 12.0 * (mer_w - lon_w) / np.pi)
    w = st * np.pi / 12.0
    alt = np.arcsin(np.sin(lat) * np.sin(sd) - np.cos(lat) * np.cos(sd) * np.cos(w))
    az = -np.arctan2(np.cos(sd) * np.sin(w),
                     -np.cos(lat) * np.sin(sd) - np.sin(lat) * np.cos(sd) * np.cos(w)) + np.pi
    return np.stack([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)], axis=-1)


def run_gendaymtx(wea: Path, args=(), suns: Path | None = None) -> bytes:
    """stdout of ``gendaymtx ARGS [-D suns] wea`` (Radiance shipped with pyradiance)."""
    import subprocess

    cmd = [_tool("gendaymtx"), *map(str, args)]
    if suns is not None:
        cmd += ["-D", str(suns)]
    res = subprocess.run(cmd + [str(wea)], capture_output=True, env=_env(), timeout=300)
    if res.returncode != 0:
        raise RuntimeError(f"gendaymtx failed: {res.stderr.decode(errors='replace')}")
    return res.stdout


def read_sun_scene(path: Path) -> tuple[list[int], np.ndarray, np.ndarray]:
    """(ids, radiance (n, 3), directions (n, 3)) of a gendaymtx -D scene."""
    txt = Path(path).read_text()
    ids = [int(x) for x in re.findall(r"void light solar(\d+)", txt)]
    rad = np.array([[float(v) for v in m.split()] for m in re.findall(r"\n3 ([^\n]+)", txt)])
    dirs = np.array([[float(v) for v in m.split()[:3]] for m in re.findall(r"\n4 ([^\n]+)", txt)])
    return ids, rad.reshape(-1, 3), dirs.reshape(-1, 3)


def solar_minute(weather) -> np.ndarray:
    """gendaymtx's id of an hour: minutes since the start of the year of its midpoint."""
    return 24 * 60 * (weather.day_of_year - 1) + (weather.hour * 60.0 + 0.5).astype(int)
