"""``hillaire2020``: Hillaire's scalable sky with the fast multiple-scattering LUT.

S. Hillaire, "A Scalable and Production Ready Sky and Atmosphere Rendering Technique",
Computer Graphics Forum 39(4), EGSR 2020 [Hil20]. Four tables replace the expensive
parts of the light transport:

1. the transmittance LUT (256 x 64) on Bruneton's (r, mu) mapping (sec. 4.1);
2. the multiple-scattering transfer LUT Psi_ms (32 x 32, sun zenith cosine x altitude):
   the radiance of all orders >= 2 per unit irradiance, from the isotropic-phase second
   order L_2 and the transfer factor f_ms summed as a geometric series,
   Psi_ms = L_2 / (1 - f_ms) (sec. 5.5, eqs. 5-10);
3. the sky-view LUT (192 x 108) with the paper's non-linear latitude mapping, marched
   with the full phase functions and Psi_ms as an extra source, sigma_s Psi_ms (eq. 11)
   (sec. 5.3);
4. the aerial-perspective volume (32 x 32 x 32 froxels, 4 km per slice, squared slice
   distribution) (sec. 5.4).

The paper works in RGB; here every table carries a wavelength axis, so the method runs
at each wavelength of the grid. See docs/sections/hillaire2020.md for the deviations.
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_choice
from skydome.models import ATMOSPHERE_PARAMETERS, Parameter, SkyModel, register

__all__ = ["Hillaire2020", "Hillaire2020Sky"]


def _bool(name, value):
    return check_choice(name, value, (True, False))


class _Tables:
    """The four tables for one atmosphere, observer, sun and internal wavelength grid."""

    def __init__(self, model, grid):
        from skydome.models.simulated import _kernels_hillaire2020 as K
        from skydome.transport._medium import medium_from_properties

        m = model
        self.grid = grid
        p = m.atmosphere.optical_properties(grid, fold=True)
        self.props = p
        self.R = float(p.planet_radius_m)
        self.Rt = float(p.top_radius_m)
        self.r0 = self.R + m.observer_altitude_m
        self.ts = 500.0
        # [Hil20] sec. 4.1: transmittance LUT
        self.medium = medium_from_properties(p)
        self.tlut = K.build_transmittance(self.medium, m.transmittance_height,
                                          m.transmittance_width, 64, self.ts)
        # [Hil20] sec. 5.5: multiple-scattering LUT (eqs. 5-10)
        self.orders = np.zeros((2, m.ms_size, m.ms_size, grid.size))
        sq = int(round(np.sqrt(m.ms_directions)))
        self.mslut = K.build_multiple_scattering(self.medium, self.tlut, m.ms_size, m.ms_size, sq,
                                                 m.ms_samples, self.ts, self.orders)
        if not m.multiple_scattering:
            self.mslut = np.zeros_like(self.mslut)
        self._sv = None
        self._ap = None
        self._model = model

    def _args(self):
        return self.medium, self.tlut, self.mslut, self._model.multiple_scattering

    @property
    def skyview(self):
        """Sky-view LUT (H, W, n_grid) per unit irradiance ([Hil20] sec. 5.3)."""
        from skydome.models.simulated import _kernels_hillaire2020 as K

        if self._sv is None:
            m = self._model
            self._sv = K.build_skyview(self.r0, float(m.sun.direction[2]), m.skyview_height,
                                       m.skyview_width, *self._args(), m.view_samples, self.ts)
        return self._sv

    @property
    def aerial(self):
        """Aerial-perspective volumes (in-scatter, transmittance) ([Hil20] sec. 5.4)."""
        from skydome.models.simulated import _kernels_hillaire2020 as K

        if self._ap is None:
            m = self._model
            n = m.ap_size
            self._ap = K.build_aerial_perspective(
                self.r0, float(m.sun.direction[2]), n, n, n, m.ap_km_per_slice, *self._args(),
                m.ap_samples, self.ts)
        return self._ap


@register
class Hillaire2020(SkyModel):
    """Hillaire's (2020) LUT-based sky with the isotropic multiple-scattering transfer
    table, run per wavelength.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position; elevation in [-10, 90] deg (the paper's method is made for the sun
        above about -10 deg; below that the earth's shadow covers most of the
        atmosphere seen and twilight needs more orders than the isotropic transfer gives).
    {atmosphere_parameters}
    n_wavelengths : int
        Wavelengths the tables are built at (default 16). A request with at most this
        many wavelengths is computed on its own grid; a denser one on ``n_wavelengths``
        evenly spaced wavelengths across it, interpolated linearly in L lambda^4.
    multiple_scattering : bool
        Add the multiple-scattering term sigma_s Psi_ms ([Hil20] eq. 11) (default True).
    use_skyview : bool
        Evaluate ``radiance`` through the sky-view LUT (default True) or by a ray march
        per direction (with the same transmittance and multiple-scattering LUTs).
    transmittance_width, transmittance_height : int
        Transmittance LUT size, mu x r (256 x 64).
    ms_size : int
        Multiple-scattering LUT size (32 x 32).
    ms_directions, ms_samples : int
        Directions on the sphere (a square number, 64) and segments per ray piece (10,
        i.e. 20 per ray as in the paper) of each multiple-scattering texel.
    skyview_width, skyview_height : int
        Sky-view LUT size (192 x 108; the height must be even).
    view_samples : int
        Segments per piece of each view ray (16).
    ap_size, ap_km_per_slice, ap_samples : int, float, int
        Aerial-perspective volume size (32^3), depth per slice [km] (4) and segments
        per piece of each froxel's ray (8).
    """

    name = "hillaire2020"
    reference = ("Hillaire, A Scalable and Production Ready Sky and Atmosphere Rendering "
                 "Technique, Computer Graphics Forum 39(4) (EGSR 2020), eqs. 1-11")
    native = "spectral"
    viewer_shader = "hillaire2020"
    viewer_parameters = ("turbidity", "observer_altitude_m")
    lut_layout = "hillaire"
    airlight = True
    # march each ray: the froxel volume (4 km slices) halves the extinction over the first
    # kilometres and clamps distances beyond ~30 km
    airlight_options = MappingProxyType({"use_volume": False})
    own_ground = "sun"                    # measured: rho E_sun sin(el) / pi at the nadir
    summary = "LUT-based sky with Hillaire's fast multiple-scattering approximation."
    parameters = (
        *ATMOSPHERE_PARAMETERS,
        Parameter("n_wavelengths", "", 16, 2, 1000, "wavelengths the tables are built at", kind="int"),
        Parameter("multiple_scattering", "", True, doc="add the multiple-scattering term",
                  kind="bool"),
        Parameter("use_skyview", "", True, doc="radiance through the sky-view LUT (else ray march)",
                  kind="bool"),
        Parameter("transmittance_width", "", 256, 4, 4096, "transmittance LUT mu size", kind="int"),
        Parameter("transmittance_height", "", 64, 4, 4096, "transmittance LUT r size", kind="int"),
        Parameter("ms_size", "", 32, 2, 1024, "multiple-scattering LUT size (square)", kind="int"),
        Parameter("ms_directions", "", 64, 4, 4096, "sphere directions per MS texel (square number)",
                  kind="int"),
        Parameter("ms_samples", "", 10, 2, 1024, "segments per ray piece in the MS LUT", kind="int"),
        Parameter("skyview_width", "", 192, 4, 4096, "sky-view LUT azimuth size", kind="int"),
        Parameter("skyview_height", "", 108, 4, 4096, "sky-view LUT latitude size (even)", kind="int"),
        Parameter("view_samples", "", 16, 2, 4096, "segments per view-ray piece", kind="int"),
        Parameter("ap_size", "", 32, 2, 256, "aerial-perspective volume size (cube)", kind="int"),
        Parameter("ap_km_per_slice", "km", 4.0, 0.01, 1000.0, "aerial-perspective depth per slice"),
        Parameter("ap_samples", "", 8, 2, 1024, "segments per froxel ray piece", kind="int"),
    )

    sun_elevation_range_deg = (-10.0, 90.0)

    def _setup(self, p, given):
        atm = p["atmosphere"]
        sq = int(round(np.sqrt(p["ms_directions"])))
        if sq * sq != p["ms_directions"]:
            raise ValueError(f"ms_directions = {p['ms_directions']} is not a square number "
                             f"in [4, 4096]")
        if p["skyview_height"] % 2:
            raise ValueError(f"skyview_height = {p['skyview_height']} is not even "
                             f"(range [4, 4096], even)")
        self.atmosphere = atm
        for k, v in p.items():
            if k != "atmosphere":
                setattr(self, k, v)
        self._tables: dict = {}

    # -- tables -----------------------------------------------------------------------------
    def _grid(self, wl):
        if wl.size <= self.n_wavelengths:
            return wl
        return np.linspace(wl[0], wl[-1], self.n_wavelengths)

    def tables(self, wavelengths_nm) -> _Tables:
        """The tables (built on first use) for the internal grid of ``wavelengths_nm``."""
        wl = as_wavelengths(wavelengths_nm)
        grid = self._grid(wl)
        key = tuple(np.round(grid, 9))
        if key not in self._tables:
            if len(self._tables) > 4:
                self._tables.clear()
            self._tables[key] = _Tables(self, grid)
        return self._tables[key]

    @staticmethod
    def _weights(grid, wl):
        """(n_wl, n_grid) matrix of the linear interpolation from ``grid`` to ``wl``
        (:func:`skydome.spectra.interpolation_matrix`, the matrix of the library's one
        resampling convention; ``wl`` lies inside ``grid``, which spans it)."""
        from skydome.spectra import interpolation_matrix

        return interpolation_matrix(grid, wl).T

    @classmethod
    def _to_grid(cls, x, grid, wl):
        """Values on ``grid`` (..., n_grid) to ``wl`` by :func:`skydome.spectra.resample`
        (linear in wavelength), identity when the grids coincide."""
        if grid.shape == wl.shape and np.array_equal(grid, wl):
            return x
        out = x.reshape(-1, grid.size) @ cls._weights(grid, wl).T
        return out.reshape(x.shape[:-1] + (wl.size,))

    @classmethod
    def _to_request(cls, x, grid, wl):
        """Radiance on ``grid`` (..., n_grid) to ``wl``: linear in x lambda^4 (exact for a
        lambda^-4 spectrum; :func:`skydome.spectra.resample` applied to x lambda^4),
        identity when the grids coincide."""
        if grid.shape == wl.shape and np.array_equal(grid, wl):
            return x
        return cls._to_grid(x * grid ** 4, grid, wl) / wl ** 4

    def _solar(self, wl):
        from skydome.spectra import solar_irradiance

        return solar_irradiance(wl) * self.sun.irradiance_scale

    # -- the model ----------------------------------------------------------------------------
    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] arriving from ``directions`` (..., 3),
        shape (..., n_wavelengths), without the sun's disc.

        Directions below the horizon see the sunlit Lambertian ground (the atmosphere's
        ground albedo) through the air in front of it. Never negative or NaN.
        """
        from skydome.models.simulated import _kernels_hillaire2020 as K

        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        tb = self.tables(wl)
        flat = np.ascontiguousarray(d.reshape(-1, 3))
        ng = tb.grid.size
        out = np.empty((flat.shape[0], ng))
        sun = np.ascontiguousarray(self.sun.direction, dtype=np.float64)
        if self.use_skyview:
            K.lookup_skyview(flat, sun, tb.r0, tb.R, tb.skyview, out)
        else:
            trans = np.empty_like(out)
            stop = np.full(flat.shape[0], -1.0)
            K.march_directions(flat, sun, tb.r0, stop, *tb._args(), True, self.view_samples,
                               tb.ts, out, trans)
        out = self._to_request(out, tb.grid, wl) * self._solar(wl)
        np.maximum(out, 0.0, out=out)
        out[~np.isfinite(out)] = 0.0
        return out.reshape(d.shape[:-1] + (wl.size,))

    def transmittance(self, directions, wavelengths_nm) -> np.ndarray:
        """Transmittance from the observer to the top of the atmosphere (transmittance
        LUT), shape (..., n_wavelengths); 0 where the ray hits the ground."""
        from skydome.models.simulated import _kernels_hillaire2020 as K

        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        tb = self.tables(wl)
        mu = np.ascontiguousarray(d.reshape(-1, 3)[:, 2])
        out = np.empty((mu.size, tb.grid.size))
        K.lookup_transmittance(np.full(mu.size, tb.r0), mu, tb.tlut, tb.R, tb.Rt, out)
        out = self._to_grid(out, tb.grid, wl)
        return np.clip(out, 0.0, 1.0).reshape(d.shape[:-1] + (wl.size,))

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Radiance of the sun's disc seen through the atmosphere [W m^-2 sr^-1 nm^-1]:
        E_sun / Omega_sun x T(observer -> top) from the transmittance LUT; 0 when the
        planet hides the sun. Uniform disc (no limb darkening)."""
        wl = as_wavelengths(wavelengths_nm)
        t = self.transmittance(self.sun.direction, wl)
        return self._solar(wl) / self.sun.solid_angle_sr * t

    def aerial_perspective(self, directions, distance_m, wavelengths_nm, *,
                           use_volume: bool = True):
        """Transmittance and in-scattered radiance between the observer and an object
        ([Hil20] sec. 5.4).

        Parameters
        ----------
        directions : array_like (..., 3)
            Unit vector(s) from the eye towards the object (East-North-Up).
        distance_m : array_like
            Eye-object distance [m] >= 0, broadcast against ``directions[..., 0]``.
        wavelengths_nm : array_like
            Wavelengths [nm].
        use_volume : bool
            Interpolate the froxel volume (default; distances beyond its last slice,
            ap_size^2 (1 - 1/(2 ap_size))^2 ap_km_per_slice / ap_size km, are clamped to it)
            or march each ray.

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            Transmittance [-] and in-scattered radiance [W m^-2 sr^-1 nm^-1], each of
            shape (..., n_wavelengths). An object seen at ``L_0`` appears as
            ``L_0 T + L_in``.
        """
        from skydome.models.simulated import _kernels_hillaire2020 as K

        d = as_directions(directions, "directions")
        s = np.asarray(distance_m, dtype=np.float64)
        if not np.all(np.isfinite(s)) or np.any(s < 0.0):
            raise ValueError("distance_m is out of range [0, inf) m (got a negative or "
                             "non-finite value)")
        use_volume = _bool("use_volume", use_volume)
        wl = as_wavelengths(wavelengths_nm)
        shape = np.broadcast_shapes(d.shape[:-1], s.shape)
        flat = np.ascontiguousarray(np.broadcast_to(d, shape + (3,)).reshape(-1, 3))
        dist = np.ascontiguousarray(np.broadcast_to(s, shape).reshape(-1))
        tb = self.tables(wl)
        ng = tb.grid.size
        L = np.empty((flat.shape[0], ng))
        T = np.empty_like(L)
        sun = np.ascontiguousarray(self.sun.direction, dtype=np.float64)
        if use_volume:
            vl, vt = tb.aerial
            K.lookup_aerial_perspective(flat, dist, sun, self.ap_km_per_slice, vl, vt, L, T)
        else:
            stop = np.where(dist > 0.0, dist, 1e-9)
            K.march_directions(flat, sun, tb.r0, stop, *tb._args(), False, self.view_samples,
                               tb.ts, L, T)
        L = np.maximum(self._to_request(L, tb.grid, wl) * self._solar(wl), 0.0)
        T = np.clip(self._to_grid(T, tb.grid, wl), 0.0, 1.0)
        return T.reshape(shape + (wl.size,)), L.reshape(shape + (wl.size,))


#: The earlier name (class names follow the registry names, without a "Sky" suffix).
Hillaire2020Sky = Hillaire2020
