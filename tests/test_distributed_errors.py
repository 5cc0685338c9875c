"""Dask errors before any work: the scheduler address checked for its form (issue 30: `foo`,
`http://...` and port 99999 waited 13-44 s before failing), a bounded wait for a scheduler
that does not answer with a message naming the option, and no chunk folder left behind.
Loopback only: tcp://127.0.0.1:1, where nothing listens."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from skydome.daylighting.skymatrix_chunks import distributed_sky_matrix
from skydome.distributed import Chunk, SchedulerError, check_scheduler, run_chunks

pytest.importorskip("distributed")


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:8786", "127.0.0.1:8786",
                                     "tcp://scheduler.example.org:1", "localhost:65535",
                                     "tls://10.0.0.2:8786", "tcp://[::1]:8786",
                                     "inproc://192.0.2.2/22822/1"])
def test_valid_addresses_pass(address):
    assert check_scheduler(address) == address


@pytest.mark.parametrize("address, why", [
    ("foo", "not a Dask scheduler address"),
    ("http://127.0.0.1:8786", "not a Dask scheduler address"),
    ("tcp://127.0.0.1", "not a Dask scheduler address"),
    ("tcp://127.0.0.1:99999", "port 99999 is out of range [1, 65535]"),
    ("127.0.0.1:0", "port 0 is out of range [1, 65535]"),
    ("tcp://bad host:8786", "not a Dask scheduler address"),
    ("", "not a Dask scheduler address"),
])
def test_bad_addresses_refused_with_option_value_and_form(address, why):
    with pytest.raises(ValueError) as info:
        check_scheduler(address)
    msg = str(info.value)
    assert msg.startswith(f"scheduler = {address!r}") and why in msg
    assert "tcp://HOST:PORT or HOST:PORT" in msg and "\n" not in msg


def _chunk(x):
    return np.full(3, float(x))


def test_bad_address_refused_before_any_work(tmp_path, monkeypatch):
    """The address is refused before the chunks are made (sky_matrix_chunks, which computes
    the sun positions) and before the folder is created."""
    import skydome.daylighting.skymatrix_chunks as D

    monkeypatch.setattr(D, "sky_matrix_chunks", lambda *a, **k: pytest.fail("work began"))
    t0 = time.perf_counter()
    for bad in ("foo", "http://127.0.0.1:8786", "tcp://127.0.0.1:99999"):
        with pytest.raises(ValueError, match="scheduler"):
            distributed_sky_matrix(None, tmp_path / "out.chunks", scheduler=bad)
    assert time.perf_counter() - t0 < 1.0
    assert list(tmp_path.iterdir()) == []


def test_unanswered_scheduler_bounded_wait_and_no_folder(tmp_path):
    """tcp://127.0.0.1:1: nothing listens there. The wait ends after the connect timeout
    (2 s here; issue 30: 44 s) with a SchedulerError naming the option and the address,
    and the chunk folder is not created."""
    folder = tmp_path / "out.mtx.chunks"
    t0 = time.perf_counter()
    with pytest.raises(SchedulerError) as info:
        run_chunks([Chunk("a", _chunk, (1,))], folder, scheduler="tcp://127.0.0.1:1",
                   connect_timeout_s=2.0)
    took = time.perf_counter() - t0
    msg = str(info.value)
    assert msg.startswith("scheduler = 'tcp://127.0.0.1:1'") and "within 2 s" in msg
    assert "\n" not in msg
    assert isinstance(info.value, ValueError)
    assert took < 15.0, took        # the timeout and the client's own shutdown
    assert not folder.exists()


@pytest.mark.parametrize("value", [0, -1, float("nan"), 1e9])
def test_bad_connect_timeout_refused(tmp_path, value):
    with pytest.raises(ValueError, match="connect_timeout_s"):
        run_chunks([Chunk("a", _chunk, (1,))], tmp_path / "c", scheduler="tcp://127.0.0.1:1",
                   connect_timeout_s=value)
    assert list(tmp_path.iterdir()) == []


def _fails(x):
    raise RuntimeError(f"chunk {x} failed")


def test_failed_run_removes_the_folder_it_made_but_keeps_an_existing_one(tmp_path):
    """A chunk that raises: the run's new folder is removed; a folder that existed before
    (a resumed run) is kept with its verified chunks."""
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                           dashboard_address=None)
    client = Client(cluster)
    try:
        new = tmp_path / "new.chunks"
        with pytest.raises(RuntimeError, match="failed"):
            run_chunks([Chunk("a", _chunk, (1,)), Chunk("b", _fails, (2,))], new,
                       client=client)
        assert not new.exists()
        old = tmp_path / "old.chunks"
        run_chunks([Chunk("a", _chunk, (1,))], old, client=client)
        with pytest.raises(RuntimeError, match="failed"):
            run_chunks([Chunk("a", _chunk, (1,)), Chunk("b", _fails, (2,))], old,
                       client=client)
        assert sorted(p.name for p in old.iterdir()) == ["a.npy", "a.npy.sha256"]
    finally:
        client.close()
        cluster.close()


# -- the command line: --scheduler and --connect-timeout checked before any work ------------
def _cli(args, timeout=300):
    import os
    import subprocess
    import sys
    from pathlib import Path

    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(__file__).resolve().parents[1] / "src")
    return subprocess.run([sys.executable, "-m", "skydome", *map(str, args)], env=env,
                          capture_output=True, text=True, timeout=timeout)


def _error_line(res) -> str:
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert res.returncode == 2, (res.returncode, res.stderr[-2000:])
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr[-2000:]
    return lines[0]


_COMMANDS = {
    # the weather file does not exist: the scheduler's check must come before it is read
    "skymatrix": ["skymatrix", "--weather", "{d}/missing.epw", "--out", "{d}/a.mtx"],
    "timelapse": ["timelapse", "--lat", "48", "--lon", "11", "--date", "2026-06-21",
                  "--model", "cie2003", "--out", "{d}/tl"],
    "compare": ["compare", "--models", "cie2003", "--reference", "cie2003", "--out",
                "{d}/cmp"],
}


@pytest.mark.parametrize("command", list(_COMMANDS))
@pytest.mark.parametrize("option, value, why", [
    ("--scheduler", "foo", "--scheduler = 'foo' is not a Dask scheduler address"),
    ("--scheduler", "tcp://127.0.0.1:99999", "port 99999 is out of range [1, 65535]"),
    ("--connect-timeout", "0", "--connect-timeout = 0"),
    ("--connect-timeout", "7200", "--connect-timeout = 7200"),
])
def test_cli_scheduler_and_timeout_refused_before_any_work(tmp_path, command, option,
                                                           value, why):
    args = [a.format(d=tmp_path) for a in _COMMANDS[command]] + [option, value]
    if option == "--connect-timeout":
        args += ["--scheduler", "tcp://127.0.0.1:1"]
    line = _error_line(_cli(args))
    assert why in line, line
    if option == "--connect-timeout":
        assert "3600" in line, line          # the valid range is named
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", ["skymatrix", "timelapse"])
def test_cli_unanswered_scheduler_one_line_after_the_connect_timeout(tmp_path, command):
    """--connect-timeout reaches the library's wait (the message says 1 s, not the default
    10 s); neither an output nor a chunk folder is left."""
    from skydome.daylighting.weather import sample_weather_path

    args = [a.format(d=tmp_path) for a in _COMMANDS[command]]
    if command == "skymatrix":
        args[args.index("--weather") + 1] = str(sample_weather_path())
    t0 = time.perf_counter()
    line = _error_line(_cli([*args, "--scheduler", "tcp://127.0.0.1:1",
                             "--connect-timeout", "1"]))
    assert line.startswith("error: --scheduler = 'tcp://127.0.0.1:1': no Dask scheduler "
                           "answered within 1 s"), line
    assert time.perf_counter() - t0 < 120.0
    assert list(tmp_path.iterdir()) == []       # no output, no OUT.chunks/


def test_local_cluster_beside_another_cluster_warns_nothing(tmp_path):
    """The local cluster binds no fixed port: with port 8787 (Dask's default for its
    scheduler's HTTP routes, where another cluster's scheduler listens) taken on every
    interface, a run gives no "already in use" warning (one line on stderr for a command
    that fails, as issue 30 asks), and its routes listen on the loopback interface only."""
    import socket
    import warnings

    holder = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        holder.bind(("", 8787))
        holder.listen(1)
    except OSError:
        pass  # held by another program already: the same situation
    try:
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            run_chunks([Chunk("a", _chunk, (1,))], tmp_path / "a.chunks", n_workers=1)
    finally:
        holder.close()
    assert not [w for w in seen if "already in use" in str(w.message)], \
        [str(w.message) for w in seen]
    assert sorted(p.name for p in (tmp_path / "a.chunks").iterdir()) == ["a.npy",
                                                                          "a.npy.sha256"]


def test_orphans_of_a_killed_writer_are_removed_live_ones_kept(tmp_path):
    """A worker killed while writing a chunk's file (SIGKILL: no handler runs) leaves its
    temporary; the run removes it once every chunk is in place, where the writer named in
    it (pid@host) is a process of this host that is gone. A live writer's temporary (another
    run over the same folder), another host's, and files not of this run's chunks are kept."""
    import socket
    import subprocess
    import sys

    from skydome.distributed import _remove_orphans

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    dead_pid = int(dead.stdout)
    host = socket.gethostname()
    out = tmp_path / "run.chunks"
    out.mkdir()
    names = {
        "orphan": f".a.npy.sha256.{dead_pid}@{host}.k2j3h4.part",
        "orphan_npy": f".a.npy.{dead_pid}@{host}.x9y8z7.part",
        "live": f".a.npy.{os.getpid()}@{host}.q1w2e3.part",
        "other_host": f".a.npy.{dead_pid}@elsewhere.example.r4t5y6.part",
        "other_chunk": f".zz.npy.{dead_pid}@{host}.u7i8o9.part",
    }
    for n in names.values():
        (out / n).write_bytes(b"partial")
    rep = run_chunks([Chunk("a", _chunk, (1,))], out, n_workers=1)
    assert rep.computed == ["a"]
    left = sorted(p.name for p in out.iterdir())
    assert left == sorted(["a.npy", "a.npy.sha256", names["live"], names["other_host"],
                           names["other_chunk"]])
    assert _remove_orphans(out, ["a", "zz"]) == [names["other_chunk"]]
