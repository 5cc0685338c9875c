"""The orders >= 3 on a subset of the table wavelengths, spread onto all of them.

Orders >= 3 are scattered at least twice: relative to order 2 they vary slowly with the
wavelength. They are computed at a subset of the table wavelengths (both ends included) and,
at every table wavelength, set to order 2's value times the ratio rho = (orders >= 3) /
(order 2) of the same node, interpolated between the two neighbouring subset wavelengths
linearly in log rho against log lambda (rho locally a power law of the wavelength, as the
Rayleigh and aerosol optical depths are); order 2, computed at every wavelength, carries the
spectral structure (ozone's Chappuis band) into the orders >= 3 (docs/models.md,
"precomputed", "Orders >= 3 at a subset of the table wavelengths").
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange


# a purely absorbing part of a row of the optical properties is line-like when it is
# below LINE_FRACTION of its largest value at more than half of the table wavelengths (water
# vapour, the oxygen bands); its table wavelengths with a vertical absorption optical depth
# above LINE_TAU are computed, never interpolated
LINE_FRACTION = 0.01
LINE_TAU = 1e-3


def subset_indices(nl, k, absorption=None, column=None, wavelengths=None):
    """(computed, nodes): the table wavelengths (of ``nl``) at which the orders >= 3 are
    computed, and among them the ``k`` interpolation nodes, spread evenly over the
    wavelengths that are not line-absorbed, the first and last of them included. Line-absorbed
    wavelengths (``absorption`` [c, l] the absorption coefficient of each row of the optical
    properties, ``column`` [c] its vertical column from the ground [m]: see ``LINE_TAU``) are
    computed too. The nodes are the wavelengths (``wavelengths`` [nm], else the indices)
    nearest to ``k`` targets evenly spread in log lambda. All of them when ``k`` is None or
    at least the count of the others."""
    every = np.arange(nl, dtype=np.int64)
    if k is None or nl <= 2:
        return every, every
    line = np.zeros(nl, dtype=bool)
    if absorption is not None:
        for a, c in zip(np.asarray(absorption, dtype=np.float64), np.asarray(column)):
            top = a.max(initial=0.0)
            if top > 0.0 and np.count_nonzero(a >= LINE_FRACTION * top) <= nl / 2:
                line |= a * c > LINE_TAU
    smooth = every[~line]
    k = int(max(k, 2))
    if smooth.size <= 2 or k >= smooth.size:
        return every, every
    # the nodes: the smooth wavelengths nearest to k targets evenly spread in log lambda
    # over them (each taken once; wl of the table: (380-780 nm) / 19 steps by default)
    x = np.log(np.asarray(wavelengths, dtype=np.float64)[smooth]) if wavelengths is not None \
        else smooth.astype(np.float64)
    free = np.ones(smooth.size, dtype=bool)
    pos = []
    for target in np.linspace(x[0], x[-1], k):
        j = int(np.argmin(np.where(free, np.abs(x - target), np.inf)))
        free[j] = False
        pos.append(j)
    nodes = smooth[np.sort(pos)]
    return np.union1d(nodes, every[line]).astype(np.int64), nodes


def band_depth(absorption, column, scattering):
    """The vertical absorption optical depth, per table wavelength, of the purely absorbing
    rows of the optical properties whose absorption is not line-like (ozone's Chappuis
    band): zeros where there is none."""
    a = np.asarray(absorption, dtype=np.float64)
    out = np.zeros(a.shape[1])
    for ac, c, sc in zip(a, np.asarray(column), np.asarray(scattering)):
        top = ac.max(initial=0.0)
        if top > 0.0 and not np.any(sc > 0.0) and \
                np.count_nonzero(ac >= LINE_FRACTION * top) > ac.size / 2:
            out += ac * c
    return out


def spread_plan(wl, computed, nodes, band=None):
    """For every table wavelength l: ``own`` its column among the computed wavelengths
    ``computed`` (-1 where it is interpolated) and ``cell`` the interval of ``nodes`` it
    lies in; the nodes' columns and table indices, their log lambda and every l's; the
    band absorber's optical depth ``band`` (:func:`band_depth`) at every l and its second
    divided differences over the nodes (zeros: no band absorber)."""
    x = np.log(np.asarray(wl, dtype=np.float64))
    col = {int(l): j for j, l in enumerate(computed)}
    own = np.array([col.get(l, -1) for l in range(x.size)], dtype=np.int64)
    cell = np.clip(np.searchsorted(nodes, np.arange(x.size)) - 1, 0, max(nodes.size - 2, 0))
    node_col = np.array([col[int(l)] for l in nodes], dtype=np.int64)
    band = np.zeros(x.size) if band is None else np.asarray(band, dtype=np.float64)
    d2 = np.zeros(max(nodes.size - 2, 0))
    second_differences(x[nodes], band[nodes], d2)
    return (own, cell.astype(np.int64), node_col, np.asarray(nodes, dtype=np.int64), x[nodes],
            x, band, d2)


@njit(cache=True)
def second_differences(x, y, out):
    """out[j] = the difference of the divided differences of (x, y) on either side of node
    j + 1."""
    for j in range(out.shape[0]):
        out[j] = ((y[j + 2] - y[j + 1]) / (x[j + 2] - x[j + 1])
                  - (y[j + 1] - y[j]) / (x[j + 1] - x[j]))


@njit(cache=True)
def pchip_slopes(x, y, d):
    """Slopes d at the nodes (x, y) of the monotone piecewise-cubic Hermite interpolant
    (Fritsch & Carlson 1980; the end slopes from the three-point formula, limited: as
    Moler, Numerical Computing with MATLAB, pchip)."""
    k = x.shape[0]
    if k == 2:
        d[0] = d[1] = (y[1] - y[0]) / (x[1] - x[0])
        return
    for j in range(1, k - 1):
        h0 = x[j] - x[j - 1]
        h1 = x[j + 1] - x[j]
        s0 = (y[j] - y[j - 1]) / h0
        s1 = (y[j + 1] - y[j]) / h1
        if s0 * s1 <= 0.0:
            d[j] = 0.0
        else:
            w1 = 2.0 * h1 + h0
            w2 = h1 + 2.0 * h0
            d[j] = (w1 + w2) / (w1 / s0 + w2 / s1)
    d[0] = _end_slope(x[1] - x[0], x[2] - x[1], (y[1] - y[0]) / (x[1] - x[0]),
                      (y[2] - y[1]) / (x[2] - x[1]))
    d[k - 1] = _end_slope(x[k - 1] - x[k - 2], x[k - 2] - x[k - 3],
                          (y[k - 1] - y[k - 2]) / (x[k - 1] - x[k - 2]),
                          (y[k - 2] - y[k - 3]) / (x[k - 2] - x[k - 3]))


@njit(cache=True)
def _end_slope(ha, hb, sa, sb):
    """pchip's end slope: the three-point formula on the end interval (width ``ha``, slope
    ``sa``) and the next (``hb``, ``sb``), set to 0 against the end interval's sign and
    limited to 3 sa where the slopes change sign."""
    v = ((2.0 * ha + hb) * sa - ha * sb) / (ha + hb)
    if v * sa <= 0.0:
        return 0.0
    if sa * sb <= 0.0 and abs(v) > 3.0 * abs(sa):
        return 3.0 * sa
    return v


@njit(cache=True, parallel=True)
def spread_ratio(base, hi, own, cell, node_col, node_l, xn, x, band, d2b, cubic, floor, out,
                 ratio=False):
    """out[n, l] += the orders >= 3 at node n and table wavelength l, from ``hi`` [n, j]
    (their value at the computed wavelengths) and ``base`` [n, l] (order 2, or order 1's
    ground irradiance, at every wavelength): at a computed wavelength its own value, else
    base[n, l] x rho, log rho = log(hi / base) interpolated in log lambda through the
    interpolation nodes (:func:`spread_plan`): monotone cubic (``cubic``) or linear, after
    taking out the band absorber's part: log rho = s(lambda) - dL band(lambda), s smooth and
    dL (the extra absorbing column of the orders >= 3, per node) the value that minimises
    the second divided differences of s over the nodes (least squares). Where
    any node's base is <= ``floor`` or its ``hi`` <= 0, the ratio is not defined or not to
    be trusted: there ``hi`` itself is interpolated linearly between the cell's two nodes
    (non-negative). ``out`` may be ``base``. ``ratio``: ``hi`` holds the ratio rho itself
    at its columns (the value: rho x base at the column's wavelength); ``own[l] == -2``:
    nothing is added at l (its value is final already)."""
    n, nl = base.shape
    k = node_col.shape[0]
    bb = 0.0
    for j in range(d2b.shape[0]):
        bb += d2b[j] * d2b[j]
    blk = 4096
    for b0 in prange((n + blk - 1) // blk):
        v = np.empty(nl)           # the node's values first: ``out`` may be ``base``
        y = np.empty(k)
        hv = np.empty(k)
        d = np.zeros(k)
        d2 = np.empty(max(k - 2, 0))
        for i in range(b0 * blk, min(n, (b0 + 1) * blk)):
            ok = True
            for j in range(k):
                bj = base[i, node_l[j]]
                hj = hi[i, node_col[j]] * bj if ratio else hi[i, node_col[j]]
                hv[j] = max(hj, 0.0)
                if bj > floor and hj > 0.0:
                    y[j] = math.log(hj / bj)
                else:
                    ok = False
            dl = 0.0
            if ok and bb > 0.0:
                second_differences(xn, y, d2)
                for j in range(d2.shape[0]):
                    dl -= d2[j] * d2b[j]
                dl /= bb
                for j in range(k):
                    y[j] += dl * band[node_l[j]]
            if ok and cubic:
                pchip_slopes(xn, y, d)
            for l in range(nl):
                if own[l] == -2:
                    v[l] = 0.0
                    continue
                if own[l] >= 0:
                    v[l] = max(hi[i, own[l]] * base[i, l] if ratio else hi[i, own[l]], 0.0)
                    continue
                c = cell[l]
                h = xn[c + 1] - xn[c]
                s = (x[l] - xn[c]) / h
                if ok:
                    if cubic:
                        s2 = s * s
                        s3 = s2 * s
                        lr = ((2.0 * s3 - 3.0 * s2 + 1.0) * y[c] + (s3 - 2.0 * s2 + s) * h * d[c]
                              + (3.0 * s2 - 2.0 * s3) * y[c + 1] + (s3 - s2) * h * d[c + 1])
                    else:
                        lr = (1.0 - s) * y[c] + s * y[c + 1]
                    v[l] = base[i, l] * math.exp(lr - dl * band[l])
                else:
                    v[l] = (1.0 - s) * hv[c] + s * hv[c + 1]
            for l in range(nl):
                out[i, l] += v[l]


# float16 in numba kernels (numba has no float16 type on the CPU): the ratio rho of the
# subset's nodes is kept as IEEE binary16 bits (uint16), read through a table of the 65536
# values and written by :func:`half_bits` (round to nearest, ties to even, as numpy's cast)


def half_table():
    """float32 value of every binary16 bit pattern (index = the bits): the exact decoding."""
    return np.arange(1 << 16, dtype=np.uint32).astype(np.uint16).view(np.float16).astype(np.float32)


@njit(cache=True)
def half_bits(u):
    """The binary16 bits (uint16) of the float32 with bits ``u`` (uint32; a finite value in
    [0, 65504]) rounded to nearest, ties to even (IEEE 754; numpy's float32 -> float16
    cast). Normal in binary16 (float32 exponent field >= 113): exponent rebiased, the 23-bit
    mantissa rounded to 10 bits (a mantissa rounded up to 2^10 carries into the exponent
    by itself); below, subnormal: the full significand (implicit bit) shifted to units of
    2^-24 and rounded the same way."""
    u = np.uint32(u)
    e = np.int64((u >> np.uint32(23)) & np.uint32(0xFF))
    m = np.int64(u & np.uint32(0x7FFFFF))
    if e >= 113:
        h = ((e - 112) << 10) | (m >> 13)
        rem = m & 0x1FFF
        if rem > 0x1000 or (rem == 0x1000 and (h & 1) == 1):
            h += 1
        return np.uint16(h)
    if e == 0:
        return np.uint16(0)        # zero, or a float32 subnormal (< 2^-126): rounds to 0
    m |= 0x800000
    sh = 126 - e                   # >= 14
    if sh > 25:
        return np.uint16(0)        # below half the smallest binary16 subnormal
    h = m >> sh
    rem = m & ((1 << sh) - 1)
    half = 1 << (sh - 1)
    if rem > half or (rem == half and (h & 1) == 1):
        h += 1
    return np.uint16(h)


# rows per work item of add_shares
SHARE_BLOCK = 4096


@njit(cache=True, parallel=True)
def add_shares(Jo, cols, dst, node, jf, rho, table, top):
    """One order's J of a batch of the computed wavelengths (``Jo`` [row, column], on the
    summed density's grid) over every row: column c = cols[m] added into jf[:, dst[m]]
    where node[m] < 0; else its share of order 2 at that wavelength, s = Jo[row, c] /
    jf[row, dst[m]] (0 where order 2 is 0), added to the float16 ratio ``rho`` [node[m],
    row] (binary16 bits, decoded by ``table`` = :func:`half_table`): the float32 sum
    min(rho + s, top), rounded to binary16 once (:func:`half_bits`). One pass over the
    rows of the summed density (its columns are strided), in blocks of rows."""
    n = jf.shape[0]
    for b in prange((n + SHARE_BLOCK - 1) // SHARE_BLOCK):
        i0 = b * SHARE_BLOCK
        i1 = min(n, i0 + SHARE_BLOCK)
        t = np.empty(1, dtype=np.float32)
        tu = t.view(np.uint32)
        for i in range(i0, i1):
            for m in range(cols.shape[0]):
                v = Jo[i, cols[m]]
                l = dst[m]
                k = node[m]
                if k < 0:
                    jf[i, l] += v
                else:
                    d = jf[i, l]
                    s = np.float32(v / d) if d > 0.0 else np.float32(0.0)
                    t[0] = min(np.float32(table[rho[k, i]] + s), top)
                    rho[k, i] = half_bits(tu[0])


@njit(cache=True, parallel=True)
def half_rows(rho, table, a, out):
    """out[i, k] = the float32 value of the binary16 bits rho[k, a + i] (``table`` =
    :func:`half_table`): the ratio of rows a .. a + out.shape[0] - 1, transposed."""
    for i in prange(out.shape[0]):
        for k in range(out.shape[1]):
            out[i, k] = table[rho[k, a + i]]
