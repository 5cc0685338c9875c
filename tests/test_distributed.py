"""Dask scale-out: a LocalCluster with 2 workers, one killed mid-run; resumable chunks."""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest

from skydome.daylighting.weather import read_weather, sample_weather_path

pytest.importorskip("distributed")

KW = dict(patches="reinhart:4", order=4)


@pytest.fixture(scope="module")
def days():
    from _daylighting import TEST_DAYS

    w = read_weather(sample_weather_path())
    return w.select(np.isin(w.day_of_year, TEST_DAYS))


def _check_same_as_serial(days, chunks, got):
    """The same as computing the same chunks one after the other in this process (bit for
    bit on some CPUs; to 1e-15 relative where the vectorised loops' rounding follows the
    arrays' alignment in memory, measured 5.2e-16), and the same as one unchunked call to
    round-off (numpy's vectorised exp/log can differ in the last bit between array
    slices)."""
    from skydome.daylighting.skymatrix import perez_sky_matrix_from_weather

    serial = np.concatenate([c.func(*c.args) for c in chunks])
    np.testing.assert_allclose(got, serial, rtol=4e-15, atol=1e-300)
    np.testing.assert_allclose(got, perez_sky_matrix_from_weather(days, **KW).sky, rtol=1e-13,
                               atol=1e-12)


@pytest.mark.slow
def test_worker_killed_mid_run_result_complete_and_identical(days, tmp_path):
    from distributed import Client, LocalCluster

    from skydome.daylighting.skymatrix_chunks import sky_matrix_chunks
    from skydome.distributed import assemble_chunks, run_chunks

    chunks = sky_matrix_chunks(days, chunk_hours=6, **KW)
    assert len(chunks) == 16
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    client = Client(cluster)
    try:
        pids = list(client.run(os.getpid).values())
        assert len(pids) == 2
        result = {}
        th = threading.Thread(target=lambda: result.update(
            rep=run_chunks(chunks, tmp_path, client=client)))
        th.start()
        t0 = time.time()
        while not list(tmp_path.glob("*.npy")) and time.time() - t0 < 120:
            time.sleep(0.05)
        done_at_kill = len(list(tmp_path.glob("*.npy")))
        os.kill(pids[0], signal.SIGKILL)
        th.join(timeout=300)
        assert not th.is_alive()
    finally:
        client.close()
        cluster.close()
    assert 1 <= done_at_kill < len(chunks)
    rep = result["rep"]
    keys = [c.key for c in chunks]
    assert sorted(rep.hashes) == sorted(keys) and sorted(rep.computed) == sorted(keys)
    files = sorted(p.name for p in tmp_path.iterdir())
    assert files == sorted([f"{k}.npy" for k in keys] + [f"{k}.npy.sha256" for k in keys])
    _check_same_as_serial(days, chunks, assemble_chunks(tmp_path, keys))


@pytest.mark.slow
def test_interrupted_run_resumes_without_recomputing(days, tmp_path):
    from distributed import Client, LocalCluster

    from skydome.daylighting.skymatrix_chunks import sky_matrix_chunks
    from skydome.distributed import assemble_chunks, run_chunks

    chunks = sky_matrix_chunks(days, chunk_hours=24, **KW)
    keys = [c.key for c in chunks]
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    client = Client(cluster)
    try:
        first = run_chunks(chunks[:2], tmp_path, client=client)  # "interrupted" after 2
        assert sorted(first.computed) == sorted(keys[:2])
        stamp = {k: (tmp_path / f"{k}.npy").stat().st_mtime_ns for k in keys[:2]}
        # corrupt nothing: the rerun verifies the two and computes only the rest
        second = run_chunks(chunks, tmp_path, client=client)
        assert sorted(second.verified) == sorted(keys[:2])
        assert sorted(second.computed) == sorted(keys[2:])
        assert {k: (tmp_path / f"{k}.npy").stat().st_mtime_ns for k in keys[:2]} == stamp
        # a damaged chunk fails its hash and is recomputed
        p = tmp_path / f"{keys[1]}.npy"
        p.write_bytes(p.read_bytes()[:-8] + b"\xff" * 8)
        third = run_chunks(chunks, tmp_path, client=client)
        assert third.repaired == [keys[1]] and third.computed == [keys[1]]
    finally:
        client.close()
        cluster.close()
    _check_same_as_serial(days, chunks, assemble_chunks(tmp_path, keys))


@pytest.mark.slow
def test_cli_skymatrix_on_local_dask_cluster_equals_in_process(tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app
    from skydome.daylighting.radiance_io import read_matrix

    lines = sample_weather_path().read_text().splitlines(keepends=True)
    w = tmp_path / "d.csv"
    w.write_text("".join(lines[:2 + 48]))
    base = ["skymatrix", "--weather", str(w), "--patches", "reinhart:2", "--format", "double"]
    r1 = CliRunner().invoke(app, base + ["--out", str(tmp_path / "a.mtx")])
    r2 = CliRunner().invoke(app, base + ["--out", str(tmp_path / "b.mtx"), "--workers", "2",
                                         "--chunk-hours", "12"])
    assert r1.exit_code == 0 and r2.exit_code == 0, r2.output
    a, _ = read_matrix(tmp_path / "a.mtx")
    b, _ = read_matrix(tmp_path / "b.mtx")
    np.testing.assert_allclose(b, a, rtol=1e-13, atol=1e-12)
    assert not (tmp_path / "b.mtx.chunks").exists()


@pytest.mark.slow
def test_cli_separate_sun_on_scheduler_equals_in_process(tmp_path):
    """--sun separate through --scheduler (a LocalCluster's address): the sky, sun and sun
    scene files equal those of the in-process run; resumed chunks are reused."""
    from _dask import run_both

    from skydome.daylighting.radiance_io import read_matrix

    lines = sample_weather_path().read_text().splitlines(keepends=True)
    w = tmp_path / "d.csv"
    w.write_text("".join(lines[:2 + 48]))
    out = run_both(["skymatrix", "--weather", w, "--patches", "reinhart:2", "--format",
                    "double", "--sun", "separate", "--chunk-hours", "12"],
                   tmp_path / "a.mtx", tmp_path / "b.mtx")
    assert "4 computed, 0 reused" in out
    for suffix in (".mtx", ".sun.mtx"):
        a, _ = read_matrix(tmp_path / f"a{suffix}")
        b, _ = read_matrix(tmp_path / f"b{suffix}")
        assert a.shape == b.shape
        np.testing.assert_allclose(b, a, rtol=1e-13, atol=1e-12)
    assert (tmp_path / "a.suns.rad").read_text() == (tmp_path / "b.suns.rad").read_text()
    assert not (tmp_path / "b.mtx.chunks").exists()


def test_chunk_bit_identical_with_read_only_arguments(days):
    """Workers get their arguments as read-only arrays (dask's zero-copy deserialisation);
    a chunk computed from them equals the serial chunk bit for bit (numba would otherwise
    run a second specialisation of the kernels, 1 ulp apart)."""
    from skydome.daylighting.skymatrix_chunks import sky_matrix_chunks

    chunks = sky_matrix_chunks(days, chunk_hours=24, **KW)[:2]

    def read_only(a):
        if not isinstance(a, np.ndarray):
            return a
        b = a.copy()
        b.flags.writeable = False
        return b

    for c in chunks:
        np.testing.assert_array_equal(c.func(*[read_only(a) for a in c.args]), c.func(*c.args))


def test_local_cluster_divides_the_cores_among_its_workers(tmp_path, monkeypatch):
    """A local cluster's worker processes run numba's parallel kernels on their share of the
    cores (the cores // workers, at least 1), not each on every core; a thread count the
    caller set is left to the workers as it is."""
    from skydome.distributed import Chunk, run_chunks, worker_environment

    def threads(_):
        import os

        import numba

        return np.array([numba.get_num_threads(),
                         int(os.environ.get("NUMBA_NUM_THREADS", "0"))])

    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    cores = len(os.sched_getaffinity(0))
    want = max(1, cores // 2)
    assert worker_environment(2) == {"NUMBA_NUM_THREADS": str(want)}
    assert worker_environment(4 * cores) == {"NUMBA_NUM_THREADS": "1"}
    run_chunks([Chunk(f"c{i}", threads, (i,)) for i in range(2)], tmp_path / "a", n_workers=2)
    for i in range(2):
        np.testing.assert_array_equal(np.load(tmp_path / "a" / f"c{i}.npy"), [want, want])
    monkeypatch.setenv("NUMBA_NUM_THREADS", "1")
    assert worker_environment(2) == {}
