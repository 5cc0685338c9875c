"""The mechanism behind setup.py's build step (numba kernels compiled into the wheel).

setup.py runs ``python -m skydome.apps.warmup --kernels`` on the build folder so that the
kernels' numba cache (``__pycache__/*.nbi, *.nbc`` beside the sources) travels in the
wheel. That only pays if numba accepts those entries after pip has copied the files to
another folder with new modification times: numba must key an entry on the source's
content, not on its path or mtime. These tests check that property of the installed numba
on a one-function module (no skydome kernel is compiled, so they take seconds), and the
warm-up's command line.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap

MODULE = textwrap.dedent("""
    from numba import njit

    @njit(cache=True)
    def twice(x):
        return 2.0 * x
""")

PROBE = textwrap.dedent("""
    import sys
    sys.path.insert(0, sys.argv[1])
    import mod
    assert mod.twice(1.5) == 3.0
    print(mod.twice.stats.cache_hits.get(mod.twice.signatures[0], 0),
          sum(mod.twice.stats.cache_misses.values()))
""")


def _probe(folder) -> tuple[int, int]:
    env = dict(os.environ)
    for var in ("NUMBA_CACHE_DIR", "NUMBA_DISABLE_JIT", "NUMBA_CACHE_LOCATOR_CLASSES"):
        env.pop(var, None)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    r = subprocess.run([sys.executable, "-c", PROBE, str(folder)], env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    hits, misses = (int(v) for v in r.stdout.split())
    return hits, misses


def test_in_tree_cache_survives_a_move_and_new_mtimes(tmp_path):
    built = tmp_path / "build" / "lib"
    built.mkdir(parents=True)
    (built / "mod.py").write_text(MODULE)
    assert _probe(built) == (0, 1)               # compiled and written to __pycache__
    assert list((built / "__pycache__").glob("mod.twice-*.nbi"))
    installed = tmp_path / "venv" / "site-packages"
    shutil.copytree(built, installed)            # as pip copies a wheel's files
    later = os.stat(installed / "mod.py").st_mtime + 3600.0
    os.utime(installed / "mod.py", (later, later))
    assert _probe(installed) == (1, 0)           # loaded, not compiled


def test_changed_source_is_not_served_a_stale_entry(tmp_path):
    (tmp_path / "mod.py").write_text(MODULE)
    assert _probe(tmp_path) == (0, 1)
    (tmp_path / "mod.py").write_text(MODULE.replace("2.0 * x", "2.0 * x + 0.0"))
    assert _probe(tmp_path) == (0, 1)            # recompiled


def test_warmup_rejects_unknown_arguments():
    r = subprocess.run([sys.executable, "-m", "skydome.apps.warmup", "--kernel"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode != 0
    assert "usage: python -m skydome.apps.warmup [--kernels]" in r.stderr
