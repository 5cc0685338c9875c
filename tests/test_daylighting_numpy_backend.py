"""The numpy backend of the Perez sky matrix against the numba kernel (an independent
implementation of the same equations: numba's scalar loop vs numpy's vectorised ufuncs),
and the typer-free command line against the typer command."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skydome.daylighting.skymatrix import perez_sky_matrix_from_weather
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


def test_numpy_backend_refuses_the_adaptive_rule(weather):
    with pytest.raises(ValueError, match="backend"):
        perez_sky_matrix_from_weather(weather, backend="numpy", order="adaptive")


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
