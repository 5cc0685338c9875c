"""skydome._threads.run_ranges: every item in exactly one range, the ranges' results in
order, the thread count numba's, and the calling thread alone for small calls. The
reference is plain arithmetic on the item indices (a kernel that writes each index
and the range it came in)."""

from __future__ import annotations

import threading

import numba
import numpy as np
import pytest
from numba import njit

from skydome import _threads


@njit(nogil=True)
def _mark(seen, owner, tag, i0, i1):
    """seen[i] += 1 and owner[i] = tag for i in i0 .. i1 - 1; the range's item count."""
    for i in range(i0, i1):
        seen[i] += 1
        owner[i] = tag
    return i1 - i0


@pytest.mark.parametrize("n", [0, 1, 7, 1000, 4097, 100_003])
@pytest.mark.parametrize("min_per_thread", [1, 64, 10**9])
def test_every_item_once(n, min_per_thread):
    seen = np.zeros(n, dtype=np.int64)
    owner = np.full(n, -1, dtype=np.int64)
    counts = _threads.run_ranges(_mark, n, (seen, owner, 0), min_per_thread)
    assert sum(counts) == n
    assert np.all(seen == 1)
    n_threads = min(_threads.thread_count(), n // min_per_thread)
    if n_threads <= 1:
        assert counts == [n]
    else:
        assert len(counts) == min(n, _threads.TASKS_PER_THREAD * n_threads)
        assert max(counts) - min(counts) <= 1          # even contiguous ranges


def test_ranges_are_contiguous_and_in_order():
    """Each range's kernel call sees its own (start, stop): the owner tags written with the
    call's start are non-decreasing along the items."""

    @njit(nogil=True)
    def tag_start(owner, i0, i1):
        for i in range(i0, i1):
            owner[i] = i0
        return i0

    n = 50_000
    owner = np.full(n, -1, dtype=np.int64)
    starts = _threads.run_ranges(tag_start, n, (owner,), 16)
    assert starts == sorted(starts) and starts[0] == 0
    assert np.all(np.diff(owner) >= 0)
    assert set(np.unique(owner)) == set(starts)


def test_thread_count_follows_numba():
    """numba.set_num_threads(1) runs everything in one range on the calling thread."""
    n0 = numba.get_num_threads()
    caller = threading.get_ident()
    idents = []

    def record(i0, i1):
        idents.append(threading.get_ident())
        return i1 - i0

    try:
        numba.set_num_threads(1)
        assert _threads.run_ranges(record, 10_000, (), 1) == [10_000]
        assert idents == [caller]
    finally:
        numba.set_num_threads(n0)
    if n0 > 1:
        idents.clear()
        out = _threads.run_ranges(record, 10_000, (), 1)
        assert sum(out) == 10_000 and caller not in idents


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="no fork here")
def test_forked_child_gets_a_pool_of_its_own():
    """A child forked after the parent's pool started runs its ranges (the parent's pool
    threads do not exist there): checked in the child, reported through its exit status."""
    import os

    if _threads.thread_count() < 2:
        pytest.skip("one numba thread: no pool")
    seen = np.zeros(10_000, dtype=np.int64)
    _threads.run_ranges(_mark, seen.size, (seen, np.zeros_like(seen), 0), 1)   # the pool
    pid = os.fork()
    if pid == 0:                                                     # the child
        ok = False
        try:
            import signal

            signal.alarm(60)        # a child waiting for threads that are not there dies
            s = np.zeros(10_000, dtype=np.int64)
            _threads.run_ranges(_mark, s.size, (s, np.zeros_like(s), 0), 1)
            ok = bool(np.all(s == 1))
        finally:
            os._exit(0 if ok else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0


def test_a_range_calling_run_ranges_again_runs_it_inline():
    """A kernel (here a Python function) that calls run_ranges from a pool thread gets one
    inline range there instead of waiting for the pool's threads, which are all busy
    running such ranges: every outer range completes and each inner call sees its items."""
    if _threads.thread_count() < 2:
        pytest.skip("one numba thread: no pool")

    def outer(i0, i1):
        inner = _threads.run_ranges(lambda a, b: b - a, 1000, (), 1)
        return (i1 - i0, inner)

    res = {}
    t = threading.Thread(target=lambda: res.update(out=_threads.run_ranges(outer, 64, (), 1)),
                         daemon=True)
    t.start()
    t.join(60.0)
    assert not t.is_alive(), "the nested run_ranges call waits for the pool's busy threads"
    out = res["out"]
    assert sum(k for k, _ in out) == 64
    assert all(inner == [1000] for _, inner in out)
