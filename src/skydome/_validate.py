"""Input validation shared by every public entry point.

Every check raises before any work starts, with a message that names the parameter,
the value it was given and the valid range, e.g.
``turbidity = -1 is out of range [1, 64]``.
"""

from __future__ import annotations

import math
import weakref
from typing import Any

import numpy as np


def _fmt(x: Any) -> str:
    if isinstance(x, float):
        return f"{x:g}"
    return str(x)


def check_number(name: str, value: Any, low: float | None = None, high: float | None = None,
                 unit: str = "", *, low_open: bool = False, high_open: bool = False) -> float:
    """Return ``value`` as a float, or raise ValueError/TypeError naming ``name``.

    ``low``/``high`` are inclusive bounds unless ``low_open``/``high_open`` is set; None
    means unbounded on that side.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a number, got {value!r} ({type(value).__name__})")
    v = float(value)
    u = f" {unit}" if unit else ""
    if not math.isfinite(v):
        raise ValueError(f"{name} = {_fmt(v)} is not a finite number")
    bad_low = low is not None and (v <= low if low_open else v < low)
    bad_high = high is not None and (v >= high if high_open else v > high)
    if bad_low or bad_high:
        lo = "(" if low_open else "["
        hi = ")" if high_open else "]"
        lo_s = "-inf" if low is None else _fmt(float(low))
        hi_s = "inf" if high is None else _fmt(float(high))
        raise ValueError(f"{name} = {_fmt(v)}{u} is out of range {lo}{lo_s}, {hi_s}{hi}{u}")
    return v


def check_int(name: str, value: Any, low: int | None = None, high: int | None = None) -> int:
    """Return ``value`` as an int within [low, high], or raise naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, got {value!r}")
    v = int(value)
    if (low is not None and v < low) or (high is not None and v > high):
        lo_s = "-inf" if low is None else str(low)
        hi_s = "inf" if high is None else str(high)
        raise ValueError(f"{name} = {v} is out of range [{lo_s}, {hi_s}]")
    return v


def check_choice(name: str, value: Any, choices) -> Any:
    """Return ``value`` if it is one of ``choices``, else raise naming them all."""
    choices = tuple(choices)
    if value not in choices:
        raise ValueError(f"{name} = {value!r} is not one of {', '.join(map(repr, choices))}")
    return value


def check_real(name: str, value: Any) -> None:
    """TypeError naming ``name`` unless ``value`` is real numeric data (not complex, not
    strings or objects). Cheap for float arrays: only the dtype is looked at."""
    if isinstance(value, np.ndarray) and value.dtype.kind == "f":
        return
    raw = np.asarray(value)
    if np.iscomplexobj(raw):
        raise TypeError(f"{name} must be real, got complex values")
    if raw.dtype.kind not in "biuf":
        try:
            raw.astype(np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be an array of numbers, got dtype {raw.dtype}") from None


def as_directions(directions: Any, name: str = "directions") -> np.ndarray:
    """Validate an array of direction vectors of shape (..., 3) and normalise them.

    Raises TypeError for complex or non-numeric input, ValueError for a wrong last axis,
    NaN or infinite entries or zero-length vectors.
    """
    raw = np.asarray(directions)
    if np.iscomplexobj(raw):
        raise TypeError(f"{name} must be real unit vectors (..., 3), got complex values")
    if raw.dtype.kind not in "biuf":
        try:
            raw = raw.astype(np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be an array of numbers of shape (..., 3), "
                            f"got dtype {raw.dtype}") from None
    d = np.asarray(raw, dtype=np.float64)
    if d.ndim == 0 or d.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got {d.shape}")
    if not np.all(np.isfinite(d)):
        raise ValueError(f"{name} contains NaN or infinite values")
    norm = np.linalg.norm(d, axis=-1, keepdims=True)
    if np.any(norm == 0.0):
        raise ValueError(f"{name} contains zero-length vectors")
    return d / norm


#: Wavelength arrays returned by :func:`as_wavelengths`, by id: (weak reference, min, max).
#: They are read-only copies, so a live entry still describes the array's contents.
_CHECKED_WAVELENGTHS: dict[int, tuple[Any, float, float]] = {}


def _forget(key: int):
    def callback(_ref):
        _CHECKED_WAVELENGTHS.pop(key, None)
    return callback


def as_wavelengths(wavelengths_nm: Any, low: float = 200.0, high: float = 4000.0,
                   name: str = "wavelengths_nm") -> np.ndarray:
    """Validate a 1-D array of wavelengths in nm within [low, high].

    Returns a read-only float64 copy and remembers it: passing that array down again
    (render -> model -> helpers) costs a look-up and two comparisons instead of a scan,
    so wavelengths are validated once per render.
    """
    entry = _CHECKED_WAVELENGTHS.get(id(wavelengths_nm))
    if entry is not None and entry[0]() is wavelengths_nm and not wavelengths_nm.flags.writeable:
        _, w_min, w_max = entry
        if w_min < low or w_max > high:
            raise ValueError(f"{name} = [{w_min:g} .. {w_max:g}] nm is out of range "
                             f"[{low:g}, {high:g}] nm")
        return wavelengths_nm
    check_real(name, wavelengths_nm)
    w = np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64))
    if w.ndim != 1 or w.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array, got shape {w.shape}")
    if not np.all(np.isfinite(w)):
        raise ValueError(f"{name} contains NaN or infinite values")
    if w.min() < low or w.max() > high:
        raise ValueError(f"{name} = [{w.min():g} .. {w.max():g}] nm is out of range [{low:g}, {high:g}] nm")
    out = np.array(w, dtype=np.float64)
    out.flags.writeable = False
    key = id(out)
    _CHECKED_WAVELENGTHS[key] = (weakref.ref(out, _forget(key)), float(out.min()), float(out.max()))
    return out


def safe_sqrt(x):
    """Square root that maps tiny negative round-off to 0 (Bruneton's SafeSqrt)."""
    return np.sqrt(np.maximum(x, 0.0))


def clamp_cosine(x):
    """Clamp a cosine to [-1, 1] (Bruneton's ClampCosine)."""
    return np.clip(x, -1.0, 1.0)
