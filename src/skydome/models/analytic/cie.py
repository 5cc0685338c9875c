"""CIE sky luminance distributions: the CIE 1994 overcast, clear and intermediate skies
(as in Radiance's gensky) and the 15 CIE standard general skies (CIE S 011/E:2003,
ISO 15469:2004).

All models here are luminance-only (``native = "luminance"``): ``luminance(directions)``
returns cd m^-2 and ``relative_luminance(directions)`` returns L/Lz (1 at the zenith).
Directions below the horizon (z < 0) get luminance 0: these are sky models, the ground
is not part of them (Radiance's gensky instead blends the sky into a ground brightness
near the horizon; see docs/sections/cie.md).

Each model is scaled by ``zenith_luminance`` [cd m^-2] or, alternatively, by
``diffuse_horizontal_illuminance`` [lx], the illuminance the sky (without the sun)
gives on a horizontal plane: E_h = int L cos(theta) d(omega) over the upper hemisphere.
Give one, not both (both are accepted only when they agree to 0.1 %, so that the values
in ``describe()`` round-trip). Without either, each model uses the default zenith
luminance documented in its class.

References
----------
[CIE94] CIE 110-1994, Spatial distribution of daylight - luminance distributions of
    various reference skies. CIE, Vienna, 1994.
[MS42] Moon, P. and Spencer, D. E. (1942), Illumination from a non-uniform sky.
    Illuminating Engineering 37, 707-726.
[Kit67] Kittler, R. (1967), Standardisation of outdoor conditions for the calculation of
    the daylight factor with clear skies. Proc. CIE Sunlight conf., Newcastle.
[CIE03] CIE S 011/E:2003 = ISO 15469:2004, Spatial distribution of daylight - CIE
    standard general sky. CIE, Vienna, 2003.
[KDP98] Kittler, R., Darula, S. and Perez, R. (1998), A set of standard skies
    characterizing daylight conditions for computer and energy conscious design.
    Final report US-SK 92 052, Bratislava / Albany.
[KS74] Krochmann, J. and Seidl, M. (1974), Quantitative data on daylight for illuminating
    engineering. Lighting Res. Technol. 6(3), 165-171.
[KNNS84] Karayel, M., Navvab, M., Ne'eman, E. and Selkowitz, S. (1984), Zenith luminance
    and sky luminance distributions for daylighting calculations. Energy and Buildings
    6, 283-291.
[Rad] Ward, G. et al., Radiance: gensky.c and skybright.cal (LBNL, github.com/LBNL-ETA/
    Radiance, src/gen/).
[Survey] eqs. 13 and 14 of the survey of sky models this package follows.
"""

from __future__ import annotations

import math

import numpy as np

from skydome._validate import clamp_cosine
from skydome.models import Parameter, SkyModel, register

__all__ = ["CIE1994Overcast", "CIE1994Clear", "CIE1994Intermediate", "CIE2003",
           "hemisphere_illuminance", "cie2003_parameters", "CIE2003_TYPE_NAMES",
           "zenith_luminance_overcast", "zenith_luminance_clear",
           "zenith_luminance_intermediate"]

#: Maximum solar elevation [deg] used in the tan() zenith-luminance formula of the clear
#: and intermediate skies (Radiance's gensky caps the sun at 87 deg for the same reason:
#: tan(elevation) diverges at the zenith).
LZ_CLEAR_MAX_ELEVATION_DEG = 87.0

_LZ_PARAM = Parameter(
    "zenith_luminance", "cd/m^2", None, 0.0, 1.0e6,
    "luminance of the zenith; None: from diffuse_horizontal_illuminance or the model's "
    "default formula")
_EH_PARAM = Parameter(
    "diffuse_horizontal_illuminance", "lx", None, 0.0, 2.0e5,
    "illuminance of the sky (no sun) on a horizontal plane; alternative to zenith_luminance")
#: The sun of a CIE sky: the standards describe the sky alone, so a user who wants the
#: solar disc (renders, illuminance on planes) gives its direct normal illuminance.
DNI_ILLUMINANCE_PARAM = Parameter(
    "dni_illuminance", "lx", None, 0.0, 135000.0,
    "direct normal illuminance of the sun; None: no sun (the sky alone)")
_TURB_PARAM = Parameter(
    "turbidity", "", 2.45, 1.5, 20.0,
    "Linke turbidity used only by the default zenith luminance formula (gensky -t)")


# -- zenith luminance formulas -----------------------------------------------------------------
def zenith_luminance_overcast(elevation_deg: float) -> float:
    """Zenith luminance of the CIE overcast sky [cd m^-2] for a solar elevation [deg].

    Lz = 123 + 8600 sin(h) cd m^-2 ([KS74]; the formula of Radiance's gensky -c,
    ``zenithbr = 8.6*sundir[2] + .123`` kcd m^-2), set to 0 where it is negative
    (sun more than 0.82 deg below the horizon), as gensky does.
    """
    h = math.radians(elevation_deg)
    return max(0.0, 1000.0 * (8.6 * math.sin(h) + 0.123))


def zenith_luminance_clear(elevation_deg: float, turbidity: float = 2.45) -> float:
    """Zenith luminance of the CIE clear sky [cd m^-2] for a solar elevation [deg].

    Lz = [(1.376 T - 1.81) tan(h) + 0.38] kcd m^-2 ([KNNS84], the formula of Radiance's
    gensky +s), with h capped at 87 deg (as gensky does) and the result set to 0 where
    it would be negative (as gensky does).
    """
    h = math.radians(min(elevation_deg, LZ_CLEAR_MAX_ELEVATION_DEG))
    return max(0.0, 1000.0 * ((1.376 * turbidity - 1.81) * math.tan(h) + 0.38))


def zenith_luminance_intermediate(elevation_deg: float, turbidity: float = 2.45) -> float:
    """Zenith luminance of the intermediate sky [cd m^-2]: the mean of the clear and
    overcast formulas (gensky +i), before clamping at 0."""
    h = min(elevation_deg, LZ_CLEAR_MAX_ELEVATION_DEG)
    clear = (1.376 * turbidity - 1.81) * math.tan(math.radians(h)) + 0.38
    over = 8.6 * math.sin(math.radians(elevation_deg)) + 0.123
    return max(0.0, 1000.0 * 0.5 * (clear + over))


# -- numerical hemisphere integral -----------------------------------------------------------
def hemisphere_illuminance(relative_luminance, n_mu: int = 256, n_phi: int = 512) -> float:
    """Horizontal illuminance int L(d) cos(theta) d(omega) over the upper hemisphere of a
    luminance function ``relative_luminance(directions)``, numerically (for any model,
    use :func:`skydome.illuminance.sky_illuminance`).

    ``relative_luminance`` must accept the keyword ``_aligned=True``, meaning that the
    directions it gets are in a frame whose azimuth origin (+y) is the solar azimuth (the
    illuminance does not depend on the solar azimuth). The azimuth nodes are offset by half
    a step from the sun so the cusp of exp(d chi) at the sun never falls on a node. With
    the defaults the relative error is about 2e-7 for the sharpest sky (CIE 2003 type 15;
    tests compare with a 4x finer grid and with the closed form 7 pi / 9 of eq. 13).
    """
    from skydome.illuminance import sky_quadrature

    # The horizontal plane's nodes of skydome.illuminance (Gauss-Legendre in the zenith
    # angle, midpoint rule in azimuth starting half a step from azimuth 0), read as
    # directions in a frame whose azimuth origin (+y) is the solar azimuth; the luminance
    # function is told so (``_aligned=True``) and uses the sun at azimuth 0 with the same
    # elevation. The illuminance does not depend on the solar azimuth. The weights
    # include cos(theta).
    d_local, w = sky_quadrature((0.0, 0.0, 1.0), n_mu, n_phi)
    return float(np.sum(w * relative_luminance(d_local, _aligned=True)))


def _check_scaling(name: str, lz, eh) -> None:
    if lz is not None and eh is not None:
        raise ValueError(
            f"{name}: give zenith_luminance or diffuse_horizontal_illuminance, not both "
            f"(got zenith_luminance = {lz:g} cd/m^2 and diffuse_horizontal_illuminance = "
            f"{eh:g} lx)")


class _CIEBase(SkyModel):
    """Shared machinery: scaling by Lz or E_h, zero below the horizon."""

    native = "luminance"
    sun_elevation_range_deg = (0.0, 90.0)

    def _begin_cie(self, sun, kwargs):
        params = self._begin(sun, kwargs)
        for k, v in params.items():
            setattr(self, k, v)
        self._sun_dir = np.asarray(sun.direction, dtype=np.float64)
        # Direction of the sun with azimuth 0 (towards +y): used by the aligned integrator.
        h = math.radians(sun.elevation_deg)
        self._sun_dir_aligned = np.array([0.0, math.cos(h), math.sin(h)])
        self._finish_params()
        return params

    def sun_luminance(self) -> float | None:
        """Mean luminance of the solar disc [cd m^-2]: ``dni_illuminance`` spread over the
        disc's solid angle; None without ``dni_illuminance`` (the CIE skies describe the sky
        only), 0 with the sun below the horizon."""
        e = getattr(self, "dni_illuminance", None)
        if e is None:
            return None
        if self.sun.elevation_deg < 0.0:
            return 0.0
        return float(e) / float(self.sun.solid_angle_sr)

    def _resolve_scale(self, default_lz: float) -> None:
        lz, eh = self.zenith_luminance, self.diffuse_horizontal_illuminance
        if lz is not None and eh is not None:
            ratio = self._illuminance_per_zenith_luminance()
            if abs(lz * ratio - eh) > 1e-3 * max(eh, 1e-300):
                _check_scaling(self.name, lz, eh)
        elif eh is not None:
            lz = eh / self._illuminance_per_zenith_luminance()
        elif lz is None:
            lz = default_lz
        self.zenith_luminance = float(lz)
        self.diffuse_horizontal_illuminance = float(lz * self._illuminance_per_zenith_luminance())

    def _illuminance_per_zenith_luminance(self) -> float:
        """E_h / Lz [sr]."""
        if not hasattr(self, "_eh_per_lz"):
            self._eh_per_lz = hemisphere_illuminance(self._relative)
        return self._eh_per_lz

    def _relative(self, d, _aligned: bool = False):  # pragma: no cover - abstract
        raise NotImplementedError

    def _finish_params(self):  # pragma: no cover - hook
        pass

    # -- public ----------------------------------------------------------------------------
    # ``_relative`` (numpy) is the reference implementation of each sky (also used for the
    # hemisphere integral); the public methods evaluate the same formulas with a parallel
    # numba kernel (``_kernels_analytic``, imported on first use), equal to 1e-12 relative.
    def _evaluate(self, directions, scale: float) -> np.ndarray:
        from skydome.models.analytic import _kernels_analytic as K

        flat, lead = K.flat_directions(directions)
        return self._kernel(K, flat, float(scale)).reshape(lead)

    def _kernel(self, K, flat, scale):  # pragma: no cover - abstract
        raise NotImplementedError

    def relative_luminance(self, directions) -> np.ndarray:
        """Luminance relative to the zenith, L/Lz (dimensionless), shape (...); 0 below
        the horizon (z < 0)."""
        return self._evaluate(directions, 1.0)

    def luminance(self, directions) -> np.ndarray:
        """Sky luminance [cd m^-2], shape (...); 0 below the horizon (z < 0)."""
        return self._evaluate(directions, self.zenith_luminance)

    def _cos_gamma(self, d, aligned):
        s = self._sun_dir_aligned if aligned else self._sun_dir
        return clamp_cosine(d @ s)


# -- CIE 1994 overcast --------------------------------------------------------------------------
@register
class CIE1994Overcast(_CIEBase):
    """CIE standard overcast sky (Moon & Spencer 1942; CIE 110-1994).

    L(theta) = Lz (1 + 2 cos theta) / 3  (survey eq. 13), theta the zenith angle of the
    viewing direction; independent of the sun's azimuth. E_h = 7 pi Lz / 9.

    Parameters
    ----------
    sun : skydome.Sun
        The sun; only its elevation is used (default zenith luminance). Any elevation is
        accepted; below -0.82 deg the default zenith luminance is 0 (a black sky).
    zenith_luminance : float, optional
        Zenith luminance [cd m^-2], [0, 1e6]. Default: 123 + 8600 sin(h) cd m^-2
        (Krochmann & Seidl 1974, the formula of Radiance's gensky -c), h the solar
        elevation, clamped at 0.
    diffuse_horizontal_illuminance : float, optional
        Horizontal illuminance of the sky [lx], [0, 2e5]; sets Lz = 9 E_h / (7 pi).

    References
    ----------
    [MS42], [CIE94], [KS74], [Rad]; survey eq. 13.
    """

    name = "cie1994_overcast"
    reference = ("Moon & Spencer (1942), Illuminating Engineering 37, 707-726; "
                 "CIE 110-1994 standard overcast sky")
    summary = "CIE standard overcast sky, L = Lz (1 + 2 cos theta) / 3"
    parameters = (_LZ_PARAM, _EH_PARAM, DNI_ILLUMINANCE_PARAM)
    sun_elevation_range_deg = (-90.0, 90.0)   # black below -0.82 deg (default Lz = 0)

    def __init__(self, sun=None, **params):
        self._begin_cie(sun, params)
        self._resolve_scale(zenith_luminance_overcast(self.sun.elevation_deg))

    def _illuminance_per_zenith_luminance(self) -> float:
        return 7.0 * math.pi / 9.0  # int (1 + 2 mu)/3 mu d(omega) = 2 pi (1/2 + 2/3)/3

    def _relative(self, d, _aligned: bool = False):
        z = d[..., 2]
        return np.where(z >= 0.0, (1.0 + 2.0 * np.maximum(z, 0.0)) / 3.0, 0.0)  # eq. 13

    def _kernel(self, K, flat, scale):
        return K.cie_overcast(flat, scale)


# -- CIE 1994 clear ------------------------------------------------------------------------------
def _clear_indicatrix(gamma, cos_gamma):
    """f(gamma) = 0.91 + 10 exp(-3 gamma) + 0.45 cos^2 gamma (survey eq. 14, [Kit67])."""
    return 0.91 + 10.0 * np.exp(-3.0 * gamma) + 0.45 * cos_gamma * cos_gamma


@register
class CIE1994Clear(_CIEBase):
    """CIE standard clear sky (Kittler 1967; CIE 1973 / CIE 110-1994).

    L = Lz f(gamma) phi(theta) / (f(theta_s) phi(0))  (survey eq. 14) with
    f(gamma) = 0.91 + 10 exp(-3 gamma) + 0.45 cos^2 gamma and
    phi(theta) = 1 - exp(-0.32 / cos theta) (phi = 1 at the horizon), gamma the angle to
    the sun, theta the zenith angle, theta_s the solar zenith angle.

    Parameters
    ----------
    sun : skydome.Sun
        The sun, elevation in [0, 90] deg (a ValueError otherwise).
    zenith_luminance : float, optional
        Zenith luminance [cd m^-2], [0, 1e6]. Default: [(1.376 T - 1.81) tan(h) + 0.38]
        kcd m^-2 (Karayel et al. 1984, the formula of Radiance's gensky +s), h the solar
        elevation capped at 87 deg.
    diffuse_horizontal_illuminance : float, optional
        Horizontal illuminance of the sky [lx], [0, 2e5] (numerical hemisphere integral).
    turbidity : float
        Linke turbidity T, [1.5, 20], default 2.45 (gensky's default); used only by the
        default zenith luminance.

    References
    ----------
    [Kit67], [CIE94], [KNNS84], [Rad]; survey eq. 14.
    """

    name = "cie1994_clear"
    reference = ("Kittler (1967); CIE 110-1994 standard clear sky (survey eq. 14); "
                 "zenith luminance of Karayel et al. (1984) as in Radiance gensky")
    summary = "CIE standard clear sky (Kittler), gensky +s"
    parameters = (_LZ_PARAM, _EH_PARAM, _TURB_PARAM, DNI_ILLUMINANCE_PARAM)

    def __init__(self, sun=None, **params):
        self._begin_cie(sun, params)
        zs = math.radians(self.sun.zenith_deg)
        # Denominator of eq. 14: f(theta_s) phi(0)
        self._norm = float(_clear_indicatrix(zs, math.cos(zs)) * (1.0 - math.exp(-0.32)))
        self._resolve_scale(zenith_luminance_clear(self.sun.elevation_deg, self.turbidity))

    def _relative(self, d, _aligned: bool = False):
        z = d[..., 2]
        cg = self._cos_gamma(d, _aligned)
        gamma = np.arccos(cg)
        zpos = np.maximum(z, 0.0)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            grad = np.where(zpos > 0.0, -np.expm1(-0.32 / np.where(zpos > 0, zpos, 1.0)), 1.0)
        rel = _clear_indicatrix(gamma, cg) * grad / self._norm  # eq. 14
        return np.where(z >= 0.0, rel, 0.0)

    def _kernel(self, K, flat, scale):
        return K.cie_kittler(flat, self._sun_dir, 0.91, 10.0, 0.45, self._norm, scale)


# -- CIE intermediate (gensky +i) ----------------------------------------------------------------
@register
class CIE1994Intermediate(_CIEBase):
    """CIE intermediate sky as defined by Radiance's gensky +i (skybright.cal).

    L = Lz g(eta, zt, gamma) / g(0, zt, zt) with
    g = [(1.35 sin(5.631 - 3.59 eta) + 3.12) sin(4.396 - 2.6 zt) + 6.37 - eta] / 2.326
        * exp(-0.563 gamma [(2.629 - eta)(1.562 - zt) + 0.812]),
    eta the zenith angle of the view direction, zt the solar zenith angle and gamma the
    angle to the sun (all in radians). gensky divides by a fitted polynomial F2(zt)
    instead of g(0, zt, zt); the two differ by 0.02-0.03 % (see docs).

    Parameters
    ----------
    sun : skydome.Sun
        The sun, elevation in [0, 90] deg.
    zenith_luminance : float, optional
        Zenith luminance [cd m^-2]. Default: the mean of the clear and overcast formulas
        (as gensky +i), in kcd m^-2: [(1.376 T - 1.81) tan(h) + 0.38 + 8.6 sin(h) + 0.123]/2.
    diffuse_horizontal_illuminance : float, optional
        Horizontal illuminance of the sky [lx] (numerical hemisphere integral).
    turbidity : float
        Linke turbidity for the default zenith luminance, [1.5, 20], default 2.45.

    References
    ----------
    [CIE94], [Rad] (skybright.cal ``intersky``, gensky.c).
    """

    name = "cie1994_intermediate"
    reference = "CIE 110-1994 intermediate sky, as implemented by Radiance gensky +i"
    summary = "CIE intermediate sky (Radiance gensky +i)"
    parameters = (_LZ_PARAM, _EH_PARAM, _TURB_PARAM, DNI_ILLUMINANCE_PARAM)

    def __init__(self, sun=None, **params):
        self._begin_cie(sun, params)
        self._zt = math.radians(self.sun.zenith_deg)
        self._norm = float(self._g(np.array(0.0), self._zt, np.array(self._zt)))
        self._resolve_scale(zenith_luminance_intermediate(self.sun.elevation_deg,
                                                          self.turbidity))

    @staticmethod
    def _g(eta, zt, gamma):
        num = ((1.35 * np.sin(5.631 - 3.59 * eta) + 3.12) * math.sin(4.396 - 2.6 * zt)
               + 6.37 - eta) / 2.326
        return num * np.exp(-0.563 * gamma * ((2.629 - eta) * (1.562 - zt) + 0.812))

    def _relative(self, d, _aligned: bool = False):
        z = d[..., 2]
        eta = np.arccos(clamp_cosine(z))
        gamma = np.arccos(self._cos_gamma(d, _aligned))
        rel = np.maximum(self._g(eta, self._zt, gamma), 0.0) / self._norm
        return np.where(z >= 0.0, rel, 0.0)

    def _kernel(self, K, flat, scale):
        return K.cie_intermediate(flat, self._sun_dir, self._zt, self._norm, scale)


# -- CIE 2003 standard general sky ----------------------------------------------------------------
CIE2003_TYPE_NAMES = {
    1: "overcast, steep luminance gradation towards zenith, azimuthal uniformity",
    2: "overcast, steep gradation, slight brightening towards the sun",
    3: "overcast, moderately graded, azimuthal uniformity",
    4: "overcast, moderately graded, slight brightening towards the sun",
    5: "sky of uniform luminance",
    6: "partly cloudy, no gradation towards zenith, slight brightening towards the sun",
    7: "partly cloudy, no gradation towards zenith, brighter circumsolar region",
    8: "partly cloudy, no gradation towards zenith, distinct solar corona",
    9: "partly cloudy, with the obscured sun",
    10: "partly cloudy, with brighter circumsolar region",
    11: "white-blue sky with distinct solar corona",
    12: "CIE standard clear sky, low atmospheric turbidity",
    13: "CIE standard clear sky, polluted atmosphere",
    14: "cloudless turbid sky with broad solar corona",
    15: "white-blue turbid sky with broad solar corona",
}


def cie2003_parameters(sky_type: int) -> tuple[float, float, float, float, float]:
    """(a, b, c, d, e) of CIE S 011/E:2003 Table 1 for sky type 1..15."""
    from skydome._validate import check_int
    from skydome.data import load_table

    t = check_int("sky_type", sky_type, 1, 15)
    cols, arr = load_table("cie2003_sky_types")
    row = arr[np.nonzero(arr[:, cols.index("type")] == t)[0][0]]
    return tuple(float(row[cols.index(k)]) for k in ("a", "b", "c", "d", "e"))


def _gradation(a, b, cos_z):
    """phi(Z) = 1 + a exp(b / cos Z) ([CIE03] eq. 2); phi = 1 at the horizon (b < 0)."""
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        safe = np.where(cos_z > 0.0, cos_z, 1.0)
        return np.where(cos_z > 0.0, 1.0 + a * np.exp(b / safe), 1.0)


def _indicatrix(c, d, e, chi, cos_chi):
    """f(chi) = 1 + c [exp(d chi) - exp(d pi/2)] + e cos^2 chi ([CIE03] eq. 3)."""
    return 1.0 + c * (np.exp(d * chi) - math.exp(d * math.pi / 2.0)) + e * cos_chi * cos_chi


@register
class CIE2003(_CIEBase):
    """The 15 CIE standard general skies (CIE S 011/E:2003 = ISO 15469:2004).

    L/Lz = f(chi) phi(Z) / (f(Zs) phi(0)) with the gradation phi(Z) = 1 + a exp(b/cos Z)
    (phi = 1 at the horizon) and the scattering indicatrix
    f(chi) = 1 + c [exp(d chi) - exp(d pi/2)] + e cos^2 chi; Z is the zenith angle of the
    view direction, Zs that of the sun, chi the angle between them; a..e from the
    standard's Table 1 (``data/cie2003_sky_types.csv``).

    Parameters
    ----------
    sun : skydome.Sun
        The sun, elevation in [0, 90] deg.
    sky_type : int
        Standard sky type, 1..15 (default 12, the CIE standard clear sky).
    zenith_luminance : float, optional
        Zenith luminance [cd m^-2]. The standard gives relative distributions only;
        without this parameter or ``diffuse_horizontal_illuminance`` the model uses
        Lz = 1000 cd m^-2 (a relative scale, not a prediction).
    diffuse_horizontal_illuminance : float, optional
        Horizontal illuminance of the sky [lx] (numerical hemisphere integral, relative
        accuracy better than 1e-6).

    References
    ----------
    [CIE03], [KDP98].
    """

    name = "cie2003"
    reference = ("CIE S 011/E:2003 = ISO 15469:2004, Spatial distribution of daylight - "
                 "CIE standard general sky")
    summary = "CIE standard general sky, 15 types (ISO 15469)"
    parameters = (
        Parameter("sky_type", "", 12, 1, 15, "CIE standard general sky type 1..15",
                  kind="int"),
        _LZ_PARAM, _EH_PARAM, DNI_ILLUMINANCE_PARAM)

    #: Default zenith luminance [cd m^-2] when no scale is given (relative scale).
    DEFAULT_ZENITH_LUMINANCE = 1000.0

    def __init__(self, sun=None, **params):
        self._begin_cie(sun, params)
        self.a, self.b, self.c, self.d, self.e = cie2003_parameters(self.sky_type)
        zs = math.radians(self.sun.zenith_deg)
        self._norm = float(_indicatrix(self.c, self.d, self.e, zs, math.cos(zs))
                           * (1.0 + self.a * math.exp(self.b)))
        self._resolve_scale(self.DEFAULT_ZENITH_LUMINANCE)

    def _relative(self, d, _aligned: bool = False):
        z = d[..., 2]
        cchi = self._cos_gamma(d, _aligned)
        chi = np.arccos(cchi)
        rel = (_indicatrix(self.c, self.d, self.e, chi, cchi)
               * _gradation(self.a, self.b, z) / self._norm)
        return np.where(z >= 0.0, np.maximum(rel, 0.0), 0.0)

    def _kernel(self, K, flat, scale):
        return K.cie2003(flat, self._sun_dir, self.a, self.b, self.c, self.d, self.e,
                         self._norm, scale)
