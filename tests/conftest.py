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
# Every process that imports skydome with SKYDOME_COMPILE_LOG set appends one line per numba
# compilation to that file (skydome._compile_log: the outermost "numba:compile" event per
# thread, since a kernel's compilation contains its callees'). The test process sets it
# before any test imports skydome, so that the subprocesses it starts (the command-line
# tests) inherit it and their compilations are counted too; the summary at the end of a run
# gives both and their share of the session's wall time. Subprocesses started with an
# environment of their own (without the variable) are not counted.
import os  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

_fd, _COMPILE_LOG = tempfile.mkstemp(prefix="skydome-compile-", suffix=".log")
os.close(_fd)
_OUTER_COMPILE_LOG = os.environ.get("SKYDOME_COMPILE_LOG")
os.environ["SKYDOME_COMPILE_LOG"] = _COMPILE_LOG
_SESSION_START = [time.perf_counter()]


def pytest_sessionstart(session):
    from skydome._compile_log import install

    install(_COMPILE_LOG)   # where skydome was imported before the variable was set
    _SESSION_START[0] = time.perf_counter()


def pytest_terminal_summary(terminalreporter):
    from skydome._compile_log import read

    wall = time.perf_counter() - _SESSION_START[0]
    per_process = read(_COMPILE_LOG)
    own_n, own_s = per_process.pop(os.getpid(), (0, 0.0))
    sub_n = sum(n for n, _ in per_process.values())
    sub_s = sum(s for _, s in per_process.values())

    def share(seconds):
        return 100.0 * seconds / wall if wall > 0 else 0.0

    terminalreporter.write_line(
        f"numba compilation: {own_s:.1f} s in the test process ({own_n} compilations, "
        f"{share(own_s):.0f} % of the session's {wall:.1f} s wall), {sub_s:.1f} s in "
        f"{len(per_process)} subprocesses ({sub_n} compilations); together "
        f"{share(own_s + sub_s):.0f} %")


def pytest_unconfigure(config):
    try:
        os.remove(_COMPILE_LOG)
    except OSError:
        pass
    if _OUTER_COMPILE_LOG is None:
        os.environ.pop("SKYDOME_COMPILE_LOG", None)
    else:
        os.environ["SKYDOME_COMPILE_LOG"] = _OUTER_COMPILE_LOG
