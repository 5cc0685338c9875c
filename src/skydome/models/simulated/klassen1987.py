"""``klassen1987``: sky and sun colour over a flat earth with two homogeneous layers.

Klassen (1987) models the atmosphere over a flat earth as a layer of haze-filled air near
the ground under a layer of haze-free air, each of constant density (survey section 7.1).
Sunlight is scattered once towards the eye; inside a homogeneous layer the optical depths
along the view ray and along the light ray are linear in the distance travelled, so the
in-scattering integral along a straight path has a closed form. The same integral, cut at
the distance of an object, gives fog (aerial perspective) between the eye and the object.

Layers (altitude z above the flat ground, ``h_haze <= h_air``)::

    0      <= z < h_haze : air (Rayleigh) + haze (Henyey-Greenstein), constant densities
    h_haze <= z < h_air  : air only
    z >= h_air           : vacuum

Coefficients: the air's Rayleigh scattering coefficient at sea level, survey eq. 8,
``beta_R = 8 pi^3 (n^2 - 1)^2 / (3 N_s lambda^4)`` with the refractive index ``n``; the
haze extinction from the Angstrom law with Preetham's turbidity fit (or a given extinction
at 550 nm), spread uniformly over the haze layer.

For a straight path x(t) = z0 + u t (u the cosine of the view zenith angle) and a sun at
apparent zenith cosine ``u_s`` with relative air mass ``m``, in a layer with constant total
extinction ``k`` the optical depth to the eye grows as ``k t`` and the optical depth to the
sun falls as ``m k u t``, so the single-scattering integral over a piece [t_a, t_b] is::

    integral exp(-A(t)) dt = (exp(-A(t_a)) - exp(-A(t_b))) / c,   c = k (1 - m u)

(``(t_b - t_a) exp(-A(t_a))`` in the limit c -> 0), where ``A(t)`` is the sum of both
optical depths, and the radiance is

    L = E_sun sum_layers sum_i beta_s,i P_i(theta) integral exp(-A(t)) dt.

References
----------
[Kla87] Klassen, R.V. 1987. Modeling the effect of the atmosphere on light. ACM Transactions
    on Graphics 6(3), 215-237.
[KRZ06] Kment, Rauter & Zotti, Modelling of Daylight for Computer Graphics (the survey),
    section 7.1 and eq. 8.
[Sae86] Saemundsson, T. 1986. Astronomical refraction. Sky and Telescope 72, 70 (as given
    in Meeus, Astronomical Algorithms, 2nd ed., 1998, eq. 16.4).
[KY89] Kasten, F. & Young, A.T. 1989. Revised optical air mass tables and approximation
    formula. Applied Optics 28(22), 4735-4738.
"""

from __future__ import annotations

import math

import numpy as np

from skydome._validate import as_directions, as_wavelengths
from skydome.models import GroundEyeAerialPerspective, Parameter, SkyModel, register

__all__ = ["Klassen1987", "Klassen1987Sky", "refraction_saemundsson_deg", "refraction_bennett_deg",
           "kasten_young_airmass"]


def refraction_saemundsson_deg(true_elevation_deg):
    """Atmospheric refraction [deg] for a body at true (geometric) elevation ``h`` [deg].

    ``R = 1.02 / tan(h + 10.3 / (h + 5.11))`` arcminutes ([Sae86]; Meeus eq. 16.4), for
    a pressure of 101.0 kPa and 10 deg C. Evaluated for h >= -1 deg (below that the
    formula is not meant to be used; it returns the value at -1 deg).
    """
    h = np.maximum(np.asarray(true_elevation_deg, dtype=np.float64), -1.0)
    arg = np.radians(h + 10.3 / (h + 5.11))
    r_arcmin = 1.02 / np.tan(arg)
    # the formula gives a tiny negative value at the zenith; Meeus adds 0.0019279' there
    return np.maximum(r_arcmin, 0.0) / 60.0


def refraction_bennett_deg(apparent_elevation_deg):
    """Refraction [deg] for an apparent elevation ``h0`` [deg] (Bennett 1982, Meeus eq.
    16.3): ``R = 1 / tan(h0 + 7.31 / (h0 + 4.4))`` arcminutes. Used in the tests as an
    independent check of :func:`refraction_saemundsson_deg`."""
    h0 = np.asarray(apparent_elevation_deg, dtype=np.float64)
    return np.maximum(1.0 / np.tan(np.radians(h0 + 7.31 / (h0 + 4.4))), 0.0) / 60.0


def kasten_young_airmass(elevation_deg):
    """Relative optical air mass for a (apparent) elevation [deg] >= 0 ([KY89]):
    ``m = 1 / (sin h + 0.50572 (h + 6.07995)^-1.6364)``; 1 at the zenith, 38.09 at the
    horizon."""
    from skydome.atmosphere.airmass import kastenyoung1989

    h = np.asarray(elevation_deg, dtype=np.float64)
    return kastenyoung1989(90.0 - h)


def _hg(cos_theta, g):
    """Henyey-Greenstein phase function normalised over the sphere [sr^-1]."""
    d = 1.0 + g * g - 2.0 * g * cos_theta
    return (1.0 - g * g) / (4.0 * math.pi * d * np.sqrt(d))


def _rayleigh_phase(cos_theta):
    """Rayleigh phase function 3/(16 pi) (1 + cos^2) [sr^-1] ([KRZ06] eq. 3 over 4 pi)."""
    return 3.0 / (16.0 * math.pi) * (1.0 + cos_theta * cos_theta)


@register
class Klassen1987(GroundEyeAerialPerspective, SkyModel):
    """Klassen's (1987) two-layer flat-earth atmosphere: sky, sun and fog colour.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position; its ``elevation_deg`` is the true (geometric) elevation, valid in
        [0, 90] deg. Refraction ([Sae86]) lifts it to the apparent elevation used for the
        light path and the scattering angle.
    turbidity : float
        Preetham turbidity [1, 32] setting the haze's vertical optical depth through the
        Angstrom law (default 2.5).
    haze_extinction_m : float, optional
        Haze extinction coefficient at 550 nm [m^-1] in [0, 0.1]; overrides turbidity.
    haze_layer_height_m : float
        Thickness of the haze-filled layer [m], 0 (no haze) or [1, air_layer_height_m]
        (default 1200).
    air_layer_height_m : float
        Total thickness of the air (top of the haze-free layer) [m], [100, 100000]
        (default 7994, the height of the homogeneous atmosphere with sea-level density).
    refractive_index : float
        Refractive index of air at sea level used in the Rayleigh coefficient, survey eq. 8
        [1.00001, 1.001] (default 1.000278, the survey's value).
    haze_g : float
        Henyey-Greenstein asymmetry of the haze phase function [-0.95, 0.95] (default 0.7).
    haze_albedo : float
        Single-scattering albedo of the haze [0, 1] (default 0.9).
    angstrom_alpha : float
        Angstrom exponent of the haze extinction [0, 4] (default 1.3).
    airmass : {"kasten_young", "flat"}
        Air mass of the path to the sun: "flat" is the flat-earth 1/cos(theta_s) of the
        paper's geometry (infinite at the horizon); "kasten_young" (default) the [KY89]
        curved-atmosphere air mass, so that a sun on the horizon keeps a finite path.
    """

    name = "klassen1987"
    reference = ("Klassen, R.V. 1987. Modeling the effect of the atmosphere on light. ACM TOG "
                 "6(3), 215-237; survey section 7.1")
    native = "spectral"
    own_ground = "own"                    # measured against rho E_h / pi: docs/models.md
    summary = "Flat earth, haze layer under haze-free air, closed-form single scattering, fog."
    parameters = (
        Parameter("turbidity", "", 2.5, 1.0, 32.0, "Preetham turbidity of the haze layer"),
        Parameter("haze_extinction_m", "m^-1", None, 0.0, 0.1,
                  "haze extinction at 550 nm (overrides turbidity)"),
        Parameter("haze_layer_height_m", "m", 1200.0, 0.0, 100_000.0, "haze layer thickness"),
        Parameter("air_layer_height_m", "m", 7994.0, 100.0, 100_000.0,
                  "total air thickness (homogeneous atmosphere)"),
        Parameter("refractive_index", "", 1.000278, 1.00001, 1.001,
                  "refractive index of air at sea level (survey eq. 8)"),
        Parameter("haze_g", "", 0.7, -0.95, 0.95, "Henyey-Greenstein asymmetry of the haze"),
        Parameter("haze_albedo", "", 0.9, 0.0, 1.0, "single-scattering albedo of the haze"),
        Parameter("angstrom_alpha", "", 1.3, 0.0, 4.0, "Angstrom exponent of the haze"),
        Parameter("airmass", "", "kasten_young", kind="choice", choices=("kasten_young", "flat"),
                  doc="air mass of the sun path"),
    )

    sun_elevation_range_deg = (0.0, 90.0)

    def _setup(self, p, params):
        sun = self.sun
        if p["haze_layer_height_m"] > p["air_layer_height_m"]:
            raise ValueError(f"haze_layer_height_m = {p['haze_layer_height_m']:g} m is out of range "
                             f"[0, {p['air_layer_height_m']:g}] m (at most air_layer_height_m)")
        if 0.0 < p["haze_layer_height_m"] < 1.0:
            raise ValueError(f"haze_layer_height_m = {p['haze_layer_height_m']:g} m is out of range "
                             "0 or [1, air_layer_height_m] m")
        if "haze_extinction_m" in params and "turbidity" in params:
            raise ValueError("give either turbidity or haze_extinction_m, not both")
        self.sun = sun
        for k, v in p.items():
            setattr(self, k, v)
        # [Sae86]: apparent elevation of the sun
        self.refraction_deg = float(refraction_saemundsson_deg(sun.elevation_deg))
        self.apparent_elevation_deg = min(sun.elevation_deg + self.refraction_deg, 90.0)
        e = math.radians(self.apparent_elevation_deg)
        a = math.radians(sun.azimuth_deg)
        self.apparent_sun_direction = np.array([math.cos(e) * math.sin(a),
                                                math.cos(e) * math.cos(a), math.sin(e)])
        if self.airmass == "flat":
            self.sun_airmass = 1.0 / max(math.sin(e), 1e-12)
        else:
            self.sun_airmass = float(kasten_young_airmass(self.apparent_elevation_deg))

    # -- optical properties ---------------------------------------------------------------
    def coefficients(self, wavelengths_nm):
        """Scattering and extinction coefficients [m^-1] of the two constituents.

        Returns
        -------
        beta_air : (n_lambda,)
            Rayleigh scattering (= extinction) coefficient of air, survey eq. 8.
        beta_haze_s, beta_haze_e : (n_lambda,)
            Haze scattering and extinction coefficients inside the haze layer.
        """
        from skydome.atmosphere.aerosols import angstrom_beta_from_turbidity
        from skydome.atmosphere.rayleigh import rayleigh_scattering_coefficient

        wl = as_wavelengths(wavelengths_nm)
        beta_air = rayleigh_scattering_coefficient(wl, refractive_index=self.refractive_index)
        h = self.haze_layer_height_m
        if h <= 0.0:
            ke = np.zeros_like(wl)
        elif self.haze_extinction_m is not None:
            ke = self.haze_extinction_m * (wl / 550.0) ** (-self.angstrom_alpha)
        else:
            # Angstrom law tau = beta (lambda / 1 um)^-alpha, beta from [PSS99] A.2,
            # spread over the haze layer
            beta = angstrom_beta_from_turbidity(self.turbidity)
            ke = beta * (wl / 1000.0) ** (-self.angstrom_alpha) / h
        return beta_air, self.haze_albedo * ke, ke

    def _layers(self, wl):
        """[(z_bottom, z_top, k_ext (nl,), [(beta_s (nl,), phase_id)...]), ...]"""
        b_air, b_hs, b_he = self.coefficients(wl)
        layers = []
        if self.haze_layer_height_m > 0.0:
            layers.append((0.0, self.haze_layer_height_m, b_air + b_he, b_air, b_hs))
        if self.air_layer_height_m > self.haze_layer_height_m:
            layers.append((self.haze_layer_height_m, self.air_layer_height_m, b_air, b_air,
                           np.zeros_like(b_air)))
        return layers

    def _vertical_depth(self, layers, z):
        """Vertical optical depth from altitude z (..., ) to the top, (..., nl)."""
        z = np.asarray(z, dtype=np.float64)[..., None]
        tau = 0.0
        for z0, z1, k, _, _ in layers:
            tau = tau + k * np.clip(z1 - np.maximum(z, z0), 0.0, None)
        return tau

    def _path(self, u, nu, distance, wl):
        """Transmittance and in-scattered radiance along straight paths from the ground.

        u : (n,) cosine of the view zenith angle (clamped to >= 0: flat ground).
        nu : (n,) cosine of the scattering angle (view direction . apparent sun).
        distance : (n,) path length [m] (inf: to the top of the air).
        """
        from skydome.spectra import solar_irradiance

        e_sun = solar_irradiance(wl) * self.sun.irradiance_scale
        layers = self._layers(wl)
        m = self.sun_airmass
        u = np.maximum(u, 1e-9)[:, None]
        d = distance[:, None]
        p_air = _rayleigh_phase(nu)[:, None]
        p_haze = _hg(nu, self.haze_g)[:, None]
        n, nl = u.shape[0], wl.size
        acc = np.zeros((n, nl))
        tau_view = np.zeros((n, nl))          # optical depth eye -> t_a
        t_a = np.zeros((n, 1))
        for z0, z1, k, b_air, b_haze in layers:
            # the piece of the path inside this layer: t in [t_a, t_b]
            t_b = np.minimum(z1 / u, d)
            dt = np.maximum(t_b - t_a, 0.0)
            # optical depth from the point at t_a (altitude u t_a) to the sun
            tau_sun_a = m * self._vertical_depth(layers, np.minimum(t_a[:, 0] * u[:, 0], z1))
            a_a = tau_view + tau_sun_a
            c = k * (1.0 - m * u)                                # rate of A(t), [Kla87]
            x = c * dt
            small = np.abs(x) < 1e-6
            safe_c = np.where(small, 1.0, c)
            with np.errstate(over="ignore", invalid="ignore"):
                integral = np.where(small, dt * np.exp(-a_a) * (1.0 - 0.5 * x),
                                    (np.exp(-a_a) - np.exp(-(a_a + x))) / safe_c)
            integral = np.where(dt > 0.0, integral, 0.0)
            acc += e_sun * (b_air * p_air + b_haze * p_haze) * integral
            tau_view = tau_view + k * dt
            t_a = np.maximum(t_b, t_a)
        return np.exp(-tau_view), np.maximum(acc, 0.0)

    # -- public API ---------------------------------------------------------------------
    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Single-scattered sky radiance [W m^-2 sr^-1 nm^-1], shape (..., n_wavelengths).

        Directions below the horizon are evaluated as the horizontal direction of the same
        azimuth (the flat ground is not modelled; use :meth:`fog` with an object radiance
        for the ground)."""
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        from skydome.models.simulated.kaneda1991 import _horizon_clamp

        flat = _horizon_clamp(d.reshape(-1, 3))
        nu = np.clip(flat @ self.apparent_sun_direction, -1.0, 1.0)
        _, L = self._path(flat[:, 2], nu, np.full(flat.shape[0], np.inf), wl)
        return L.reshape(d.shape[:-1] + (wl.size,))

    def transmittance(self, directions, wavelengths_nm) -> np.ndarray:
        """Transmittance from the eye to the top of the air, (..., n_wavelengths)."""
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        flat = d.reshape(-1, 3)
        t, _ = self._path(flat[:, 2], np.zeros(flat.shape[0]), np.full(flat.shape[0], np.inf), wl)
        return t.reshape(d.shape[:-1] + (wl.size,))

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Radiance of the sun's disc [W m^-2 sr^-1 nm^-1]: E_sun / Omega_sun x
        exp(-m tau_vertical), m the sun's air mass (the ``airmass`` parameter)."""
        from skydome.spectra import solar_irradiance

        wl = as_wavelengths(wavelengths_nm)
        tau = self._vertical_depth(self._layers(wl), 0.0)
        return (solar_irradiance(wl) * self.sun.irradiance_scale / self.sun.solid_angle_sr
                * np.exp(-self.sun_airmass * tau))

    def _aerial_rays(self, dd, dist, wl):
        """The rays of ``aerial_perspective`` (closed form per layer); a direction below the
        horizon is taken as the horizontal direction of the same azimuth."""
        from skydome.models.simulated.kaneda1991 import _horizon_clamp

        dd = _horizon_clamp(dd)
        nu = np.clip(dd @ self.apparent_sun_direction, -1.0, 1.0)
        return self._path(dd[:, 2], nu, dist, wl)


#: The earlier name (class names follow the registry names, without a "Sky" suffix).
Klassen1987Sky = Klassen1987
