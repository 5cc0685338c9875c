"""``dobashi1995``: fast sky colour from basis functions (Dobashi, Nishita, Kaneda, Yamashita 1995).

A wrapper over any other spectral (or XYZ) model. The sky is precomputed for a set of sun
altitudes; the dome is divided into slices of constant elevation (rings), and on every
ring the intensity as a function of the azimuth phi measured from the sun is expressed by
a cosine (Fourier) series ([DNKY95] sec. 3; survey sec. 7.4, figs. 11-12)

    I(theta_r, phi; alpha) = sum_{n=0}^{N_r - 1} a_n(theta_r, alpha) cos(n phi)

(the sky is symmetric about the sun's vertical plane, so no sine terms), with N_r the
smallest number of terms for which the reconstruction error on the ring stays within
``max_error`` ([DNKY95]'s criterion for the minimum number of cosine functions, survey
figs. 12-13). For any sun altitude the paper interpolates the coefficients linearly
between the two nearest precomputed altitudes and the intensity linearly in elevation
between rings; this implementation uses cubic (Catmull-Rom / Hermite) interpolation for
both by default (``ring_interpolation="linear"`` restores the paper's rings), which cuts
the error about threefold for the same table. Evaluation runs in numba kernels: either the
series per ray, each ring summed over its own number of terms, or (default) a ring x azimuth
grid of the series built once per sun and wavelength grid and interpolated per ray.

References
----------
[DNKY95] Dobashi, Y., Nishita, T., Kaneda, K., Yamashita, H. 1995. A fast display method of
    sky colour using basis functions. Pacific Graphics '95; J. Visualization and Computer
    Animation 8(3), 115-127 (1997).
[KRZ06] Kment, Rauter & Zotti, Modelling of Daylight for Computer Graphics, sec. 7.4.
"""

from __future__ import annotations

import math

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_int, check_number
from skydome.models import Parameter, SkyModel, get_model_class, register

__all__ = ["Dobashi1995", "Dobashi1995Sky"]


@register
class Dobashi1995(SkyModel):
    """Cosine-series (basis function) representation of another model's sky [DNKY95].

    Parameters
    ----------
    sun : skydome.Sun
        Sun position; elevation within [``min_sun_elevation_deg``, 90] deg.
    base : str
        Registered name of the model to represent (default "nishita1996"); it must
        compute radiance (native "spectral" or "xyz").
    max_error : float
        Largest relative reconstruction error allowed on every ring [0.0001, 1]
        (default 0.01): the number of cosine terms per ring is the smallest that meets it
        (up to ``azimuth_samples``). Between sun altitudes the coefficients are
        interpolated by Catmull-Rom splines.
    sun_altitudes : int
        Precomputed sun altitudes, equally spaced over [min_sun_elevation_deg, 90]
        ([2, 91], default 19: every 5 deg from 0).
    rings : int
        Elevation slices over [-90, 90] deg, denser near the horizon ([5, 181], default 65).
        The defaults are the smallest of the tried settings that keep the error against
        the base under 1 % in every direction (single_scattering base, sun between grid
        altitudes; 10 altitudes and 33 rings: p95 2.4 %, max 8.3 % near the sun).
    azimuth_samples : int
        Samples per ring over [0, 180] deg relative to the sun ([4, 720], default 64).
    min_sun_elevation_deg : float
        Lowest precomputed sun altitude [deg], [-20, 80] (default 0), and the lowest sun
        the model accepts. It may not lie below the base model's valid sun range (e.g. 0 deg
        for ``preetham1999``): that fails at construction, naming this parameter.
    ring_interpolation : {"cubic", "linear"}
        Interpolation of the intensity between rings in elevation: cubic Hermite with
        finite-difference slopes over four rings (default; a deviation from the paper, which
        interpolates linearly, that cuts the error of the default 33 rings by about 3x), or
        ``linear`` between the two nearest rings, as [DNKY95].
    evaluation : {"grid", "series"}
        ``series``: the cosine series is summed for every ray (each ring with its own number
        of terms). ``grid`` (default): once per sun and wavelength grid, the series of every
        ring is evaluated at 721 azimuths (0.25 deg steps) from the sun, and rays interpolate
        that ring x azimuth grid (linearly in azimuth), like the paper's display step,
        which evaluates the basis functions at the vertices of the dome's mesh and
        interpolates between them. Cost per ray no longer grows with the number of terms;
        the difference from ``series`` is below 0.2 % (see docs).
    **base_params
        Passed to the base model.
    """

    name = "dobashi1995"
    reference = ("Dobashi, Nishita, Kaneda & Yamashita 1995, A fast display method of sky colour "
                 "using basis functions, Pacific Graphics '95")
    native = "spectral"
    own_ground = "sun_and_sky"            # its default base's; an instance takes its base's
    summary = "Any model's sky as cosine series per elevation ring, interpolated in sun altitude."
    parameters = (
        Parameter("base", "", "nishita1996", doc="registered name of the model represented",
                  kind="object"),
        Parameter("max_error", "", 0.01, 1e-4, 1.0, "largest relative error per ring"),
        Parameter("sun_altitudes", "", 19, 2, 91, "precomputed sun altitudes", kind="int"),
        Parameter("rings", "", 65, 5, 181, "elevation slices over [-90, 90] deg", kind="int"),
        Parameter("azimuth_samples", "", 64, 4, 720, "samples per ring over [0, 180] deg",
                  kind="int"),
        Parameter("min_sun_elevation_deg", "deg", 0.0, -20.0, 80.0, "lowest precomputed sun altitude"),
        Parameter("ring_interpolation", "", "cubic", doc="interpolation between rings in elevation",
                  kind="choice", choices=("cubic", "linear")),
        Parameter("evaluation", "", "grid", doc="per-ray cosine series or ring x azimuth grid",
                  kind="choice", choices=("grid", "series")),
    )

    #: Azimuths of the evaluation grid over [0, 180] deg from the sun (0.25 deg steps).
    GRID_AZIMUTHS = 721

    #: With the default ``min_sun_elevation_deg`` = 0; that parameter lowers it (to -20 deg
    #: at most, and not below the base model's own range).
    sun_elevation_range_deg = (0.0, 90.0)

    def __init__(self, sun, base: str = "nishita1996", **params):
        from skydome.sun import Sun

        if not isinstance(sun, Sun):
            raise TypeError(f"sun must be a skydome.Sun, not {type(sun).__name__}")
        own = {p.name for p in self.parameters}
        mine = {k: v for k, v in params.items() if k in own}
        base_params = {k: v for k, v in params.items() if k not in own}
        if not isinstance(base, str):
            raise TypeError(f"base must be a model name (str), not {type(base).__name__}")
        if base == self.name:
            raise ValueError("base = 'dobashi1995' is not allowed (a model cannot wrap itself)")
        cls = get_model_class(base)
        if cls.native == "luminance":
            raise ValueError(f"base = {base!r} is luminance-only; dobashi1995 needs a model "
                             "with radiance (native 'spectral' or 'xyz')")
        cls._validate_params(base_params)     # fail early on the base's parameters
        mine["base"] = base
        p = self._validate_params(mine)
        lo = p["min_sun_elevation_deg"]
        base_lo = cls.sun_elevation_range_deg[0] if cls.sun_outside_range == "raise" else -90.0
        if lo < base_lo:
            raise ValueError(f"min_sun_elevation_deg = {lo:g} deg is out of range "
                             f"[{base_lo:g}, 90] deg for base = {base!r} (its valid sun range)")
        check_number("sun.elevation_deg", sun.elevation_deg, lo, 90.0, "deg")
        self.sun = sun
        self.base = base
        self.base_params = base_params
        # below the horizon it represents its base's ground (capabilities, skydome.models)
        self.own_ground = cls.own_ground
        self.observer_altitude_m = float(base_params.get("observer_altitude_m") or 0.0)
        self.max_error = p["max_error"]
        self.sun_altitudes = p["sun_altitudes"]
        self.rings = p["rings"]
        self.azimuth_samples = p["azimuth_samples"]
        self.min_sun_elevation_deg = lo
        self.ring_interpolation = p["ring_interpolation"]
        self.evaluation = p["evaluation"]
        self._tables: dict = {}
        self._grids: dict = {}

    # -- grids ------------------------------------------------------------------------------
    def sun_grid_deg(self) -> np.ndarray:
        """Precomputed sun altitudes [deg]."""
        return np.linspace(self.min_sun_elevation_deg, 90.0, self.sun_altitudes)

    def ring_elevations_deg(self) -> np.ndarray:
        """Ring elevations [deg]: 90 sign(w) w^2, w uniform in [-1, 1] (dense at the horizon)."""
        w = np.linspace(-1.0, 1.0, self.rings)
        return 90.0 * np.sign(w) * w * w

    def azimuths_deg(self) -> np.ndarray:
        """Azimuths relative to the sun sampled on every ring [deg] (cell centres)."""
        return (np.arange(self.azimuth_samples) + 0.5) * 180.0 / self.azimuth_samples

    # -- precomputation ---------------------------------------------------------------------
    def table(self, wavelengths_nm) -> dict:
        """The precomputed representation for a wavelength grid: coefficients
        ``coef`` (n_sun, n_rings, n_terms_max, n_lambda), ``terms`` (n_sun, n_rings), the
        reconstruction error per ring ``error`` and the sample radiance ``samples``."""
        wl = as_wavelengths(wavelengths_nm)
        key = tuple(np.round(wl, 9))
        if key not in self._tables:
            if len(self._tables) > 2:
                self._tables.clear()
            self._tables[key] = self._precompute(wl)
        return self._tables[key]

    def _precompute(self, wl):
        from skydome._progress import report
        from skydome.sun import Sun
        from skydome.transport.geometry import direction_from_angles

        el = self.ring_elevations_deg()
        az = self.azimuths_deg()
        E, A = np.meshgrid(el, az, indexing="ij")
        dirs = direction_from_angles(E, A)          # sun at azimuth 0
        m = az.size
        phi = np.radians(az)
        n_all = np.arange(m)
        basis = np.cos(np.outer(n_all, phi))        # (n, m)
        cls = get_model_class(self.base)
        samples = []
        grid = self.sun_grid_deg()
        for k, alt in enumerate(grid):
            sky = cls(sun=Sun(elevation_deg=float(alt), azimuth_deg=0.0), **self.base_params)
            L = np.asarray(sky.radiance(dirs, wl), dtype=np.float64)
            samples.append(np.maximum(np.nan_to_num(L, nan=0.0, posinf=0.0), 0.0))
            report("dobashi1995: sky table", k + 1, len(grid))
        S = np.stack(samples)                        # (ns, nr, m, nl)
        # cosine-series coefficients by the discrete cosine transform on the cell centres
        coef_full = np.einsum("nm,srml->srnl", basis, S) * (2.0 / m)
        coef_full[:, :, 0] *= 0.5
        ns, nr = S.shape[:2]
        terms = np.zeros((ns, nr), dtype=np.int64)
        err = np.zeros((ns, nr))
        for i in range(ns):
            for r in range(nr):
                ref = S[i, r]                         # (m, nl)
                scale = np.maximum(np.abs(ref), 1e-3 * max(np.abs(ref).max(), 1e-300))
                partial = np.zeros_like(ref)
                for n in range(m):
                    partial += np.outer(basis[n], coef_full[i, r, n])
                    e = float(np.max(np.abs(partial - ref) / scale)) if ref.any() else 0.0
                    if e <= self.max_error or n == m - 1:
                        terms[i, r] = n + 1
                        err[i, r] = e
                        break
        nmax = int(terms.max())
        coef = coef_full[:, :, :nmax].copy()
        for i in range(ns):
            for r in range(nr):
                coef[i, r, terms[i, r]:] = 0.0
        return dict(coef=coef, terms=terms, error=err, samples=S, wl=wl,
                    memory_bytes=int(terms.sum()) * wl.size * 8)

    # -- evaluation -------------------------------------------------------------------------
    def _coefficients(self, wl):
        """Coefficients for the actual sun altitude, (n_rings, n_terms_max, n_lambda), and
        the number of non-zero terms per ring (n_rings,)."""
        t = self.table(wl)
        coef = t["coef"]
        # interpolate coefficients in sun altitude
        grid = self.sun_grid_deg()
        a = float(np.clip(self.sun.elevation_deg, grid[0], grid[-1]))
        i = int(min(np.searchsorted(grid, a, side="right") - 1, grid.size - 2))
        f = (a - grid[i]) / (grid[i + 1] - grid[i])
        # Catmull-Rom (cubic Hermite) interpolation between the two nearest altitudes
        # (deviation: the paper interpolates linearly; the cubic halves the error)
        used = (max(i - 1, 0), i, i + 1, min(i + 2, grid.size - 1))
        p0, p1, p2, p3 = (coef[k] for k in used)
        m1 = 0.5 * (p2 - p0) if i > 0 else p2 - p1
        m2 = 0.5 * (p3 - p1) if i + 2 < grid.size else p2 - p1
        f2, f3 = f * f, f * f * f
        c = ((2 * f3 - 3 * f2 + 1) * p1 + (f3 - 2 * f2 + f) * m1 + (-2 * f3 + 3 * f2) * p2
             + (f3 - f2) * m2)                                      # (nr, n, nl)
        # beyond the largest count among the altitudes used, a ring's coefficients are 0
        n_terms = t["terms"][list(used)].max(axis=0).astype(np.int64)
        return c, n_terms

    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] from the cosine series, shape
        (..., n_wavelengths); never negative.

        Evaluated by a numba kernel (parallel over rays for large batches) that sums, on
        each ring around a ray, only that ring's own number of cosine terms;
        :meth:`_radiance_reference` is the same sum in numpy over all terms.
        """
        from skydome.models.simulated import _kernels_dobashi1995 as K

        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        cubic = self.ring_interpolation == "cubic"
        az = math.radians(self.sun.azimuth_deg)
        if self.evaluation == "grid":
            out = K.evaluate_grid(d.reshape(-1, 3), self._ring_grid(wl),
                                  self.ring_elevations_deg(), az, cubic)
        else:
            c, n_terms = self._coefficients(wl)
            out = K.evaluate(d.reshape(-1, 3), c, n_terms, self.ring_elevations_deg(), az,
                             cubic)
        return out.reshape(d.shape[:-1] + (wl.size,))

    def _ring_grid(self, wl):
        """Every ring's cosine series (at the actual sun altitude) evaluated at
        ``GRID_AZIMUTHS`` azimuths over [0, 180] deg from the sun, (n_rings, n_az, n_lambda);
        cached per wavelength grid."""
        from skydome.models.simulated import _kernels_dobashi1995 as K

        key = tuple(np.round(wl, 9))
        if key not in self._grids:
            if len(self._grids) > 2:
                self._grids.clear()
            c, n_terms = self._coefficients(wl)
            self._grids[key] = K.ring_table(np.ascontiguousarray(c), n_terms,
                                            self.GRID_AZIMUTHS)
        return self._grids[key]

    def _ring_weights(self, elev):
        """numpy form of the ring interpolation: lowest ring index j - 1 of the four rings
        j-1..j+2 and their weights, (N,) and (N, 4)."""
        rings = self.ring_elevations_deg()
        nr = rings.size
        j = np.clip(np.searchsorted(rings, elev, side="right") - 1, 0, nr - 2)
        e1, e2 = rings[j], rings[j + 1]
        h = e2 - e1
        t = np.clip((elev - e1) / h, 0.0, 1.0)
        w = np.zeros(elev.shape + (4,))
        if self.ring_interpolation == "linear":
            w[:, 1], w[:, 2] = 1.0 - t, t
            return j - 1, w
        t2, t3 = t * t, t * t * t
        h00, h10 = 2 * t3 - 3 * t2 + 1, t3 - 2 * t2 + t          # cubic Hermite basis
        h01, h11 = -2 * t3 + 3 * t2, t3 - t2
        w[:, 1], w[:, 2] = h00, h01
        first, last = j == 0, j + 2 >= nr
        s1 = np.where(first, 0.0, h10 * h / (e2 - rings[np.maximum(j - 1, 0)]))
        w[:, 0] -= s1
        w[:, 2] += np.where(first, h10, s1)
        w[:, 1] -= np.where(first, h10, 0.0)
        s2 = np.where(last, 0.0, h11 * h / (rings[np.minimum(j + 2, nr - 1)] - e1))
        w[:, 3] += s2
        w[:, 1] -= np.where(last, h11, s2)
        w[:, 2] += np.where(last, h11, 0.0)
        return j - 1, w

    def _radiance_reference(self, directions, wavelengths_nm) -> np.ndarray:
        """numpy reference implementation of :meth:`radiance` (all terms on every ring)."""
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        c, _ = self._coefficients(wl)
        flat = d.reshape(-1, 3)
        elev = np.degrees(np.arcsin(np.clip(flat[:, 2], -1.0, 1.0)))
        az = np.arctan2(flat[:, 0], flat[:, 1]) - math.radians(self.sun.azimuth_deg)
        cphi = np.cos(az)
        # cos(n phi) by the Chebyshev recurrence: T (n_terms, N)
        n_terms = c.shape[1]
        T = np.empty((n_terms, cphi.size))
        T[0] = 1.0
        if n_terms > 1:
            T[1] = cphi
        for n in range(2, n_terms):
            T[n] = 2.0 * cphi * T[n - 1] - T[n - 2]
        j0, w = self._ring_weights(elev)
        nr = c.shape[0]
        out = np.zeros((flat.shape[0], wl.size))
        for q in range(4):
            r = np.clip(j0 + q, 0, nr - 1)
            ring_val = np.einsum("nk,knl->kl", T, c[r])          # (N, nl)
            out += w[:, q:q + 1] * ring_val
        np.maximum(out, 0.0, out=out)
        return out.reshape(d.shape[:-1] + (wl.size,))

    def sun_radiance(self, wavelengths_nm):
        """The base model's sun radiance for the actual sun (not tabulated)."""
        cls = get_model_class(self.base)
        return cls(sun=self.sun, **self.base_params).sun_radiance(wavelengths_nm)

    def describe(self):
        out = super().describe()
        out["parameters"]["base_params"] = {k: (v.describe() if hasattr(v, "describe") else v)
                                            for k, v in self.base_params.items()}
        return out


#: The earlier name (class names follow the registry names, without a "Sky" suffix).
Dobashi1995Sky = Dobashi1995
