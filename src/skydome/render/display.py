"""Display: physically based exposure and display transforms (linear light -> sRGB).

Exposure
--------
A camera of ISO speed S = 100 with aperture N and shutter time t saturates at the scene
luminance [LdR14] eq. 12 (the saturation-based speed of ISO 12232 with q = 0.65)

    L_max = 78 / (S q) N^2 / t = 1.2 x 2^EV100  [cd m^-2],   EV100 = log2(N^2 / t),

so the exposure multiplier that maps L_max to display value 1 is ``k = 1 / (1.2 x
2^EV100)`` [m^2/cd]. Every picture records both k and its EV100. Automatic exposure
(:meth:`SkyImage.auto_exposure`) puts the log-average sky luminance at Reinhard's key
0.18 [Rei02], which is EV100 = log2(L_avg / (0.18 x 1.2)); sequences (timelapse,
twilight, day sheets) use ONE such exposure or an explicit ramp, so a darker sky gives a
darker picture.

Display transforms
------------------
``"hue-preserving"`` (default)
    Out-of-gamut colours (a negative sRGB component) are first brought into the gamut
    along the line to the grey of the same luminance (Rec. 709 weights), which keeps
    luminance and, closely, hue. Then the largest component m of the exposed colour is
    tone mapped with the ACES fit of [Nar15] and the colour scaled by f(m) / m: the ratios
    R:G:B, hence hue and saturation, are kept, and nothing clips. Highlights far above
    the display's white run to white ("path to white", as film and AgX do) only when
    m exceeds 4 (two stops above white), blending fully to white at m = 64: a sunset
    stays orange, the noon zenith stays deep blue, the sun's disc is white.
``"filmic"``
    The [Nar15] curve on each channel separately (the former default): bright
    saturated colours shift towards yellow and white (an orange-red sunset turns pale
    yellow), dark blues lose saturation.
``"reinhard"``, ``"clamp"``
    x / (1 + x) per channel [Rei02] eq. 3; min(x, 1).

Why this default: on the demo skies (docs/rendering.md) the per-channel curve clips the
orange-red horizon under a 2 deg sun (linear (1, 0.31, 0.05)) to pale yellow and greys
the zenith; the hue-preserving curve keeps both hues within a few degrees (CIELAB), which
the tests check, at the price of less "filmic" desaturation in bright skies.

References
----------
.. [LdR14] S. Lagarde, C. de Rousiers, "Moving Frostbite to physically based rendering
   3.0", SIGGRAPH course notes, 2014, section 5.1 (EV100, saturation-based exposure).
.. [Rei02] E. Reinhard et al., "Photographic tone reproduction for digital images",
   ACM TOG 21(3), 2002.
.. [Nar15] K. Narkowicz, "ACES filmic tone mapping curve", 2015.
"""

from __future__ import annotations

import numpy as np

__all__ = ["DISPLAY_TRANSFORMS", "DEFAULT_TRANSFORM", "ev100_to_exposure",
           "exposure_to_ev100", "display_transform", "aces_fit"]

DISPLAY_TRANSFORMS = ("hue-preserving", "filmic", "reinhard", "clamp")
DEFAULT_TRANSFORM = "hue-preserving"
_LUMA = np.array([0.2126, 0.7152, 0.0722])   # Rec. 709 luminance weights (IEC 61966-2-1)
_WHITE_START, _WHITE_FULL = 4.0, 64.0          # path to white: exposed max component


def ev100_to_exposure(ev100: float) -> float:
    """Exposure multiplier k = 1 / (1.2 x 2^EV100) [m^2/cd] [LdR14]."""
    from skydome._validate import check_number

    ev = check_number("ev100", ev100, -20.0, 30.0)
    return 1.0 / (1.2 * 2.0 ** ev)


def exposure_to_ev100(k: float) -> float:
    """EV100 of an exposure multiplier k [m^2/cd]: log2(1 / (1.2 k))."""
    return float(np.log2(1.0 / (1.2 * float(k))))


def aces_fit(x) -> np.ndarray:
    """[Nar15] x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), clipped to [0, 1]."""
    x = np.maximum(np.asarray(x, dtype=np.float64), 0.0)
    return np.clip(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)


def _into_gamut(rgb: np.ndarray) -> np.ndarray:
    """Move colours with a negative component towards the grey of equal luminance until
    the smallest component is 0 (black if the luminance is not positive)."""
    Y = rgb @ _LUMA
    lo = rgb.min(axis=-1)
    bad = lo < 0.0
    if not np.any(bad):
        return rgb
    out = rgb.copy()
    Yb = np.maximum(Y[bad], 0.0)[..., None]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(Yb > 0.0, Yb / (Yb - lo[bad][..., None]), 0.0)
    out[bad] = Yb + t * (rgb[bad] - Yb)
    return np.maximum(out, 0.0)


def display_transform(rgb, transform: str = DEFAULT_TRANSFORM) -> np.ndarray:
    """Linear display values in [0, 1] (before sRGB encoding) of exposed linear sRGB
    ``rgb`` (..., 3); see the module docstring for the transforms."""
    from skydome._validate import check_choice

    check_choice("transform", transform, DISPLAY_TRANSFORMS)
    rgb = np.asarray(rgb, dtype=np.float64)
    if transform == "filmic":
        return aces_fit(rgb)
    if transform == "reinhard":
        x = np.maximum(rgb, 0.0)
        return np.clip(x / (1.0 + x), 0.0, 1.0)
    if transform == "clamp":
        return np.clip(rgb, 0.0, 1.0)
    rgb = _into_gamut(rgb)
    m = rgb.max(axis=-1, keepdims=True)
    fm = aces_fit(m)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(m > 0.0, rgb * (fm / np.where(m > 0.0, m, 1.0)), 0.0)
    # path to white, logarithmic in the over-exposure from 4 to 64 x the display's white
    w = np.clip(np.log2(np.maximum(m, 1e-300) / _WHITE_START)
                / np.log2(_WHITE_FULL / _WHITE_START), 0.0, 1.0)
    out = out * (1.0 - w) + fm * w
    return np.clip(out, 0.0, 1.0)
