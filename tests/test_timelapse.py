"""`skydome timelapse` (survey 5.1): frames, contact sheet, colour plot and the day's colour
signatures."""

import csv

import numpy as np
import pytest
from typer.testing import CliRunner

from skydome.cli import app
from skydome.apps.timelapse import day_times, parse_every

runner = CliRunner()


def test_parse_every_and_day_times():
    assert parse_every("10min") == 10 and parse_every("1h") == 60 and parse_every("30s") == 0.5
    t = day_times("2026-06-21", "+02:00", 60, "06:00", "09:00")
    assert [x.hour for x in t] == [6, 7, 8, 9]
    with pytest.raises(ValueError, match="every = 'soon'"):
        parse_every("soon")


def test_timelapse_vienna_solstice(tmp_path):
    """Vienna, 21 June 2026, every 2 h: frames only while the sun is above -6 deg; the
    zenith is bluer (higher B/R) at noon than the horizon under the sun in the evening,
    and the sun's disc is redder (chromaticity x) at 20:00 than at 12:00 (SPA: elevation
    about 5.6 and 64.9 deg)."""
    out = tmp_path / "day"
    res = runner.invoke(app, ["timelapse", "--lat", "48.21", "--lon", "16.37", "--date", "2026-06-21",
                              "--utc-offset", "+02:00", "--every", "2h", "--size", "24",
                              "--wavelengths", "8", "--out", str(out)])
    assert res.exit_code == 0, res.output
    rows = list(csv.DictReader(open(out / "colours.csv")))
    hours = [r["time"][11:16] for r in rows]
    assert hours == ["06:00", "08:00", "10:00", "12:00", "14:00", "16:00", "18:00", "20:00"]
    assert (out / "contact_sheet.png").exists() and (out / "colours.png").exists()
    assert len(list(out.glob("frame_*.png"))) == 8
    by = {h: r for h, r in zip(hours, rows)}

    def xy(r, k):
        X, Y, Z = (float(r[f"{k}_{c}"]) for c in "XYZ")
        return X / (X + Y + Z), Y / (X + Y + Z)

    assert xy(by["20:00"], "sun")[0] > xy(by["12:00"], "sun")[0] + 0.05
    assert xy(by["12:00"], "zenith")[0] < xy(by["20:00"], "horizon")[0]
    assert float(by["12:00"]["zenith_Y"]) > 3 * float(by["06:00"]["zenith_Y"])


def test_timelapse_bad_input(tmp_path):
    out = tmp_path / "d"
    res = runner.invoke(app, ["timelapse", "--lat", "95", "--lon", "0", "--date", "2026-06-21",
                              "--out", str(out)])
    assert res.exit_code == 2 and "lat = 95" in res.output
    res = runner.invoke(app, ["timelapse", "--lat", "89", "--lon", "0", "--date", "2026-12-21",
                              "--out", str(out)])
    assert res.exit_code == 2 and "never rises" in res.output
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_timelapse_frames_on_dask_equal_in_process(tmp_path):
    """--scheduler: every frame a Dask task (a LocalCluster's address); the frames, the CSV and
    the contact sheet equal the in-process run's byte for byte; the chunk folder is gone."""
    from _dask import run_both

    run_both(["timelapse", "--lat", "48.21", "--lon", "16.37", "--date", "2026-06-21",
              "--utc-offset", "+02:00", "--every", "3h", "--size", "24", "--wavelengths", "8",
              "--model", "preetham1999"], tmp_path / "a", tmp_path / "b")
    names = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "b").iterdir())
    assert sum(n.startswith("frame_") for n in names) >= 4
    for n in names:
        # colours.png is matplotlib drawing colours.csv, compared through the CSV
        if n.endswith(".png") and n != "colours.png" or n.endswith(".csv"):
            assert (tmp_path / "a" / n).read_bytes() == (tmp_path / "b" / n).read_bytes(), n
    assert not (tmp_path / "b.chunks").exists()
