"""Build step: the default render path's numba kernels compiled into the wheel.

Everything else about the package is in pyproject.toml. After the sources are copied into
the build folder, ``python -m skydome.apps.warmup --kernels`` runs on that copy with numba's
cache in the package's own ``__pycache__`` folders (numba's in-tree cache), so the wheel
carries the compiled precomputation, render and display kernels. numba 0.68 and later
(numba pull request 10659; 0.67 and earlier used the file's modification time and size) key
a cache entry on the source file's content (a SHA-256 of it), the numba and Python versions
and the CPU (name and features), so the entries stay valid wherever pip puts the files and
whatever modification times it gives them; on another CPU, numba version or Python they are
ignored and the kernels compile on first use as before (tests/test_kernel_build_cache.py
checks the installed numba).

``SKYDOME_BUILD_KERNELS=0`` skips the step. It is skipped, with one line, when the build
environment cannot import skydome's dependencies; editable installs (``pip install -e``)
never run it (their kernels are cached beside the sources on first use, or by the set-up's
warm-up).
"""

import os
import subprocess
import sys
import tempfile

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithKernels(build_py):
    """``build_py`` followed by the kernels' compilation into the build folder."""

    def run(self):
        super().run()
        if getattr(self, "editable_mode", False) or self.dry_run:
            return
        if os.environ.get("SKYDOME_BUILD_KERNELS", "1") == "0":
            print("skydome: SKYDOME_BUILD_KERNELS=0, numba kernels not compiled into the build")
            return
        lib = os.path.abspath(self.build_lib)
        env = dict(os.environ)
        for var in ("NUMBA_CACHE_DIR", "NUMBA_DISABLE_JIT", "NUMBA_CACHE_LOCATOR_CLASSES"):
            env.pop(var, None)
        env["PYTHONPATH"] = os.pathsep.join([lib] + [p for p in [env.get("PYTHONPATH")] if p])
        env["PYTHONDONTWRITEBYTECODE"] = "1"
        with tempfile.TemporaryDirectory(prefix="skydome-build-") as tables:
            env["SKYDOME_CACHE_DIR"] = tables    # the user's table cache stays untouched
            r = subprocess.run([sys.executable, "-m", "skydome.apps.warmup", "--kernels"],
                               env=env, cwd=tables, capture_output=True, text=True)
        if r.returncode != 0:
            last = (r.stderr.strip().splitlines() or ["(no output)"])[-1]
            print(f"skydome: numba kernels not compiled into the build ({last}); they "
                  "compile on first use")
            _remove_kernel_caches(lib)
        else:
            print("skydome: " + r.stdout.strip().splitlines()[-1])


def _remove_kernel_caches(lib):
    """Remove partial numba cache files from the build folder."""
    for folder, _, files in os.walk(lib):
        for f in files:
            if f.endswith((".nbi", ".nbc")):
                os.remove(os.path.join(folder, f))


setup(cmdclass={"build_py": BuildPyWithKernels})
