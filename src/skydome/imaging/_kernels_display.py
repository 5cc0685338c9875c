"""numba kernel of the Hunt-effect chroma gain (:func:`skydome.imaging.display.scale_chroma`).

The same arithmetic as the NumPy version, one pixel at a time in a parallel loop, so that
the save path of a large picture does not pay for a dozen full-size temporaries: scale
each colour to Y = 1, CIELAB [CIE15] a* and b* times the gain at L* = 100, back to linear
sRGB at the colour's own Y, then stop on the segment towards the boosted colour where its
smallest component reaches 0 (in-gamut colours stay in gamut; out-of-gamut ones are left
as they are). Imported only where a picture is made (numba is not loaded by
``import skydome``).
"""

from __future__ import annotations

from numba import njit, prange

_D = 6.0 / 29.0


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


@njit(parallel=True, cache=True)
def scale_chroma_kernel(rgb, gain, to_xyz, to_rgb, white, out):
    """out[i] = rgb[i] with its CIELAB chroma times ``gain`` (rgb, out: (n, 3) linear sRGB;
    to_xyz / to_rgb the 3 x 3 matrices; white the white's XYZ at Y = 1)."""
    for i in prange(rgb.shape[0]):
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
