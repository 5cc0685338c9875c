"""A catalogue of bad invocations of every command.

Each must exit with code 2 before any work, print exactly one line on stderr that starts
with ``error:`` and names the option and the value given, and leave the output folder as it
was (nothing created, an existing file untouched). The ranges are the documented ones
(``skydome COMMAND --help``, ``skydome models``).
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from skydome.cli import app

runner = CliRunner()

# placeholders: OUT_PNG / OUT_DIR / OUT_EXR are output paths inside the test's folder;
# FILE is an existing file there (for the folder commands), MISSING a missing folder.
OK_TIME = ["--lat", "48.21", "--lon", "16.37", "--date", "2026-06-21"]

CASES = [
    # -- render: sun, place and time
    ("render", ["--sun-elevation", "91"], "--sun-elevation", "91"),
    ("render", ["--sun-elevation", "-90.5"], "--sun-elevation", "-90.5"),
    ("render", ["--sun-elevation", "nan"], "--sun-elevation", "nan"),
    ("render", ["--sun-elevation", "high"], "--sun-elevation", "'high'"),
    ("render", ["--sun-azimuth", "1e300"], "--sun-azimuth", "1e+300"),
    ("render", ["--sun-azimuth", "361"], "--sun-azimuth", "361"),
    ("render", ["--sun-azimuth", "-400"], "--sun-azimuth", "-400"),
    ("render", ["--sun-azimuth", "south"], "--sun-azimuth", "'south'"),
    ("render", ["--lat", "91", "--lon", "0", "--time", "2026-06-21T12:00Z"], "--lat", "91"),
    ("render", ["--lat", "0", "--lon", "181", "--time", "2026-06-21T12:00Z"], "--lon", "181"),
    ("render", ["--lat", "north", "--lon", "0", "--time", "2026-06-21T12:00Z"], "--lat", "'north'"),
    ("render", ["--lat", "48", "--lon", "16", "--time", "yesterday"], "--time", "'yesterday'"),
    ("render", ["--lat", "48", "--lon", "16", "--time", "2026-06-21T12:00"], "--time", "2026-06-21T12:00"),
    ("render", ["--lat", "48", "--lon", "16", "--time", "2026-02-30T12:00Z"], "--time", "2026-02-30"),
    ("render", ["--lat", "48", "--lon", "16"], "--time", "missing"),
    ("render", ["--lat", "48", "--lon", "16", "--time", "2026-06-21T12:00Z", "--sun-method", "guess"],
     "--sun-method", "'guess'"),
    ("render", ["--lat", "48", "--lon", "16", "--time", "2026-06-21T12:00Z", "--sun-elevation", "10"],
     "--sun-elevation", "--lat"),
    # -- render: image
    ("render", ["--size", "0"], "--size", "'0'"),
    ("render", ["--size", "1"], "--size", "'1'"),
    ("render", ["--size", "abc"], "--size", "'abc'"),
    ("render", ["--size", "64x"], "--size", "'64x'"),
    ("render", ["--size", "-64"], "--size", "'-64'"),
    ("render", ["--size", "40000"], "--size", "'40000'"),
    ("render", ["--size", "32768"], "--size", "32768"),
    ("render", ["--projection", "equirect", "--size", "16384x8192"], "--size", "16384x8192"),
    ("render", ["--projection", "fisheye", "--size", "64x32"], "--size", "'64x32'"),
    ("render", ["--projection", "cylinder"], "--projection", "'cylinder'"),
    ("render", ["--projection", "camera"], "--projection", "'camera'"),
    ("render", ["--wavelengths", "2"], "--wavelengths", "2"),
    ("render", ["--wavelengths", "402"], "--wavelengths", "402"),
    ("render", ["--wavelengths", "many"], "--wavelengths", "'many'"),
    ("render", ["--wavelengths", "3.5"], "--wavelengths", "'3.5'"),
    ("render", ["--exposure", "1e400"], "--exposure", "inf"),
    ("render", ["--exposure", "0"], "--exposure", "0"),
    ("render", ["--exposure", "-1"], "--exposure", "-1"),
    ("render", ["--exposure", "nan"], "--exposure", "nan"),
    ("render", ["--exposure", "bright"], "--exposure", "'bright'"),
    ("render", ["--tonemap", "hable"], "--tonemap", "'hable'"),
    ("render", ["--bits", "12"], "--bits", "12"),
    ("render", ["--bits", "eight"], "--bits", "'eight'"),
    ("render", ["--model", "nosuchmodel"], "--model", "'nosuchmodel'"),
    # -- render: model options
    ("render", ["--turbidity", "-1"], "--turbidity", "-1"),
    ("render", ["--turbidity", "1e400"], "--turbidity", "inf"),
    ("render", ["--turbidity", "hazy"], "--turbidity", "'hazy'"),
    ("render", ["--turbidity"], "--turbidity", "needs a value"),
    ("render", ["--observer-altitude-m", "-5000"], "--observer-altitude-m", "-5000"),
    ("render", ["--model", "single_scattering", "--view-samples", "2.5"], "--view-samples", "'2.5'"),
    ("render", ["--bogus-flag", "3"], "--bogus-flag", "no option"),
    ("render", ["--model", "nishita1993", "--sun-disc", "maybe"], "--sun-disc", "'maybe'"),
    ("render", ["--model", "nishita1993", "--sun-disc", "on"], "--sun-disc", "'on'"),
    ("render", ["--model", "nishita1993", "--light-exact", "2"], "--light-exact", "'2'"),
    ("render", ["--model", "cie2003", "--sky-type", "16"], "--sky-type", "16"),
    ("render", ["--model", "cie2003", "--sky-type", "twelve"], "--sky-type", "'twelve'"),
    ("render", ["--model", "preetham1999", "--turbidity", "1.5"], "--turbidity", "1.5"),
    ("render", ["--model", "preetham1999", "--sun-elevation", "-5"], "--sun-elevation", "-5"),
    ("render", ["--model", "cie2003", "--sun-elevation", "-5"], "--sun-elevation", "-5"),
    ("render", ["stray"], "'stray'", "unexpected"),
    # -- render: output file
    ("render", ["--out", "OUT_JPG"], "--out", "out.jpg"),
    ("render", ["--out", "MISSING/a.png"], "--out", "a.png"),
    ("render", ["--out", "OUT_DIR_EXISTING"], "--out", "existing"),
    # -- sun
    ("sun", ["--lat", "91", "--lon", "0", "--time", "2026-06-21T12:00Z"], "--lat", "91"),
    ("sun", ["--lat", "0", "--lon", "-181", "--time", "2026-06-21T12:00Z"], "--lon", "-181"),
    ("sun", ["--lat", "x", "--lon", "0", "--time", "2026-06-21T12:00Z"], "--lat", "'x'"),
    ("sun", ["--lat", "0", "--lon", "0", "--time", "noon"], "--time", "'noon'"),
    ("sun", ["--lat", "0", "--lon", "0", "--time", "2026-06-21T12:00Z", "--method", "guess"], "--method", "'guess'"),
    ("sun", ["--lon", "0", "--time", "2026-06-21T12:00Z"], "--lat", "missing"),
    # -- plot luminance / plot compare
    ("plot luminance", ["--model", "cie2003:99", "--out", "OUT_PNG"], "--sky-type", "99"),
    ("plot luminance", ["--model", "nosuch", "--out", "OUT_PNG"], "--model", "'nosuch'"),
    ("plot luminance", ["--model", "cie2003", "--out", "OUT_JPG"], "--out", "out.jpg"),
    ("plot luminance", ["--model", "cie2003", "--out", "MISSING/a.png"], "--out", "a.png"),
    ("plot luminance", ["--model", "cie2003", "--sun-elevation", "95", "--out", "OUT_PNG"], "--sun-elevation", "95"),
    ("plot luminance", ["--model", "cie2003", "--sun-azimuth", "400", "--out", "OUT_PNG"], "--sun-azimuth", "400"),
    ("plot luminance", ["--model", "cie2003", "--sun-azimuth", "west", "--out", "OUT_PNG"], "--sun-azimuth", "'west'"),
    ("plot luminance", ["--model", "preetham1999", "--turbidity", "50", "--out", "OUT_PNG"], "--turbidity", "50"),
    ("plot compare", ["--models", "cie2003:12,nosuch", "--out", "OUT_PNG"], "--model", "'nosuch'"),
    ("plot compare", ["--models", "cie2003,preetham1999", "--out", "OUT_SVGZ"], "--out", "out.svgz"),
    ("plot compare", ["--models", "cie2003,preetham1999", "--sun-elevation", "-91", "--out", "OUT_PNG"],
     "--sun-elevation", "-91"),
    ("plot compare", ["--models", "cie2003,preetham1999", "--turbidity", "0", "--out", "OUT_PNG"], "--turbidity", "0"),
    # -- compare
    ("compare", ["--models", "preetham1999", "--out", "FILE"], "--out", "existing file"),
    ("compare", ["--models", "preetham1999", "--out", "MISSING/x"], "--out", "missing"),
    ("compare", ["--models", "preetham1999", "--size", "8", "--out", "OUT_DIR"], "--size", "8"),
    ("compare", ["--models", "preetham1999", "--size", "big", "--out", "OUT_DIR"], "--size", "'big'"),
    ("compare", ["--models", "preetham1999", "--size", "32768", "--out", "OUT_DIR"], "--size", "32768"),
    ("compare", ["--models", "preetham1999", "--wavelengths", "1", "--out", "OUT_DIR"], "--wavelengths", "1"),
    ("compare", ["--models", "preetham1999", "--sun-elevation", "5,x", "--out", "OUT_DIR"], "--sun-elevation", "'5,x'"),
    ("compare", ["--models", "preetham1999", "--sun-elevation", "5,95", "--out", "OUT_DIR"], "--sun-elevation", "95"),
    ("compare", ["--models", "preetham1999", "--sun-elevation", ",", "--out", "OUT_DIR"], "--sun-elevation", "','"),
    ("compare", ["--models", "preetham1999", "--sun-azimuth", "1e300", "--out", "OUT_DIR"], "--sun-azimuth", "1e+300"),
    ("compare", ["--models", "preetham1999", "--reference", "nosuch", "--out", "OUT_DIR"], "--reference", "'nosuch'"),
    ("compare", ["--models", "nosuch", "--out", "OUT_DIR"], "--model", "'nosuch'"),
    ("compare", ["--models", "preetham1999", "--turbidity", "1", "--out", "OUT_DIR"], "--turbidity", "1"),
    ("compare", ["--models", "preetham1999", "--frobnicate", "1", "--out", "OUT_DIR"], "--frobnicate", "no model"),
    # -- timelapse
    ("timelapse", OK_TIME + ["--out", "FILE"], "--out", "existing file"),
    ("timelapse", OK_TIME + ["--out", "MISSING/x"], "--out", "missing"),
    ("timelapse", ["--lat", "48", "--lon", "16", "--date", "2026-13-01", "--out", "OUT_DIR"], "--date", "'2026-13-01'"),
    ("timelapse", ["--lat", "48", "--lon", "16", "--date", "21.06.2026", "--out", "OUT_DIR"], "--date", "'21.06.2026'"),
    ("timelapse", ["--lat", "48", "--lon", "16", "--date", "tomorrow", "--out", "OUT_DIR"], "--date", "'tomorrow'"),
    ("timelapse", OK_TIME + ["--utc-offset", "2", "--out", "OUT_DIR"], "--utc-offset", "'2'"),
    ("timelapse", OK_TIME + ["--utc-offset", "+15:00", "--out", "OUT_DIR"], "--utc-offset", "'+15:00'"),
    ("timelapse", OK_TIME + ["--utc-offset", "CET", "--out", "OUT_DIR"], "--utc-offset", "'CET'"),
    ("timelapse", OK_TIME + ["--start", "25:00", "--out", "OUT_DIR"], "--start", "'25:00'"),
    ("timelapse", OK_TIME + ["--start", "noon", "--out", "OUT_DIR"], "--start", "'noon'"),
    ("timelapse", OK_TIME + ["--end", "12:60", "--out", "OUT_DIR"], "--end", "'12:60'"),
    ("timelapse", OK_TIME + ["--start", "18:00", "--end", "06:00", "--out", "OUT_DIR"], "--end", "'06:00'"),
    ("timelapse", OK_TIME + ["--every", "0.5min", "--out", "OUT_DIR"], "--every", "0.5"),
    ("timelapse", OK_TIME + ["--every", "often", "--out", "OUT_DIR"], "--every", "'often'"),
    ("timelapse", OK_TIME + ["--every", "13h", "--out", "OUT_DIR"], "--every", "780"),
    ("timelapse", OK_TIME + ["--min-elevation", "95", "--out", "OUT_DIR"], "--min-elevation", "95"),
    ("timelapse", OK_TIME + ["--size", "8", "--out", "OUT_DIR"], "--size", "8"),
    ("timelapse", OK_TIME + ["--size", "4096", "--out", "OUT_DIR"], "--size", "4096"),
    ("timelapse", OK_TIME + ["--wavelengths", "500", "--out", "OUT_DIR"], "--wavelengths", "500"),
    ("timelapse", OK_TIME + ["--projection", "camera", "--out", "OUT_DIR"], "--projection", "'camera'"),
    ("timelapse", OK_TIME + ["--model", "nosuch", "--out", "OUT_DIR"], "--model", "'nosuch'"),
    ("timelapse", OK_TIME + ["--turbidity", "0.5", "--out", "OUT_DIR"], "--turbidity", "0.5"),
    ("timelapse", ["--lat", "95", "--lon", "16", "--date", "2026-06-21", "--out", "OUT_DIR"], "--lat", "95"),
    ("timelapse", ["--lat", "48", "--lon", "east", "--date", "2026-06-21", "--out", "OUT_DIR"], "--lon", "'east'"),
    # -- polarisation
    ("polarisation", ["--sun-azimuth", "1e300", "--out", "OUT_PNG"], "--sun-azimuth", "1e+300"),
    ("polarisation", ["--sun-elevation", "91", "--out", "OUT_PNG"], "--sun-elevation", "91"),
    ("polarisation", ["--method", "guess", "--out", "OUT_PNG"], "--method", "'guess'"),
    ("polarisation", ["--size", "2", "--out", "OUT_PNG"], "--size", "2"),
    ("polarisation", ["--samples", "1", "--out", "OUT_PNG"], "--samples", "1"),
    ("polarisation", ["--seed", "-1", "--out", "OUT_PNG"], "--seed", "-1"),
    ("polarisation", ["--wavelength", "200", "--out", "OUT_PNG"], "--wavelength", "200"),
    ("polarisation", ["--wavelength", "green", "--out", "OUT_PNG"], "--wavelength", "'green'"),
    ("polarisation", ["--turbidity", "40", "--out", "OUT_PNG"], "--turbidity", "40"),
    ("polarisation", ["--out", "OUT_JPG"], "--out", "out.jpg"),
    ("polarisation", ["--out", "OUT_PNG", "--csv", "OUT_TXT"], "--csv", "out.txt"),
    ("polarisation", ["--out", "OUT_PNG", "--csv", "MISSING/a.csv"], "--csv", "a.csv"),
    # -- twilight
    ("twilight", ["--out", "FILE"], "--out", "existing file"),
    ("twilight", ["--out", "MISSING/x"], "--out", "missing"),
    ("twilight", ["--step", "0.1", "--out", "OUT_DIR"], "--step", "0.1"),
    ("twilight", ["--step", "10", "--out", "OUT_DIR"], "--step", "10"),
    ("twilight", ["--size", "4", "--out", "OUT_DIR"], "--size", "4"),
    ("twilight", ["--wavelengths", "0", "--out", "OUT_DIR"], "--wavelengths", "0"),
    ("twilight", ["--exposure", "manual", "--out", "OUT_DIR"], "--exposure", "'manual'"),
    ("twilight", ["--model", "preetham1999", "--out", "OUT_DIR"], "--model", "'preetham1999'"),
    ("twilight", ["--model", "nosuch", "--out", "OUT_DIR"], "--model", "'nosuch'"),
    ("twilight", ["--turbidity", "-3", "--out", "OUT_DIR"], "--turbidity", "-3"),
    # -- airlight
    ("airlight", ["--synthetic", "--out", "OUT_JPG"], "--out", "out.jpg"),
    ("airlight", ["--synthetic", "--out", "MISSING/a.png"], "--out", "a.png"),
    ("airlight", ["--synthetic", "--method", "guess", "--out", "OUT_PNG"], "--method", "'guess'"),
    ("airlight", ["--synthetic", "--white-balance", "auto", "--out", "OUT_PNG"], "--white-balance", "'auto'"),
    ("airlight", ["--synthetic", "--sun-elevation", "99", "--out", "OUT_PNG"], "--sun-elevation", "99"),
    ("airlight", ["--synthetic", "--sun-azimuth", "1e300", "--out", "OUT_PNG"], "--sun-azimuth", "1e+300"),
    ("airlight", ["--synthetic", "--view-azimuth", "720", "--out", "OUT_PNG"], "--view-azimuth", "720"),
    ("airlight", ["--synthetic", "--fov", "wide", "--out", "OUT_PNG"], "--fov", "'wide'"),
    ("airlight", ["--image", "MISSING/a.png", "--depth", "MISSING/d.npy", "--out", "OUT_PNG"], "--image", "a.png"),
    ("airlight", ["--out", "OUT_PNG"], "--image", "--depth"),
    # -- aureole
    ("aureole", ["--out", "FILE"], "--out", "existing file"),
    ("aureole", ["--out", "MISSING/x"], "--out", "missing"),
    ("aureole", ["--aerosol", "dust", "--out", "OUT_DIR"], "--aerosol", "'dust'"),
    ("aureole", ["--sun-elevation", "0", "--out", "OUT_DIR"], "--sun-elevation", "0"),
    ("aureole", ["--sun-elevation", "low", "--out", "OUT_DIR"], "--sun-elevation", "'low'"),
    ("aureole", ["--fov", "1", "--out", "OUT_DIR"], "--fov", "1"),
    ("aureole", ["--size", "2048", "--out", "OUT_DIR"], "--size", "2048"),
    ("aureole", ["--size", "1e3", "--out", "OUT_DIR"], "--size", "'1e3'"),
    # -- the parser itself
    ("table1", ["--fast"], "--fast", "no such option"),
    ("models", ["extra"], "(extra)", "unexpected"),
    ("nosuchcommand", [], "'nosuchcommand'", "no such command"),
]

FOLDER_COMMANDS = {"compare", "timelapse", "twilight", "aureole"}


@pytest.fixture(autouse=True)
def memory_cap(monkeypatch):
    """The documented cap (16 GiB), so that the memory refusals do not depend on the machine."""
    monkeypatch.setenv("SKYDOME_MEMORY_LIMIT", str(16 * 2 ** 30))


def _materialise(command, args, root: Path):
    """Replace the placeholders by paths in ``root``; return the argument list."""
    subs = {"OUT_PNG": root / "out.png", "OUT_JPG": root / "out.jpg", "OUT_SVGZ": root / "out.svgz",
            "OUT_TXT": root / "out.txt", "OUT_DIR": root / "out", "FILE": root / "existing.txt",
            "OUT_DIR_EXISTING": root / "existing"}
    out = []
    for a in args:
        for key in sorted(subs, key=len, reverse=True):
            if a == key:
                a = str(subs[key])
                break
        if a.startswith("MISSING/"):
            a = str(root / "missing" / a[len("MISSING/"):])
        out.append(a)
    if command in ("render",) and "--out" not in out:
        out += ["--out", str(root / "out.png")]
    if command == "render" and "--size" not in out:
        out += ["--size", "16"]
    return command.split() + out


def _prepare(root: Path) -> dict:
    (root / "existing.txt").write_text("keep me")
    (root / "existing").mkdir()
    return {p.name: p.stat().st_mtime_ns for p in root.iterdir()}


def _check(root: Path, before: dict, code: int, stderr: str, option: str, value: str):
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert code == 2, stderr
    assert len(lines) == 1, stderr
    line = lines[0]
    assert line.startswith("error: "), line
    assert option.lower() in line.lower(), line
    assert value.lower() in line.lower(), line
    after = {p.name: p.stat().st_mtime_ns for p in root.iterdir()}
    assert after == before                     # nothing created, nothing touched
    assert (root / "existing.txt").read_text() == "keep me"
    assert list((root / "existing").iterdir()) == []


def test_catalogue_is_large_and_covers_every_command():
    assert len(CASES) >= 100
    commands = {c for c, *_ in CASES}
    for name in ("render", "sun", "plot luminance", "plot compare", "compare", "timelapse",
                 "polarisation", "twilight", "airlight", "aureole", "table1", "models"):
        assert name in commands


@pytest.mark.parametrize("command, args, option, value", CASES,
                         ids=[f"{i:03d}-{c.replace(' ', '_')}" for i, (c, *_) in enumerate(CASES)])
def test_bad_invocation(tmp_path, command, args, option, value):
    before = _prepare(tmp_path)
    res = runner.invoke(app, _materialise(command, args, tmp_path))
    _check(tmp_path, before, res.exit_code, res.stderr, option, value)
    assert res.stdout == ""


@pytest.mark.parametrize("command, args, option, value", [
    ("render", ["--size", "abc"], "--size", "'abc'"),
    ("timelapse", OK_TIME + ["--out", "FILE"], "--out", "existing file"),
    ("render", ["--exposure", "1e400"], "--exposure", "inf"),
    ("aureole", ["--sun-elevation", "low", "--out", "OUT_DIR"], "--sun-elevation", "'low'"),
])
def test_bad_invocation_in_a_real_process(tmp_path, command, args, option, value):
    before = _prepare(tmp_path)
    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(__file__).resolve().parents[1] / "src")
    proc = subprocess.run([sys.executable, "-m", "skydome.cli"] + _materialise(command, args, tmp_path),
                          capture_output=True, text=True, env=env, timeout=120)
    _check(tmp_path, before, proc.returncode, proc.stderr, option, value)
    assert proc.stdout == ""


@pytest.mark.parametrize("limit, fragment", [("1e6", "GiB of memory"), ("lots", "SKYDOME_MEMORY_LIMIT = 'lots'")])
def test_memory_limit_from_the_environment(tmp_path, monkeypatch, limit, fragment):
    monkeypatch.setenv("SKYDOME_MEMORY_LIMIT", limit)
    res = runner.invoke(app, ["render", "--size", "512", "--out", str(tmp_path / "a.png")])
    assert res.exit_code == 2
    assert fragment in res.stderr
    assert list(tmp_path.iterdir()) == []


def test_version():
    from skydome import __version__

    res = runner.invoke(app, ["--version"])
    assert res.exit_code == 0
    assert res.stdout.strip() == f"skydome {__version__}"
