"""Validation of skydome's models against measured skies.

* :mod:`.kider2014`: the Kider et al. 2014 spectral sky scans of 2013-05-27 (Cornell).
* :mod:`.aeronet`: AERONET almucantar inversions and the aerosol optics they give.
* :mod:`.compare`: :func:`compare_measured`, the errors of each model against the scans.
* :mod:`.scanner_polarisation`: the test of whether the scanner's response to polarised
  light explains the angular error (docs/validation_measured.md).

Imports are lazy: ``import skydome.validation`` loads nothing heavy.
"""

from __future__ import annotations

import importlib

_LAZY = {
    "load_captures": "skydome.validation.kider2014",
    "fit_conventions": "skydome.validation.kider2014",
    "read_pfn": "skydome.validation.aeronet",
    "aerosol_atmosphere": "skydome.validation.aeronet",
    "compare_measured": "skydome.validation.compare",
}

__all__ = sorted(_LAZY)


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'skydome.validation' has no attribute {name!r}")
