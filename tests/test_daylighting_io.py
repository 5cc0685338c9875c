"""Radiance matrix files: round trips, Radiance's rmtxop reading skydome's files, and the
skymatrix command's outputs and refusals."""

from __future__ import annotations

import numpy as np
import pytest

from skydome.daylighting.radiance_io import read_matrix, write_matrix
from skydome.daylighting.weather import sample_weather_path


@pytest.mark.parametrize("fmt", ["ascii", "float", "double"])
def test_round_trip(tmp_path, fmt):
    rng = np.random.default_rng(1)
    m = rng.uniform(0, 1e4, (5, 7, 3))
    write_matrix(tmp_path / "m.mtx", m, fmt=fmt, info=["test"])
    r, head = read_matrix(tmp_path / "m.mtx")
    assert head["NROWS"] == "5" and head["NCOLS"] == "7" and head["FORMAT"] == fmt
    np.testing.assert_allclose(r, m, rtol={"ascii": 1e-6, "float": 1e-7, "double": 0}[fmt])


@pytest.mark.parametrize("fmt", ["ascii", "float", "double"])
def test_rmtxop_reads_our_files(tmp_path, fmt):
    """rmtxop (Radiance) converts our file to ascii with the same numbers, and transposes it
    as a 5 x 7 matrix should be."""
    from _radiance import run_radiance

    m = np.arange(5 * 7 * 3, dtype=float).reshape(5, 7, 3) * 1.5 + 0.25
    write_matrix(tmp_path / "m.mtx", m, fmt=fmt)
    out = run_radiance("rmtxop", ["-fa", "-t", "m.mtx"], cwd=tmp_path)
    (tmp_path / "t.mtx").write_text(out)
    t, head = read_matrix(tmp_path / "t.mtx")
    assert (head["NROWS"], head["NCOLS"]) == ("7", "5")
    np.testing.assert_allclose(t, np.swapaxes(m, 0, 1), rtol=1e-6)


def test_refuses_existing_and_nan(tmp_path):
    p = tmp_path / "m.mtx"
    write_matrix(p, np.ones((2, 2, 3)))
    before = p.read_bytes()
    with pytest.raises(ValueError, match="exists"):
        write_matrix(p, np.zeros((2, 2, 3)))
    assert p.read_bytes() == before
    with pytest.raises(ValueError, match="nan"):
        write_matrix(tmp_path / "n.mtx", np.full((2, 2, 3), np.nan))
    assert not (tmp_path / "n.mtx").exists()


@pytest.mark.parametrize("fmt", ["float", "double"])
def test_matrix_file_filled_in_place(tmp_path, fmt):
    """matrix_file: the filled body gives the same file as write_matrix of the same matrix;
    a nan, or an exception inside the block, leaves nothing on disk (no temporary either)."""
    from skydome.daylighting.radiance_io import matrix_file

    m = np.arange(5 * 7 * 3, dtype=float).reshape(5, 7, 3) * 1.5 + 0.25
    write_matrix(tmp_path / "w.mtx", m, fmt=fmt, info=["test"])
    with matrix_file(tmp_path / "f.mtx", 5, 7, 3, fmt=fmt, info=["test"]) as body:
        assert not (tmp_path / "f.mtx").exists()
        body[...] = m
    assert (tmp_path / "f.mtx").read_bytes() == (tmp_path / "w.mtx").read_bytes()
    with pytest.raises(ValueError, match="nan"):
        with matrix_file(tmp_path / "n.mtx", 2, 2, 3, fmt=fmt) as body:
            body[1, 1, 1] = np.nan
    with pytest.raises(RuntimeError):
        with matrix_file(tmp_path / "e.mtx", 2, 2, 3, fmt=fmt) as body:
            raise RuntimeError("interrupted")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.mtx", "w.mtx"]
    with pytest.raises(ValueError, match="exists"):
        with matrix_file(tmp_path / "f.mtx", 5, 7, 3, fmt=fmt):
            pass


def _cli(args):
    from typer.testing import CliRunner

    from skydome.cli import app

    return CliRunner().invoke(app, args)


def _days_tmy3(tmp_path, ndays=2):
    lines = sample_weather_path().read_text().splitlines(keepends=True)
    p = tmp_path / "two_days.csv"
    p.write_text("".join(lines[:2 + 24 * ndays]))
    return p


def test_cli_skymatrix_separate_sun(tmp_path):
    w = _days_tmy3(tmp_path)
    out = tmp_path / "annual.mtx"
    r = _cli(["skymatrix", "--weather", str(w), "--patches", "reinhart:2", "--sun", "separate",
              "--out", str(out)])
    assert r.exit_code == 0, r.output
    sky, head = read_matrix(out)
    assert sky.shape == (578, 48, 3)
    sun, _ = read_matrix(tmp_path / "annual.sun.mtx")
    assert sun.shape == (1, 48, 3)
    scene = (tmp_path / "annual.suns.rad").read_text()
    # one sun per hour with the sun in the sky (as gendaymtx -D, black where no direct light)
    from skydome.daylighting.weather import read_weather

    wd = read_weather(w)
    in_sky = wd.sun_directions[:, 2] > -np.sin(np.radians(0.2665))
    assert scene.count(" source sun") == int(np.count_nonzero(in_sky)) > 10
    assert np.all(sun[0, ~in_sky] == 0) and np.count_nonzero(sun[0, :, 0] > 0) > 10
    assert np.all(sky >= 0) and np.all(np.isfinite(sky))


@pytest.mark.parametrize("args, message", [
    (["--patches", "klems"], "patches = 'klems' is unknown"),
    (["--sun", "blur"], "sun = 'blur' is unknown"),
    (["--format", "xml"], "format = 'xml'"),
    (["--albedo", "2"], "albedo"),
    (["--model", "hosek"], "model = 'hosek'"),
])
def test_cli_skymatrix_bad_input(tmp_path, args, message):
    w = _days_tmy3(tmp_path)
    out = tmp_path / "x.mtx"
    r = _cli(["skymatrix", "--weather", str(w), "--out", str(out), *args])
    assert r.exit_code == 2
    assert message in r.output
    assert list(tmp_path.iterdir()) == [w]  # nothing partial on disk


def test_cli_skymatrix_bad_weather_and_existing_output(tmp_path):
    lines = sample_weather_path().read_text().splitlines(keepends=True)
    bad = tmp_path / "bad.csv"
    bad.write_text("".join(lines[:2] + lines[2:50:2]))  # 2-hour steps
    r = _cli(["skymatrix", "--weather", str(bad), "--out", str(tmp_path / "a.mtx")])
    assert r.exit_code == 2 and "time step" in r.output
    assert not (tmp_path / "a.mtx").exists()
    w = _days_tmy3(tmp_path)
    (tmp_path / "a.mtx").write_text("keep")
    r = _cli(["skymatrix", "--weather", str(w), "--out", str(tmp_path / "a.mtx")])
    assert r.exit_code == 2 and "exists" in r.output
    assert (tmp_path / "a.mtx").read_text() == "keep"
    assert r.output.count("\n") == 1


def test_cli_float_file_equals_one_pass_matrix(tmp_path):
    """The CLI's float file (the kernel fills the file's map in place) holds the bytes that
    writing the whole matrix in one pass holds (write_matrix of the in-memory matrix)."""
    from skydome.daylighting.skymatrix import perez_sky_matrix_from_weather
    from skydome.daylighting.weather import read_weather

    w = _days_tmy3(tmp_path)
    out = tmp_path / "cli.mtx"
    r = _cli(["skymatrix", "--weather", str(w), "--patches", "reinhart:2", "--out", str(out)])
    assert r.exit_code == 0, r.output
    m = perez_sky_matrix_from_weather(read_weather(w), patches="reinhart:2", dtype=np.float32)
    write_matrix(tmp_path / "one.mtx", m.sky, fmt="float", transpose=True)
    a, b = out.read_bytes(), (tmp_path / "one.mtx").read_bytes()
    body_a, body_b = a[a.index(b"\n\n") + 2:], b[b.index(b"\n\n") + 2:]
    assert len(body_a) == 578 * 48 * 3 * 4 and body_a == body_b
    assert np.count_nonzero(np.frombuffer(body_a, np.float32)) > 1000


def test_cli_error_inside_the_kernel_leaves_nothing(tmp_path, monkeypatch):
    """A failure after part of the body is written: one line, exit 2, no file, no
    temporary."""
    from skydome.daylighting import skymatrix

    def fail_half_way(weather, out=None, **kw):
        out[: out.shape[0] // 2] = 1.0
        raise ValueError("interrupted half way")

    monkeypatch.setattr(skymatrix, "perez_sky_matrix_from_weather", fail_half_way)
    w = _days_tmy3(tmp_path)
    r = _cli(["skymatrix", "--weather", str(w), "--patches", "reinhart:2", "--out",
              str(tmp_path / "x.mtx")])
    assert r.exit_code == 2 and "interrupted half way" in r.output
    assert list(tmp_path.iterdir()) == [w]


@pytest.mark.parametrize("order", ["fine", "17", "-1"])
def test_cli_bad_order(tmp_path, order):
    w = _days_tmy3(tmp_path)
    r = _cli(["skymatrix", "--weather", str(w), "--order", order, "--out",
              str(tmp_path / "x.mtx")])
    assert r.exit_code == 2 and "order" in r.output
    assert list(tmp_path.iterdir()) == [w]


@pytest.mark.parametrize("fmt", ["float", "double"])
def test_binary_data_starts_aligned(tmp_path, fmt):
    """A binary file's data starts at a multiple of 8 bytes whatever the header's text (the
    NCOMP line carries the padding), so the memory map matrix_file yields is aligned (numpy
    writes into a misaligned one through copies); the file reads back unchanged."""
    from skydome.daylighting.radiance_io import matrix_file

    m = np.arange(2 * 3 * 3, dtype=float).reshape(2, 3, 3)
    for k in range(1, 10):
        info = ["x" * k]
        with matrix_file(tmp_path / f"f{k}.mtx", 2, 3, 3, fmt=fmt, info=info) as body:
            assert body.flags.aligned and body.ctypes.data % 8 == 0
            body[...] = m
        raw = (tmp_path / f"f{k}.mtx").read_bytes()
        assert raw.find(b"\n\n") % 8 == 6  # data at find + 2
        back, head = read_matrix(tmp_path / f"f{k}.mtx")
        np.testing.assert_array_equal(back, m)
        assert int(head["NCOMP"]) == 3 and head["lines"][1] == info[0]
