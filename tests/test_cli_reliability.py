"""The command line when the disk or the folder says no, when it is killed, and what it
writes: a full disk, a read-only folder, SIGTERM mid-run, the files' permissions, and the
printed time including the model's construction."""

import errno
import os
import re
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from skydome.cli import app

runner = CliRunner()
SRC = Path(__file__).resolve().parents[1] / "src"


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(SRC)
    return env


def _one_error_line(res):
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert res.exit_code == 2, res.output
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    return lines[0]


@pytest.fixture
def full_disk(monkeypatch):
    """Every PNG written (through Pillow, or skydome's own encoder of sky pictures) writes a
    few bytes and then finds the disk full."""
    from PIL import Image

    from skydome.imaging import image

    def save(self, fp, format=None, **kw):
        with open(fp, "wb") as fh:
            fh.write(b"\x89PNG partial")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(fp))
    monkeypatch.setattr(Image.Image, "save", save)
    monkeypatch.setattr(image, "_write_png_chunks", lambda path, *a, **k: save(None, path))


def test_full_disk_render_one_line_nothing_left(tmp_path, full_disk):
    res = runner.invoke(app, ["render", "--model", "cie2003", "--size", "16", "--out", str(tmp_path / "a.png")])
    line = _one_error_line(res)
    assert "no space left on device" in line.lower()
    assert list(tmp_path.iterdir()) == []


def test_full_disk_folder_command_one_line_nothing_left(tmp_path, full_disk):
    res = runner.invoke(app, ["aureole", "--size", "16", "--out", str(tmp_path / "aur")])
    line = _one_error_line(res)
    assert "no space left on device" in line.lower()
    assert list(tmp_path.iterdir()) == []


@pytest.fixture
def read_only(monkeypatch):
    """A folder the user may not write to (simulated: the tests may run as root, whom
    permission bits do not stop)."""
    def make(folder: Path):
        real = os.access

        def access(path, mode, *a, **k):
            if Path(path).resolve() == folder.resolve() and mode & os.W_OK:
                return False
            return real(path, mode, *a, **k)
        monkeypatch.setattr(os, "access", access)
        return folder
    return make


@pytest.mark.parametrize("args", [
    ["aureole", "--size", "16", "--out", "RO/aur"],
    ["airlight", "--synthetic", "--method", "preetham1999", "--out", "RO/a.png"],
    ["timelapse", "--lat", "48", "--lon", "16", "--date", "2026-06-21", "--out", "RO/t"],
    ["render", "--size", "16", "--out", "RO/a.png"],
    ["polarisation", "--method", "rayleigh_single", "--out", "RO/p.png"],
])
def test_read_only_folder_refused_up_front(tmp_path, read_only, args):
    ro = read_only(tmp_path / "ro")
    ro.mkdir()
    res = runner.invoke(app, [a.replace("RO", str(ro)) for a in args])
    line = _one_error_line(res)
    assert "--out" in line and "not writable" in line
    assert list(ro.iterdir()) == []


def test_sigterm_mid_run_leaves_no_temporary(tmp_path):
    # the timelapse keeps its temporary folder beside --out while it renders the frames
    out = tmp_path / "day"
    proc = subprocess.Popen([sys.executable, "-m", "skydome.cli", "timelapse", "--lat", "48.2",
                             "--lon", "16.4", "--date", "2026-06-21", "--utc-offset", "+02:00",
                             "--every", "10min", "--model", "preetham1999", "--min-elevation", "1",
                             "--size", "256", "--out", str(out)], env=_env(), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not any(p.name.startswith(".") for p in tmp_path.iterdir()):
            assert proc.poll() is None, "finished before its temporary folder was seen"
            time.sleep(0.05)
        assert any(p.name.startswith(".") for p in tmp_path.iterdir())
        proc.send_signal(signal.SIGTERM)
        rc = proc.wait(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert rc == -signal.SIGTERM
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600)])
def test_output_files_follow_the_umask(tmp_path, mask, mode):
    for name in ("a.png", "a.exr"):
        subprocess.run([sys.executable, "-m", "skydome.cli", "render", "--model", "cie2003", "--size", "8",
                        "--out", str(tmp_path / name)], env=_env(), check=True, capture_output=True,
                       preexec_fn=lambda: os.umask(mask))
        assert stat.S_IMODE(os.stat(tmp_path / name).st_mode) == mode


def test_printed_time_includes_model_construction(tmp_path, monkeypatch):
    import skydome.models as M

    real = M.get_model_class("cie2003")

    class Slow(real):
        def __init__(self, *a, **k):
            time.sleep(1.5)
            super().__init__(*a, **k)
    monkeypatch.setattr(M, "get_model_class", lambda name: Slow)
    res = runner.invoke(app, ["render", "--model", "cie2003", "--size", "8", "--out", str(tmp_path / "a.png")])
    assert res.exit_code == 0, res.output
    seconds = float(re.search(r", ([0-9.]+) s\)", res.stdout).group(1))
    assert seconds >= 1.5
