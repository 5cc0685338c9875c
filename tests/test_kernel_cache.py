"""skydome's numba cache locators (``skydome._kernel_cache``): a cached kernel is compiled
again when a file it imports changes, not only when its own file does.

numba keys a cache entry on the kernel's own source file; a kernel compiled against an
``@njit`` function of another file keeps that function's old machine code after the other
file changes. The subprocess tests build a two-file package (a caller and its callee), let
numba cache the caller, change the callee, and read the caller's value in a new process:
numba's own locators serve the stale entry (the hazard, checked as the control), skydome's
compile the caller again. They compile three one-line functions, so they take seconds.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import skydome
from skydome import _kernel_cache

SRC = Path(skydome.__file__).parent

CALLEE = textwrap.dedent("""
    from numba import njit

    @njit(cache=True)
    def step(x):
        return x + 1.0
""")

CALLER = textwrap.dedent("""
    from numba import njit

    from pkgk.callee import step

    @njit(cache=True)
    def twice_step(x):
        return 2.0 * step(x)
""")

PROBE = textwrap.dedent("""
    import sys
    sys.path.insert(0, sys.argv[1])
    if sys.argv[2] == "skydome":
        from skydome import _kernel_cache
        _kernel_cache.register_package("pkgk", sys.argv[1] + "/pkgk")
    from pkgk.caller import twice_step
    value = twice_step(1.0)
    sig = twice_step.signatures[0]
    print(value, twice_step.stats.cache_hits.get(sig, 0),
          sum(twice_step.stats.cache_misses.values()))
""")


def _package(root: Path) -> None:
    pkg = root / "pkgk"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "callee.py").write_text(CALLEE)
    (pkg / "caller.py").write_text(CALLER)
    (pkg / "other.py").write_text("X = 1\n")


def _probe(root: Path, locators: str) -> tuple[float, int, int]:
    """(caller's value at 1, its cache hits, its compilations) in a new process."""
    env = dict(os.environ)
    for var in ("NUMBA_CACHE_DIR", "NUMBA_DISABLE_JIT", "NUMBA_CACHE_LOCATOR_CLASSES"):
        env.pop(var, None)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    r = subprocess.run([sys.executable, "-c", PROBE, str(root), locators], env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    value, hits, misses = r.stdout.split()
    return float(value), int(hits), int(misses)


def test_a_changed_callee_file_compiles_the_cached_caller_again(tmp_path):
    _package(tmp_path)
    assert _probe(tmp_path, "skydome") == (4.0, 0, 1)      # 2 (1 + 1): compiled, cached
    assert _probe(tmp_path, "skydome") == (4.0, 1, 0)      # loaded from the cache
    (tmp_path / "pkgk" / "other.py").write_text("X = 2\n")  # a file the caller does not import
    assert _probe(tmp_path, "skydome") == (4.0, 1, 0)      # still loaded
    (tmp_path / "pkgk" / "callee.py").write_text(CALLEE.replace("x + 1.0", "x + 2.0"))
    assert _probe(tmp_path, "skydome") == (6.0, 0, 1)      # 2 (1 + 2): compiled again
    assert _probe(tmp_path, "skydome") == (6.0, 1, 0)


def test_numba_alone_serves_the_stale_caller(tmp_path):
    """The control: the hazard the locators remove, on the installed numba."""
    _package(tmp_path)
    assert _probe(tmp_path, "numba") == (4.0, 0, 1)
    (tmp_path / "pkgk" / "callee.py").write_text(CALLEE.replace("x + 1.0", "x + 2.0"))
    value, hits, misses = _probe(tmp_path, "numba")
    if value == 6.0:
        pytest.skip("this numba keys a cached caller on its callees' files itself")
    assert (value, hits, misses) == (4.0, 1, 0)            # the old callee's code


def test_entries_stay_valid_where_the_package_is_moved(tmp_path):
    """As pip copies a wheel's files (with the entries its build compiled) to another folder
    with new modification times: the stamp names files by their path inside the package."""
    built = tmp_path / "build"
    _package(built)
    assert _probe(built, "skydome") == (4.0, 0, 1)
    installed = tmp_path / "site-packages"
    shutil.copytree(built, installed)
    for f in (installed / "pkgk").glob("*.py"):
        later = os.stat(f).st_mtime + 3600.0
        os.utime(f, (later, later))
    assert _probe(installed, "skydome") == (4.0, 1, 0)


def test_imports_read_from_the_source(tmp_path, monkeypatch):
    """Module-level imports only (absolute, relative, a parenthesised list with comments, a
    submodule by name), transitively; an indented import is not a kernel's global."""
    pkg = tmp_path / "pkgi"
    (pkg / "sub").mkdir(parents=True)
    for name in ("__init__.py", "sub/__init__.py", "a.py", "b.py", "c.py", "d.py", "e.py",
                 "sub/f.py", "sub/g.py"):
        (pkg / name).write_text("")
    (pkg / "a.py").write_text(textwrap.dedent("""
        import numpy as np
        from pkgi.b import x  # noqa: F401
        from .sub import (f,  # the submodule
                          g as gg)
        def later():
            from pkgi import e
    """))
    (pkg / "b.py").write_text("from . import c\nimport pkgi.sub.g\n")
    (pkg / "c.py").write_text("Y = 1\n")
    monkeypatch.setitem(_kernel_cache._PACKAGES, "pkgi", str(pkg))
    _kernel_cache._forget()
    rel = lambda files: sorted(os.path.relpath(f, pkg) for f in files)  # noqa: E731
    assert rel(_kernel_cache.imported_files(str(pkg / "a.py"))) == ["b.py", "sub/f.py",
                                                                      "sub/g.py"]
    assert rel(_kernel_cache._closure(str(pkg / "a.py"))) == ["b.py", "c.py", "sub/f.py",
                                                               "sub/g.py"]
    before = _kernel_cache.imports_digest(str(pkg / "a.py"))
    (pkg / "e.py").write_text("Z = 3\n")         # imported inside a function only
    _kernel_cache._forget()                      # (read once per process)
    assert _kernel_cache.imports_digest(str(pkg / "a.py")) == before
    (pkg / "c.py").write_text("Y = 2\n")         # imported by b, which a imports
    _kernel_cache._forget()
    assert _kernel_cache.imports_digest(str(pkg / "a.py")) != before
    _kernel_cache._forget()


def test_every_kernel_file_takes_njit_from_the_locators_module():
    """A kernel module that took ``njit`` from numba before ``skydome._kernel_cache`` is
    imported would get numba's own locators; every file with a kernel imports it."""
    kernel_files = []
    for path in SRC.rglob("*.py"):
        text = path.read_text()
        if re.search(r"^@njit", text, re.M):
            kernel_files.append(path.relative_to(SRC))
            assert re.search(r"^from skydome\._kernel_cache import njit", text, re.M), path
            assert not re.search(r"^from numba import .*\bnjit\b", text, re.M), path
    assert len(kernel_files) >= 25


def test_the_package_kernels_use_the_locators():
    from skydome.models.fitted import _kernels as fitted
    from skydome.transport import _geometry

    for kernel in (fitted.lookup_blocks, _geometry.safe_sqrt):
        locator = kernel._cache._impl.locator
        assert isinstance(locator, _kernel_cache._ImportsKeyed), type(locator)
    stamp = fitted.lookup_blocks._cache._impl.locator.get_source_stamp()
    assert stamp[1] == _kernel_cache.imports_digest(fitted.__file__)
    files = {os.path.relpath(f, SRC) for f in _kernel_cache._closure(fitted.__file__)}
    assert {"models/fitted/_grid.py", "_kernel_cache.py"} <= files
