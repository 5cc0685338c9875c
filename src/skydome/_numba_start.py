"""Numba's CPU target started without SciPy's BLAS probe (private).

Numba's target initialisation (the first kernel a process calls or loads from numba's cache)
imports ``numba.np.arraymath``, which probes for BLAS by importing
``scipy.linalg.cython_blas`` and with it all of ``scipy.linalg``: 0.25-0.30 s of CPU on a
2-core EPYC, a sixth of a warm ``skydome render`` (docs/performance.md). The probe decides
one thing only: whether ``np.correlate`` and ``np.convolve`` compile as BLAS calls or as
plain loops; skydome's kernels use neither. ``np.dot`` and ``np.linalg`` look SciPy's BLAS
up themselves when a kernel that uses them is compiled, and so keep working after this
start.
"""

from __future__ import annotations

import sys

_BLAS = "scipy.linalg.cython_blas"


def start_numba_without_blas() -> bool:
    """Initialise numba's CPU target without importing SciPy's BLAS bindings; True if it
    did.

    The bindings' import is made to fail during the initialisation only (the module entry
    is set to None and removed again), so that numba records "no BLAS" for ``np.correlate``
    and ``np.convolve`` (it then compiles them as plain loops) while ``np.dot`` and
    ``np.linalg`` still find SciPy when a kernel that uses them is compiled later. Does
    nothing if numba's target or SciPy's BLAS bindings are loaded already."""
    if "numba.np.arraymath" in sys.modules or _BLAS in sys.modules:
        return False
    sys.modules[_BLAS] = None  # ``import`` of a None entry raises ImportError
    try:
        from numba.core.registry import cpu_target

        cpu_target.target_context.refresh()  # loads the registries: numba.np.arraymath
    finally:
        if sys.modules.get(_BLAS, 0) is None:
            del sys.modules[_BLAS]
    return True
