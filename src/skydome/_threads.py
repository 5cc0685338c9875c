"""Serial numba kernels run over ranges of their items on a pool of Python threads.

A kernel compiled with ``parallel=True`` (a ``prange`` loop) costs numba's parfor passes and
the threading layer's outlining on its first compilation: the ``fitted`` lookup compiled in
5.8-11.6 s that way on a 2-core AMD EPYC (Zen 3), and in 1.8-3.8 s as a serial kernel; the
display kernels 1.8-1.9 s each against 0.6-0.8 s (docs/performance.md, "Kernels on Python
threads"). Where such a compilation lands on a user's first command (a first use without
numba's cache: another CPU than the wheel's, an editable install before the set-up's
warm-up), the kernel is instead compiled serial with ``nogil=True``, taking the first and
the end of its range of items as its last two arguments, and :func:`run_ranges` runs it
on several threads at once.

The thread count is numba's (``NUMBA_NUM_THREADS``, ``numba.set_num_threads``), as for the
``prange`` kernels. The items are dealt out in :data:`TASKS_PER_THREAD` runs per thread,
taken by whichever thread is free, so that a thread slowed down by the machine's load takes
fewer; each run is the kernel's own contiguous loop, so the values do not depend on the
thread count.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor

#: Runs per thread of a threaded call.
TASKS_PER_THREAD = 8

_pool: ThreadPoolExecutor | None = None
_pool_key = (0, 0)                # (threads, process id) of _pool
_pool_lock = threading.Lock()
_local = threading.local()        # .in_pool: True in the pool's own threads


def _mark_pool_thread() -> None:
    _local.in_pool = True


def thread_count() -> int:
    """numba's thread count (at least 1)."""
    import numba

    return max(1, int(numba.get_num_threads()))


def _executor(n_threads: int) -> ThreadPoolExecutor:
    """The module's pool of ``n_threads`` threads: made on first use, made anew when
    numba's thread count changes, and in a forked child (whose copy of the parent's pool
    has no threads: it would wait for them forever)."""
    global _pool, _pool_key
    key = (n_threads, os.getpid())
    with _pool_lock:
        if _pool is None or _pool_key != key:
            if _pool is not None and _pool_key[1] == key[1]:
                _pool.shutdown(wait=False)
            _pool = ThreadPoolExecutor(max_workers=n_threads, thread_name_prefix="skydome",
                                       initializer=_mark_pool_thread)
            _pool_key = key
        return _pool


def run_ranges(kernel, n: int, args: tuple, min_per_thread: int) -> list:
    """``kernel(*args, start, stop)`` over the items 0 .. n - 1, split into contiguous
    ranges run on numba's thread count of threads; the list of the ranges' return values,
    in the ranges' order.

    ``kernel`` must release the interpreter lock (``nogil=True``) for the threads to run at
    once. Fewer than ``min_per_thread`` items per thread (a task's hand-over to the pool
    costs some tens of microseconds) and the call runs on the calling thread alone, in one
    range; so does a call made from one of the pool's own threads (a range whose kernel
    called ``run_ranges`` again would otherwise wait for threads busy waiting for it)."""
    n = int(n)
    n_threads = min(thread_count(), n // max(int(min_per_thread), 1))
    if n_threads <= 1 or getattr(_local, "in_pool", False):
        return [kernel(*args, 0, n)]
    n_tasks = min(n, TASKS_PER_THREAD * n_threads)
    edges = [k * n // n_tasks for k in range(n_tasks + 1)]
    pool = _executor(n_threads)
    futures = [pool.submit(kernel, *args, edges[k], edges[k + 1]) for k in range(n_tasks)]
    return [f.result() for f in futures]
