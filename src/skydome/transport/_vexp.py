"""exp over short arrays of non-positive arguments, to the accuracy of the C library.

numba's ``math.exp`` is a scalar libm call; the density profiles of the view-ray
quadrature need one per node and constituent, which made them the largest cost of the
single-scattering kernel. :func:`exp_neg_many` evaluates a whole piece of a ray at once in
a loop that LLVM vectorises, accurate to a few units in the last place (the relative
difference from libm's exp is below 1e-15 on [-708, 0]; ``tests/test_transport_vexp.py``).

Method (the classical argument reduction of Cody & Waite 1980, *Software Manual for the
Elementary Functions*, ch. 6; Tang 1989, ACM TOMS 15, 144): k = round(x / ln 2),
t = x - k ln 2 with ln 2 split into a high part of 32 significant bits (k ln2_hi is exact
for |k| < 2^21) and a low part, so |t| <= ln(2)/2; exp(t) by its Taylor series to degree
13 (truncation error (ln(2)/2)^14 / 14! < 6e-18); 2^k assembled from the IEEE-754
exponent bits. Arguments below -708 (where 2^k would leave the normal range) give 0,
which differs from libm's subnormal results by less than 3e-308.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit

_LN2_HI = 6.93147180369123816490e-01   # ln 2, high 32 bits (fdlibm e_exp.c ln2HI)
_LN2_LO = 1.90821492927058770002e-10   # ln 2 - _LN2_HI (fdlibm e_exp.c ln2LO)
_INV_LN2 = 1.44269504088896338700e+00
_X_MIN = -708.0

# no reassociation (it would undo the split of ln 2), no "no infinities" (-inf gives 0)
_FLAGS = {"nsz", "contract", "afn"}


@njit(cache=True, fastmath=_FLAGS, inline="always")
def _exp_parts(x):
    """(exp(t), bits of 2^k) with x = k ln 2 + t, k = round(x / ln 2), |t| <= ln(2)/2:
    exp(x) is their product (Cody-Waite reduction, Taylor series to degree 13)."""
    k = math.floor(x * _INV_LN2 + 0.5)
    t = (x - k * _LN2_HI) - k * _LN2_LO
    p = 1.0 + t * (1.0 + t * (0.5 + t * (1.0 / 6.0 + t * (1.0 / 24.0 + t * (
        1.0 / 120.0 + t * (1.0 / 720.0 + t * (1.0 / 5040.0 + t * (1.0 / 40320.0 + t * (
            1.0 / 362880.0 + t * (1.0 / 3628800.0 + t * (1.0 / 39916800.0 + t * (
                1.0 / 479001600.0 + t / 6227020800.0))))))))))))
    return p, (np.int64(k) + 1023) << 52


@njit(cache=True, fastmath=_FLAGS)
def exp_neg_many(x, n, out, ibuf, fbuf):
    """out[i] = exp(x[i]) for i < n, x[i] <= 0 (x may be out); ibuf an int64 array and
    fbuf its float64 view (``ibuf.view(np.float64)``), both at least n long."""
    for i in range(n):
        xi = x[i]
        if xi < _X_MIN:
            out[i] = 0.0
            ibuf[i] = 1023 << 52
            continue
        out[i], ibuf[i] = _exp_parts(xi)
    for i in range(n):
        out[i] *= fbuf[i]


@njit(cache=True, fastmath=_FLAGS)
def expm1_many(x, n, out, ibuf, fbuf):
    """out[i] = exp(x[i]) - 1 for i < n, 0 <= x[i] <= 700 (x may be out), to a few units in
    the last place: below 1/2 by its Taylor series to degree 16 (truncation error
    (1/2)^16 / 17! < 5e-20 relative), above it exp(x) - 1 with exp as in
    :func:`exp_neg_many` (the subtraction at most doubles the relative error of
    exp there); ibuf, fbuf as in :func:`exp_neg_many`."""
    for i in range(n):
        xi = x[i]
        out[i], ibuf[i] = _exp_parts(xi)
    for i in range(n):
        xi = x[i]
        s = xi * (1.0 + xi * (1.0 / 2.0 + xi * (1.0 / 6.0 + xi * (1.0 / 24.0 + xi * (
            1.0 / 120.0 + xi * (1.0 / 720.0 + xi * (1.0 / 5040.0 + xi * (1.0 / 40320.0 + xi * (
                1.0 / 362880.0 + xi * (1.0 / 3628800.0 + xi * (1.0 / 39916800.0 + xi * (
                    1.0 / 479001600.0 + xi * (1.0 / 6227020800.0 + xi * (
                        1.0 / 87178291200.0 + xi * (1.0 / 1307674368000.0 + xi * (
                            1.0 / 20922789888000.0))))))))))))))))
        out[i] = s if xi < 0.5 else out[i] * fbuf[i] - 1.0
