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

Colourfulness (Hunt effect)
---------------------------
A clear sky of a few thousand cd m^-2 looks more colourful than the same chromaticities
on an 80 cd m^-2 display: colourfulness grows with the adapting luminance (the Hunt
effect). CAM16 [Li17] eq. 15 writes it M = C F_L^(1/4), F_L from the adapting luminance
L_A ([CIE159] eq. 7). Pictures keep M: the CIELAB chroma of each colour is scaled by
g = (F_L(L_A scene) / F_L(L_A display))^(1/4) at constant luminance and hue, with L_A of
the scene its log-average sky luminance and of the display a fifth of its 80 cd m^-2
white (IEC 61966-2-1; [CIE159]'s L_A = L_W / 5). g is about 1.6 at noon, 1.4 at sunset
and kept at 1 in dim twilight (where the eye's colours fade but a photograph's do not).
In-gamut colours are boosted at most to the gamut's boundary. Deviation: CIELAB chroma
stands in for CAM16 chroma (whose C grows as the 0.9 power of the opponent signal), so
the gain is applied about 10 % more gently than CAM16 would; the adaptation white stays
D65 (no camera-like "daylight" white balance).

Measured on the default model (``docs/display_figures.py``): the noon zenith (sun 60 deg)
is linear sRGB (4490, 5309, 7295) cd m^-2, CIE xy (0.281, 0.293), about 9700 K: a pale
blue 30 deg from the sun, in the aureole. Auto exposure (EV100 14.3) puts it at display
Y 0.2-0.3, as bright as in a photograph (the sRGB (60-90, 110-140, 200-230) of a clear
zenith has Y 0.16-0.27), so exposure was not what made it grey: the colorimetric
picture (every transform keeps or lowers its chroma) shows CIELAB C* 14 (sRGB 141, 152,
176); with the Hunt gain C* 21.5 (130, 150, 187). The rest of the way to a photograph's
C* 50 is the camera's rendering (daylight white balance near 5500 K, saturated picture
styles), not the sky's colour.

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
``"agx"``
    Troy Sobotka's AgX base as in Blender 4.x [Sob23], with the sigmoid fit of [Wre23]:
    Rec. 2020 inset matrix, log2 encoding over [-12.47, 4.03] EV, per-channel sigmoid,
    outset matrix. Gamut compression and a path to white by construction; it lowers the
    chroma of mid-tones (the noon zenith C* 14 -> 8) and turns hues by up to 9 deg.
``"aces-hill"``
    The ACES 1.x reference rendering + sRGB output transform as fitted by S. Hill [Hil16]
    (not ACES 2.0): darker (mid-grey 0.18 -> 0.106) and contrasty; it turns the
    orange-red horizon under a 2 deg sun yellow (hue off by 21 deg).
``"filmic"``
    The [Nar15] curve on each channel separately (the former default): bright
    saturated colours shift towards yellow and white (an orange-red sunset turns pale
    yellow), dark blues lose saturation.
``"reinhard"``, ``"clamp"``
    x / (1 + x) per channel [Rei02] eq. 3; min(x, 1).

Why this default: on the demo skies (docs/figures/display_transforms.png) the
hue-preserving curve with the Hunt gain gives the deepest blue zenith and keeps every
tested hue within 2.3 deg of the linear colour (horizon under a 2 deg sun, noon zenith,
Belt of Venus at -2 deg; tests/test_display.py); AgX passes the hue tests too (within
9.5 deg) but is visibly greyer; the per-channel ACES curves fail the sunset.

References
----------
.. [LdR14] S. Lagarde, C. de Rousiers, "Moving Frostbite to physically based rendering
   3.0", SIGGRAPH course notes, 2014, section 5.1 (EV100, saturation-based exposure).
.. [Rei02] E. Reinhard et al., "Photographic tone reproduction for digital images",
   ACM TOG 21(3), 2002.
.. [Nar15] K. Narkowicz, "ACES filmic tone mapping curve", 2015.
.. [Sob23] T. Sobotka, AgX (github.com/sobotka/AgX) and its Blender 4.0 configuration
   (the Rec. 2020 inset/outset matrices, log2 range -12.47393 .. 4.026069 EV), as
   reproduced in three.js's AgXToneMapping (2024).
.. [Wre23] B. Wrensch, "Minimal AgX implementation", iolite engine blog, 2023 (the
   6th-order polynomial fit of the AgX base sigmoid).
.. [Hil16] S. Hill, BakingLab ACES.hlsl, 2016 (RRTAndODTFit and its two matrices).
.. [CIE159] CIE 159:2004, A colour appearance model for colour management systems:
   CIECAM02 (eq. 7, F_L; worked example F_L = 1.16754 at L_A = 318.31 cd m^-2).
.. [Li17] C. Li et al., "Comprehensive color solutions: CAM16, CAT16, and CAM16-UCS",
   Color Res. Appl. 42(6), 2017.
.. [CIE15] CIE 15:2004, Colorimetry (CIELAB).
.. [709], [2020] ITU-R BT.709-6 and BT.2020-2 primaries; [RP177] SMPTE RP 177
   (normalised primary matrix); ITU-R BT.2087-0 (the 709 -> 2020 matrix, tested).
"""

from __future__ import annotations

import numpy as np

__all__ = ["DISPLAY_TRANSFORMS", "DEFAULT_TRANSFORM", "ev100_to_exposure",
           "exposure_to_ev100", "display_transform", "aces_fit", "agx", "aces_hill"]

DISPLAY_TRANSFORMS = ("hue-preserving", "agx", "aces-hill", "filmic", "reinhard", "clamp")
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


# --------------------------------------------------------------------------------------
# AgX [Sob23] (the base of Blender 4.x) with the sigmoid fit of [Wre23]
# --------------------------------------------------------------------------------------
# Linear Rec. 709 <-> linear Rec. 2020 (both D65), derived from the primaries [709],
# [2020] by the normalised primary matrix [RP177]: AgX works in Rec. 2020.
_REC2020_PRIMARIES_XY = ((0.708, 0.292), (0.170, 0.797), (0.131, 0.046))  # [2020] table 3


def _rec709_rec2020() -> tuple[np.ndarray, np.ndarray]:
    from skydome.spectra import SRGB_WHITE_XY, _SRGB_PRIMARIES_XY, normalised_primary_matrix

    m709 = normalised_primary_matrix(_SRGB_PRIMARIES_XY, SRGB_WHITE_XY)
    m2020 = normalised_primary_matrix(_REC2020_PRIMARIES_XY, SRGB_WHITE_XY)
    to2020 = np.linalg.solve(m2020, m709)
    return to2020, np.linalg.inv(to2020)


# [Sob23] Blender 4.x AgX base, for linear Rec. 2020 input: the "inset" pulls each primary
# towards the achromatic axis (rows sum to 1, so greys stay grey) so that bright saturated
# colours run to white through their own hue; the "outset" after the curve restores part
# of the purity. Rows act on (R, G, B) as M @ rgb.
_AGX_INSET = np.array([[0.856627153315983, 0.0951212405381588, 0.0482516061458583],
                       [0.137318972929847, 0.761241990602591, 0.101439036467562],
                       [0.11189821299995, 0.0767994186031903, 0.811302368396859]])
_AGX_OUTSET = np.array([[1.1271005818144368, -0.11060664309660323, -0.016493938717834573],
                        [-0.1413297634984383, 1.157823702216272, -0.016493938717834257],
                        [-0.14132976349843826, -0.11060664309660294, 1.2519364065950405]])
# [Sob23] log2 encoding range: 0.18 x 2^-10 .. 0.18 x 2^6.5 (16.5 stops, mid-grey at 10/16.5)
_AGX_MIN_EV, _AGX_MAX_EV = -12.47393, 4.026069
# [Wre23] 6th-order polynomial fit of the AgX base sigmoid on [0, 1] (display-encoded
# output, to be decoded with the 2.2 power of the sRGB reference display)
_AGX_SIGMOID = (15.5, -40.14, 31.96, -6.868, 0.4298, 0.1191, -0.00232)


def agx(rgb) -> np.ndarray:
    """AgX base [Sob23] of exposed linear sRGB ``rgb`` (..., 3): linear display values in
    [0, 1].

    Rec. 709 -> Rec. 2020, inset matrix, log2 encoding over [-12.47, 4.03] EV relative to
    1 (mid-grey 0.18 at 10/16.5 of the range), the sigmoid per channel ([Wre23]'s fit),
    outset matrix, decoded with the 2.2 power, Rec. 2020 -> Rec. 709, clipped to [0, 1].
    """
    to2020, to709 = _rec709_rec2020()
    x = np.asarray(rgb, dtype=np.float64) @ (_AGX_INSET @ to2020).T
    x = np.log2(np.maximum(x, 1e-10))
    x = np.clip((x - _AGX_MIN_EV) / (_AGX_MAX_EV - _AGX_MIN_EV), 0.0, 1.0)
    y = np.polyval(_AGX_SIGMOID, x)
    y = np.maximum(y @ _AGX_OUTSET.T, 0.0) ** 2.2
    return np.clip(y @ to709.T, 0.0, 1.0)


# --------------------------------------------------------------------------------------
# ACES 1.x RRT + sRGB ODT, fitted by S. Hill [Hil16] (not ACES 2.0)
# --------------------------------------------------------------------------------------
# [Hil16] sRGB -> XYZ -> D65-to-D60 -> AP1 -> RRT_SAT, and ODT_SAT -> XYZ -> D60-to-D65 -> sRGB
_HILL_IN = np.array([[0.59719, 0.35458, 0.04823],
                     [0.07600, 0.90834, 0.01566],
                     [0.02840, 0.13383, 0.83777]])
_HILL_OUT = np.array([[1.60475, -0.53108, -0.07367],
                      [-0.10208, 1.10813, -0.00605],
                      [-0.00327, -0.07276, 1.07602]])


def aces_hill(rgb) -> np.ndarray:
    """The ACES 1.x reference rendering + sRGB output transform as fitted by [Hil16]:
    input matrix (with the RRT's 0.96 desaturation), the rational fit
    (v (v + 0.0245786) - 0.000090537) / (v (0.983729 v + 0.432951) + 0.238081) per
    channel, output matrix, clipped to [0, 1]. Maps 0.18 to 0.106 (ACES puts mid-grey
    at about 10 % of display white)."""
    v = np.asarray(rgb, dtype=np.float64) @ _HILL_IN.T
    v = np.maximum(v, 0.0)
    v = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081)  # [Hil16]
    return np.clip(v @ _HILL_OUT.T, 0.0, 1.0)


# --------------------------------------------------------------------------------------
# Colourfulness: the Hunt effect between the sky and the display [CIE159], [Li17]
# --------------------------------------------------------------------------------------
#: sRGB reference display white [cd m^-2] (IEC 61966-2-1); its adapting luminance is a
#: fifth of it, the grey-world convention of [CIE159] (L_A = L_W / 5).
DISPLAY_WHITE_CD_M2 = 80.0


def luminance_adaptation_factor(adapting_luminance_cd_m2) -> np.ndarray:
    """F_L of CIECAM02 / CAM16 [CIE159] eq. 7 ([Li17] eq. 4) for the adapting luminance
    L_A [cd m^-2]: k = 1 / (5 L_A + 1), F_L = 0.2 k^4 (5 L_A) + 0.1 (1 - k^4)^2 (5 L_A)^(1/3)."""
    la = np.maximum(np.asarray(adapting_luminance_cd_m2, dtype=np.float64), 0.0)
    k = 1.0 / (5.0 * la + 1.0)
    k4 = k ** 4
    return 0.2 * k4 * (5.0 * la) + 0.1 * (1.0 - k4) ** 2 * np.cbrt(5.0 * la)  # [CIE159] eq. 7


def hunt_chroma_gain(scene_adapting_luminance_cd_m2: float,
                     display_white_cd_m2: float = DISPLAY_WHITE_CD_M2) -> float:
    """Chroma gain that keeps the colourfulness M = C F_L^(1/4) of CAM16 [Li17] eq. 15 when a
    scene seen at adapting luminance L_A is shown on a display of white L_W (L_A = L_W / 5):
    (F_L(scene) / F_L(display))^(1/4), never below 1.

    A clear day sky (L_A ~ 4000 cd m^-2) looks about 1.6 x more colourful than the same
    chromaticities on an 80 cd m^-2 display (the Hunt effect); the gain puts that back.
    Dim scenes (twilight) would get a gain below 1 (the eye's colours fade as light falls);
    we keep 1 there, as a photograph does, so twilight blues are shown as measured.
    """
    from skydome._validate import check_number

    la = check_number("scene_adapting_luminance_cd_m2", scene_adapting_luminance_cd_m2, 0.0, None)
    lw = check_number("display_white_cd_m2", display_white_cd_m2, 0.0, None, low_open=True)
    g = (luminance_adaptation_factor(la) / luminance_adaptation_factor(lw / 5.0)) ** 0.25
    return float(max(1.0, g))


def _lab_f(t):
    d = 6.0 / 29.0
    return np.where(t > d ** 3, np.cbrt(np.maximum(t, d ** 3)), t / (3.0 * d * d) + 4.0 / 29.0)


def scale_chroma(rgb, gain: float) -> np.ndarray:
    """Scale the CIELAB chroma [CIE15] of linear sRGB colours ``rgb`` (..., 3) by ``gain`` at
    constant luminance Y and CIELAB hue (D65 white). Each colour is scaled to Y = 1 first,
    so the result does not depend on the exposure. Colours with Y <= 0 are left as they are;
    colours inside the sRGB gamut are boosted at most to its boundary (luminance kept),
    colours outside it (already more saturated than the display shows) not at all.
    """
    from skydome._threads import run_ranges
    from skydome.imaging._kernels_display import MIN_PIXELS_PER_THREAD, scale_chroma_kernel
    from skydome.spectra import SRGB_WHITE_XY, _M_SRGB_TO_XYZ, _M_XYZ_TO_SRGB, _xy_to_white_xyz

    rgb = np.asarray(rgb, dtype=np.float64)
    if gain == 1.0:
        return rgb
    # one pass per pixel in a numba kernel (3.5x less CPU time than the array expression
    # it replaced, without its full-size temporaries: benchmarks/bench_display.py)
    flat = np.ascontiguousarray(rgb.reshape(-1, 3))
    out = np.empty_like(flat)
    run_ranges(scale_chroma_kernel, flat.shape[0],
               (flat, float(gain), _M_SRGB_TO_XYZ, _M_XYZ_TO_SRGB,
                _xy_to_white_xyz(SRGB_WHITE_XY), out), MIN_PIXELS_PER_THREAD)
    return out.reshape(rgb.shape)


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
    if transform == "agx":
        return agx(rgb)
    if transform == "aces-hill":
        return aces_hill(rgb)
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
