"""numba's compilations timed into a file, for the test suite's compile share (diagnostic).

With ``SKYDOME_COMPILE_LOG`` set to a file, every process that imports skydome appends one
line per compilation to it: its process id and the compilation's seconds. numba announces
each compilation as a ``numba:compile`` event (:mod:`numba.core.event`); only the
outermost per thread is timed, since a kernel's compilation contains those of the functions
it calls. The suite's ``tests/conftest.py`` sets the variable, so that the compilations in
the command-line tests' subprocesses are counted beside the test process's own.

numba is not imported for this: where it is not loaded yet, an audit hook watches the
imports and registers the listener once ``numba.core.event`` is loaded (numba compiles
nothing before then). Lines are written with one ``write`` in append mode, so that
concurrent processes do not mix them.
"""

from __future__ import annotations

import os
import sys
import threading
import time

_installed: set[str] = set()


class _Clock:
    def __init__(self, path: str):
        self.path = path
        self.local = threading.local()

    def on_start(self) -> None:
        depth = getattr(self.local, "depth", 0)
        if depth == 0:
            self.local.t0 = time.perf_counter()
        self.local.depth = depth + 1

    def on_end(self) -> None:
        self.local.depth -= 1
        if self.local.depth == 0:
            seconds = time.perf_counter() - self.local.t0
            try:
                fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
                try:
                    os.write(fd, f"{os.getpid()} {seconds:.6f}\n".encode())
                finally:
                    os.close(fd)
            except OSError:
                pass


def _register(clock: _Clock) -> None:
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev):
            clock.on_start()

        def on_end(self, ev):
            clock.on_end()

    event.register("numba:compile", _Listener())


def install(path: str) -> None:
    """Log this process's numba compilations to ``path`` (once per path and process)."""
    if not path or path in _installed:
        return
    _installed.add(path)
    clock = _Clock(path)
    loaded = sys.modules.get("numba.core.event")
    if loaded is not None and hasattr(loaded, "register"):
        _register(clock)
        return
    pending = [clock]

    def _watch(name, args):
        if not pending or name != "import":
            return
        ev = sys.modules.get("numba.core.event")
        if ev is not None and hasattr(ev, "register"):
            _register(pending.pop())

    sys.addaudithook(_watch)


def read(path: str) -> dict[int, tuple[int, float]]:
    """{process id: (compilations, seconds)} from a log file."""
    out: dict[int, tuple[int, float]] = {}
    try:
        lines = open(path).read().splitlines()
    except OSError:
        return out
    for line in lines:
        try:
            pid, seconds = line.split()
            n, s = out.get(int(pid), (0, 0.0))
            out[int(pid)] = (n + 1, s + float(seconds))
        except ValueError:
            continue
    return out
