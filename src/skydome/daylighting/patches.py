"""Tregenza and Reinhart sky patches with Radiance's geometry and order.

Reinhart's subdivision MF:n of Tregenza's 145 patches [T87] [R09]: 7 n rows of equal altitude
width alpha = 90 deg / (7 n + 0.5) from the horizon up, with n x (30, 30, 24, 24, 18, 12, 6)
patches per original band, and a zenith cap of half a row's width. The order is that of
Radiance's reinhart.cal and gendaymtx: patch 0 is the ground (the whole lower hemisphere),
then row by row from the horizon up, in each row from north (the first patch is centred on
azimuth 0) towards east, and last the zenith cap. MF:1 is Tregenza's 145 patches (146 with
the ground); MF:n has 144 n^2 + 2.

Patch values are means over each patch, integrated with a tensor Gauss-Legendre rule of order
q in sin(altitude) (in which the solid angle element is uniform: dOmega = d(sin a) d(phi)) and
in azimuth; the zenith cap uses q Gauss-Legendre nodes in sin(altitude) times 6 q equally
spaced azimuths (periodic trapezoid rule). Order q integrates a patch mean of a polynomial in
sin(altitude) of degree <= 2 q - 1 exactly. ``order=0`` takes gendaymtx's single point per
patch (altitude and azimuth at the patch's centre, the zenith for the cap) with the patch's
solid angle as weight: point sampling, as Radiance does.

References
----------
.. [T87] P. R. Tregenza, "Subdivision of the sky hemisphere for luminance measurements",
   Lighting Research & Technology 19(1) 13-14 (1987).
.. [R09] C. F. Reinhart, "Tutorial on the use of Daysim simulations for sustainable design"
   (2006-2010); G. Ward, Radiance ``reinhart.cal`` and ``gendaymtx.c`` (rh_init), Radiance 5.4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = ["PatchSet", "patches", "AdaptiveRule", "tiered_nodes", "TREGENZA_BAND_COUNTS"]

#: Patches per Tregenza band from the horizon up (the zenith cap not counted) [T87].
TREGENZA_BAND_COUNTS = (30, 30, 24, 24, 18, 12, 6)
MAX_MF = 12


@dataclass(frozen=True, eq=False)
class PatchSet:
    """A sky subdivision: ground patch 0, sky patches 1..n-1 (Radiance's order).

    Attributes (sky patches are entries 1..n-1; entry 0 is the ground)
    ----------
    name : str
        "tregenza" or "reinhart:MF".
    mf : int
        Reinhart subdivision (1 = Tregenza).
    altitude_low_rad, altitude_high_rad : numpy.ndarray
        Altitude bounds [rad] (ground: -pi/2, 0).
    azimuth_centre_rad, azimuth_half_width_rad : numpy.ndarray
        Azimuth of the centre (from north towards east) and half width [rad] (cap: 0, pi).
    centre_altitude_rad : numpy.ndarray
        gendaymtx's centre altitude (row's mid altitude; pi/2 for the cap; -pi/2 ground).
    solid_angle_sr : numpy.ndarray
        2 pi (sin a_hi - sin a_lo) / n_row [sr] (ground 2 pi).
    """

    name: str
    mf: int
    altitude_low_rad: np.ndarray
    altitude_high_rad: np.ndarray
    azimuth_centre_rad: np.ndarray
    azimuth_half_width_rad: np.ndarray
    centre_altitude_rad: np.ndarray
    solid_angle_sr: np.ndarray

    def __len__(self) -> int:
        return int(self.solid_angle_sr.shape[0])

    @property
    def n_sky(self) -> int:
        """Number of sky patches (without the ground)."""
        return len(self) - 1

    @property
    def centres(self) -> np.ndarray:
        """gendaymtx's patch directions (n, 3), ENU unit vectors; the ground's is (0, 0, -1)."""
        return _vector(self.centre_altitude_rad, self.azimuth_centre_rad)

    def nodes(self, order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Quadrature nodes over the sky patches (computed once per set and order, cached).

        Returns
        -------
        directions : numpy.ndarray
            (n_nodes, 3) ENU unit vectors, patch after patch.
        weights : numpy.ndarray
            (n_nodes,) [sr]; each patch's weights sum to its solid angle.
        offsets : numpy.ndarray
            (n_sky + 1,) int: sky patch k (patch index k + 1) owns nodes offsets[k]:offsets[k+1].
        """
        return _nodes(self.name, int(order))

    def patch_of(self, directions) -> np.ndarray:
        """Index of the patch that holds each direction (..., 3) (0 below the horizon),
        as reinhart.cal's ``rbin``."""
        d = np.asarray(directions, dtype=np.float64)
        alt = np.degrees(np.arcsin(np.clip(d[..., 2], -1.0, 1.0)))
        azi = np.degrees(np.arctan2(d[..., 0], d[..., 1])) % 360.0
        alpha = 90.0 / (7 * self.mf + 0.5)
        row = np.floor(alt / alpha).astype(np.int64)
        counts = _row_counts(self.mf)
        first = np.concatenate([[1], 1 + np.cumsum(counts)])  # first index of each row
        rowc = np.clip(row, 0, len(counts) - 1)
        nrow = counts[rowc]
        inc = 360.0 / nrow
        col = np.floor((azi + 0.5 * inc) / inc).astype(np.int64) % nrow
        idx = first[rowc] + col
        idx = np.where(row >= len(counts), len(self) - 1, idx)
        return np.where(alt < 0.0, 0, idx)


def _vector(alt, azi) -> np.ndarray:
    alt, azi = np.broadcast_arrays(alt, azi)
    ca = np.cos(alt)
    return np.stack([ca * np.sin(azi), ca * np.cos(azi), np.sin(alt)], axis=-1)


def _row_counts(mf: int) -> np.ndarray:
    return np.repeat(np.asarray(TREGENZA_BAND_COUNTS) * mf, mf)


def patches(spec: str = "tregenza") -> PatchSet:
    """The patch set named by ``spec``: "tregenza" (= "reinhart:1"), "reinhart:MF" with MF in
    1..12 (also "mf:MF")."""
    if not isinstance(spec, str):
        raise TypeError(f"patches must be a string such as 'tregenza' or 'reinhart:4', got "
                        f"{spec!r}")
    s = spec.strip().lower()
    if s in ("tregenza", "reinhart", "reinhart:1", "mf:1"):
        return _patches(1)
    for prefix in ("reinhart:", "mf:"):
        if s.startswith(prefix):
            tail = s[len(prefix):]
            if tail.isdigit() and 1 <= int(tail) <= MAX_MF:
                return _patches(int(tail))
    raise ValueError(f"patches = {spec!r} is unknown; use 'tregenza' or 'reinhart:MF' with MF "
                     f"in [1, {MAX_MF}]")


@lru_cache(maxsize=None)
def _patches(mf: int) -> PatchSet:
    alpha = (math.pi / 2.0) / (7 * mf + 0.5)  # gendaymtx rh_init: row width
    counts = _row_counts(mf)
    # per row (each value in the same float operations as a scalar loop over the patches,
    # which took 0.011 s of a command line's start-up at MF:4), then one entry per patch:
    # the ground first, the zenith cap last
    lo = [alpha * i for i in range(len(counts))]
    hi = [alpha * (i + 1) for i in range(len(counts))]
    row_w = [2.0 * math.pi * (math.sin(h) - math.sin(a)) / n for a, h, n in zip(lo, hi, counts)]
    j = np.concatenate([np.arange(n, dtype=np.float64) for n in counts])  # index in the row
    n_of = np.repeat(counts, counts).astype(np.float64)

    def per_patch(ground, rows, cap):
        rows = np.repeat(np.asarray(rows, np.float64), counts)
        return np.concatenate([[ground], rows, [cap]])

    alo = per_patch(-math.pi / 2, lo, math.pi / 2 - 0.5 * alpha)
    ahi = per_patch(0.0, hi, math.pi / 2)
    azc = np.concatenate([[0.0], 2.0 * math.pi * j / n_of, [0.0]])
    azh = per_patch(math.pi, [math.pi / n for n in counts], math.pi)
    calt = per_patch(-math.pi / 2, [alpha * (i + 0.5) for i in range(len(counts))], math.pi / 2)
    dom = per_patch(2.0 * math.pi, row_w, 2.0 * math.pi * (1.0 - math.cos(0.5 * alpha)))
    arr = [np.ascontiguousarray(v) for v in (alo, ahi, azc, azh, calt, dom)]
    for a in arr:
        a.setflags(write=False)
    name = "tregenza" if mf == 1 else f"reinhart:{mf}"
    return PatchSet(name, mf, *arr)


@lru_cache(maxsize=32)
def _nodes(name: str, order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    ps = patches(name)
    if order < 0 or order > 16:
        raise ValueError(f"order = {order} is out of range [0, 16]")
    if order == 0:
        d = ps.centres[1:]
        w = ps.solid_angle_sr[1:].copy()
        offsets = np.arange(ps.n_sky + 1)
        return _frozen(d, w, offsets)
    n_rows = len(_row_counts(ps.mf)) + 1
    return _row_rule(name, (order,) * n_rows, (order,) * n_rows)


def _frozen(d, w, offsets):
    d = np.ascontiguousarray(d)
    w = np.ascontiguousarray(w)
    offsets = np.ascontiguousarray(offsets, dtype=np.int64)
    for a in (d, w, offsets):
        a.setflags(write=False)
    return d, w, offsets


@lru_cache(maxsize=32)
def _row_rule(name: str, q_alt: tuple, q_az: tuple) -> tuple[np.ndarray, np.ndarray,
                                                               np.ndarray]:
    """Nodes of a rule with q_alt[i] x q_az[i] Gauss-Legendre nodes in (sin a, phi) on each
    patch of row i, and q_alt x 6 q_az (periodic trapezoid in azimuth) on the zenith cap
    (the last entry); nodes of a patch altitude-major (runs of equal altitude)."""
    ps = patches(name)
    counts = _row_counts(ps.mf)
    sl = slice(1, None)
    slo = np.sin(ps.altitude_low_rad[sl])
    shi = np.sin(ps.altitude_high_rad[sl])
    azc = ps.azimuth_centre_rad[sl]
    azh = ps.azimuth_half_width_rad[sl]
    first = np.concatenate([[0], np.cumsum(counts)])
    parts_d, parts_w, sizes = [], [], []
    for i in range(len(counts) + 1):
        qa, qz = int(q_alt[i]), int(q_az[i])
        xa, wxa = np.polynomial.legendre.leggauss(qa)
        u, wu = 0.5 * (xa + 1.0), 0.5 * wxa  # on [0, 1]
        if i < len(counts):  # ring patches: tensor rule in (sin a, phi)
            ring = slice(first[i], first[i + 1])
            xz, wxz = np.polynomial.legendre.leggauss(qz)
            s = slo[ring, None] + (shi - slo)[ring, None] * u[None, :]  # (p, qa)
            ws = (shi - slo)[ring, None] * wu[None, :]
            h = azh[ring]
            phi = azc[ring, None] + h[:, None] * xz[None, :]  # (p, qz)
            wp = h[:, None] * wxz[None, :]
            p_n, m = counts[i], qz
        else:  # zenith cap: qa nodes in sin a times 6 qz azimuths (periodic trapezoid)
            m = 6 * qz
            s = (slo[-1] + (shi[-1] - slo[-1]) * u)[None, :]
            ws = ((shi[-1] - slo[-1]) * wu)[None, :]
            phi = (2.0 * math.pi * (np.arange(m) + 0.5) / m)[None, :]
            wp = np.full(m, 2.0 * math.pi / m)[None, :]
            p_n = 1
        d = _vector(np.arcsin(s)[:, :, None], phi[:, None, :]).reshape(p_n, qa * m, 3)
        w = (ws[:, :, None] * wp[:, None, :]).reshape(p_n, qa * m)
        parts_d.append(d.reshape(-1, 3))
        parts_w.append(w.reshape(-1))
        sizes.append(np.full(p_n, qa * m))
    offsets = np.concatenate([[0], np.cumsum(np.concatenate(sizes))])
    return _frozen(np.concatenate(parts_d), np.concatenate(parts_w), offsets)


@dataclass(frozen=True)
class AdaptiveRule:
    """A patch quadrature that spends nodes where the Perez integrand needs them.

    Three rules, chosen each hour for each patch by the angle between the sun and the
    patch's nearest point (its centre's angle to the sun less the patch's angular radius,
    the angle from its centre to its farthest corner):

    - within ``near_angle_deg``: ``near_order`` x ``near_order`` Gauss-Legendre nodes (the
      circumsolar peak and the cusp of exp(d gamma) at the sun);
    - within ``mid_angle_deg``: ``mid_order`` x ``mid_order``;
    - elsewhere: ``far_order`` nodes in sin(altitude) x ``far_az_order`` in azimuth.

    In the rows whose lower altitude is below ``horizon_deg``, where the gradation term
    1 + a exp(b / cos zeta) changes fastest, every rule takes at least ``horizon_order``
    nodes in sin(altitude). The zenith cap takes q_alt x 6 q_az nodes as in
    :meth:`PatchSet.nodes`. The defaults (:meth:`default_for`) are chosen against order 16
    over the sample year (docs/daylighting.md, section 2).
    """

    near_order: int = 8
    near_angle_deg: float = 5.0
    mid_order: int = 3
    mid_angle_deg: float = 10.0
    far_order: int = 2
    far_az_order: int = 2
    horizon_order: int = 4
    horizon_deg: float = 6.0

    @classmethod
    def default_for(cls, ps: "PatchSet") -> "AdaptiveRule":
        """The default rule of a patch set: the class defaults for Reinhart MF >= 2; for
        Tregenza's 12-degree patches finer rules (near 12, mid 4, far 3 x 3, horizon 10),
        which its cusp patch and horizon row need to stay within 0.1 % of order 16."""
        if ps.mf == 1:
            return cls(near_order=12, mid_order=4, far_order=3, far_az_order=3,
                       horizon_order=10)
        return cls()

    def __post_init__(self):
        for name in ("near_order", "mid_order", "far_order", "far_az_order", "horizon_order"):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or not 1 <= v <= 16:
                raise ValueError(f"{name} = {v!r} must be an integer in [1, 16]")
        for name, hi in (("near_angle_deg", 180.0), ("mid_angle_deg", 180.0),
                         ("horizon_deg", 90.0)):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or not 0.0 <= v <= hi:
                raise ValueError(f"{name} = {v!r} must be a number in [0, {hi:g}]")

    def nodes(self, ps: "PatchSet"):
        """(nodes, weights, offsets (3, n_sky + 1), cos_tier (3, n_sky)) of the near, mid and
        far rules (see :func:`tiered_nodes`)."""
        n_rows = len(_row_counts(ps.mf)) + 1
        alpha = 90.0 / (7 * ps.mf + 0.5)
        low = np.append(alpha * np.arange(n_rows - 1), 90.0) < self.horizon_deg
        rules = []
        for qa, qz in ((self.near_order,) * 2, (self.mid_order,) * 2,
                       (self.far_order, self.far_az_order)):
            q_alt = tuple(max(qa, self.horizon_order) if lo else qa for lo in low)
            rules.append((q_alt, (qz,) * n_rows))
        return tiered_nodes(ps.name, tuple(rules), (self.near_angle_deg, self.mid_angle_deg))


@lru_cache(maxsize=16)
def tiered_nodes(name: str, rules: tuple, angles_deg: tuple):
    """Several rules over the same patches, for a kernel that picks one per patch and hour.

    ``rules``: T pairs (q_alt per row, q_az per row) (see :func:`_row_rule`; the last entry
    of each tuple is the zenith cap); ``angles_deg``: T - 1 angles: rule t < T - 1 applies
    where the sun is within angles_deg[t] of the patch's nearest point. Returns nodes (M,
    3), weights (M,) [sr], offsets (T, n_sky + 1) into them, cos_tier (T, n_sky) (the
    cosine of the angle from the patch centre below which rule t does not apply; -2 for
    the last rule, which applies everywhere else)."""
    ps = patches(name)
    parts = [_row_rule(name, qa, qz) for qa, qz in rules]
    starts = np.cumsum([0] + [p[0].shape[0] for p in parts[:-1]])
    offsets = np.stack([p[2] + s0 for p, s0 in zip(parts, starts)])
    radius = np.degrees(_patch_radius(name))
    cos_tier = np.full((len(rules), ps.n_sky), -2.0)
    for t, ang in enumerate(angles_deg):
        cos_tier[t] = np.cos(np.radians(np.minimum(ang + radius, 180.0)))
    d, w, o = _frozen(np.concatenate([p[0] for p in parts]),
                      np.concatenate([p[1] for p in parts]), offsets)
    cos_tier.setflags(write=False)
    return d, w, o, cos_tier


@lru_cache(maxsize=None)
def _patch_radius(name: str) -> np.ndarray:
    """Angle [rad] from each sky patch's centre (gendaymtx's) to its farthest corner."""
    ps = patches(name)
    sl = slice(1, None)
    c = ps.centres[sl]
    r = np.zeros(ps.n_sky)
    for alt in (ps.altitude_low_rad[sl], ps.altitude_high_rad[sl]):
        for sign in (-1.0, 1.0):
            corner = _vector(alt, ps.azimuth_centre_rad[sl] + sign * ps.azimuth_half_width_rad[sl])
            cosang = np.clip(np.sum(corner * c, axis=-1), -1.0, 1.0)
            r = np.maximum(r, np.arccos(cosang))
    r[-1] = math.pi / 2 - ps.altitude_low_rad[-1]  # the zenith cap: its rim
    r.setflags(write=False)
    return r
