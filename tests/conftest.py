"""Test-wide fixtures."""

import pytest


@pytest.fixture(scope="session")
def _session_cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("skydome-cache")


@pytest.fixture(autouse=True)
def _private_cache_dir(_session_cache_dir, tmp_path_factory, request, monkeypatch):
    """Point the precomputed model's table cache at a temporary folder, so that tests never
    write into the user's cache folder. The folder is shared by the session (tables at the
    default settings are built once), except for the tests of the cache itself, which get
    one folder each (no such test sees another's tables)."""
    if request.module.__name__.endswith("test_precomputed_cache"):
        folder = tmp_path_factory.mktemp("skydome-cache-own")
    else:
        folder = _session_cache_dir
    monkeypatch.setenv("SKYDOME_CACHE_DIR", str(folder))
    monkeypatch.delenv("SKYDOME_CACHE_LIMIT_BYTES", raising=False)


# -- the suite's compile share (issue 27, item 5) ------------------------------------------
# numba announces each compilation as a "numba:compile" event (numba.core.event); the clock
# below sums the outermost ones per thread (a kernel's nested compilations of its callees
# are inside its own), so that the summary can say how much of the session's wall time went
# into compiling in this process. Compilations in subprocesses (the CLI tests) are not seen.
import threading  # noqa: E402
import time  # noqa: E402


class _CompileClock:
    def __init__(self):
        self.local = threading.local()
        self.lock = threading.Lock()
        self.seconds = 0.0
        self.count = 0
        self.session_start = time.perf_counter()

    def on_start(self, event):
        depth = getattr(self.local, "depth", 0)
        if depth == 0:
            self.local.t0 = time.perf_counter()
        self.local.depth = depth + 1

    def on_end(self, event):
        self.local.depth -= 1
        if self.local.depth == 0:
            with self.lock:
                self.seconds += time.perf_counter() - self.local.t0
                self.count += 1


_CLOCK = _CompileClock()


def pytest_sessionstart(session):
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev):
            _CLOCK.on_start(ev)

        def on_end(self, ev):
            _CLOCK.on_end(ev)

    event.register("numba:compile", _Listener())
    _CLOCK.session_start = time.perf_counter()


def pytest_terminal_summary(terminalreporter):
    wall = time.perf_counter() - _CLOCK.session_start
    share = 100.0 * _CLOCK.seconds / wall if wall > 0 else 0.0
    terminalreporter.write_line(
        f"numba compilation in the test process: {_CLOCK.seconds:.1f} s in "
        f"{_CLOCK.count} compilations, {share:.0f} % of the session's {wall:.1f} s wall "
        "(compilations in subprocesses not counted)")
