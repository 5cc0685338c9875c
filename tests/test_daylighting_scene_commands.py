"""Radiance scene command lines (``!command``) refused unless asked for, rtrace parameters
checked before any work, binary sensor files named."""

from __future__ import annotations

import numpy as np
import pytest

from skydome.daylighting.daylight_factor import (check_rtrace_parameters, read_sensors,
                                                 room_daylight_factor)
from skydome.daylighting.scene import check_scene_files, find_scene_command

UP = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 1.0]])


@pytest.mark.parametrize("name, value, message", [
    ("ab", 17, r"ab = 17 is out of range \[0, 16\]"),
    ("ab", -1, r"ab = -1 is out of range \[0, 16\]"),
    ("ad", 0, r"ad = 0 is out of range \[1, 2147483647\]"),
    ("as_", 2**31, r"as_ = 2147483648 is out of range \[0, 2147483647\]"),
    ("aa", 1.5, r"aa = 1.5 is out of range \[0, 1\]"),
    ("lw", float("nan"), "lw = nan is not a finite number"),
])
def test_rtrace_parameters_refused_before_any_work(tmp_path, name, value, message):
    with pytest.raises(ValueError, match=message):
        check_rtrace_parameters(**{name: value})
    # before the scene or the sensors are even looked at
    with pytest.raises(ValueError, match=message):
        room_daylight_factor(tmp_path / "missing.rad", tmp_path / "missing.pts", **{name: value})


def test_command_lines_found_and_refused(tmp_path):
    room = tmp_path / "room.rad"
    room.write_text("# a room\nvoid plastic grey\n0\n0\n5 .5 .5 .5 0 0\n"
                    "  !xform -t 1 0 0 chair.rad\n")
    assert find_scene_command(room.read_text()) == (6, "!xform -t 1 0 0 chair.rad")
    assert find_scene_command("void glow g\n0\n0\n4 1 1 1 0\n# !not a command\n") is None
    with pytest.raises(ValueError, match=r"room.rad': line 6 is a command line "
                                         r"\('!xform -t 1 0 0 chair.rad'\).*allow_commands"):
        check_scene_files([room])
    with pytest.raises(ValueError, match="line 6 is a command line"):
        room_daylight_factor(room, UP, ab=0)
    assert check_scene_files(room, allow_commands=True) == [room.resolve()]
    (tmp_path / "plain.rad").write_text("# nothing\n")
    with pytest.raises(ValueError, match="sky: line 1 is a command line"):
        room_daylight_factor(tmp_path / "plain.rad", UP, sky="!gensky -c\n")


def test_command_line_runs_only_when_allowed(tmp_path):
    """With allow_commands=True Radiance runs the line: a marker file appears; without, the
    scene is refused and nothing runs."""
    marker = tmp_path / "ran"
    scene = tmp_path / "cmd.rad"
    scene.write_text(f"!touch {marker}\n")
    with pytest.raises(ValueError, match="command line"):
        room_daylight_factor(scene, UP, ab=0)
    assert not marker.exists()
    try:
        df = room_daylight_factor(scene, UP, ab=1, ad=256, allow_commands=True)
    except RuntimeError as exc:  # pragma: no cover - no Radiance
        pytest.skip(str(exc))
    assert marker.exists()
    assert df[0] == pytest.approx(100.0, rel=0.1)  # an empty scene: the open sky


def test_binary_sensor_file_named_with_its_line(tmp_path):
    p = tmp_path / "pts.bin"
    p.write_bytes(b"0 0 0 0 0 1\n" + bytes(range(256)) * 4)
    with pytest.raises(ValueError, match=r"sensors = '.*pts.bin': line 2 is not text"):
        read_sensors(p)
    q = tmp_path / "long.pts"
    q.write_bytes(b"1 " * 100_000)
    with pytest.raises(ValueError, match="line 1 is longer than 4096 bytes"):
        read_sensors(q)
    r = tmp_path / "ok.pts"
    r.write_bytes(b"\xef\xbb\xbf# sensors\r\n0 0 0.8 0 0 1\r\n")
    np.testing.assert_array_equal(read_sensors(r), [[0, 0, 0.8, 0, 0, 1]])
