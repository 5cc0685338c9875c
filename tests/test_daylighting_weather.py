"""Weather input: the TMY3 file pvlib ships (Greensboro, NC), EPW, bad files."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from skydome.daylighting.weather import read_weather, sample_weather_path, write_wea


@pytest.fixture(scope="module")
def tmy3():
    return read_weather(sample_weather_path())


def test_tmy3_site_and_period(tmy3):
    # Header of pvlib/data/723170TYA.CSV: 723170,"GREENSBORO PIEDMONT TRIAD INT",NC,-5.0,
    # 36.100,-79.950,273
    s = tmy3.site
    assert (s.latitude_deg, s.longitude_deg, s.utc_offset_h, s.elevation_m) == (
        36.1, -79.95, -5.0, 273.0)
    assert "GREENSBORO" in s.name
    assert len(tmy3) == 8760
    # the record labelled 01:00 covers 00:00-01:00: the sun is taken at 00:30
    assert str(tmy3.time[0]) == "2021-01-01T00:30:00"
    assert str(tmy3.time[-1]) == "2021-12-31T23:30:00"
    assert tmy3.hour[0] == 0.5 and tmy3.hour[12] == 12.5
    # first record's values from the file: GHI, DNI, DHI = 0 at night; dew point 6.1 C
    assert tmy3.dni[0] == 0.0 and tmy3.dhi[0] == 0.0 and tmy3.dew_point_c[0] == 6.1
    # the file's albedo and AOD columns are 0 with source '?' (missing): not invented
    assert tmy3.albedo is None and tmy3.aod is None
    assert tmy3.dni_illuminance is not None


def test_sun_at_hour_midpoints_matches_gendaymtx(tmy3, tmp_path):
    """The sun of every daylight hour against gendaymtx's (its -D sun file) for the same .wea:
    Radiance's sun.c is a low-order approximation (declination and equation of time as short
    sine series) and differs from NREL SPA by up to 0.9 deg over this year; a half-hour
    shift of the instant would show as up to 7.5 deg."""
    from _daylighting import TEST_DAYS, read_sun_scene, run_gendaymtx, solar_minute

    w = tmy3.select(np.isin(tmy3.day_of_year, TEST_DAYS))
    write_wea(w, tmp_path / "t.wea")
    run_gendaymtx(tmp_path / "t.wea", ["-n"], suns=tmp_path / "suns.rad")
    ids, _, dirs = read_sun_scene(tmp_path / "suns.rad")
    assert len(ids) > 40
    pos = {m: i for i, m in enumerate(solar_minute(w))}
    ours = w.sun_directions[[pos[i] for i in ids]]
    ang = np.degrees(np.arccos(np.clip(np.sum(ours * dirs / np.linalg.norm(dirs, axis=1)[:, None],
                                              axis=1), -1, 1)))
    assert ang.max() < 1.0
    assert np.median(ang) < 0.6


def _copy_lines(src, dst, transform):
    lines = src.read_text().splitlines(keepends=True)
    dst.write_text("".join(transform(lines)))
    return dst


def _epw_from_tmy3(tmy3_path, dst, ndays=2):
    """A small EPW written from the TMY3 records (EPW data dictionary field order; the values
    not used here are set to the EPW missing codes)."""
    import csv

    rows = list(csv.reader(tmy3_path.open()))[2:2 + 24 * ndays]
    head = ["LOCATION,Greensboro,NC,USA,TMY3,723170,36.10,-79.95,-5.0,273.0",
            "DESIGN CONDITIONS,0", "TYPICAL/EXTREME PERIODS,0",
            "GROUND TEMPERATURES,0", "HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0",
            "COMMENTS 1,made from pvlib 723170TYA.CSV", "COMMENTS 2,",
            f"DATA PERIODS,1,1,Data,Sunday, 1/ 1,1/{ndays}"]
    out = []
    for r in rows:
        mo, da, yr = r[0].split("/")
        hr = int(r[1].split(":")[0])
        f = [yr, str(int(mo)), str(int(da)), str(hr), "60", "?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9",
             r[31], r[34], r[37], r[40] + "00", "9999", "9999", "9999", r[4], r[7], r[10],
             r[13], r[16], r[19], r[22], r[43], r[46], r[25], r[28], r[49], r[52], "9", "999999999",
             str(float(r[55]) * 10), "0.999", "999", "99", "999", "999", "99"]
        out.append(",".join(f))
    dst.write_text("\n".join(head + out) + "\n")
    return dst


def test_epw_reads_same_values_as_tmy3(tmy3, tmp_path):
    p = _epw_from_tmy3(sample_weather_path(), tmp_path / "g.epw")
    w = read_weather(p)
    assert len(w) == 48 and w.format == "epw"
    assert w.site.latitude_deg == 36.1 and w.site.utc_offset_h == -5.0
    np.testing.assert_array_equal(w.dni, tmy3.dni[:48])
    np.testing.assert_array_equal(w.dhi, tmy3.dhi[:48])
    np.testing.assert_allclose(w.sun_zenith_deg, tmy3.sun_zenith_deg[:48], atol=1e-9)
    assert w.aod is None  # 0.999 = missing


@pytest.mark.parametrize("case, message", [
    ("truncated", "truncated"),
    ("missing", "missing dni"),
    ("units", "out of range"),
    ("step", "time step"),
])
def test_bad_weather_files(tmp_path, case, message):
    src = sample_weather_path()
    dst = tmp_path / "bad.csv"
    if case == "truncated":  # cut in the middle of a record
        _copy_lines(src, dst, lambda ls: ls[:1002] + [ls[1002][:20]])
    elif case == "missing":  # an empty DNI field
        def blank(ls):
            f = ls[500].split(",")
            f[7] = ""
            return ls[:500] + [",".join(f)] + ls[501:]
        _copy_lines(src, dst, blank)
    elif case == "units":  # DNI in lux instead of W/m^2 (x 100)
        def lux(ls):
            out = ls[:2]
            for ln in ls[2:]:
                f = ln.split(",")
                f[7] = str(float(f[7]) * 100)
                out.append(",".join(f))
            return out
        _copy_lines(src, dst, lux)
    else:  # every other hour: a 2-hour step
        _copy_lines(src, dst, lambda ls: ls[:2] + ls[2::2])
    with pytest.raises(ValueError, match=message):
        read_weather(dst)


def test_missing_file_and_not_weather(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        read_weather(tmp_path / "none.epw")
    p = tmp_path / "x.txt"
    p.write_text("hello\n")
    with pytest.raises(ValueError, match="not an EPW or TMY3"):
        read_weather(p)


def test_cli_weather_info_and_bad_file(tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app

    r = CliRunner().invoke(app, ["weather", "info", str(sample_weather_path())])
    assert r.exit_code == 0, r.output
    assert "36.100" in r.output and "8760 records" in r.output
    bad = tmp_path / "bad.csv"
    shutil.copy(sample_weather_path(), bad)
    _copy_lines(sample_weather_path(), bad, lambda ls: ls[:2] + ls[2::2])
    r = CliRunner().invoke(app, ["weather", "info", str(bad)])
    assert r.exit_code == 2
    assert "time step" in r.output


@pytest.mark.parametrize("edit, message", [
    (lambda f: f[:3], "record 2: 3 of 5 fields"),
    (lambda f: f + ["7"], "record 2: 6 of 5 fields"),
    (lambda f: f[:3] + ["x", f[4]], "not numeric"),
])
def test_bad_wea_records(tmy3, tmp_path, edit, message):
    """A .wea record without its 5 fields is named; a field that is not a number is refused."""
    write_wea(tmy3.select(np.arange(len(tmy3)) < 48), tmp_path / "g.wea")
    lines = (tmp_path / "g.wea").read_text().splitlines()
    lines[7] = " ".join(edit(lines[7].split()))  # the header is 6 lines: record 2
    (tmp_path / "b.wea").write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=message):
        read_weather(tmp_path / "b.wea")
    assert len(read_weather(tmp_path / "g.wea")) == 48


@pytest.mark.parametrize("utc_offset_h", [-5.0, 5.5, 0.0])
def test_spa_without_pandas_equals_pvlib_get_solarposition(tmy3, utc_offset_h):
    # The sun positions are pvlib's NREL SPA called without pandas or the pvlib package's
    # imports; pvlib's public get_solarposition (method "nrel_numpy", the site's altitude)
    # is the reference, bit for bit, at the site's offset and at a half-hour one.
    import dataclasses
    import datetime

    import pandas as pd
    from pvlib import solarposition

    from skydome.daylighting.weather import _spa_zenith_azimuth

    site = dataclasses.replace(tmy3.site, utc_offset_h=utc_offset_h)
    zen, azi = _spa_zenith_azimuth(site, tmy3.time)
    tz = datetime.timezone(datetime.timedelta(hours=utc_offset_h))
    ref = solarposition.get_solarposition(pd.DatetimeIndex(tmy3.time).tz_localize(tz),
                                          site.latitude_deg, site.longitude_deg,
                                          altitude=site.elevation_m, method="nrel_numpy")
    assert np.array_equal(zen, ref["zenith"].to_numpy())
    assert np.array_equal(azi, ref["azimuth"].to_numpy())


def test_wea_with_spa_suns_imports_neither_pandas_nor_pvlib(tmy3, tmp_path):
    # A .wea read with the default (SPA) suns needs numpy alone: pvlib's package import
    # (SciPy, pandas) is most of a short run's start-up.
    import os
    import subprocess
    import sys

    write_wea(tmy3, tmp_path / "y.wea")
    code = ("import sys; from skydome.daylighting.weather import read_weather; "
            f"w = read_weather({str(tmp_path / 'y.wea')!r}); "
            "assert w.sun_model == 'spa' and len(w) == 8760; "
            "print(sorted(m for m in ('pandas', 'pvlib', 'scipy') if m in sys.modules))")
    env = dict(os.environ)
    env.pop("PVLIB_USE_NUMBA", None)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       check=True)
    assert r.stdout.strip() == "[]"
