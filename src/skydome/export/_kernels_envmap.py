"""numba kernels of the environment-map path: the lat-long direction grid, the map's RGB
from XYZ and the EXR channels (half or float32 planes), each one pass over the pixels
instead of several numpy passes and their temporaries.

The per-band passes (directions, RGB) are serial: a parallel launch costs more than the
work of a band (64 rows of a 4096-wide map) and, on a shared 2-core machine, numba's OpenMP
threads wait for each other (17 bands' RGB: 0.28 s of wall and 0.14 s of CPU on two
threads, 0.05 s and 0.03 s on one, at load 11). The whole map's half or float32 conversion,
one call, runs on both cores (0.09 s against 0.10-0.16 s on one), as serial kernels on
Python threads (:func:`skydome._threads.run_ranges`: a ``prange`` kernel's first
compilation costs seconds more, docs/performance.md, "Kernels on Python threads").

Every kernel gives the values of the numpy code it replaces, bit for bit
(tests/test_envmap_kernels.py): plain IEEE arithmetic (no fastmath), the XYZ -> RGB
product in the order of the BLAS product it replaces, and the float64 -> half rounding of
IEEE 754 (round to nearest, ties to even, subnormals, overflow to infinity).
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import types
from skydome._kernel_cache import njit
from numba.core.extending import intrinsic


@intrinsic
def _fma(typingctx, a, b, c):
    """a b + c rounded once (LLVM's llvm.fma.f64; a single instruction on x86-64 since
    Haswell)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        f = builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d]))
        return builder.call(f, args)

    return sig, codegen


@njit(cache=True)
def latlong_directions(s, c, hx, hy, out):
    """out[i, j] = (s[i] hx[j], s[i] hy[j], c[i]): the pixel centres' unit vectors of a
    lat-long map, sin and cos of the zenith angle per row, the horizontal unit vector per
    column (out (H, W, 3)). Serial: called per band of a map (see the module notes)."""
    for i in range(out.shape[0]):
        si = s[i]
        ci = c[i]
        for j in range(out.shape[1]):
            out[i, j, 0] = si * hx[j]
            out[i, j, 1] = si * hy[j]
            out[i, j, 2] = ci


@njit(cache=True)
def xyz_to_map_rgb(flat, m, k_m):
    """Rows of ``flat`` (n, 3) XYZ -> linear RGB = m @ xyz / k_m, negatives clipped to 0,
    in place; returns the number of rows with a NaN or infinite entry (left as they are).

    The product is the fused multiply-add chain ((x m0 + y m1) + z m2) that OpenBLAS's
    dgemm kernels compute for a (n, 3) x (3, 3) product (k in order, one rounding per
    step): ``np.dot(xyz, m.T)`` of :func:`skydome.spectra.xyz_to_linear_srgb` on x86-64,
    bit for bit. Then the division by k_m and numpy's maximum(v, 0) (+0 for -0)."""
    n = flat.shape[0]
    bad = 0
    for i in range(n):
        x = flat[i, 0]
        y = flat[i, 1]
        z = flat[i, 2]
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
            bad += 1
            continue
        for j in range(3):
            v = _fma(z, m[j, 2], _fma(y, m[j, 1], x * m[j, 0])) / k_m
            flat[i, j] = v if v > 0.0 else 0.0
    return bad


# float64 bit fields and the half's (IEEE 754 binary64 -> binary16)
_SIGN = np.uint64(0x8000000000000000)
_EXP = np.uint64(0x7FF0000000000000)
_FRAC = np.uint64(0x000FFFFFFFFFFFFF)
_HIDDEN = np.uint64(0x0010000000000000)
_EXP_OVERFLOW = np.uint64(0x40F0000000000000)   # 2^16: beyond the largest half
_EXP_NORMAL = np.uint64(0x3F00000000000000)     # 2^-15: below it subnormal halves
_EXP_ZERO = np.uint64(0x3E60000000000000)       # 2^-25: below it rounds to zero
_LOW42 = np.uint64(0x000007FFFFFFFFFF)
_HALF42 = np.uint64(0x0000020000000000)
_LOW54 = np.uint64(0x003FFFFFFFFFFFFF)
_U48 = np.uint64(48)
_U52 = np.uint64(52)
_U53 = np.uint64(53)
_U42 = np.uint64(42)
_U998 = np.uint64(998)


@njit(cache=True, inline="always")
def _half_bits(d):
    """The binary16 bits nearest the binary64 with bits ``d`` (ties to even); infinity
    beyond the half range, a quiet NaN for NaN."""
    sign = np.uint16((d & _SIGN) >> _U48)
    e = d & _EXP
    if e >= _EXP_OVERFLOW:
        if e == _EXP and (d & _FRAC) != np.uint64(0):
            return sign | np.uint16(0x7E00)                # NaN (quiet)
        return sign | np.uint16(0x7C00)                    # infinity, or overflow to it
    if e <= _EXP_NORMAL:
        if e < _EXP_ZERO:
            return sign                                    # rounds to (signed) zero
        sig = _HIDDEN + (d & _FRAC)
        sig = sig << ((e >> _U52) - _U998)                 # the half's ulp at bit 53
        if (sig & _LOW54) != _HIDDEN:                      # not an exact tie to even
            sig += _HIDDEN
        return sign | np.uint16(sig >> _U53)
    sig = d & _FRAC
    if (sig & _LOW42) != _HALF42:                          # not an exact tie to even
        sig += _HALF42
    # a carry out of the fraction raises the exponent (to infinity past 65504)
    return sign | np.uint16(((e - _EXP_NORMAL) >> _U42) + (sig >> _U42))


#: Pixels per thread below which a plane conversion runs on the calling thread alone.
MIN_PIXELS_PER_THREAD = 65536


@njit(nogil=True, cache=True)
def half_planes(bits, r, g, b, i0, i1):
    """Interleaved float64 pixels (bits (n, 3) as uint64) -> the half bits of each channel
    in r, g, b (n,) uint16: float64 -> float16 as numpy's astype rounds it; pixels i0 .. i1 -
    1 (serial: :func:`skydome._threads.run_ranges` runs it on several threads)."""
    for i in range(i0, i1):
        r[i] = _half_bits(bits[i, 0])
        g[i] = _half_bits(bits[i, 1])
        b[i] = _half_bits(bits[i, 2])


@njit(nogil=True, cache=True)
def float32_planes(flat, r, g, b, i0, i1):
    """Interleaved float64 pixels (n, 3) -> float32 planes r, g, b (n,) (IEEE rounding);
    pixels i0 .. i1 - 1 (serial: :func:`skydome._threads.run_ranges` runs it on several
    threads)."""
    for i in range(i0, i1):
        r[i] = np.float32(flat[i, 0])
        g[i] = np.float32(flat[i, 1])
        b[i] = np.float32(flat[i, 2])
