"""Weather files as they come: oversized lines and files, junk fields, encodings, and a fuzz
test that every input is either read or refused with a ValueError naming file and record."""

from __future__ import annotations

import re
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from skydome.daylighting.weather import (MAX_LINE_BYTES, MAX_RECORDS, read_weather,
                                         sample_weather_path, write_wea)

from test_daylighting_weather import _epw_from_tmy3


def _tmy3_lines() -> list[str]:
    return sample_weather_path().read_text().splitlines()


def _write(path, lines, encoding="utf-8", bom=False):
    data = ("\n".join(lines) + "\n").encode(encoding)
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + data)
    return path


def _refused_quickly(path, pattern, limit_s=1.0):
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=pattern) as exc:
        read_weather(path)
    dt = time.perf_counter() - t0
    assert dt < limit_s, f"refusal took {dt:.2f} s"
    assert str(path) in str(exc.value)
    return str(exc.value)


def test_tmy3_with_a_10_mb_line_is_refused_quickly(tmp_path):
    ls = _tmy3_lines()
    p = tmp_path / "long.csv"
    with p.open("w") as f:
        f.write("\n".join(ls[:2]) + "\n")
        f.write("1" * (10 * 2**20) + "\n")
        f.write("\n".join(ls[2:]) + "\n")
    _refused_quickly(p, rf"line 3 is longer than {MAX_LINE_BYTES} bytes")


def test_one_line_of_100000_fields_is_refused_quickly(tmp_path):
    ls = _tmy3_lines()
    p = tmp_path / "wide.csv"
    _write(p, ls[:2] + [",".join(["1.5e+3"] * 100_000)] + ls[2:40])
    assert p.stat().st_size > 500_000
    _refused_quickly(p, "line 3 is longer")
    q = tmp_path / "wide.wea"  # the same line in a .wea file
    head = ["place x", "latitude 36", "longitude 80", "time_zone 75", "site_elevation 1",
            "weather_data_file_units 1"]
    _write(q, head + [" ".join(["1"] * 100_000)])
    _refused_quickly(q, "line 7 is longer")


def test_record_with_too_many_fields_is_refused(tmp_path):
    ls = _tmy3_lines()
    p = _write(tmp_path / "f.csv", ls[:2] + [ls[2] + ",1" * 200] + ls[3:50])
    _refused_quickly(p, r"record 1 \(line 3\) has 271 fields; a record has at most 128")


def test_epw_over_10_gb_is_refused_at_its_first_record_past_a_year(tmp_path):
    epw = _epw_from_tmy3(sample_weather_path(), tmp_path / "g.epw", ndays=2)
    lines = epw.read_text().splitlines()
    head, recs = lines[:8], lines[8:]
    p = tmp_path / "huge.epw"
    with p.open("w") as f:
        f.write("\n".join(head) + "\n")
        for _ in range(MAX_RECORDS // len(recs) + 2):
            f.write("\n".join(recs) + "\n")
    try:  # extend it to 11 GB without writing the bytes (a sparse file)
        with p.open("r+b") as f:
            f.truncate(11 * 2**30)
    except OSError:
        pytest.skip("this file system cannot hold an 11 GB sparse file")
    _refused_quickly(p, rf"more than {MAX_RECORDS} records \(line {8 + MAX_RECORDS + 1}\)",
                     limit_s=3.0)


@pytest.mark.parametrize("fmt", ["tmy3", "epw"])
def test_junk_in_dni_names_file_record_line_and_field(tmp_path, fmt):
    if fmt == "tmy3":
        ls = _tmy3_lines()[:2 + 48]
        f = ls[2 + 9].split(",")
        f[7] = "abc"  # DNI (W/m^2) of record 10 [WM08]
        ls[2 + 9] = ",".join(f)
        p = _write(tmp_path / "j.csv", ls)
        line = 12
    else:
        epw = _epw_from_tmy3(sample_weather_path(), tmp_path / "g.epw", ndays=2)
        ls = epw.read_text().splitlines()
        f = ls[8 + 9].split(",")
        f[14] = "abc"  # DNI of record 10 [EPW data dictionary, field 15]
        ls[8 + 9] = ",".join(f)
        p = _write(tmp_path / "j.epw", ls)
        line = 18
    msg = _refused_quickly(p, "is not a number")
    assert msg == (f"weather = {str(p)!r}: record 10 (line {line}), field DNI = 'abc' is not "
                   "a number")


def test_latin1_utf8_and_bom_read_alike(tmp_path):
    """A site name with a non-ASCII character (real EPW files from Europe carry them in
    Latin-1 or UTF-8) and a UTF-8 byte-order mark are read alike in EPW, TMY3 and .wea."""
    name = "Zürich-Kloten Aéroport"
    ref = read_weather(sample_weather_path())
    ls = _tmy3_lines()[:2 + 48]
    ls[0] = ls[0].replace('"GREENSBORO PIEDMONT TRIAD INT"', f'"{name}"')
    epw = _epw_from_tmy3(sample_weather_path(), tmp_path / "g.epw", ndays=2)
    els = epw.read_text().splitlines()
    els[0] = els[0].replace("Greensboro", name)
    write_wea(ref.select(np.arange(len(ref)) < 48), tmp_path / "g.wea")
    wls = (tmp_path / "g.wea").read_text().splitlines()
    wls[0] = "place " + name.replace(" ", "_")
    for fmt, lines in (("csv", ls), ("epw", els), ("wea", wls)):
        got = []
        for enc, bom in (("utf-8", False), ("utf-8", True), ("latin-1", False)):
            p = _write(tmp_path / f"s_{enc}_{bom}.{fmt}", lines, enc, bom)
            got.append(read_weather(p))
        for w in got:
            assert w.site.name == name, (fmt, w.site.name)
            np.testing.assert_array_equal(w.dni, got[0].dni)
            np.testing.assert_array_equal(w.dhi, got[0].dhi)
            assert w.site == got[0].site
        np.testing.assert_allclose(got[0].dni, ref.dni[:48], atol=0.05)  # .wea: 1 decimal


# -- fuzz -----------------------------------------------------------------------------------
def _seed_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("seed")
    tmy = _write(d / "s.csv", _tmy3_lines()[:2 + 48])
    epw = _epw_from_tmy3(sample_weather_path(), d / "s.epw", ndays=2)
    w = read_weather(tmy)
    write_wea(w, d / "s.wea")
    return {"csv": tmy.read_bytes(), "epw": epw.read_bytes(), "wea": (d / "s.wea").read_bytes()}


_JUNK = st.sampled_from([b"abc", b"", b"nan", b"inf", b"-1e400", b"1e400", b"\xff\xfe", b"\x00",
                         b"9" * 40, b"-", b"1,2", b" ", b"\xc3\xa9", b"12:00", b"/", b"'"])


@st.composite
def _mutations(draw):
    fmt = draw(st.sampled_from(["csv", "epw", "wea"]))
    kind = draw(st.sampled_from(["truncate", "junk", "encoding", "drop_line", "dup_line"]))
    return fmt, kind, draw(st.integers(0, 10**9)), draw(_JUNK), draw(st.booleans())


@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    return _seed_files(tmp_path_factory)


@settings(max_examples=150, deadline=2000, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(m=_mutations())
def test_fuzz_read_or_refuse_naming_file_and_record(seeds, tmp_path, m):
    fmt, kind, r, junk, bom = m
    data = seeds[fmt]
    lines = data.split(b"\n")
    if kind == "truncate":
        data = data[: r % (len(data) + 1)]
    elif kind == "junk":  # replace one field of one line with junk
        k = r % len(lines)
        sep = b" " if fmt == "wea" else b","
        f = lines[k].split(sep)
        f[(r // 7) % len(f)] = junk
        lines[k] = sep.join(f)
        data = b"\n".join(lines)
    elif kind == "encoding":
        text = data.decode("utf-8").replace("Greensboro", "Gr\u00e9ensboro").replace(
            "GREENSBORO", "GR\u00c9ENSBORO").replace("place ", "place \u00e9")
        data = text.encode("latin-1" if r % 2 else "utf-8")
    elif kind == "drop_line":
        del lines[r % len(lines)]
        data = b"\n".join(lines)
    else:
        k = r % len(lines)
        lines.insert(k, lines[k])
        data = b"\n".join(lines)
    if bom:
        data = b"\xef\xbb\xbf" + data
    p = tmp_path / f"fuzz.{fmt}"
    p.write_bytes(data)
    t0 = time.perf_counter()
    try:
        w = read_weather(p, sun_position="radiance")
    except ValueError as exc:
        msg = str(exc)
        assert str(p) in msg, msg
        # the record (or line) is named wherever the fault lies in one
        if re.search(r"not a number|not numeric|fields|longer than|not a date", msg):
            assert re.search(r"record \d+|line \d+", msg), msg
    else:
        assert len(w) > 0 and np.all(np.isfinite(w.dni)) and np.all(np.isfinite(w.dhi))
        assert np.all(w.dni >= 0) and np.all(w.dhi >= 0)
    assert time.perf_counter() - t0 < 2.0
