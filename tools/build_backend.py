"""skydome's build backend: setuptools', plus the packages that setup.py's kernel step needs
for wheel builds only.

A wheel build (``pip install .``) compiles the default render path's numba kernels into the
wheel (setup.py), so its isolated build environment needs numpy, scipy, numba and
threadpoolctl. An editable install (``pip install -e .``, the set-up's) skips that step, so
its build environment gets setuptools' requirements alone.
"""

from setuptools import build_meta as _setuptools
from setuptools.build_meta import *  # noqa: F401,F403  (the PEP 517 and 660 hooks)

#: what ``python -m skydome.apps.warmup --kernels`` imports
KERNEL_STEP_REQUIRES = ["numpy>=1.26", "scipy>=1.11", "numba>=0.59", "threadpoolctl>=3.1"]


def get_requires_for_build_wheel(config_settings=None):
    return _setuptools.get_requires_for_build_wheel(config_settings) + KERNEL_STEP_REQUIRES
