"""Helpers shared by the daylighting tests: the test days of the sample year, gendaymtx runs
and its sun files."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from _radiance import _env, _tool

#: Days of the sample year used by the fast tests (winter, spring, summer, autumn).
TEST_DAYS = (15, 100, 172, 290)


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
