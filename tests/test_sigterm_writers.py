"""SIGTERM during every writer leaves nothing behind (issue 30: `skydome skymatrix` left
`.a.mtx.*.part`, up to 242 MB, in 5 of 8 runs, and `.a.zarr.part/` for Zarr output): the
command line (Radiance float and ascii matrices, Zarr) is started in a subprocess, killed
with SIGTERM once its temporary is seen, and must die of SIGTERM with no temporary left;
the writers whose temporary lives too briefly to catch from outside (.npy matrices, LUT
folders) are held mid-write in a child process that says when."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(SRC)
    return env


def _hidden(folder):
    return [p.name for p in Path(folder).iterdir() if p.name.startswith(".")]


def _term_when_temporary_seen(args, folder, wait_s=300):
    """Start ``python -m skydome ARGS``, send SIGTERM as soon as a hidden temporary appears
    in ``folder``; return (return code, what the folder held when the signal was sent)."""
    proc = subprocess.Popen([sys.executable, "-m", "skydome", *map(str, args)], env=_env(),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + wait_s
        seen = []
        while time.monotonic() < deadline and not seen:
            if proc.poll() is not None:
                pytest.fail(f"finished (rc {proc.returncode}) before its temporary was seen: "
                            + proc.stderr.read()[-2000:])
            seen = _hidden(folder)
            time.sleep(0.01)
        assert seen, "no temporary within the wait"
        proc.send_signal(signal.SIGTERM)
        rc = proc.wait(timeout=300)     # bounded: a compiled kernel ends before the handler
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return rc, seen


@pytest.fixture(scope="module")
def year(tmp_path_factory):
    from skydome.daylighting.weather import sample_weather_path

    return sample_weather_path()


@pytest.fixture(scope="module")
def two_days(tmp_path_factory):
    from skydome.daylighting.weather import sample_weather_path

    lines = sample_weather_path().read_text().splitlines(keepends=True)
    p = tmp_path_factory.mktemp("weather") / "d.csv"
    p.write_text("".join(lines[:2 + 48]))
    return p


@pytest.mark.parametrize("fmt, patches", [("float", "reinhart:4"), ("ascii", "reinhart:2")])
def test_sigterm_during_skymatrix_leaves_nothing(fmt, patches, tmp_path, year):
    out = tmp_path / "out"
    out.mkdir()
    rc, seen = _term_when_temporary_seen(
        ["skymatrix", "--weather", year, "--patches", patches, "--format", fmt,
         "--out", out / "a.mtx"], out)
    assert any(n.startswith(".a.mtx.") and n.endswith(".part") for n in seen), seen
    assert rc == -signal.SIGTERM
    assert list(out.iterdir()) == []


def test_sigterm_during_zarr_skymatrix_leaves_nothing(tmp_path, two_days):
    out = tmp_path / "out"
    out.mkdir()
    rc, seen = _term_when_temporary_seen(
        ["skymatrix", "--weather", two_days, "--patches", "reinhart:1", "--model", "oneil2005",
         "--components", "luminance", "--order", "0", "--chunk-hours", "1",
         "--out", out / "a.zarr"], out)
    assert ".a.zarr.part" in seen
    assert rc == -signal.SIGTERM
    assert list(out.iterdir()) == []


_NPY_CHILD = r"""
import sys, time
import numpy as np
from skydome.daylighting import radiance_io

def chunks():
    yield b"\x93NUMPY" + b"0" * 1000
    print("ready", flush=True)
    time.sleep(60)
    yield b"1" * 1000

radiance_io.atomic_write_stream(sys.argv[1] + "/a.npy", chunks())
"""

_LUTS_CHILD = r"""
import sys, time
import skydome as sd
from skydome.export.luts import write_luts

sky = sd.model("hillaire2020", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=180.0))

def progress(done, total):
    if done == 2:
        print("ready", flush=True)
        time.sleep(60)

write_luts(sky, sys.argv[1] + "/luts", formats=("npy", "bin"), progress=progress)
"""


@pytest.mark.parametrize("child, temporary", [(_NPY_CHILD, ".a.npy."), (_LUTS_CHILD, ".luts.")])
def test_sigterm_mid_write_in_a_child(child, temporary, tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", child, str(tmp_path)],
                            stdout=subprocess.PIPE, env=_env(), text=True)
    try:
        assert proc.stdout.readline().strip() == "ready"
        seen = _hidden(tmp_path)
        assert len(seen) == 1 and seen[0].startswith(temporary), seen   # mid-write
        proc.send_signal(signal.SIGTERM)
        rc = proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert rc == -signal.SIGTERM
    assert list(tmp_path.iterdir()) == []
