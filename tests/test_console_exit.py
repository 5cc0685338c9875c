"""The console script's end (``skydome.__main__.console``): the process ends with
``os._exit`` after the command, without the interpreter's teardown, so everything Python's
own exit does that a command's results depend on must happen first. The reference for
each behaviour is Python's own exit, run in a subprocess beside it."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

import skydome as sd
from skydome.__main__ import _exit_status

ENV = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}


def run(code: str, timeout: float = 300, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=timeout, env=kw.pop("env", ENV), **kw)


@pytest.mark.parametrize("code", [None, 0, 3, 255, 256 + 5, -1, True, "a message"])
def test_exit_status_is_pythons(code):
    """``_exit_status`` gives the status (and, for a non-integer, the stderr line) that
    Python's own ``sys.exit(code)`` gives."""
    ref = run(f"import sys; sys.exit({code!r})")
    got = run(f"""
        import os, sys
        from skydome.__main__ import _exit_status
        os._exit(_exit_status({code!r}))""")
    assert got.returncode == ref.returncode
    assert got.stderr == ref.stderr
    assert _exit_status(None) == 0


@pytest.mark.parametrize("code", [None, 0, 4, "stopped"])
def test_console_finishes_what_pythons_exit_finishes(tmp_path, code):
    """Through ``console()`` as through Python's own exit: a non-daemon thread still running
    finishes (its file complete), the atexit handlers run (last registered first),
    buffered stdout reaches a pipe whole, and the status is the one ``sys.exit`` gives."""
    script = textwrap.dedent(f"""
        import atexit, sys, threading, time
        import skydome.__main__ as entry

        def late(path):
            time.sleep(0.3)
            with open(path, "w") as f:
                f.write("x" * 100000)

        def main():
            threading.Thread(target=late, args=(r"{tmp_path}/{{tag}}-thread",)).start()
            atexit.register(lambda: open(r"{tmp_path}/{{tag}}-atexit", "a").write("1"))
            atexit.register(lambda: open(r"{tmp_path}/{{tag}}-atexit", "a").write("2"))
            sys.stdout.write("y" * 70000)   # more than a pipe's buffer: flushed at the end
            sys.exit({code!r})
        """)
    ref = run(script.replace("{tag}", "ref") + "\nmain()\n")
    got = run(script.replace("{tag}", "got") + "\nentry.main = main\nentry.console()\n")
    assert got.returncode == ref.returncode and got.stderr == ref.stderr
    assert got.stdout == ref.stdout == "y" * 70000
    for part in ("thread", "atexit"):
        assert (tmp_path / f"got-{part}").read_text() == (tmp_path / f"ref-{part}").read_text()
    assert (tmp_path / "got-atexit").read_text() == "21"
    assert len((tmp_path / "got-thread").read_text()) == 100000


def test_console_ends_with_an_idle_thread_pool_alive():
    """A ThreadPoolExecutor left open (as Dask's threaded scheduler keeps its pool): its idle
    workers are non-daemon threads that stop only when the threading module's exit hooks
    tell them to; Python's exit runs those hooks before joining, and so does console()
    (a join alone would wait for ever)."""
    script = textwrap.dedent("""
        import concurrent.futures, sys
        import skydome.__main__ as entry
        pool = concurrent.futures.ThreadPoolExecutor(2)
        def main():
            print(pool.submit(lambda: 42).result())
            sys.exit(0)
        """)
    ref = run(script + "main()\n", timeout=60)
    got = run(script + "entry.main = main\nentry.console()\n", timeout=60)
    assert (got.returncode, got.stdout) == (ref.returncode, ref.stdout) == (0, "42\n")


def test_console_leaves_an_exception_to_python(tmp_path):
    """An exception other than SystemExit propagates: Python's traceback and status 1."""
    got = run("""
        import skydome.__main__ as entry
        def main():
            raise RuntimeError("boom")
        entry.main = main
        entry.console()
        """)
    assert got.returncode == 1
    assert "RuntimeError: boom" in got.stderr and "Traceback" in got.stderr


def test_command_line_of_a_new_atmosphere_leaves_its_cache_entry_complete(tmp_path,
                                                                           monkeypatch):
    """``python -m skydome render`` (the console script's end) of an atmosphere not in the
    table cache: the entry it writes beside the render is complete when the process has
    ended, and a model of the same settings in this process reads it from the cache."""
    tiny = dict(scattering_r_size=4, scattering_mu_size=8, scattering_mu_s_size=4,
                scattering_nu_size=2, irradiance_mu_s_size=4, irradiance_r_size=4,
                transmittance_mu_size=8, transmittance_r_size=4, orders=2, n_wavelengths=1)
    opts = []
    for k, v in tiny.items():
        opts += ["--" + k.replace("_", "-"), str(v)]
    cache = tmp_path / "cache"
    env = {**ENV, "SKYDOME_CACHE_DIR": str(cache)}
    res = subprocess.run([sys.executable, "-m", "skydome", "render", "--sun-elevation", "30",
                          "--size", "16", "--out", str(tmp_path / "x.png"), *opts],
                         capture_output=True, text=True, timeout=600, env=env)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "x.png").stat().st_size > 0
    entries = [p for p in cache.iterdir() if not p.name.startswith(".")]
    assert len(entries) == 1 and (entries[0] / "meta.json").is_file()
    monkeypatch.setenv("SKYDOME_CACHE_DIR", str(cache))
    kw = {k: v for k, v in tiny.items() if k != "n_wavelengths"}
    m = sd.model("precomputed", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=180.0),
                 table_wavelengths_nm=[550.0], **kw)
    assert m.from_cache
