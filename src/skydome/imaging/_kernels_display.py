"""numba kernel of the Hunt-effect chroma gain (:func:`skydome.imaging.display.scale_chroma`).

The same arithmetic as the NumPy version, one pixel at a time in a loop run on several
threads (:func:`skydome._threads.run_ranges`: serial kernels compile in a third of the time
a ``prange`` loop takes, docs/performance.md, "Kernels on Python threads"), so that
the save path of a large picture does not pay for a dozen full-size temporaries: scale
each colour to Y = 1, CIELAB [CIE15] a* and b* times the gain at L* = 100, back to linear
sRGB at the colour's own Y, then stop on the segment towards the boosted colour where its
smallest component reaches 0 (in-gamut colours stay in gamut; out-of-gamut ones are left
as they are). Imported only where a picture is made (numba is not loaded by
``import skydome``).
"""

from __future__ import annotations

import math

from skydome._kernel_cache import njit

_D = 6.0 / 29.0
#: Pixels per thread below which a display kernel runs on the calling thread alone.
MIN_PIXELS_PER_THREAD = 16384


@njit(cache=True, inline="always")
def _lab_f(t):
    """[CIE15] f(t): cube root above (6/29)^3, the linear segment below."""
    if t > _D * _D * _D:
        return t ** (1.0 / 3.0)
    return t / (3.0 * _D * _D) + 4.0 / 29.0


@njit(cache=True, inline="always")
def _lab_f_inv(f):
    if f > _D:
        return f * f * f
    return 3.0 * _D * _D * (f - 4.0 / 29.0)


@njit(nogil=True, cache=True)
def scale_chroma_kernel(rgb, gain, to_xyz, to_rgb, white, out, i0, i1):
    """out[i] = rgb[i] with its CIELAB chroma times ``gain`` for i in i0 .. i1 - 1 (rgb,
    out: (n, 3) linear sRGB; to_xyz / to_rgb the 3 x 3 matrices; white the white's XYZ at Y
    = 1). Serial: :func:`skydome._threads.run_ranges` runs it on several threads."""
    for i in range(i0, i1):
        r0 = rgb[i, 0]
        g0 = rgb[i, 1]
        b0 = rgb[i, 2]
        X = to_xyz[0, 0] * r0 + to_xyz[0, 1] * g0 + to_xyz[0, 2] * b0
        Y = to_xyz[1, 0] * r0 + to_xyz[1, 1] * g0 + to_xyz[1, 2] * b0
        Z = to_xyz[2, 0] * r0 + to_xyz[2, 1] * g0 + to_xyz[2, 2] * b0
        if not Y > 0.0:
            out[i, 0] = r0
            out[i, 1] = g0
            out[i, 2] = b0
            continue
        fx = _lab_f(X / Y / white[0])
        fz = _lab_f(Z / Y / white[2])
        # [CIE15] a* = 500 (fx - fy), b* = 200 (fy - fz) at fy = 1, scaled, then inverted
        a = gain * 500.0 * (fx - 1.0)
        b = gain * 200.0 * (1.0 - fz)
        X2 = _lab_f_inv(1.0 + a / 500.0) * white[0] * Y
        Y2 = white[1] * Y
        Z2 = _lab_f_inv(1.0 - b / 200.0) * white[2] * Y
        c = (to_rgb[0, 0] * X2 + to_rgb[0, 1] * Y2 + to_rgb[0, 2] * Z2,
             to_rgb[1, 0] * X2 + to_rgb[1, 1] * Y2 + to_rgb[1, 2] * Z2,
             to_rgb[2, 0] * X2 + to_rgb[2, 1] * Y2 + to_rgb[2, 2] * Z2)
        src = (r0, g0, b0)
        t = 0.0
        if min(r0, g0, b0) >= 0.0:
            t = 1.0
            for k in range(3):
                if c[k] < 0.0:
                    t = min(t, src[k] / (src[k] - c[k]))
            t = min(max(t, 0.0), 1.0)
        for k in range(3):
            out[i, k] = src[k] + t * (c[k] - src[k])


@njit(inline="always")
def _aces_fit(x):
    """[Nar15] x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14) of x >= 0, clipped to [0, 1]
    (:func:`skydome.imaging.display.aces_fit`)."""
    v = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)
    return min(max(v, 0.0), 1.0)


@njit(inline="always")
def _srgb_encode(v):
    """[IEC 61966-2-1] 5.2: 12.92 L for L <= 0.0031308, else 1.055 L^(1/2.4) - 0.055, of L
    clipped to [0, 1] (:func:`skydome.spectra.srgb_encode`)."""
    v = min(max(v, 0.0), 1.0)
    if v <= 0.0031308:
        return 12.92 * v
    return min(max(1.055 * v ** (1.0 / 2.4) - 0.055, 0.0), 1.0)


@njit(nogil=True, cache=True)
def hue_preserving_srgb_kernel(rgb, luma, white_start, log2_span, mask, out, i0, i1):
    """out[i] = the sRGB-encoded display value in [0, 1] of exposed linear sRGB rgb[i] under
    the hue-preserving transform (:func:`skydome.imaging.display.display_transform`, its
    default), 0 where ``mask[i]`` is False; the number of pixels holding NaN (which the
    NumPy path refuses). Per pixel, the same steps as the NumPy path: into the gamut towards
    the grey of equal luminance (``_into_gamut``), the largest component m through [Nar15]'s
    curve and every component scaled by f(m) / m, a path to white logarithmic in m from
    ``white_start`` over ``log2_span`` octaves, clipped to [0, 1], then [IEC]'s encoding
    (clipped to [0, 1] as the NumPy path clips it). Equal to that path to a few units in
    the last place (libm's pow and log2 against NumPy's own). For the pixels i0 .. i1 - 1:
    serial, :func:`skydome._threads.run_ranges` runs it on several threads."""
    n_nan = 0
    for i in range(i0, i1):
        r = rgb[i, 0]
        g = rgb[i, 1]
        b = rgb[i, 2]
        if r != r or g != g or b != b:
            n_nan += 1
            out[i, 0] = 0.0
            out[i, 1] = 0.0
            out[i, 2] = 0.0
            continue
        if not mask[i]:
            out[i, 0] = 0.0
            out[i, 1] = 0.0
            out[i, 2] = 0.0
            continue
        lo = min(r, g, b)
        if lo < 0.0:
            Y = max(r * luma[0] + g * luma[1] + b * luma[2], 0.0)
            t = Y / (Y - lo) if Y > 0.0 else 0.0
            r = max(Y + t * (r - Y), 0.0)
            g = max(Y + t * (g - Y), 0.0)
            b = max(Y + t * (b - Y), 0.0)
        m = max(r, g, b)
        fm = _aces_fit(max(m, 0.0))
        s = fm / m if m > 0.0 else 0.0
        w = min(max(math.log2(max(m, 1e-300) / white_start) / log2_span, 0.0), 1.0)
        out[i, 0] = _srgb_encode(min(max(r * s * (1.0 - w) + fm * w, 0.0), 1.0))
        out[i, 1] = _srgb_encode(min(max(g * s * (1.0 - w) + fm * w, 0.0), 1.0))
        out[i, 2] = _srgb_encode(min(max(b * s * (1.0 - w) + fm * w, 0.0), 1.0))
    return n_nan
