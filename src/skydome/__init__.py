"""skydome: physically based daylight modelling.

Every model answers one question: the spectral radiance (or, for luminance-only models,
the luminance) arriving at an observer from a set of directions. Directions are unit
vectors in the East-North-Up frame (x east, y north, z up); wavelengths are in nm;
spectral radiance is in W m^-2 sr^-1 nm^-1 and luminance in cd m^-2.

The package imports lazily: heavy dependencies (numba kernels, pvlib, matplotlib) load
only when the feature that needs them is used.

Examples
--------
>>> import skydome as sd
>>> sky = sd.model("single_scattering", sun=sd.Sun(elevation_deg=30, azimuth_deg=135))
>>> image = sd.render(sky, sd.Fisheye(256))
"""

from __future__ import annotations

import importlib
import os

__version__ = "0.1.0"

if os.environ.get("SKYDOME_COMPILE_LOG"):
    # numba's compilations timed into that file (the test suite's compile share)
    from skydome._compile_log import install as _install_compile_log

    _install_compile_log(os.environ["SKYDOME_COMPILE_LOG"])

# public name -> module that defines it (imported on first access)
_LAZY = {
    "Sun": "skydome.sun",
    "Atmosphere": "skydome.atmosphere",
    "model": "skydome.models",
    "available_models": "skydome.models",
    "SkyModel": "skydome.models",
    "render": "skydome.imaging",
    "SkyImage": "skydome.imaging.image",
    "Equirect": "skydome.imaging.projections",
    "Fisheye": "skydome.imaging.projections",
    "AngularMap": "skydome.imaging.projections",
    "wavelength_grid": "skydome.spectra",
    "direction_from_angles": "skydome.transport.geometry",
}

__all__ = sorted(_LAZY) + ["__version__"]


_SUBMODULES = {"models", "spectra", "atmosphere", "transport", "imaging", "sun", "effects", "data",
               "illuminance"}


def __getattr__(name: str):
    if name in _SUBMODULES:
        return importlib.import_module(f"skydome.{name}")
    if name == "available_models":
        from skydome.models import available

        return available
    try:
        module = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'skydome' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return __all__
