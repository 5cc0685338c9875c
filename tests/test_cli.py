"""The command line: outputs, every bad input named in issue 2, and start-up hygiene."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from skydome.cli import app

runner = CliRunner()


def _run(*args):
    return runner.invoke(app, list(args))


def test_table1_prints_survey_values():
    res = _run("table1")
    assert res.exit_code == 0
    for text in ("4.1842e-06", "9.5170e-06", "1.1815e-05", "2.0588e-05", "3.9243e-05"):
        assert text in res.output


def test_models_lists_registry_with_units_and_ranges():
    res = _run("models")
    assert res.exit_code == 0
    assert "single_scattering" in res.output
    assert "--observer-altitude-m [m]" in res.output


def test_sun_command():
    res = _run("sun", "--lat", "48.21", "--lon", "16.37", "--time", "2026-06-21T13:00+02:00")
    assert res.exit_code == 0, res.output
    line = [ln for ln in res.output.splitlines() if ln.startswith("elevation")][0]
    # solstice solar noon in Vienna: 90 - 48.21 + 23.44 = 65.2 deg (geometry)
    assert float(line.split()[1]) == pytest.approx(65.2, abs=0.3)


def test_render_small_png_and_exr(tmp_path):
    png = tmp_path / "sky.png"
    # the file path of the CLI (the default model's accuracy is tested in test_precomputed)
    res = _run("render", "--model", "single_scattering", "--sun-elevation", "30", "--sun-azimuth", "135",
               "--projection", "fisheye", "--size", "48", "--wavelengths", "8", "--out", str(png))
    assert res.exit_code == 0, res.output
    assert png.exists()
    from PIL import Image

    im = np.asarray(Image.open(png))
    assert im.shape == (48, 48, 3)
    centre = im[24, 24].astype(int)
    assert centre[2] > centre[0]  # blue zenith


def test_render_model_option_and_location(tmp_path):
    out = tmp_path / "sunset.exr"
    res = _run("render", "--model", "single_scattering", "--lat", "48.21", "--lon", "16.37",
               "--time", "2026-06-21T20:45+02:00", "--projection", "equirect", "--size", "32x16",
               "--wavelengths", "6", "--turbidity", "3", "--out", str(out))
    assert res.exit_code == 0, res.output
    assert out.exists()


@pytest.mark.parametrize("args, fragment", [
    (["--turbidity", "-1"], "turbidity = -1"),
    (["--sun-elevation", "91"], "--sun-elevation = 91"),
    (["--model", "nosuchmodel"], "model = 'nosuchmodel'"),
    (["--projection", "cylinder"], "projection = 'cylinder'"),
    (["--lat", "48", "--lon", "16", "--time", "yesterday noon"], "time"),
    (["--lat", "48", "--lon", "16"], "--time missing"),
    (["--size", "0"], "size"),
    (["--bogus-flag", "3"], "no option --bogus-flag"),
])
def test_bad_input_exit_2_and_nothing_written(tmp_path, args, fragment):
    out = tmp_path / "x.png"
    res = runner.invoke(app, ["render", "--size", "16", "--out", str(out)] + args)
    assert res.exit_code == 2, res.output
    assert fragment in res.output
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_unwritable_output_path(tmp_path):
    out = tmp_path / "no" / "such" / "dir" / "x.png"
    res = _run("render", "--size", "16", "--out", str(out))
    assert res.exit_code == 2
    assert "x.png" in res.output


def test_unknown_output_extension(tmp_path):
    res = _run("render", "--size", "16", "--out", str(tmp_path / "x.jpg"))
    assert res.exit_code == 2
    assert ".exr" in res.output


def test_error_is_one_line_on_stderr(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "skydome.cli", "render", "--sun-elevation", "91",
                           "--out", str(tmp_path / "a.png")], capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr.strip().count("\n") == 0
    assert proc.stderr.startswith("error: ")


def test_import_is_light():
    """`import skydome` and `skydome --help` must not pull in the heavy libraries
    (numba kernels, pvlib, matplotlib, colour-science); timings are in
    benchmarks/bench_startup.py."""
    code = ("import sys, skydome, skydome.cli, skydome.models; skydome.models.available(); "
            "heavy = [m for m in ('numba', 'pvlib', 'matplotlib', 'colour', 'pandas', 'OpenEXR') "
            "if m in sys.modules]; print(','.join(heavy))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == ""


def test_model_parameters_have_one_parser(tmp_path):
    """`export radiance` takes a model's parameters as every command does (--sky-type 1) or
    as --param sky_type=1: both through the one parser, the same files; an unknown or
    malformed parameter is refused as one line before anything is written."""
    common = ["export", "radiance", "--model", "cie2003", "--sun-elevation", "40"]
    r1 = runner.invoke(app, common + ["--sky-type", "1", "--out", str(tmp_path / "a.rad")])
    r2 = runner.invoke(app, common + ["--param", "sky_type=1", "--out", str(tmp_path / "b.rad")])
    assert r1.exit_code == 0 and r2.exit_code == 0, r1.output + r2.output
    assert (tmp_path / "a.dat").read_bytes() == (tmp_path / "b.dat").read_bytes()
    r3 = runner.invoke(app, common + ["--sky-type", "12", "--out", str(tmp_path / "c.rad")])
    assert r3.exit_code == 0 and (tmp_path / "c.dat").read_bytes() != (tmp_path / "a.dat").read_bytes()
    before = sorted(p.name for p in tmp_path.iterdir())
    for extra, words in ((["--param", "nope=1"], "has no option --nope"),
                         (["--nope", "1"], "has no option --nope"),
                         (["--param", "sky_type"], "NAME=VALUE"),
                         (["--sky-type", "x"], "--sky-type = 'x'")):
        r = runner.invoke(app, common + extra + ["--out", str(tmp_path / "d.rad")])
        assert r.exit_code == 2 and words in r.output, (extra, r.output)
        assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_view_verbose_logs_requests_and_its_help_says_so():
    """`skydome view --verbose` (make_server(verbose=True)): each request one line on stderr;
    its help names the requests and the clients that hung up or timed out."""
    import os
    import re
    import signal
    import urllib.request

    res = _run("view", "--help")
    assert res.exit_code == 0
    text = " ".join(re.sub(r"[│╭╮╰╯─]", " ", res.output).split())
    assert ("log every request, and one line per client that hung up or timed out, on stderr"
            in text), text
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "src"))
    p = subprocess.Popen([sys.executable, "-m", "skydome.cli", "view", "--port", "0",
                          "--no-browser", "--verbose"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    try:
        url = p.stdout.readline().strip()
        assert url.startswith("http://127.0.0.1:"), url
        with urllib.request.urlopen(url, timeout=30) as r:
            assert r.status == 200
        p.send_signal(signal.SIGINT)
        assert p.wait(timeout=20) == 0
        err = p.stderr.read()
        assert re.search(r'"GET / HTTP/1\.[01]" 200', err), err
        assert "Traceback" not in err
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()


def test_view_bad_port_one_line():
    res = _run("view", "--port", "70000", "--no-browser", "--verbose")
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert res.exit_code == 2 and len(lines) == 1, res.output
    assert lines[0].startswith("error: ") and "port" in lines[0] and "70000" in lines[0]
