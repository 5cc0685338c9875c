"""The numpy backend of the Perez sky matrix against the numba kernel (an independent
implementation of the same equations: numba's scalar loop vs numpy's vectorised ufuncs),
and the typer-free command line against the typer command."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skydome.daylighting.skymatrix import perez_sky_matrix, perez_sky_matrix_from_weather
from skydome.daylighting.weather import read_weather, sample_weather_path

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def weather():
    return read_weather(sample_weather_path(), sun_position="radiance")


@pytest.mark.parametrize("spec,order,sun", [("tregenza", 0, "spread"),
                                            ("reinhart:2", 0, "disc:0.533"),
                                            ("tregenza", 3, "separate")])
def test_numpy_backend_equals_numba_kernel(weather, spec, order, sun):
    kw = dict(patches=spec, order=order, sun=sun, sun_position="radiance")
    a = perez_sky_matrix_from_weather(weather, backend="numba", **kw).radiance_layout()
    b = perez_sky_matrix_from_weather(weather, backend="numpy", **kw).radiance_layout()
    assert np.all(b >= 0.0) and np.all(np.isfinite(b))
    assert np.array_equal(a == 0.0, b == 0.0)  # same unlit hours and empty patches
    np.testing.assert_allclose(b, a, rtol=1e-11, atol=0.0)


@pytest.mark.parametrize("spec,order,sun", [("reinhart:4", 0, "spread"),
                                            ("tregenza", 3, "separate")])
def test_numpy_backend_float32_within_two_ulp_of_numba_kernel(weather, spec, order, sun):
    """A float32 matrix (what a "float" file holds): the numpy backend rounds the patch mean
    and the hour's factor (scale x tint) to float32 and multiplies them in float32, so each
    value is within about 2 units in the last place of the kernel's once-rounded float64
    product (over the sample year: 2.3e-7 relative at most, a third of the values differ in
    the last bit); the sun's patches and the zeros are the kernel's."""
    kw = dict(patches=spec, order=order, sun=sun, sun_position="radiance", dtype=np.float32)
    a = perez_sky_matrix_from_weather(weather, backend="numba", **kw).radiance_layout()
    b = perez_sky_matrix_from_weather(weather, backend="numpy", **kw).radiance_layout()
    assert a.dtype == b.dtype == np.float32
    assert np.array_equal(a == 0.0, b == 0.0)
    np.testing.assert_allclose(b.astype(np.float64), a.astype(np.float64), rtol=2.5e-7,
                               atol=0.0)


@pytest.mark.parametrize("spec,sun", [("tregenza", "spread"), ("reinhart:4", "spread"),
                                      ("reinhart:2", "separate")])
def test_numpy_backend_adaptive_rule_equals_numba_kernel(weather, spec, sun):
    """The adaptive (tiered) rule: numpy computes the far rule for every patch-hour and
    recomputes those nearer the sun with their finer rule, the kernel picks the rule per
    patch-hour; the same tier choice and the same matrix to rounding."""
    kw = dict(patches=spec, order="adaptive", sun=sun, sun_position="radiance")
    a = perez_sky_matrix_from_weather(weather, backend="numba", **kw).radiance_layout()
    b = perez_sky_matrix_from_weather(weather, backend="numpy", **kw).radiance_layout()
    assert np.all(b >= 0.0) and np.all(np.isfinite(b))
    assert np.array_equal(a == 0.0, b == 0.0)
    np.testing.assert_allclose(b, a, rtol=1e-11, atol=0.0)


def _cli(module, args):
    env = {"PYTHONPATH": str(ROOT / "src")}
    import os
    env = dict(os.environ, **env)
    return subprocess.run([sys.executable, "-m", module, "skymatrix"] + args, env=env,
                          capture_output=True, text=True)


def test_fast_command_line_writes_the_typer_commands_file(tmp_path):
    wea = str(sample_weather_path())
    args = ["--weather", wea, "--patches", "tregenza", "--order", "0", "--backend", "numpy",
            "--sun-position", "radiance"]
    r1 = _cli("skydome", args + ["--out", str(tmp_path / "a.mtx")])
    r2 = _cli("skydome.cli", args + ["--out", str(tmp_path / "b.mtx")])
    assert r1.returncode == 0 and r2.returncode == 0, r1.stderr + r2.stderr
    assert (tmp_path / "a.mtx").read_bytes() == (tmp_path / "b.mtx").read_bytes()
    # bad input goes to the typer command: one line, exit 2, nothing on disk
    r3 = _cli("skydome", args + ["--out", str(tmp_path / "a.mtx")])
    assert r3.returncode == 2 and r3.stderr.startswith("error: ") and "exists" in r3.stderr
    r4 = _cli("skydome", ["--weather", wea, "--order", "0", "--backend", "numpy",
                          "--patches", "nope", "--out", str(tmp_path / "c.mtx")])
    assert r4.returncode == 2 and len(r4.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "c.mtx").exists()


def test_numpy_backend_file_equals_numba_file(weather, tmp_path):
    """The whole sample year written by perez_sky_matrix_file with each backend (double files,
    both filling the file's memory map): the same header, zeros and values within 1e-12
    relative (measured over the year: 2.4e-14 at Tregenza, 1.4e-13 at MF:4)."""
    from skydome.daylighting.radiance_io import read_matrix
    from skydome.daylighting.skymatrix import perez_sky_matrix_file

    kw = dict(patches="tregenza", order=0, sun="spread", sun_position="radiance",
              fmt="double", info=["test"])
    perez_sky_matrix_file(tmp_path / "a.mtx", weather, backend="numba", **kw)
    m = perez_sky_matrix_file(tmp_path / "b.mtx", weather, backend="numpy", **kw)
    a, ha = read_matrix(tmp_path / "a.mtx")
    b, hb = read_matrix(tmp_path / "b.mtx")
    assert ha["lines"] == hb["lines"] and a.shape == (146, len(weather), 3)
    assert np.array_equal(a == 0.0, b == 0.0)
    np.testing.assert_allclose(b, a, rtol=1e-12, atol=0.0)
    np.testing.assert_array_equal(np.swapaxes(np.asarray(m.sky), 0, 1), b)  # its memory map


def test_streamed_files_are_written_in_bounded_calls(tmp_path, monkeypatch):
    """atomic_write_stream writes each chunk in calls of at most WRITE_SLICE bytes and the
    file holds exactly the chunks' bytes (bytes and a numpy buffer)."""
    import os

    from skydome.daylighting import radiance_io

    monkeypatch.setattr(radiance_io, "WRITE_SLICE", 1000)
    sizes = []

    class Spy:
        def __init__(self, f):
            self.f = f

        def write(self, data):
            sizes.append(len(data))
            return self.f.write(data)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return self.f.__exit__(*exc)

    real_fdopen = os.fdopen
    monkeypatch.setattr(radiance_io.os, "fdopen", lambda *a, **k: Spy(real_fdopen(*a, **k)))
    arr = np.arange(2600, dtype=np.float32)  # 10 400 bytes
    radiance_io.atomic_write_stream(tmp_path / "x.bin", [b"head\n", arr.data, b""])
    assert (tmp_path / "x.bin").read_bytes() == b"head\n" + arr.tobytes()
    assert max(sizes) == 1000 and sum(sizes) == 5 + arr.nbytes


def test_skymatrix_entry_point_turns_off_numpy_huge_pages(monkeypatch):
    """`skydome skymatrix ...` sets NUMPY_MADVISE_HUGEPAGE=0 before numpy is imported, and
    OPENBLAS_NUM_THREADS=1 for a perez1993 command line the fast path parses (unless the user
    set them), whose run it makes with Python's cyclic garbage collector off; other command
    lines leave both alone."""
    import os

    import skydome.__main__ as entry
    from skydome.cli import skymatrix_fast as skymatrix_cli

    import gc

    seen = []
    monkeypatch.setattr(skymatrix_cli, "fast_skymatrix",
                        lambda argv: seen.append(gc.isenabled()) or True)
    args = ["skydome", "skymatrix", "--weather", "w", "--out", "o"]
    for user_value in (None, "4"):
        for name in ("NUMPY_MADVISE_HUGEPAGE", "OPENBLAS_NUM_THREADS"):
            if user_value is None:
                monkeypatch.delenv(name, raising=False)
            else:
                monkeypatch.setenv(name, user_value)
        monkeypatch.setattr(sys, "argv", args)
        with pytest.raises(SystemExit) as e:
            entry.main()
        assert e.value.code == 0
        assert os.environ["NUMPY_MADVISE_HUGEPAGE"] == (user_value or "0")
        assert os.environ["OPENBLAS_NUM_THREADS"] == (user_value or "1")
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    monkeypatch.setattr(sys, "argv", args + ["--model", "precomputed"])
    with pytest.raises(SystemExit):
        entry.main()
    assert "OPENBLAS_NUM_THREADS" not in os.environ
    # the cyclic collector is off during a perez1993 run only, and on again afterwards
    assert seen == [False, False, True] and gc.isenabled()


def test_numpy_backend_checks_the_values_it_writes(tmp_path):
    """The numpy backend raises on a value that is not finite in the matrix's type (here a
    diffuse irradiance whose sky overflows float32), so that its file needs no second reading
    of the memory map (``matrix_file(check_finite=False)``); the map check itself still
    catches a nan written by any other filler."""
    from skydome.daylighting.radiance_io import matrix_file
    from skydome.daylighting.skymatrix import perez_sky_matrix

    sd = [[0.0, -0.5, 0.75 ** 0.5]]
    kw = dict(patches="tregenza", order=0, backend="numpy")
    ok = perez_sky_matrix([600.0], [100.0], sd, [172], dtype=np.float32, **kw).sky
    assert np.all(np.isfinite(ok)) and ok.max() > 0.0
    with pytest.raises(ValueError, match="nan or inf"):
        perez_sky_matrix([600.0], [1e300], sd, [172], dtype=np.float32, **kw)
    with pytest.raises(ValueError, match="nan or inf"):
        perez_sky_matrix([1e300], [100.0], sd, [172], dtype=np.float32, **kw)
    with pytest.raises(ValueError, match="nan or inf"):
        with matrix_file(tmp_path / "a.mtx", 2, 2, 1) as body:
            body[1, 1, 0] = np.nan
    assert not list(tmp_path.iterdir())
    with matrix_file(tmp_path / "b.mtx", 2, 2, 1, check_finite=False) as body:
        body[1, 1, 0] = np.nan  # the caller's responsibility
    assert (tmp_path / "b.mtx").exists()


@pytest.mark.parametrize("dtype,rtol", [(np.float64, 1e-11), (np.float32, 2.5e-7)])
def test_numpy_backend_long_runs_of_lit_hours(dtype, rtol):
    """Polar days: 100 consecutive lit hours (more than a block of lit hours at MF:4, 56, and
    than a written run, 32), then a night hour and 3 lit hours; the same matrix as the
    kernel's."""
    n = 104
    t = np.arange(n) * (2.0 * np.pi / 24.0)
    alt = np.radians(20.0 + 10.0 * np.sin(t))
    sd = np.stack([np.cos(alt) * np.sin(t), np.cos(alt) * np.cos(t), np.sin(alt)], axis=-1)
    dni = 300.0 + 200.0 * np.cos(t) ** 2
    dhi = 80.0 + 40.0 * np.sin(t) ** 2
    dni[100], dhi[100] = 0.0, 0.0
    kw = dict(patches="reinhart:4", order=0, dtype=dtype)
    a = perez_sky_matrix(dni, dhi, sd, np.full(n, 172), backend="numba", **kw).sky
    b = perez_sky_matrix(dni, dhi, sd, np.full(n, 172), backend="numpy", **kw).sky
    assert np.array_equal(a == 0.0, b == 0.0) and np.all(b[100] == 0.0)
    np.testing.assert_allclose(np.asarray(b, np.float64), np.asarray(a, np.float64),
                               rtol=rtol, atol=0.0)


@pytest.mark.parametrize("spec", ["tregenza", "reinhart:4"])
def test_nearest_patches_equal_a_search_over_every_patch(spec):
    """The sun's nearest patch centres, sought first in the rows near the sun's altitude, are
    those of a search over every patch with the kernel's dot products and tie-break (the
    lower index first), for suns all over the sky (the zenith, the horizon, between rows)."""
    from skydome.daylighting._numpy_sky import nearest_patches
    from skydome.daylighting.patches import patches

    c = patches(spec).centres[1:]
    rng = np.random.default_rng(7)
    v = rng.normal(size=(3000, 3))
    v[:, 2] = np.abs(v[:, 2])
    v[:3] = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 1e-3]]
    v /= np.linalg.norm(v, axis=1)[:, None]
    for nsuns in (1, 4):
        near, ndot = nearest_patches(c, v, np.arange(len(v)), nsuns)
        dots = c[None, :, 0] * v[:, 0:1] + c[None, :, 1] * v[:, 1:2] + c[None, :, 2] * v[:, 2:3]
        ref = np.argsort(-dots, axis=1, kind="stable")[:, :nsuns]
        np.testing.assert_array_equal(near, ref)
        np.testing.assert_array_equal(ndot, np.take_along_axis(dots, ref, axis=1))
