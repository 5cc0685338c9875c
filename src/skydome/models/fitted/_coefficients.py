"""The coefficient file of the ``fitted`` model and the angular tables built from it.

The representation (written by tools/fit_fitted.py from the data set of
tools/fitted_dataset.py):

For every node (AOD a_i, albedo b_j, sun elevation e_k, altitude h_l, wavelength w_m) the
reference's radiance per unit extraterrestrial irradiance L [sr^-1] on the view grid is
stored as

    y = ln(L / s + DELTA),   s = the mean of L over the sky part of the grid,

and y over the grid's directions is a low-rank expansion in an angular basis of its own
sun-elevation node,

    y(direction) = mean_k(direction) + sum_n c_n(a_i, b_j, e_k, h_l, w_m) B_kn(direction),

the basis B_k and mean_k from a truncated singular value decomposition of every y of that
elevation node (every atmosphere, altitude and wavelength), the sky and the ground apart
(``K_SKY`` and ``K_GROUND`` terms). The coefficients c themselves are stored, per sun
node, as spectral terms (``tools/fit_fitted.py --spectral-rank``, the shipped file 24):

    c_n(a_i, b_j, e_k, h_l, w_m) = M_k(w_m) + sum_q A_q,n(a_i, b_j, e_k, h_l) V_kq(w_m),

M_k and V_k from a truncated singular value decomposition along the wavelength of every
(atmosphere, altitude, term) row of that node (:func:`_coefficients_mixed` expands the
few nodes a configuration reads; a file may also hold c per
wavelength). A configuration
between the nodes (:func:`stencil`,
the degrees in :data:`ELEMENT_ORDER`, chosen on the held-out grid):

* at each AOD and albedo node, c and ln s cubic in altitude (four nodes) at the four
  elevation nodes around the sun's elevation, then y and ln s cubic in elevation (ln s:
  the sky's brightness, which falls by orders of magnitude per degree in twilight, is
  interpolated in its logarithm), L = s (exp(y) - DELTA);
* in AOD (:func:`aod_stencil`), quadratic in sqrt(AOD): with the sun above the horizon up
  to 0.1 L over the nodes up to 0.1 (0, 0.0125, 0.025, 0.05, 0.075, 0.1), above ln L over
  the nodes from 0.1 up (0.1, 0.15, 0.25, 0.35, 0.5, 0.75, 1); with the sun below -1 deg
  ln L; between -1 and 0 deg the two blended linearly; with the sun above the horizon and
  the AOD below the second node above 0 (0.025), the thin-haze form L = (a + b tau)
  exp(-c tau) through the nodes 0, 0.0125, 0.025 (:func:`thin_haze_form`);
* between the albedo nodes 0, 1/2 and 1 the radiance follows the form of a Lambertian
  ground under a scattering atmosphere,

    L(b) = L_0 + b G / (1 - b S)

(G: the light reflected once by a white ground and scattered to the eye; S: the share of
the ground's light that the atmosphere sends back down, the atmosphere's spherical albedo
seen from below), whose G and S the three nodes determine (S clamped to [0, 0.95]).

The sun's disc is not part of this fit: Beer's law over the columns along the ray to the
sun, as the reference computes it (:mod:`._sun`; its arrays are in the same file).
"""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import numpy as np

from skydome.models.fitted import _grid

#: The coefficient file shipped with the package.
COEFFICIENT_FILE = Path(__file__).parent / "data" / "fitted_coefficients.npz"

#: Offset of the logarithm (relative to the mean sky radiance).
DELTA = 1e-3
#: Floor of L [sr^-1] where ln L is interpolated (in AOD).
TINY = 1e-30


@functools.lru_cache(maxsize=2)
def load(path: str | None = None) -> dict:
    """The coefficient arrays (loaded once, on first use)."""
    p = Path(path) if path is not None else COEFFICIENT_FILE
    if not p.is_file():
        raise FileNotFoundError(f"the fitted model's coefficient file {p.name} is missing "
                                "(make it with tools/fit_fitted.py)")
    with np.load(p, allow_pickle=False) as z:
        out = {k: z[k] for k in z.files}
    out["meta"] = json.loads(str(out["meta"]))
    # a file written with --float16: each row of coefficients and each basis vector over
    # its largest magnitude, the scales beside them. The bases are scaled here; the
    # coefficients (17.7 M) stay in float16 and are scaled where a configuration reads its
    # few nodes (:func:`_coefficients_mixed`): the first model 276-361 ms instead of 442-452
    # (docs/performance.md, "The fitted model with 14 altitude nodes")
    for key in ("sky_basis", "ground_basis"):
        scale = out.pop(key + "_scale", None)
        if scale is not None:
            out[key] = out[key].astype(np.float32) * scale[..., None]
    return out


def _rows(c: dict, name: str, i: int, j: int, ks: list, h: int) -> np.ndarray:
    """``c[name][i, j, ks, h]`` in float32, scaled where the file stores it in float16 with a
    scale per row (``name + "_scale"``)."""
    v = c[name][i, j, ks, h]
    scale = c.get(name + "_scale")
    return v if scale is None else v.astype(np.float32) * scale[i, j, ks, h][..., None]


def _coefficients_mixed(c: dict, key: str, i: int, j: int, ks: list, stencil) -> np.ndarray:
    """sum of w c[key][i, j, ks, h] over the altitude stencil [(h, w)] (``coef_sky`` or
    ``coef_ground``: (len(ks), wavelengths, terms)). A file fitted with ``--spectral-rank
    K`` holds them as K spectral terms per sun node (``key + "_amp"``, ``_spec``,
    ``_spec_mean``: :func:`spectral_factors`); the amplitudes are mixed first and expanded
    once (the expansion is linear)."""
    if key + "_amp" not in c:
        return sum(w * _rows(c, key, i, j, ks, h) for h, w in stencil)
    a = sum(w * _rows(c, key + "_amp", i, j, ks, h) for h, w in stencil)   # (len(ks), K, T)
    w_sum = sum(w for _, w in stencil)
    return expand_spectral(a, c[key + "_spec"][ks], w_sum * c[key + "_spec_mean"][ks])


def spectral_factors(coef: np.ndarray, rank: int):
    """The coefficients ``coef`` (A, B, E, H, W, T: AOD, albedo, sun node, altitude,
    wavelength, term) as ``rank`` spectral terms per sun node E: (amplitudes (A, B, E, H,
    rank, T), spectral vectors (E, rank, W), mean spectra (E, W), relative RMS of the
    truncation), coef ~ :func:`expand_spectral` of them: the singular value decomposition
    along the wavelength of the rows (a, b, h, t) of each sun node, their mean removed
    first, truncated to its first ``rank`` terms (tools/fit_fitted.py --spectral-rank;
    docs/models.md, "fitted", "The spectral terms")."""
    A, B, E, H, W, T = coef.shape
    dt = np.result_type(coef.dtype, np.float32)        # float32 from the fit's float32
    amp = np.empty((A, B, E, H, rank, T), dtype=dt)
    spec = np.empty((E, rank, W), dtype=dt)
    mean = np.empty((E, W), dtype=dt)
    sq = tot = 0.0
    for e in range(E):
        X = np.moveaxis(coef[:, :, e], 3, -1).reshape(-1, W).astype(np.float64)
        m = X.mean(axis=0)
        U, S, Vt = np.linalg.svd(X - m, full_matrices=False)
        P = U[:, :rank] * S[:rank]                                  # rows x rank
        amp[:, :, e] = np.moveaxis(P.reshape(A, B, H, T, rank), -1, 3)
        spec[e], mean[e] = Vt[:rank], m
        sq += float(np.sum((X - m - P @ Vt[:rank]) ** 2))
        tot += float(np.sum(X ** 2))
    return amp, spec, mean, float(np.sqrt(sq / max(tot, 1e-300)))


def expand_spectral(amp: np.ndarray, spec: np.ndarray, mean: np.ndarray) -> np.ndarray:
    """mean + sum_k amp[..., k, t] spec[..., k, w]: (..., W, T) from amplitudes (..., K, T),
    spectral vectors (..., K, W) and mean spectra (..., W) (leading axes broadcast)."""
    return np.einsum("...kt,...kw->...wt", amp, spec) + mean[..., :, None]


def bracket(nodes: np.ndarray, x: float) -> tuple[int, float]:
    """(i, f): x = (1 - f) nodes[i] + f nodes[i + 1], x clamped to the nodes' span."""
    n = nodes.size
    if n == 1:
        return 0, 0.0
    x = min(max(float(x), float(nodes[0])), float(nodes[-1]))
    i = int(np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, n - 2))
    return i, (x - float(nodes[i])) / (float(nodes[i + 1]) - float(nodes[i]))


def stencil(nodes: np.ndarray, x: float, order: int = 1) -> list[tuple[int, float]]:
    """[(node index, weight)]: Lagrange interpolation of degree ``order`` (1 linear, 2
    quadratic, 3 cubic) at x over the ``order + 1`` nodes around it (the stencil shifted
    inside the nodes at their ends; quadratic: the third node on the side x is nearer);
    x clamped to the nodes' span; cubic becomes quadratic in the first and last intervals.
    The weights sum to 1 and reproduce the node values at the nodes."""
    nodes = np.asarray(nodes, dtype=np.float64)
    i, f = bracket(nodes, x)
    if order <= 1 or nodes.size <= 2:
        return [(i, 1.0 - f), (i + 1, f)]
    order = min(order, nodes.size - 1)
    if order == 3 and (i == 0 or i == nodes.size - 2):
        # the first and last intervals: quadratic (a cubic stencil there is off-centred and
        # bends the deep-twilight ground between -12 and -11 deg away from the geometric
        # interpolation of engine bakes; measured on the held-out grid: docs/models.md)
        order = 2
    x = float(nodes[i] + f * (nodes[i + 1] - nodes[i]))
    if order == 2:
        lo = i - 1 if (f < 0.5 and i > 0) or i + 2 >= nodes.size else i
    else:
        lo = min(max(i - (order - 1) // 2, 0), nodes.size - order - 1)
    return lagrange(nodes, range(lo, lo + order + 1), x)


def lagrange(nodes: np.ndarray, idx, x: float) -> list[tuple[int, float]]:
    """[(node index, weight)]: the Lagrange weights at x over the nodes ``nodes[idx]``."""
    out = []
    for p in idx:
        w = 1.0
        for q in idx:
            if q != p:
                w *= (x - nodes[q]) / (nodes[p] - nodes[q])
        out.append((p, w))
    return out


#: The offset c [deg] of the variable ln(e + c) in which, at the clear AOD nodes (up to
#: :data:`LOG_ELEVATION_AOD_MAX`), the elevation stencils that read the node at 0 deg (a sun
#: between 0 and the node above 0 deg) are Lagrange's: :func:`elevation_stencil`.
ELEVATION_LOG_OFFSET_DEG = 2.0
#: The offset c [deg] at the clearest AOD nodes (below :data:`CLEAREST_AOD_BELOW`: pure air
#: and 0.00625), where the node at 0 deg departs most from the risen sun's sky:
#: :func:`elevation_log_offset`.
ELEVATION_LOG_OFFSET_CLEAREST_DEG = 0.5
CLEAREST_AOD_BELOW = 0.0125
#: The largest AOD node whose elevation stencil is taken in ln(e + c) (the hazier nodes
#: keep it in e): :func:`elevation_log_offset`.
LOG_ELEVATION_AOD_MAX = 0.1


def elevation_log_offset(aod_node: float) -> float | None:
    """The offset c [deg] of :func:`elevation_stencil`'s variable ln(e + c) at the AOD node
    ``aod_node``, or None (the stencil in e). In the clearest air the sky next to the horizon
    of a sun between 0 and 2 deg is mostly light scattered once along long paths that the
    sun's disc lights through the air next to the ground, and at the node 0 deg half the disc
    is below that horizon: that node's sky is darker than the smooth curve through the
    risen sun's, and a cubic in e bends through it. In a thicker haze the light near the
    horizon is scattered many times and the node at 0 deg bends a cubic in e less than one
    in ln(e + 2 deg) overshoots. Measured with the model itself at a sun of 0.5 and 1.5 deg
    against the reference computed there, at node atmospheres (albedo 0.5, 0-3 km; none
    of the held-out grid; ``tools/fitted_horizon_diagnosis.py measure``): ln(e + 2 deg)
    lowered the largest error at AOD 0 from 8.0 to 5.8 %, at 0.0125 and 0.05 from 2.4 to
    2.0 % at most, at 0.075 and 0.1 from 7.1 to 4.9 % at most, and raised it at AOD 0.15
    on the ground from 1.9 to 5.3 % (from 0.25 up little change either way): hence the
    nodes up to 0.1 (docs/models.md, "fitted", "The elevation interval 0-2 deg in clear
    air").

    With the sun node at 0.5 deg the stencil reads 0, 0.5, 1, 2 deg for a sun between 0 and
    1 deg, and at the two clearest nodes (AOD 0 and 0.00625) c = 0.5 deg: the reference's
    own values interpolated so ("elevation alone", albedo 0.5, suns 0.25 and 0.75 deg, 0 and
    350 m; node atmospheres only) were at AOD 0 0.45 / 7.8 % (largest RMS / max, luminance
    more than 5 deg from the sun) with c = 2 deg and 0.38 / 6.0 % with 0.5 deg, at 0.00625
    0.26 / 4.1 and 0.27 / 3.3 %; at 0.0125, 0.05 and 0.1 c = 2 deg stayed the better
    (0.14 / 1.9, 0.06 / 0.3, 0.15 / 1.1 %; with 0.5 deg 0.22 / 1.9, 0.28 / 1.2, 0.30 / 2.0
    %): docs/models.md, "fitted", "The sun node at 0.5 deg"."""
    if aod_node < CLEAREST_AOD_BELOW - 1e-12:
        return ELEVATION_LOG_OFFSET_CLEAREST_DEG
    return ELEVATION_LOG_OFFSET_DEG if aod_node <= LOG_ELEVATION_AOD_MAX + 1e-12 else None


def elevation_stencil(nodes: np.ndarray, elevation_deg: float,
                      log_offset_deg: float | None = None) -> list[tuple[int, float]]:
    """[(node index, weight)] of the sun elevation: :func:`stencil` of degree
    ``ELEMENT_ORDER["elevation"]`` (cubic), but with the sun above the horizon no node below
    it: where the stencil of a sun between 0 deg and the next node reaches below 0 deg, the
    nodes from 0 deg up (0, 0.5, 1, 2 deg; 0, 1, 2, 3.5 deg on the nodes of the files
    before the node at 0.5 deg: one-sided, through the node at 0). A sun below
    the horizon lights the sky next to it only from below the horizon, so the node at -1
    deg bends the cubic through the aureole of a sun at 0.5 deg: on the reference itself
    (AOD 0.15, albedo 0.5, 2 km, all nodes but the sun; ``tools/fitted_horizon_diagnosis.py``,
    "elevation alone"), y and ln s cubic over -1, 0, 1, 2 deg are 0.93 / 7.5 % (RMS / max,
    luminance, more than 5 deg from the sun) off at 0.5 deg, over 0, 1, 2, 3.5 deg 0.29 /
    1.6 % (docs/models.md, "fitted", "The elevation interval 0-1 deg").

    With ``log_offset_deg`` = c (:func:`elevation_log_offset`: the clear AOD nodes), where
    the stencil reads the node at 0 deg with the sun above it (a sun between 0 and 1 deg:
    the nodes 0, 0.5, 1, 2; between 0 and 2 deg over the nodes 0, 1, 2, 3.5 of the files
    before), the weights are Lagrange's in x = ln(e + c), not in e. On the
    reference itself ("elevation alone") at the node atmospheres AOD 0, 0.0125, 0.05 and
    0.25 (albedo 0.5; 0, 1.1 and 3 km), at 0.5 deg: mean RMS 0.27 -> 0.21 %, largest 8.7 ->
    6.2 %; at 1.5 deg 0.14 -> 0.08 %, 2.7 -> 1.3 % (c chosen there among 1.25-6 deg). The
    weights still reproduce the nodes, so nothing steps at 0 or 2 deg."""
    nodes = np.asarray(nodes, dtype=np.float64)
    st = stencil(nodes, elevation_deg, ELEMENT_ORDER["elevation"])
    if elevation_deg > 0.0 and nodes[st[0][0]] < 0.0:
        k0 = int(np.searchsorted(nodes, 0.0))
        if k0 < nodes.size and nodes[k0] == 0.0:
            n = len(st)
            x = min(float(elevation_deg), float(nodes[-1]))
            st = lagrange(nodes, range(k0, min(k0 + n, nodes.size)), x)
    if log_offset_deg is not None and elevation_deg > 0.0 and nodes[st[0][0]] == 0.0:
        idx = [k for k, _ in st]
        c = float(log_offset_deg)
        logs = np.full(nodes.size, np.nan)
        logs[idx] = np.log(nodes[idx] + c)
        st = lagrange(logs, idx, math.log(float(elevation_deg) + c))
    return st


def aod_stencil(aod_nodes: np.ndarray, aod: float, twilight: bool = False
                ) -> tuple[list[tuple[int, float]], str]:
    """(stencil, how) over the AOD nodes: ``how`` "L" or "lnL", quadratic in sqrt(AOD) in L or
    ln L (the choices measured on the held-out grid: docs/models.md, "fitted", "The AOD
    between its nodes"), or "form": :func:`thin_haze_form` through the stencil's three
    nodes 0, h, 2 h at t = AOD / h (its weights: L quadratic in AOD, the form's own
    fallback where a node value is 0).

    Sun above the horizon, AOD between 0 and 0.025 (:data:`THIN_HAZE_MAX`), where the
    nodes from 0 up double (0, 0.00625, 0.0125, 0.025): the thin-haze form through 0 and the
    two nodes around the AOD (:func:`thin_haze_interval`: through 0, 0.00625, 0.0125 below
    0.0125, through 0, 0.0125, 0.025 above; t = AOD / h in (0, 2)). Near the horizon the
    radiance is far from linear in the first 0.025 of AOD: along a grazing path of 30-100
    air masses that much aerosol already makes the path's aerosol optical depth 1-2, so
    that its light rises and then saturates (on the ground, sun at 4
    deg, 1.45 deg above the horizon under the sun, 560 nm: 0.050, 0.225, 0.320, 0.375 sr^-1
    at AOD 0, 0.0125, 0.025, 0.05); a quadratic in sqrt(AOD) through the nodes 0, 0.025,
    0.05 was 10-16 % off at AOD 0.0125 and 30-50 % at 0.005 there, the form through them
    still 6-25 % at 0.003-0.0125 seen from 2.2 km; with the node at 0.0125 the form through
    0, 0.0125, 0.025 is 1.3-9.4 % at most at 0.003-0.009 and 2.1 % at 0.018, where L
    quadratic in sqrt(AOD) through 0.0125, 0.025, 0.05 was 2.3 % (docs/models.md,
    "fitted", "The AOD nodes at 0.0125 and 0.075"); with the node at 0.00625 too, the form
    through 0, 0.00625, 0.0125 is 1.9 % at most at 0.003 and 0.7 % at 0.009 ("The AOD node
    at 0.00625").

    Sun above the horizon: up to :data:`LINEAR_AOD_MAX` (0.1) L itself, over the nodes up
    to it (in a thin haze the aerosol's light grows nearly in proportion to its optical
    depth, which ln L would turn into a geometric mean); above it ln L over the nodes from
    0.1 up (a thick haze attenuates the long paths near the horizon exponentially). Sun
    below the horizon (``twilight``): ln L (the twilight sky is light attenuated along
    long grazing paths, and falls by orders of magnitude between the AOD nodes). sqrt(AOD)
    as the coordinate: the sky changes fastest with the first aerosol, and the AOD nodes
    (0, 0.00625, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.25, 0.35, 0.5, 0.75, 1) are
    0.03-0.16 apart in it."""
    nodes = np.asarray(aod_nodes, dtype=np.float64)
    order = ELEMENT_ORDER["aod"]
    x = math.sqrt(max(aod, 0.0))
    if twilight:
        return stencil(np.sqrt(nodes), x, order), "lnL"
    k = thin_haze_interval(nodes, aod)
    if k:
        # the form through 0, h, 2 h (h = nodes[k]) at t = AOD / h in [1, 2) (in (0, 2)
        # for k = 1); the weights: L quadratic in AOD over the three nodes
        return lagrange(nodes, (0, k, k + 1), float(aod)), "form"
    # the last node of the thin-haze part: the node at LINEAR_AOD_MAX (at least the third)
    n_thin = max(3, int(np.searchsorted(nodes, LINEAR_AOD_MAX + 1e-12)))
    if nodes.size <= n_thin or aod <= float(nodes[n_thin - 1]):
        return stencil(np.sqrt(nodes[:n_thin]), x, order), "L"
    k = n_thin - 1
    return [(i + k, w) for i, w in stencil(np.sqrt(nodes[k:]), x, order)], "lnL"


def thin_haze_interval(nodes: np.ndarray, aod: float) -> int:
    """k > 0 where the day sky at ``aod`` follows the thin-haze form through the nodes 0,
    h = nodes[k], 2 h = nodes[k + 1] (:func:`aod_stencil`), else 0: for 0 < AOD <
    THIN_HAZE_MAX, the smallest k with AOD < nodes[k + 1] where the nodes from 0 to nodes[k
    + 1] double each time (0, h, 2 h for k = 1; 0, h/2, h, 2 h for k = 2). Each interval
    between two such nodes is read by the form through 0 and the two nodes around it (t =
    AOD / h in (0, 2) for k = 1, [1, 2) above): every form passes through its three nodes,
    so the rule is continuous at the node where it changes. A file whose nodes are 0,
    0.025, 0.05 keeps its rule (the form below 0.025 only, t < 1)."""
    nodes = np.asarray(nodes, dtype=np.float64)
    if nodes.size < 3 or nodes[0] != 0.0 or not 0.0 < aod < THIN_HAZE_MAX:
        return 0
    for k in range(1, nodes.size - 1):
        if abs(nodes[k + 1] - 2.0 * nodes[k]) > 1e-12:
            return 0
        if aod < nodes[k + 1]:
            return k
    return 0


def thin_haze_form(L0: np.ndarray, L1: np.ndarray, L2: np.ndarray, t: float) -> np.ndarray:
    """L at tau = t h (0 <= t <= 2) from its values L0, L1, L2 >= 0 at tau = 0, h, 2 h.

    The light scattered by a thin haze along a path grows in proportion to its optical
    depth tau and is attenuated as exp(-m tau) along the path (m its air mass): L = (a +
    b tau) exp(-c tau), c of either sign. Through the three values (q = exp(-c h)): a = L0,
    and q the root of L0 q^2 - 2 L1 q + L2 = 0 nearer 1, q = L2 / (L1 + sqrt(D)), D = L1^2 -
    L0 L2, which gives L(t h) = L0 (1 - t) q^t + L1 t q^(t - 1) (exact for L linear in tau:
    q = 1; and for L exponential in tau: D = 0). Where D < 0 (ln L convex in tau) no such
    form passes through the three: ln L quadratic in tau there, which meets it at D = 0
    (both then exponential), so the result is continuous in the values. Where L1 or L2 is
    not positive (the clamp's zeros), L quadratic in tau. Each form passes through the three
    values at t = 0, 1, 2."""
    shape = np.broadcast(L0, L1, L2).shape
    L0, L1, L2 = (np.broadcast_to(np.asarray(v, dtype=np.float64), shape).ravel()
                  for v in (L0, L1, L2))
    lag = ((t - 1.0) * (t - 2.0) / 2.0, -t * (t - 2.0), t * (t - 1.0) / 2.0)
    out = lag[0] * L0 + lag[1] * L1 + lag[2] * L2          # L quadratic in tau
    D = L1 * L1 - L0 * L2
    pos = (L0 >= 0.0) & (L1 > 0.0) & (L2 > 0.0)     # D < 0 implies L0 > 0 too
    m = pos & (D >= 0.0)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        a, b, c = L0[m], L1[m], L2[m]
        q = c / (b + np.sqrt(D[m]))                  # > 0: L2 > 0, L1 + sqrt(D) > 0
        # L0 (1 - t) q^t + L1 t q^(t - 1), one logarithm and one exponential
        v = (a * (1.0 - t) * q + b * t) * np.exp((t - 1.0) * np.log(q))
        out[m] = np.where(np.isfinite(v), v, out[m])
        m = pos & (D < 0.0)
        v = np.exp(lag[0] * np.log(L0[m]) + lag[1] * np.log(L1[m]) + lag[2] * np.log(L2[m]))
        out[m] = np.where(np.isfinite(v), v, out[m])
    return np.maximum(out, 0.0).reshape(shape)


def apply_aod_stencil(aod_nodes, aod: float, st, how: str, value_at) -> np.ndarray:
    """L at ``aod`` from the values ``value_at(i)`` at the AOD nodes of the stencil ``st``
    (:func:`aod_stencil`'s ``(st, how)``): the thin-haze form, ln L or L combined with the
    stencil's weights (L clamped at 0)."""
    if how == "form":
        return thin_haze_form(*(value_at(i) for i, _ in st),
                              aod / float(np.asarray(aod_nodes)[st[1][0]]))
    in_log = how == "lnL"
    acc = 0.0
    for i, wi in st:
        if wi != 0.0:
            v = value_at(i)
            acc = acc + wi * (np.log(np.maximum(v, TINY)) if in_log else v)
    return np.exp(acc) if in_log else np.maximum(acc, 0.0)


#: Below this AOD (and below the third AOD node) the day sky follows the thin-haze form
#: (:func:`aod_stencil`); above it, between 0.025 and 0.05, the form through 0, 0.025,
#: 0.05 was measured no better than L quadratic in sqrt(AOD) (0.0375: 4.5 against 4.1 % at
#: most on the reference itself; docs/models.md, "fitted", "The AOD nodes at 0.0125 and
#: 0.075"). A file without the node at 0.0125 keeps its rule: the form below 0.025 only.
THIN_HAZE_MAX = 0.025
#: Up to this AOD (a node) the day sky is interpolated in L, above it in ln L.
LINEAR_AOD_MAX = 0.1


#: Degrees of the interpolation between nodes (measured on the held-out grid:
#: docs/models.md, "fitted"): y and ln s cubic in sun elevation, coefficients and ln s
#: cubic in altitude, L or ln L quadratic in sqrt(AOD).
ELEMENT_ORDER = {"elevation": 3, "altitude": 3, "aod": 2}
#: Between these sun elevations [deg] the day and twilight AOD interpolations are blended
#: linearly (no step at sunset).
AOD_BLEND_DEG = (-1.0, 0.0)


def ground_altitude_stencil(nodes: np.ndarray, altitude_m: float) -> list[tuple[int, float]]:
    """The altitude stencil of the ground's coefficients: as the sky's, but from the first
    node above the ground up the ground node (h = 0) is left out. From the ground the view
    below the horizon is the ground at the observer's feet, with no air in front of it (for
    a black ground y = ln(DELTA), about -6.9), a limit the ground seen from above does not
    approach smoothly; in a cubic stencil its small weight (-0.046 at 600 m over the nodes
    0, 350, 700, 1100 m) times that gap made the ground seen from 400-700 m too bright: 19-26 %
    just below the horizon at AOD 0.7, up to 39-56 % at single directions at AOD 0.07
    (docs/models.md, "fitted", "The ground seen from above between the altitude nodes")."""
    nodes = np.asarray(nodes, dtype=np.float64)
    order = ELEMENT_ORDER["altitude"]
    if nodes.size < 3 or nodes[0] != 0.0 or altitude_m < nodes[1]:
        return stencil(nodes, altitude_m, order)
    return [(p + 1, w) for p, w in stencil(nodes[1:], altitude_m, order)]


def radiance_grid(c: dict, aod: float, albedo: float, elevation_deg: float,
                  altitude_m: float) -> np.ndarray:
    """The radiance per unit extraterrestrial irradiance [sr^-1] of a configuration on the
    view grid at the table wavelengths: (N_SKY + N_GROUND, N_PHI, n_wl), >= 0."""
    lo, hi = AOD_BLEND_DEG
    f = min(max((elevation_deg - lo) / (hi - lo), 0.0), 1.0)    # 1: day, 0: twilight
    parts = [(w, aod_stencil(c["aod_nodes"], aod, tw)) for w, tw in ((f, False),
                                                                     (1.0 - f, True))
             if w > 0.0]
    # the stencil in e (None) and, at the clear AOD nodes, the same nodes with the weights
    # in ln(e + c), c per AOD node (elevation_log_offset)
    offsets = {None} | {elevation_log_offset(float(a)) for a in c["aod_nodes"]}
    st_by = {off: elevation_stencil(c["elevation_nodes_deg"], elevation_deg, off)
             for off in offsets}
    st_h = stencil(c["altitude_nodes_m"], altitude_m, ELEMENT_ORDER["altitude"])
    st_hg = ground_altitude_stencil(c["altitude_nodes_m"], altitude_m)
    ks = [k for k, _ in st_by[None]]          # the same nodes in every st_by, other weights
    weights = {off: np.array([w for _, w in st]) for off, st in st_by.items()}
    # near the sun each elevation node's sky is read where it stands to its own sun as the
    # grid's directions stand to this one (:func:`turned_reads`); elsewhere at the grid's
    # own directions
    turns = [turned_reads(elevation_deg, float(c["elevation_nodes_deg"][k]), altitude_m)
             for k in ks]
    turned = any(t is not None for t in turns)
    # the bases of the stencil's elevation nodes stacked: one product per AOD node (the
    # last stack kept for the next configuration, most often at the same nodes and, away
    # from the turned range, at any sun between them)
    key = (tuple(ks), (round(float(elevation_deg), 12), round(float(altitude_m), 9))
           if turned else None)
    last = c.get("_stacked")
    if last is None or last[0] != key:
        sky_b = [c["sky_basis"][k] for k in ks]
        sky_m = [c["sky_mean"][k].astype(np.float64) for k in ks]
        for n, t in enumerate(turns):
            if t is not None:
                sky_b[n] = _read_turned(sky_b[n].T, *t).T
                sky_m[n] = _read_turned(sky_m[n], *t)
        last = c["_stacked"] = (key, (
            np.concatenate(sky_b).astype(np.float32),
            np.concatenate([c["ground_basis"][k] for k in ks]).astype(np.float32)),
            np.stack(sky_m))
    basis_sky, basis_ground = last[1]
    means = {off: (np.einsum("k,kd->d", we, last[2]),
                   np.einsum("k,kd->d", we, c["ground_mean"][ks].astype(np.float64)))
             for off, we in weights.items()}
    cache: dict = {}

    def at_node(i, j):
        """L at AOD node i, albedo node j, interpolated in elevation and altitude."""
        if (i, j) not in cache:
            off = elevation_log_offset(float(c["aod_nodes"][i]))
            we = weights[off]
            mean_sky, mean_ground = means[off]
            # coefficients and ln s of each elevation node, interpolated in altitude
            cs = _coefficients_mixed(c, "coef_sky", i, j, ks, st_h)          # (k, wl, n)
            cg = _coefficients_mixed(c, "coef_ground", i, j, ks, st_hg)
            log_s = we @ sum(wh * c["log_scale"][i, j, ks, h] for h, wh in st_h)
            # (wl, k n) in float32: y to 1e-7, far below the fit's residual
            cs = np.concatenate(list(we[:, None, None] * cs), axis=-1).astype(np.float32)
            cg = np.concatenate(list(we[:, None, None] * cg), axis=-1).astype(np.float32)
            y = np.concatenate([mean_sky + cs @ basis_sky, mean_ground + cg @ basis_ground],
                               axis=1)
            cache[i, j] = np.exp(log_s)[:, None] * np.maximum(np.exp(y) - DELTA, 0.0)
        return cache[i, j]

    per_albedo = []
    for j in range(c["albedo_nodes"].size):
        total = 0.0
        for wp, (st_a, how) in parts:
            total = total + wp * apply_aod_stencil(c["aod_nodes"], aod, st_a, how,
                                                   lambda i: at_node(i, j))
        per_albedo.append(total)
    L = albedo_form(c["albedo_nodes"], per_albedo, albedo)
    n_wl = c["wavelengths_nm"].size
    out = np.ascontiguousarray(L.T.reshape(_grid.N_SKY + _grid.N_GROUND, _grid.N_PHI, n_wl))
    # the zenith (the sky's last row) and the nadir (the ground's) are one direction each:
    # their azimuth columns, equal but for the float32 rounding of the basis products
    # (about 1e-8 relative), are made one value, so that any azimuth reads the same there
    for row in (_grid.N_SKY - 1, _grid.N_SKY + _grid.N_GROUND - 1):
        out[row] = out[row].mean(axis=0)
    return out


#: The sun-relative reading of the elevation nodes (:func:`turned_reads`): fully turned
#: within ``gamma_deg[0]`` of the sun, not at all beyond ``gamma_deg[1]``; only where the
#: direction and its turned image both stand more than ``above_horizon_deg[1]`` above the
#: observer's horizon (none below ``above_horizon_deg[0]``); for suns above ``sun_deg[1]``
#: (none below ``sun_deg[0]``; the nodes 19 and 25 deg and above them are 6-15 deg apart), where the
#: aureole of one node lies next to the 5-deg circle of a sun between them. Linear ramps
#: between the ends; chosen on the held-out grid (docs/models.md, "fitted", "The aureole
#: between the elevation nodes").
TURN = {"gamma_deg": (8.0, 20.0), "above_horizon_deg": (2.0, 8.0), "sun_deg": (19.0, 25.0)}


def turned_reads(elevation_deg: float, node_deg: float, altitude_m: float):
    """Where the sky of the elevation node ``node_deg`` is read for a sun at
    ``elevation_deg``: None (at the grid's own nodes), or (index (n, 4), weight (n, 4),
    keep (n,)) over the N_SKY x N_PHI sky nodes: value = keep x own + sum weight x node
    values at index.

    The aureole moves with the sun, so between elevation nodes it is interpolated where it
    stands relative to each node's sun: each grid direction is turned about the horizontal
    axis normal to the sun's vertical plane by node_deg - elevation_deg (which takes this
    sun onto the node's and keeps the scattering angle), and the node's sky is read there
    (bilinear, the lookup's inverse mappings of :mod:`._grid`). Away from the sun and near
    the horizon the sky is shaped by the view's zenith angle rather than by the scattering
    angle: there the nodes are read in place (weights :data:`TURN`)."""
    s_lo, s_hi = TURN["sun_deg"]
    strength = min(max((elevation_deg - s_lo) / (s_hi - s_lo), 0.0), 1.0)
    delta = math.radians(node_deg - elevation_deg)
    if strength == 0.0 or delta == 0.0:
        return None
    theta_h, th, x, y, z, gamma = _sky_geometry(float(elevation_deg), float(altitude_m))
    x2 = x * math.cos(delta) - z * math.sin(delta)
    z2 = x * math.sin(delta) + z * math.cos(delta)
    th2 = np.arctan2(np.hypot(x2, y), z2)
    ph2 = np.arctan2(np.abs(y), x2)
    above = np.degrees(theta_h - np.maximum(th, th2))     # both above the horizon by
    g0, g1 = TURN["gamma_deg"]
    a0, a1 = TURN["above_horizon_deg"]
    w = (strength * np.clip((g1 - gamma) / (g1 - g0), 0.0, 1.0)
         * np.clip((above - a0) / (a1 - a0), 0.0, 1.0))
    # the turned directions in the sky grid (the kernel's inverse mappings)
    iu, it, fu, ft = _grid.sky_cell(th2, ph2, theta_h)
    k0 = iu * _grid.N_PHI + it
    idx = np.stack([k0, k0 + 1, k0 + _grid.N_PHI, k0 + _grid.N_PHI + 1], axis=1)
    wt = np.stack([(1 - fu) * (1 - ft), (1 - fu) * ft, fu * (1 - ft), fu * ft], axis=1)
    return idx, wt * w[:, None], 1.0 - w


@functools.lru_cache(maxsize=4)
def _sky_geometry(elevation_deg: float, altitude_m: float):
    """(theta_h, th, x, y, z, gamma): the horizon's zenith angle, the sky grid's nodes'
    zenith angles and unit vectors (the sun's vertical plane x-z, the sun at +x) and their
    angles from a sun at ``elevation_deg`` [deg], for :func:`turned_reads`, which reads the
    four elevation nodes of a configuration at the same (sun, altitude): computed once for
    them (read-only arrays)."""
    theta_h = _grid.horizon_zenith_rad(altitude_m)
    sky, _ = _grid.theta_nodes_rad(altitude_m)
    phi = _grid.phi_nodes_rad()
    th = np.repeat(sky, phi.size)
    ph = np.tile(phi, sky.size)
    x = np.sin(th) * np.cos(ph)
    y = np.sin(th) * np.sin(ph)
    z = np.cos(th)
    e = math.radians(elevation_deg)
    gamma = np.degrees(np.arccos(np.clip(x * math.cos(e) + z * math.sin(e), -1.0, 1.0)))
    for a in (th, x, y, z, gamma):
        a.flags.writeable = False
    return theta_h, th, x, y, z, gamma


def _read_turned(values: np.ndarray, idx, wt, keep) -> np.ndarray:
    """values (n, ...) over the sky nodes read as :func:`turned_reads` says."""
    v = np.asarray(values, dtype=np.float64)
    ext = (slice(None),) + (None,) * (v.ndim - 1)
    out = keep[ext] * v
    for j in range(4):
        out = out + wt[:, j][ext] * v[idx[:, j]]
    return out


def albedo_form(nodes, values, albedo: float) -> np.ndarray:
    """The radiance at ground albedo ``albedo`` from its values at the albedo nodes 0, 1/2,
    1: L(b) = L_0 + b G / (1 - b S) (module docstring), solved for G and S per element."""
    if not (len(nodes) == 3 and np.allclose(nodes, [0.0, 0.5, 1.0])):
        raise ValueError("the albedo form needs the albedo nodes 0, 0.5, 1")
    L0, Lh, L1 = values
    d1 = Lh - L0                     # = G / (2 - S)
    d2 = L1 - L0                     # = G / (1 - S)
    # d2 / d1 = (2 - S) / (1 - S) = r  ->  S = (r - 2) / (r - 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(d1 > 0.0, d2 / np.where(d1 > 0.0, d1, 1.0), 2.0)
        S = np.clip(np.where(r > 2.0, (r - 2.0) / (r - 1.0), 0.0), 0.0, 0.95)
    G = d2 * (1.0 - S)
    b = float(albedo)
    return np.maximum(L0 + b * G / (1.0 - b * S), 0.0)
