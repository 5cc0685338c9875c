"""Helper of the full-disk tests: a small tmpfs mounted for one test, so that a write really
fails with ENOSPC (errno 28). Mounting needs root (or CAP_SYS_ADMIN); where it is not
permitted the test is skipped, saying why."""

from __future__ import annotations

import contextlib
import os
import subprocess

import pytest


@contextlib.contextmanager
def small_disk(folder, size: str):
    """Mount a tmpfs of ``size`` (e.g. "64k") on ``folder`` (created) for the block."""
    os.makedirs(folder, exist_ok=True)
    try:
        res = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size},mode=0777", "tmpfs",
                              str(folder)], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as exc:
        pytest.skip(f"cannot mount a tmpfs to fill a disk: {exc}")
    if res.returncode != 0:
        pytest.skip("mounting a tmpfs to fill a disk is not permitted here: "
                    + " ".join(res.stderr.split()))
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], capture_output=True, timeout=30)
