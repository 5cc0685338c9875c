"""Single scattering in a spherical-shell atmosphere (survey eqs. 15-16).

The radiance scattered once towards an observer, for every constituent c (molecules,
aerosols; ozone only absorbs):

    L(lambda) = E_sun(lambda) sum_c beta_s,c(lambda) P_c(theta)
                integral_0^L rho_c(t) exp(-tau(P_o, P_t) - tau(P_t, sun)) dt

([KRZ06] eqs. 15-16, [NSTN93] eqs. 1-3), with E_sun the extraterrestrial solar spectral
irradiance, beta_s the scattering coefficients at reference density, P_c the normalised
phase functions, rho_c the relative densities and tau the optical depths of eq. 12 along
the view ray and along the light ray. The light ray is cut by the planet (earth shadow).
Where the view ray hits the ground, the sunlit ground adds its Lambertian reflection of
the attenuated direct sun.

References
----------
[KRZ06] Kment, Rauter & Zotti, "Modelling of Daylight for Computer Graphics" (the survey).
[NSTN93] Nishita, Sirai, Tadamura, Nakamae 1993. Display of the Earth taking into account
    atmospheric scattering. SIGGRAPH 93.
"""

from __future__ import annotations

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_int, check_number

__all__ = ["SingleScattering"]


class SingleScattering:
    """The single-scattering integrator for one atmosphere, observer and wavelength grid.

    Holds the optical properties and the light-path column table (built once), and
    evaluates radiance for any set of view directions and sun directions.

    Parameters
    ----------
    atmosphere : skydome.atmosphere.Atmosphere
    wavelengths_nm : array_like
    observer_altitude_m : float
        Observer altitude above the ground [m], inside the atmosphere.
    view_samples : int
        Quadrature nodes along each piece of the view ray (>= 2).
    light_samples : int
        Quadrature nodes for each light-path column (table entries, or every light ray
        when ``light_exact``).
    light_exact : bool
        Integrate every light path by quadrature instead of interpolating the column table
        (slow; used to verify the table).
    table_size : (int, int)
        (n_r, n_mu) of the column table.
    """

    def __init__(self, atmosphere, wavelengths_nm, observer_altitude_m: float = 0.0,
                 view_samples: int = 16, light_samples: int = 128, light_exact: bool = False,
                 table_size=(256, 512), quadrature_scale_m: float = 500.0):
        from skydome.transport._medium import medium_from_properties
        from skydome.transport.optical_depth import ColumnTable

        self.wavelengths_nm = as_wavelengths(wavelengths_nm)
        top = atmosphere.top_altitude_m
        self.observer_altitude_m = check_number("observer_altitude_m", observer_altitude_m, 0.0,
                                                top, "m", high_open=True)
        self.view_samples = check_int("view_samples", view_samples, 2, 100_000)
        self.light_samples = check_int("light_samples", light_samples, 2, 100_000)
        self.light_exact = bool(light_exact)
        self.scale_m = check_number("quadrature_scale_m", quadrature_scale_m, 1.0, 1e6, "m")
        self.atmosphere = atmosphere
        self.props = atmosphere.optical_properties(self.wavelengths_nm, fold=True)
        self.medium = medium_from_properties(self.props)
        n_r, n_mu = table_size
        self.table = ColumnTable.cached(self.props, n_r, n_mu, self.light_samples, self.scale_m)

    @property
    def r0(self) -> float:
        return self.props.planet_radius_m + self.observer_altitude_m

    def radiance(self, directions, sun_direction, solar_irradiance) -> np.ndarray:
        """Single-scattered spectral radiance [W m^-2 sr^-1 nm^-1], shape (..., n_lambda).

        Parameters
        ----------
        directions : array_like (..., 3)
            Unit vectors the light arrives from (East-North-Up).
        sun_direction : array_like (3,)
            Unit vector towards the sun.
        solar_irradiance : array_like (n_lambda,)
            Solar spectral irradiance at the top of the atmosphere [W m^-2 nm^-1].
        """
        from skydome.transport import _kernels as K

        d = as_directions(directions)
        s = as_directions(sun_direction).reshape(3)
        e_sun = np.ascontiguousarray(solar_irradiance, dtype=np.float64)
        p = self.props
        flat = np.ascontiguousarray(d.reshape(-1, 3))
        out = np.empty((flat.shape[0], p.wavelengths_nm.size))
        K.single_scattering(flat, self.r0, s, self.medium, e_sun, self.table.table,
                            self.view_samples, self.scale_m, self.light_exact, self.light_samples,
                            out)
        np.maximum(out, 0.0, out=out)
        return out.reshape(d.shape[:-1] + (p.wavelengths_nm.size,))

    def transmittance(self, directions) -> np.ndarray:
        """Transmittance from the observer to the top of the atmosphere along directions,
        shape (..., n_lambda); 0 where the ray hits the ground."""
        from skydome.transport import _kernels as K

        d = as_directions(directions)
        mu = np.ascontiguousarray(d.reshape(-1, 3)[:, 2])
        p = self.props
        r = np.full(mu.shape, self.r0)
        out = np.empty((mu.size, p.wavelengths_nm.size))
        K.transmittance_to_top(r, mu, self.table.table, self.medium, self.light_exact,
                               self.light_samples, self.scale_m, out)
        return out.reshape(d.shape[:-1] + (p.wavelengths_nm.size,))
