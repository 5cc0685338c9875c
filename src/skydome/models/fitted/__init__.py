"""``fitted``: skydome's own fitted sky model, the ``precomputed`` reference at analytic speed.

A low-rank angular basis per sun-elevation node, with coefficients interpolated over the
atmosphere (aerosol optical depth at 550 nm, ground albedo), the observer's altitude and the
sun's elevation, fitted to spectral skies of the ``precomputed`` model (Bruneton 2017 as
built by skydome, validated against DISORT and Monte Carlo: docs/validation.md). The data
set is made by tools/fitted_dataset.py (on Dask) and the coefficients by
tools/fit_fitted.py; :mod:`._coefficients` describes the representation, :mod:`._grid` the
nodes and the view grid, docs/models.md ("fitted") the range and the measured errors.

Per model (one configuration) the angular table is built once (a few milliseconds: one
small matrix product per albedo node and neighbouring elevation node); every direction is
then a lookup in a numba kernel (:mod:`._kernels`: cubic along the zenith angle, linear in
azimuth).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from skydome._validate import as_wavelengths
from skydome.models import Parameter, SkyModel, register
from skydome.models.fitted import _grid

__all__ = ["FittedSky"]

#: Wavelengths the model answers [nm] (its table wavelengths span them).
WAVELENGTH_RANGE_NM = (300.0, 1100.0)


#: An in-between wavelength gets its own value (:func:`gas_plan`) where the gases'
#: vertical absorption optical depth changes across its interval by at least this much
#: (|tau_1 - tau_0| + |tau - linear interpolation of tau|).
GAS_DEPTH_CHANGE = 0.01


@functools.lru_cache(maxsize=4)
def gas_plan(table_wl: tuple) -> tuple:
    """The in-between wavelengths [nm] (halfway between the table wavelengths ``table_wl``)
    where the gases' absorption changes across the interval, each with the table
    wavelengths (indices) and the weights of its value's logarithm:
    ((wavelength, indices, weights), ...).

    Where ozone (Huggins band), water vapour or O2 absorb, the radiance relative to the solar
    spectrum is far from linear between two table wavelengths 20 nm apart (the absorption
    is exponential in the gas's optical depth along the light's paths, which the 10-nm
    spectrum of the gases does not follow linearly). Its logarithm is taken as
    a + b lambda - M tau(lambda) (Beer's law on a smooth spectrum, tau the gases' vertical
    absorption optical depth of the model's atmosphere, M an effective air mass that the
    three nearest table wavelengths determine, per direction): the weights solve it at the
    two neighbours and the third table wavelength that gives the smallest weights; where
    the three are ill-conditioned (a weight above 4) or tau is linear across the interval
    (within 0.003 of its linear interpolation), ln L is linear in wavelength between the
    two neighbours. Elsewhere (no plan entry) the model stays linear relative to the solar
    spectrum (docs/models.md, "fitted", "Wavelengths": the figures of both)."""
    from skydome.models.fitted._dataset import atmosphere

    tw = np.asarray(table_wl, dtype=np.float64)
    mids = 0.5 * (tw[1:] + tw[:-1])
    grid = np.concatenate([tw, mids])
    t = atmosphere(0.1, 0.1).vertical_optical_depth(grid)   # gases: AOD- and albedo-free
    tau_all = t["ozone"] + t["water_vapour"] + t["mixed_gases"]
    tau_n, tau_m = tau_all[:tw.size], tau_all[tw.size:]
    plan = []
    for j, x in enumerate(mids):
        t0, t1, tx = tau_n[j], tau_n[j + 1], tau_m[j]
        d = tx - 0.5 * (t0 + t1)
        if abs(t1 - t0) + abs(d) < GAS_DEPTH_CHANGE:
            continue                                     # linear relative to the sun
        best = None
        if abs(d) >= 0.003:
            for third in (j - 1, j + 2):
                if not 0 <= third < tw.size:
                    continue
                idx = [j, j + 1, third]
                m = np.array([[1.0, 1.0, 1.0], tw[idx], tau_n[idx]])
                try:
                    w = np.linalg.solve(m, [1.0, x, tx])
                except np.linalg.LinAlgError:
                    continue
                if best is None or np.abs(w).max() < np.abs(best[1]).max():
                    best = (idx, w)
        if best is None or np.abs(best[1]).max() >= 4.0:
            best = ([j, j + 1], np.array([0.5, 0.5]))    # ln L linear in wavelength
        plan.append((float(x), tuple(best[0]), tuple(float(v) for v in best[1])))
    return tuple(plan)


def spectral_table(values, table_wl) -> tuple[np.ndarray, np.ndarray]:
    """(values at the model's spectral wavelengths (..., n), those wavelengths [nm]): the
    table wavelengths and the in-between ones of :func:`gas_plan`, whose values come from
    the logarithms of the table's (where a value used is not positive, or the result
    exceeds 4 times the largest value used: linear between the neighbours instead)."""
    v = np.asarray(values, dtype=np.float64)
    tw = np.asarray(table_wl, dtype=np.float64)
    plan = gas_plan(tuple(float(x) for x in tw))
    if not plan:
        return v, tw
    n = len(plan)
    w_ln = np.zeros((tw.size, n))        # the logarithms' weights
    lin = np.zeros((tw.size, n))         # linear between the neighbours (the fallback)
    for k, (x, idx, w) in enumerate(plan):
        w_ln[list(idx), k] = w
        j = int(np.searchsorted(tw, x)) - 1
        f = (x - tw[j]) / (tw[j + 1] - tw[j])
        lin[j, k], lin[j + 1, k] = 1.0 - f, f
    pos = v > 0.0
    e = np.exp(np.clip(np.log(np.where(pos, v, 1.0)) @ w_ln, -700.0, 700.0))
    ok = ((~pos).astype(np.float64) @ (w_ln != 0.0)) == 0.0
    for k, (x, idx, w) in enumerate(plan):
        hi = v[..., idx[0]]
        for i in idx[1:]:
            hi = np.maximum(hi, v[..., i])
        ok[..., k] &= e[..., k] <= 4.0 * hi
    extra = np.where(ok, e, v @ lin)
    wl = np.concatenate([tw, [p[0] for p in plan]])
    order = np.argsort(wl, kind="stable")
    return np.concatenate([v, extra], axis=-1)[..., order], wl[order]


def _checked_out(out, shape: tuple, directions) -> np.ndarray:
    """``out`` if it can take a result of ``shape``: a C-contiguous, writeable float64
    array of that shape sharing no memory with ``directions``; else a ValueError that names
    it, what it is and what it must be."""
    if not isinstance(out, np.ndarray):
        raise ValueError(f"out must be a numpy array or None, got {type(out).__name__}")
    want = f"a C-contiguous, writeable float64 array of shape {shape}"
    if out.dtype != np.float64 or out.shape != shape or not out.flags.c_contiguous \
            or not out.flags.writeable:
        raise ValueError(f"out must be {want}, got a {'' if out.flags.c_contiguous else 'non-'}"
                         f"C-contiguous{'' if out.flags.writeable else ', read-only'} "
                         f"{out.dtype} array of shape {out.shape}")
    if isinstance(directions, np.ndarray) and np.shares_memory(out, directions):
        raise ValueError("out must not share memory with directions")
    return out


def interpolate_spectrum(values, table_wl, wl) -> np.ndarray:
    """``values`` (..., n_table) relative to the solar spectrum at the table wavelengths
    ``table_wl``, interpolated to ``wl`` [nm] as the model interpolates its tables
    (:func:`spectral_table`, then linear): (..., n) (tools/fitted_accuracy.py applies it
    to the reference's own values to measure the interpolation alone)."""
    from skydome.spectra import interpolation_matrix

    v, sw = spectral_table(values, table_wl)
    return v @ interpolation_matrix(sw, wl)


@register
class FittedSky(SkyModel):
    """skydome's fitted sky: the ``precomputed`` reference at analytic speed, spectral.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position; elevation in [-12, 90] deg: noon to the end of nautical twilight
        (the data set comes from ``precomputed`` in its twilight reference configuration,
        validated against Monte Carlo to -12 deg: docs/validation.md).
    aerosol_optical_depth : float
        Vertical aerosol optical depth at 550 nm, in [0, 1] (Angstrom exponent 1.3, the
        aerosol of ``Atmosphere.earth``).
    ground_albedo : float
        Grey Lambertian ground albedo, in [0, 1].
    observer_altitude_m : float [m]
        Observer altitude above the ground, in [0, 15000].

    Notes
    -----
    The atmosphere is ``Atmosphere.earth(aerosol_optical_depth=..., ground_albedo=...)``
    with its other constituents at their defaults (ozone 300 DU, water vapour 1.42 cm,
    mixed gases). The reference's table wavelengths are 300-1100 nm every 20 nm and the gas
    bands' 310, 330, 570, 590, 610, 690, 710, 730, 770, 890, 930 nm; halfway between two of
    them where the gases absorb (ozone's Huggins band, O2, water vapour) the value comes
    from the logarithms of the nearest three (:func:`spectral_table`); other
    wavelengths are interpolated linearly, relative to the solar spectrum, between these
    10-nm values (docs/models.md, "fitted", "Wavelengths"). Below the horizon the model
    returns the reference's ground (Lambertian, lit by the sun and the sky, seen through
    the air), for an observer on the ground as above it. Errors against the reference on
    a held-out grid: docs/models.md, "fitted".

    :meth:`radiance`, :meth:`xyz` and :meth:`luminance` take ``out=``: a C-contiguous,
    writeable float64 array of the result's shape that shares no memory with the
    directions; the result is written into it and it is returned (its contents are
    undefined where the call raises for bad directions). A caller that evaluates the model
    again and again (a frame loop) saves the first touch of a fresh output's memory: page
    faults that cost up to a third of an XYZ call of 2 M directions on a 2-core virtual
    machine (docs/performance.md, "The fitted lookup into a reused output").
    """

    name = "fitted"
    reference = ("skydome's fitted model (low-rank angular basis per sun elevation, "
                 "fitted to the precomputed reference: Bruneton 2017 as built by skydome)")
    native = "spectral"
    summary = ("skydome's own fit of the precomputed reference (spectral, sun -12..90 deg, "
               "0-15 km)")
    own_ground = "sun_and_sky"
    #: the viewer's shader (viewer/static/shaders/fitted.glsl: the lookup of xyz_table) and
    #: the engine bake (export/fitted_luts.py, export/glsl/fitted.glsl)
    viewer_shader = "fitted"
    viewer_parameters = ("aerosol_optical_depth", "ground_albedo", "observer_altitude_m")
    lut_layout = "fitted"
    sun_elevation_range_deg = _grid.SUN_ELEVATION_RANGE_DEG
    parameters = (
        Parameter("aerosol_optical_depth", "", 0.1, *_grid.AOD_RANGE,
                  "vertical aerosol optical depth at 550 nm (Angstrom exponent 1.3)"),
        Parameter("ground_albedo", "", 0.1, *_grid.ALBEDO_RANGE,
                  "grey Lambertian ground albedo"),
        Parameter("observer_altitude_m", "m", 0.0, *_grid.ALTITUDE_RANGE_M,
                  "observer altitude above the ground"),
    )

    def _setup(self, p, given):
        super()._setup(p, given)
        from skydome.models.fitted import _coefficients

        self._c = _coefficients.load()
        # [sr^-1] per unit extraterrestrial irradiance, (rows, phi, n_spectral) at the
        # spectral wavelengths: the table wavelengths and the in-between ones where the
        # gases absorb (spectral_table)
        self._table, self._table_wl = spectral_table(_coefficients.radiance_grid(
            self._c, self.aerosol_optical_depth, self.ground_albedo,
            float(self.sun.elevation_deg), self.observer_altitude_m),
            self._c["wavelengths_nm"])
        self._theta_h = _grid.horizon_zenith_rad(self.observer_altitude_m)
        az = math.radians(float(self.sun.azimuth_deg))
        self._sin_az, self._cos_az = math.sin(az), math.cos(az)
        self._derived: dict = {}

    # -- tables per output ---------------------------------------------------------------
    def _weights(self, wl: np.ndarray) -> np.ndarray:
        """(n_table, n): linear interpolation from the table wavelengths to ``wl``, times
        the extraterrestrial solar irradiance at ``wl`` [W m^-2 nm^-1] (the sun's distance
        included)."""
        from skydome.spectra import interpolation_matrix, solar_irradiance

        W = interpolation_matrix(self._table_wl, wl)
        return W * (solar_irradiance(wl) * self.sun.irradiance_scale)[None, :]

    def _derived_table(self, key, make):
        t = self._derived.get(key)
        if t is None:
            if len(self._derived) > 8:
                self._derived.clear()
            t = self._derived[key] = np.ascontiguousarray(make(), dtype=np.float64)
        return t

    def _xyz_matrix(self) -> np.ndarray:
        """(n_table, 3): table values -> CIE XYZ [cd m^-2] through the default wavelength
        grid (as the base class integrates a spectral model's radiance)."""
        from skydome.spectra import solar_xyz_matrix

        return solar_xyz_matrix(self._table_wl, irradiance_scale=self.sun.irradiance_scale)

    def _lookup(self, directions, table, out=None, squeeze=False) -> np.ndarray:
        """The table at ``directions`` (..., 3): shape (..., C), or (...) with ``squeeze``
        (C = 1); written into ``out`` where it is given (and ``out`` returned)."""
        from skydome.models.fitted import _kernels

        # the checks of flat_directions (skydome.models.analytic), with its messages: the
        # kernel counts the non-finite and zero-length rows in its own pass over the array
        d = np.asarray(directions, dtype=np.float64)
        if d.ndim == 0 or d.shape[-1] != 3:
            raise ValueError(f"directions must have shape (..., 3), got {d.shape}")
        lead = d.shape[:-1]
        flat = np.ascontiguousarray(d.reshape(-1, 3))
        c = table.shape[2]
        shape = lead if squeeze else lead + (c,)
        if out is None:
            res = np.empty(shape)
        else:
            res = _checked_out(out, shape, directions)
        n_bad, n_zero = _kernels.lookup(flat, flat.view(np.int64), table.reshape(-1), c,
                                        self._theta_h, self._sin_az, self._cos_az,
                                        res.reshape(flat.shape[0], c))
        if n_bad:
            raise ValueError("directions contains NaN or infinite values")
        if n_zero:
            raise ValueError("directions contains zero-length vectors")
        return res

    # -- the protocol --------------------------------------------------------------------
    def radiance(self, directions, wavelengths_nm, *, out=None) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] arriving from ``directions`` (..., 3),
        shape (..., n_wavelengths); wavelengths in [300, 1100] nm. ``out``: where to write
        the result (returned), as numpy's ``out=`` (class Notes)."""
        wl = as_wavelengths(wavelengths_nm, *WAVELENGTH_RANGE_NM)
        key = ("wl", wl.tobytes())
        table = self._derived_table(key, lambda: self._table @ self._weights(wl))
        return self._lookup(directions, table, out)

    def _spectral_basis(self, wavelengths_nm):
        """(sample, B): ``radiance(d, wavelengths_nm) == sample(d) @ B``, sample(d) the
        table values (n, n_used) [sr^-1] at the table wavelengths that ``wavelengths_nm``
        reach and B the interpolation from them to ``wavelengths_nm`` times the solar
        spectrum, so that a renderer folds B into its spectrum -> XYZ
        weights (skydome.imaging.render)."""
        wl = as_wavelengths(wavelengths_nm, *WAVELENGTH_RANGE_NM)
        B = self._weights(wl)
        # only the spectral wavelengths that reach ``wavelengths_nm`` (380-780 nm: 39 of
        # the shipped file's 81): the other rows of B are zero, so the product is the same,
        # at less cost
        used = np.flatnonzero(np.any(B != 0.0, axis=1))
        j0, j1 = (int(used[0]), int(used[-1]) + 1) if used.size else (0, 1)
        table = self._derived_table(("rows", j0, j1), lambda: self._table[:, :, j0:j1])
        return (lambda d: self._lookup(d, table)), B[j0:j1]

    def _fused_xyz(self, wavelengths_nm, M):
        """sample(d) -> (n, 3): the renderer's XYZ (skydome.imaging.render: radiance at
        ``wavelengths_nm`` times its weights ``M`` (n, 3)) in one lookup of the table times
        the wavelength interpolation, the solar spectrum and ``M``. The lookup is linear in
        the table's values, so this is the product of the spectral lookup and ``M`` but for
        the clamp at 0 (here on the three channels, there on each wavelength: they differ
        only where the rows' spline overshoots below 0), as :meth:`xyz` is; it reads three
        channels per direction instead of the 29 table wavelengths that 380-780 nm reach."""
        wl = as_wavelengths(wavelengths_nm, *WAVELENGTH_RANGE_NM)
        M = np.asarray(M, dtype=np.float64)
        key = ("fused", wl.tobytes(), M.tobytes())
        table = self._derived_table(key, lambda: self._table @ (self._weights(wl) @ M))
        return lambda d: self._lookup(d, table)

    def xyz(self, directions, *, out=None) -> np.ndarray:
        """CIE 1931 XYZ, Y = luminance [cd m^-2], shape (..., 3). ``out``: where to write
        the result (returned), as numpy's ``out=`` (class Notes)."""
        return self._lookup(directions, self._derived_table(
            "xyz", lambda: self._table @ self._xyz_matrix()), out)

    def xyz_table(self) -> np.ndarray:
        """The angular table that :meth:`xyz` looks up: CIE 1931 XYZ [cd m^-2] on the view
        grid of :mod:`._grid`, (N_SKY + N_GROUND, N_PHI, 3) (for the GLSL evaluators)."""
        return self._derived_table("xyz", lambda: self._table @ self._xyz_matrix())

    def luminance(self, directions, *, out=None) -> np.ndarray:
        """Luminance [cd m^-2], shape (...). ``out``: where to write the result
        (returned), as numpy's ``out=`` (class Notes)."""
        return self._lookup(directions, self._derived_table(
            "y", lambda: self._table @ self._xyz_matrix()[:, 1:2]), out, squeeze=True)

    def _sun_arrays(self) -> dict:
        if "sun_columns" not in self._c:
            raise FileNotFoundError("the fitted model's coefficient file has no sun arrays "
                                    "(add them with tools/fit_fitted.py --add-sun)")
        return self._c

    def sun_transmittance(self, wavelengths_nm) -> np.ndarray:
        """Transmittance of the air along the path to the sun's centre, (n,), in [0, 1]:
        Beer's law over the constituents' columns along the ray (the reference's column
        table and its look-up; below the observer's horizon the horizon's columns, as the
        reference reads them) and their extinction at each wavelength (:mod:`._sun`)."""
        from skydome.models.fitted import _sun

        wl = as_wavelengths(wavelengths_nm, *WAVELENGTH_RANGE_NM)
        c = self._sun_arrays()
        # the spectra per wavelength set (the sun's elevation does not enter them)
        beta = self._derived_table(("sun_beta", wl.tobytes()), lambda: _sun.extinction(
            c, self.aerosol_optical_depth, wl))
        return np.clip(_sun.transmittance(c, float(self.sun.direction[2]),
                                          self.observer_altitude_m, beta), 0.0, 1.0)

    def sun_visible_fraction(self) -> float:
        """Fraction of the sun's disc above the observer's horizon, which
        :meth:`sun_radiance` includes: the reference's rule ([Bru17]
        GetTransmittanceToSun, a smoothstep over the disc's radius in the sun's zenith
        cosine around the horizon's, :func:`._sun.visible_fraction`)."""
        from skydome.models.fitted import _sun

        return _sun.visible_fraction(self._sun_arrays(), float(self.sun.direction[2]),
                                     self.observer_altitude_m,
                                     float(self.sun.angular_radius_deg))

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Radiance of the sun's disc [W m^-2 sr^-1 nm^-1], shape (n,): E_sun / Omega_sun
        x the transmittance x the fraction of the disc above the horizon
        (:meth:`sun_visible_fraction`)."""
        from skydome.spectra import solar_irradiance

        wl = as_wavelengths(wavelengths_nm, *WAVELENGTH_RANGE_NM)
        e = solar_irradiance(wl) * self.sun.irradiance_scale / self.sun.solid_angle_sr
        return e * self.sun_transmittance(wl) * self.sun_visible_fraction()
