"""``single_scattering``: brute-force single scattering (no multiple scattering) in a spherical atmosphere.

Survey eqs. 15-16 integrated numerically in a spherical-shell atmosphere with any
:class:`skydome.atmosphere.Atmosphere` (Rayleigh, aerosols with their phase function,
ozone absorption, earth shadow, sunlit ground). Later, faster models are measured against
it; its sample counts are exposed so that its convergence can be shown
(``tests/test_single_scattering.py``).
"""

from __future__ import annotations

import numpy as np

from skydome._validate import as_directions, as_wavelengths
from skydome.models import ATMOSPHERE_PARAMETERS, Parameter, SkyModel, register

__all__ = ["SingleScattering", "SingleScatteringSky"]


@register
class SingleScattering(SkyModel):
    """Single scattering of sunlight (Rayleigh + aerosols + ozone), integrated numerically.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position; any elevation in [-90, 90] deg (below the horizon only the upper
        atmosphere is lit, through the earth's shadow boundary).
    {atmosphere_parameters}
    view_samples : int, optional
        Quadrature nodes per piece of each view ray (default 16 with the sun above the
        horizon: error <= 0.2 % against the converged result; 64 with the sun below it:
        error <= 2 %, RMS <= 0.4 %; see docs/sections/transport.md).
    light_samples : int
        Quadrature nodes per light-path column (default 128).
    light_exact : bool
        Integrate each light path directly instead of through the column table.
    """

    name = "single_scattering"
    reference = ("Kment, Rauter & Zotti, Modelling of Daylight for Computer Graphics, eqs. 12, "
                 "15-16; Nishita et al. 1993, SIGGRAPH, eqs. 1-3 (numerical integration)")
    native = "spectral"
    own_ground = "sun"                    # measured: rho E_sun sin(el) / pi at the nadir
    summary = ("Brute-force single scattering in a spherical atmosphere: first order only, so "
               "too dark away from the sun and at the horizon (use precomputed for the sky).")
    parameters = (
        *ATMOSPHERE_PARAMETERS,
        Parameter("view_samples", "", None, 2, 4096,
                  "quadrature nodes per view-ray piece (default 16; 64 with the sun below the horizon)",
                  kind="int"),
        Parameter("light_samples", "", 128, 2, 4096, "quadrature nodes per light-path column",
                  kind="int"),
        Parameter("light_exact", "", False, doc="integrate light paths directly (slow)", kind="bool"),
    )

    def _setup(self, p, given):
        sun = self.sun
        self.atmosphere = p["atmosphere"]
        self.turbidity = p["turbidity"]
        self.observer_altitude_m = p["observer_altitude_m"]
        # twilight rays are lit only beyond the earth's shadow, where the light path's
        # transmittance rises steeply: they need more nodes (docs/sections/transport.md)
        if p["view_samples"] is None:
            p["view_samples"] = 16 if sun.elevation_deg >= 0.0 else 64
        self.view_samples = p["view_samples"]
        self.light_samples = p["light_samples"]
        self.light_exact = bool(p["light_exact"])
        self._integrators: dict = {}

    def _integrator(self, wl):
        from skydome.transport.single import SingleScattering

        key = tuple(np.round(wl, 9))
        if key not in self._integrators:
            if len(self._integrators) > 4:
                self._integrators.clear()
            self._integrators[key] = SingleScattering(
                self.atmosphere, wl, self.observer_altitude_m, self.view_samples,
                self.light_samples, self.light_exact)
        return self._integrators[key]

    def _solar(self, wl):
        from skydome.spectra import solar_irradiance

        return solar_irradiance(wl) * self.sun.irradiance_scale

    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] arriving from ``directions`` (..., 3),
        shape (..., n_wavelengths). Directions below the horizon see the sunlit ground
        (Lambertian, the atmosphere's ground albedo) through the air in front of it."""
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        ss = self._integrator(wl)
        return ss.radiance(d, self.sun.direction, self._solar(wl))

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Radiance of the sun's disc seen through the atmosphere [W m^-2 sr^-1 nm^-1]:
        E_sun / Omega_sun x T(observer -> top); 0 when the planet hides the sun. The disc is
        uniform (no limb darkening)."""
        wl = as_wavelengths(wavelengths_nm)
        t = self._integrator(wl).transmittance(self.sun.direction)
        return self._solar(wl) / self.sun.solid_angle_sr * t


#: The earlier name (class names follow the registry names, without a "Sky" suffix).
SingleScatteringSky = SingleScattering
