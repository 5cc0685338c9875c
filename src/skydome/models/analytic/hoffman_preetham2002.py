"""Hoffman & Preetham (2002): "Rendering Outdoor Light Scattering in Real Time".

A homogeneous-medium simplification of Preetham et al. (1999) built for vertex and pixel
shaders. Along a path of length s the light of an object is attenuated by the extinction
factor F_ex and the air adds in-scattered sunlight L_in::

    F_ex = exp(-(beta_R + beta_M) s)
    L_in = (beta_R(theta) + beta_M(theta)) / (beta_R + beta_M) * E_sun * (1 - F_ex)
    beta_R(theta) = beta_R 3 / (16 pi) (1 + cos^2 theta)
    beta_M(theta) = beta_M 1 / (4 pi) (1 - g)^2 / (1 + g^2 - 2 g cos theta)^(3/2)

theta being the angle between the view ray and the sun. beta_R follows the Rayleigh
formula and beta_M Preetham's haze formula for a turbidity T (both at sea level, from
:mod:`skydome.models.analytic.preetham1999`); E_sun is the sun's spectral irradiance at the
ground, attenuated as in Preetham et al. (1999) Appendix A.1.

The same formulas give a sky: ``radiance(directions)`` is L_in along each direction for a
path through a homogeneous shell (see :class:`HoffmanPreetham2002`).

References
----------
.. [HP02] N. Hoffman, A. J. Preetham, "Rendering Outdoor Light Scattering in Real Time",
   Game Developers Conference 2002 / ATI Technologies white paper (2002).
.. [PSS99] A. J. Preetham, P. Shirley, B. Smits, "A Practical Analytic Model for Daylight",
   Proc. SIGGRAPH 99, pp. 91-100 (1999).
.. [HG41] L. G. Henyey, J. L. Greenstein, "Diffuse radiation in the galaxy", Astrophys. J.
   93, 70-83 (1941).
"""

from __future__ import annotations

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_choice, check_number
from skydome.models import Parameter, SkyModel, register
from skydome.models.analytic import preetham1999 as _p99

__all__ = [
    "HoffmanPreetham2002",
    "rayleigh_phase",
    "mie_phase",
    "aerial_perspective",
    "PHASE_FORMS",
    "EARTH_RADIUS_M",
]

#: Mie phase forms: "hoffman_preetham" is the [HP02] form with (1 - g)^2 in the numerator;
#: "henyey_greenstein" the normalised [HG41] form with (1 - g^2).
PHASE_FORMS = ("hoffman_preetham", "henyey_greenstein")

#: Mean Earth radius for the sky-view path length [m] (IUGG mean radius R1).
EARTH_RADIUS_M = 6371.0e3

#: Ratio of the haze to the molecular scale height in [PSS99] (1200 m / 8803 m): the
#: factor that turns the sea-level haze coefficient into the one of a homogeneous layer
#: as thick as the molecular scale height with the same haze column.
_HAZE_COLUMN_FACTOR = _p99.ALPHA_MOLECULES / _p99.ALPHA_HAZE

_WL_RANGE = (380.0, 780.0)


def rayleigh_phase(cos_theta) -> np.ndarray:
    """Rayleigh phase function 3 / (16 pi) (1 + cos^2 theta) [sr^-1] ([HP02]); integrates
    to 1 over the sphere."""
    c = np.asarray(cos_theta, dtype=np.float64)
    return 3.0 / (16.0 * np.pi) * (1.0 + c * c)


def mie_phase(cos_theta, g: float, form: str = "hoffman_preetham") -> np.ndarray:
    """Henyey-Greenstein Mie phase function [sr^-1].

    ``form="hoffman_preetham"``: ``(1 - g)^2 / (4 pi (1 + g^2 - 2 g cos theta)^1.5)`` as
    printed in [HP02]; it integrates to (1 - g) / (1 + g) over the sphere, not 1.
    ``form="henyey_greenstein"``: ``(1 - g^2) / (4 pi (...)^1.5)`` [HG41], normalised.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the angle between the view ray and the sun [-].
    g : float
        Asymmetry parameter in (-1, 1).
    form : {"hoffman_preetham", "henyey_greenstein"}
    """
    g = check_number("g", g, -1.0, 1.0, low_open=True, high_open=True)
    check_choice("form", form, PHASE_FORMS)
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), -1.0, 1.0)
    num = (1.0 - g) ** 2 if form == "hoffman_preetham" else 1.0 - g * g
    return num / (4.0 * np.pi * (1.0 + g * g - 2.0 * g * c) ** 1.5)


def _coefficients(w, turbidity, rayleigh_multiplier, mie_multiplier):
    beta_r = _p99.rayleigh_coefficient(w) * rayleigh_multiplier
    beta_m = _p99.mie_coefficient(w, turbidity) * mie_multiplier
    return beta_r, beta_m


def _sun_irradiance(w, sun, turbidity):
    """Spectral irradiance of the attenuated sun on a plane normal to it [W m^-2 nm^-1]."""
    return _p99.sun_radiance(w, sun, turbidity) * sun.solid_angle_sr


def aerial_perspective(view_direction, distance_m, wavelengths_nm, *, sun, turbidity: float = 2.0,
                       g: float = 0.76, rayleigh_multiplier: float = 1.0,
                       mie_multiplier: float = 1.0, phase: str = "hoffman_preetham"):
    """Extinction factor and in-scattered radiance of [HP02] along view rays.

    Parameters
    ----------
    view_direction : array_like
        Unit vector(s) (..., 3) from the eye towards the object (East-North-Up).
    distance_m : array_like
        Path length s [m] >= 0, broadcast against ``view_direction[..., 0]``.
    wavelengths_nm : array_like
        1-D strictly increasing wavelengths [nm] in [380, 780].
    sun : skydome.Sun
        The sun; below the horizon E_sun = 0 (no in-scattering, extinction only).
    turbidity : float
        Preetham turbidity T [-] in [2, 10], sets beta_M.
    g : float
        Henyey-Greenstein asymmetry in (-1, 1); default 0.76 (a typical haze value; [HP02]
        leaves it to the user).
    rayleigh_multiplier, mie_multiplier : float
        Scale factors on beta_R and beta_M [-] in [0, 100] ([HP02] exposes such artist
        controls); 1 = sea-level coefficients.
    phase : {"hoffman_preetham", "henyey_greenstein"}
        Mie phase form, see :func:`mie_phase`.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        F_ex [-] and L_in [W m^-2 sr^-1 nm^-1], each shape (..., n).
    """
    d = as_directions(view_direction, "view_direction")
    s = _p99.check_distances(distance_m)
    w = as_wavelengths(wavelengths_nm, *_WL_RANGE)
    T = check_number("turbidity", turbidity, *_p99.TURBIDITY_RANGE)
    g = check_number("g", g, -1.0, 1.0, low_open=True, high_open=True)
    kr = check_number("rayleigh_multiplier", rayleigh_multiplier, 0.0, 100.0)
    km = check_number("mie_multiplier", mie_multiplier, 0.0, 100.0)
    check_choice("phase", phase, PHASE_FORMS)
    beta_r, beta_m = _coefficients(w, T, kr, km)
    beta = beta_r + beta_m
    cos_t = np.clip(d @ sun.direction, -1.0, 1.0)[..., None]
    f_ex = np.exp(-beta * s[..., None])                                        # [HP02] F_ex
    ang = beta_r * rayleigh_phase(cos_t) + beta_m * mie_phase(cos_t, g, phase)  # [HP02] beta(theta)
    e_sun = _sun_irradiance(w, sun, T)
    safe = np.where(beta > 0.0, beta, 1.0)
    l_in = np.where(beta > 0.0, ang / safe, 0.0) * e_sun * (1.0 - f_ex)        # [HP02] L_in
    shape = np.broadcast_shapes(f_ex.shape, l_in.shape)
    return np.broadcast_to(f_ex, shape).copy(), np.maximum(np.broadcast_to(l_in, shape), 0.0)


def shell_path_length(cos_zenith, thickness_m: float, radius_m: float = EARTH_RADIUS_M):
    """Length [m] of a ray from the ground to the top of a shell of given thickness around a
    sphere: ``-R u + sqrt(R^2 u^2 + 2 R H + H^2)`` (u = cos of the view zenith angle, >= 0)."""
    u = np.asarray(cos_zenith, dtype=np.float64)
    R, H = radius_m, thickness_m
    return -R * u + np.sqrt(R * R * u * u + 2.0 * R * H + H * H)


@register
class HoffmanPreetham2002(SkyModel):
    """Hoffman & Preetham (2002) real-time scattering, as a sky and as aerial perspective.

    Parameters
    ----------
    sun : skydome.Sun
        Elevation in [0, 90] deg (ValueError otherwise: the model has no twilight).
    turbidity : float
        Preetham turbidity T [-] in [2, 10].
    g : float
        Henyey-Greenstein asymmetry [-] in [0, 0.99]; default 0.76.
    sky_distance_m : float
        Thickness H [m] of the homogeneous shell used for the sky view, in [100, 100000];
        default 8803 m, the molecular scale height of [PSS99] (a homogeneous layer that
        thick at sea-level density holds the molecular column of the exponential
        atmosphere).
    phase : {"hoffman_preetham", "henyey_greenstein"}
        Mie phase form (see :func:`mie_phase`); default the [HP02] form.

    Notes
    -----
    Native quantity: spectral radiance (the formulas are per wavelength). The sky radiance
    in a direction of view zenith angle theta_v is L_in of :func:`aerial_perspective` for
    the path length through the shell, ``s = -R cos theta_v + sqrt(R^2 cos^2 theta_v +
    2 R H + H^2)`` with R = 6371 km (finite at the horizon: about 335 km for H = 8803 m).
    In the sky view the haze coefficient is scaled by 1200 / 8803 (haze over molecular scale
    height of [PSS99]) so that the shell holds the haze column of Preetham's exponential
    atmosphere; :meth:`aerial_perspective` uses the unscaled sea-level coefficients.
    Directions below the horizon return 0. There is no multiple scattering and no skylight
    in-scattering (the [HP02] simplification), so the sky is darker than Preetham's fit.
    """

    name = "hoffman_preetham2002"
    reference = ("N. Hoffman, A. J. Preetham, 'Rendering Outdoor Light Scattering in Real "
                 "Time', Game Developers Conference 2002 (ATI white paper)")
    native = "spectral"
    viewer_shader = "hoffman_preetham2002"
    viewer_parameters = ("turbidity", "g", "sky_distance_m", "phase")
    airlight = True                       # F_ex, L_in
    summary = "Homogeneous single-scattering sky and aerial perspective for shaders"
    parameters = (
        Parameter("turbidity", "", 2.5, _p99.TURBIDITY_RANGE[0], _p99.TURBIDITY_RANGE[1],
                  "Preetham turbidity; sets the haze scattering coefficient"),
        Parameter("g", "", 0.76, 0.0, 0.99, "Henyey-Greenstein asymmetry of haze"),
        Parameter("sky_distance_m", "m", 1.0 / _p99.ALPHA_MOLECULES, 100.0, 100000.0,
                  "thickness of the homogeneous shell of the sky view"),
        Parameter("phase", "", "hoffman_preetham", kind="choice", choices=PHASE_FORMS,
                  doc="Mie phase form"),
    )

    sun_elevation_range_deg = (0.0, 90.0)

    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Sky spectral radiance [W m^-2 sr^-1 nm^-1], shape (..., n); wavelengths in
        [380, 780] nm; zero below the horizon."""
        from skydome.models.analytic._kernels_analytic import flat_directions
        from skydome.models.analytic._kernels_hoffman_preetham import hoffman_preetham_sky

        w = as_wavelengths(wavelengths_nm, *_WL_RANGE)
        flat, lead = flat_directions(directions)
        # the equations of aerial_perspective along shell_path_length, in one parallel
        # pass (the same order of operations; its exponentials by the kernel core's
        # vectorised exp: tests/test_hoffman_preetham.py compares the two)
        beta_r, beta_m = _coefficients(w, self.turbidity, 1.0, _HAZE_COLUMN_FACTOR)
        g = float(self.g)
        num = (1.0 - g) ** 2 if self.phase == "hoffman_preetham" else 1.0 - g * g
        out = np.empty((flat.shape[0], w.size))
        hoffman_preetham_sky(flat, np.ascontiguousarray(self.sun.direction, dtype=np.float64),
                             EARTH_RADIUS_M, float(self.sky_distance_m), beta_r, beta_m,
                             beta_r + beta_m, _sun_irradiance(w, self.sun, self.turbidity),
                             g, num, out)
        return out.reshape(lead + (w.size,))

    def _radiance_numpy(self, directions, wavelengths_nm) -> np.ndarray:
        """:meth:`radiance` by the module's NumPy functions (the kernel's check)."""
        d = as_directions(directions)
        u = d[..., 2]
        s = shell_path_length(np.maximum(u, 0.0), self.sky_distance_m)
        _, l_in = aerial_perspective(d, s, wavelengths_nm, sun=self.sun,
                                     turbidity=self.turbidity, g=self.g,
                                     mie_multiplier=_HAZE_COLUMN_FACTOR, phase=self.phase)
        return np.where((u >= 0.0)[..., None], l_in, 0.0)

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Spectral radiance of the sun's disc at the ground [W m^-2 sr^-1 nm^-1] (Preetham
        1999 Appendix A.1 attenuation), shape (n,)."""
        return _p99.sun_radiance(wavelengths_nm, self.sun, self.turbidity)

    def aerial_perspective(self, directions, distance_m, wavelengths_nm, **kwargs):
        """(F_ex, L_in) of :func:`aerial_perspective` with this model's sun, turbidity, g
        and phase form (sea-level coefficients)."""
        kw = dict(turbidity=self.turbidity, g=self.g, phase=self.phase)
        kw.update(kwargs)
        return aerial_perspective(directions, distance_m, wavelengths_nm, sun=self.sun, **kw)
