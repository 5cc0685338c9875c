"""Numba's CPU target started without SciPy's BLAS probe (private), in the calling thread or
beside it.

Numba's target initialisation (the first kernel a process calls or loads from numba's cache)
imports ``numba.np.arraymath``, which probes for BLAS by importing
``scipy.linalg.cython_blas`` and with it all of ``scipy.linalg``: 0.25-0.30 s of CPU on a
2-core EPYC, a sixth of a warm ``skydome render`` (docs/performance.md). The probe decides
one thing only: whether ``np.correlate`` and ``np.convolve`` compile as BLAS calls or as
plain loops; skydome's kernels use neither. ``np.dot`` and ``np.linalg`` look SciPy's BLAS
up themselves when a kernel that uses them is compiled, and so keep working after this
start.

The start itself (``import numba`` and the target's registries, about 0.5 s of CPU, nearly
all of it Python holding the interpreter lock) can run on a second thread while the calling
thread does work that releases the lock: :func:`start_numba_in_background` (used by the
command line while a model reads its tables from the cache, which is file reads, CRC-32 and
NumPy decoding).
"""

from __future__ import annotations

import sys
import threading

_BLAS = "scipy.linalg.cython_blas"
_LINALG = "scipy.linalg"


class _NoBlasFor:
    """A meta-path finder that makes ``import scipy.linalg.cython_blas`` fail in one thread
    only (the one starting numba) where ``scipy.linalg`` is not imported yet, without
    importing ``scipy.linalg`` (the finder refuses the package as well, in that thread);
    another thread importing SciPy meanwhile is not affected. Finders are consulted only for
    modules not in ``sys.modules``."""

    def __init__(self, thread_id: int):
        self.thread_id = thread_id

    def find_spec(self, name, path=None, target=None):
        if name in (_LINALG, _BLAS) and threading.get_ident() == self.thread_id:
            raise ImportError(f"{name} is left out of numba's start")
        return None


def start_numba_without_blas() -> bool:
    """Initialise numba's CPU target without importing SciPy's BLAS bindings; True if it
    did.

    The bindings' import is made to fail in this thread during the initialisation only, so
    that numba records "no BLAS" for ``np.correlate`` and ``np.convolve`` (it then compiles
    them as plain loops) while ``np.dot`` and ``np.linalg`` still find SciPy when a kernel
    that uses them is compiled later. Does nothing if numba's target or SciPy's BLAS
    bindings are loaded already. Holds numba's compiler lock during the initialisation, so
    that a kernel called meanwhile from another thread waits for it."""
    if "numba.np.arraymath" in sys.modules or _BLAS in sys.modules:
        return False
    from numba.core.compiler_lock import global_compiler_lock
    from numba.core.registry import cpu_target

    finder = _NoBlasFor(threading.get_ident())
    with global_compiler_lock:
        if "numba.np.arraymath" in sys.modules or _BLAS in sys.modules:
            return False
        sys.meta_path.insert(0, finder)
        try:
            cpu_target.target_context.refresh()  # loads the registries: numba.np.arraymath
        finally:
            sys.meta_path.remove(finder)
    return True


class _Start:
    """A numba start running on its own thread; :meth:`join` waits for it."""

    def __init__(self):
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, name="skydome-numba-start",
                                       daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            start_numba_without_blas()
        except BaseException as exc:  # re-raised in the joining thread
            self.error = exc

    def join(self) -> None:
        """Wait for the start to finish; re-raises its error, if any."""
        self.thread.join()
        if self.error is not None:
            err, self.error = self.error, None
            raise err


def start_numba_in_background() -> _Start | None:
    """Start numba's CPU target (:func:`start_numba_without_blas`) on a daemon thread and
    return a handle whose ``join()`` waits for it; None where numba is started already.

    The caller may go on with work that releases the interpreter lock (file reads, NumPy)
    meanwhile; an ``import numba`` or a kernel call in the caller's thread waits for the
    start (Python's import lock, numba's compiler lock). Call ``join()`` before relying on
    numba's start being complete."""
    if "numba.np.arraymath" in sys.modules or _BLAS in sys.modules:
        return None
    return _Start()
