"""ASRC-CIE sky: a weighted combination of four reference skies driven by the Perez
sky clearness and sky brightness (Perez et al. 1990; Littlefair 1994).

The four skies are the CIE standard clear sky (Kittler), a high-turbidity clear sky
(Matsuura 1987), the intermediate sky (Matsuura 1987, Nakamura's formulation as adopted by
CIE 110-1994) and the CIE standard overcast sky (Moon & Spencer). Each is normalised to
its zenith (L/Lz = 1 at the zenith) and two neighbouring skies are mixed linearly:

    eps <= 1.2      L/Lz = s psi_is + (1 - s) psi_os,  s = min{1, max[0, (eps-1)/0.2, (Delta-0.05)/0.4]}
    1.2 < eps <= 3  L/Lz = s psi_ts + (1 - s) psi_is,  s = (eps - 1.2)/1.8
    eps > 3         L/Lz = s psi_cs + (1 - s) psi_ts,  s = min[1, (eps - 3)/3]

These weights are those of Perez et al. (1990) as implemented in DOE-2 and EnergyPlus
(EnergyPlus Engineering Reference, "Time-Step Sky Luminance"); see docs/sections/cie.md for
what was reconstructed and why.

References
----------
[PISMS90] Perez, R., Ineichen, P., Seals, R., Michalsky, J. and Stewart, R. (1990),
    Modeling daylight availability and irradiance components from direct and global
    irradiance. Solar Energy 44(5), 271-289.
[Lit94] Littlefair, P. J. (1994), A comparison of sky luminance models with measured data
    from Garston, United Kingdom. Solar Energy 53(4), 315-322.
[Mat87] Matsuura, K. (1987), Luminance distributions of various reference skies. CIE
    Technical Report of TC 3-09.
[EPlus] EnergyPlus Engineering Reference, "Daylight Factor Calculation: Sky Luminance
    Distributions" and "Time-Step Daylighting Calculation: Time-Step Sky Luminance"
    (github.com/NREL/EnergyPlus, doc/engineering-reference/src/daylighting-and-window-
    calculations/).
[Kas66] Kasten, F. (1966), A new table and approximation formula for the relative optical
    air mass. Arch. Meteorol. Geophys. Bioklimatol. B14, 206-223.
"""

from __future__ import annotations

import math

import numpy as np

from skydome.constants import SOLAR_CONSTANT_WRC
from skydome.models import Parameter, register
from skydome.models.analytic.cie import (DNI_ILLUMINANCE_PARAM, CIE1994Clear,
                                         CIE1994Intermediate, CIE1994Overcast, _CIEBase)

__all__ = ["ASRCCIE", "sky_clearness", "sky_brightness", "asrc_weights",
           "SOLAR_CONSTANT_W_M2", "PEREZ_KAPPA"]

#: Solar constant [W m^-2] used for the sky brightness (as in Perez et al. 1990 and
#: Radiance's gendaylit).
SOLAR_CONSTANT_W_M2 = SOLAR_CONSTANT_WRC   # [PISMS90] fitted with 1367 W m^-2
#: kappa of the sky clearness for the zenith angle in radians [PISMS90].
PEREZ_KAPPA = 1.041


def relative_air_mass(zenith_deg: float) -> float:
    """Relative optical air mass, Kasten (1966): 1/(cos Z + 0.15 (93.885 - Z)^-1.253),
    Z in degrees (the form used by Perez et al. 1990 and gendaylit)."""
    from skydome.atmosphere.airmass import kasten1966

    z = min(max(zenith_deg, 0.0), 93.0)
    return float(kasten1966(z))


def sky_clearness(direct_normal_irradiance: float, diffuse_horizontal_irradiance: float,
                  zenith_deg: float) -> float:
    """Perez sky clearness epsilon = ((Dh + In)/Dh + kappa Z^3)/(1 + kappa Z^3), Z in
    radians, kappa = 1.041 [PISMS90]."""
    z3 = PEREZ_KAPPA * math.radians(zenith_deg) ** 3
    ratio = (diffuse_horizontal_irradiance + direct_normal_irradiance) / diffuse_horizontal_irradiance
    return (ratio + z3) / (1.0 + z3)


def sky_brightness(diffuse_horizontal_irradiance: float, zenith_deg: float,
                   distance_au: float = 1.0) -> float:
    """Perez sky brightness Delta = Dh m / E0, with the extraterrestrial normal irradiance
    E0 = 1367 W m^-2 / distance_au^2 and the Kasten (1966) air mass [PISMS90]."""
    e0 = SOLAR_CONSTANT_W_M2 / (distance_au * distance_au)
    return diffuse_horizontal_irradiance * relative_air_mass(zenith_deg) / e0


def asrc_weights(epsilon: float, delta: float) -> dict[str, float]:
    """Weights of the four component skies (clear, turbid, intermediate, overcast) for a
    sky clearness ``epsilon`` and brightness ``delta``; they sum to 1 ([PISMS90] as
    given in [EPlus])."""
    w = {"clear": 0.0, "turbid": 0.0, "intermediate": 0.0, "overcast": 0.0}
    if epsilon <= 1.2:
        s = min(1.0, max(0.0, (epsilon - 1.0) / 0.2, (delta - 0.05) / 0.4))
        w["intermediate"], w["overcast"] = s, 1.0 - s
    elif epsilon <= 3.0:
        s = (epsilon - 1.2) / 1.8
        w["turbid"], w["intermediate"] = s, 1.0 - s
    else:
        s = min(1.0, (epsilon - 3.0) / 3.0)
        w["clear"], w["turbid"] = s, 1.0 - s
    return w


class _TurbidClear(_CIEBase):
    """High-turbidity clear sky of Matsuura (1987) ([EPlus] "Clear Turbid Sky"):
    L/Lz = f(gamma) (1 - exp(-0.32/cos theta)) / (f(theta_s) (1 - exp(-0.32))) with
    f(gamma) = 0.856 + 16 exp(-3 gamma) + 0.3 cos^2 gamma. Not registered on its own
    (CIE 2003 type 13 is the same sky)."""

    name = "_asrc_turbid_clear"
    parameters = ()

    def __init__(self, sun):
        self._begin_cie(sun, {})
        zs = math.radians(sun.zenith_deg)
        self._norm = float(self._f(zs, math.cos(zs)) * (1.0 - math.exp(-0.32)))

    @staticmethod
    def _f(gamma, cos_gamma):
        return 0.856 + 16.0 * np.exp(-3.0 * gamma) + 0.3 * cos_gamma * cos_gamma

    def _relative(self, d, _aligned: bool = False):
        z = d[..., 2]
        cg = self._cos_gamma(d, _aligned)
        zpos = np.maximum(z, 0.0)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            grad = np.where(zpos > 0.0, -np.expm1(-0.32 / np.where(zpos > 0, zpos, 1.0)), 1.0)
        rel = self._f(np.arccos(cg), cg) * grad / self._norm
        return np.where(z >= 0.0, rel, 0.0)

    def _kernel(self, K, flat, scale):
        return K.cie_kittler(flat, self._sun_dir, 0.856, 16.0, 0.3, self._norm, scale)


@register
class ASRCCIE(_CIEBase):
    """ASRC-CIE sky (Perez et al. 1990): clear, turbid, intermediate and overcast CIE
    skies mixed by the sky clearness and brightness.

    Parameters
    ----------
    sun : skydome.Sun
        The sun, elevation in [0, 90] deg; its ``distance_au`` sets the extraterrestrial
        irradiance used for the sky brightness.
    epsilon : float, optional
        Perez sky clearness epsilon, [1, 1000] (give it with ``delta``).
    delta : float, optional
        Perez sky brightness Delta, [0, 5].
    dni : float, optional
        Direct normal irradiance [W m^-2], [0, 1500]; with ``dhi`` it gives epsilon and
        Delta (alternative to epsilon/delta). The names are pvlib's and Perez 1993's.
    dhi : float, optional
        Diffuse horizontal irradiance [W m^-2], (0, 1000].
    dni_illuminance : float, optional
        Direct normal illuminance of the sun [lx], [0, 135000]. Default: with ``dni``,
        ``dni`` times the Perez et al. 1990 direct luminous efficacy (W = 2 cm); without
        it the model has no sun (:meth:`sun_luminance` returns None).
    zenith_luminance : float, optional
        Zenith luminance [cd m^-2]; default 1000 cd m^-2 (a relative scale) unless
        ``diffuse_horizontal_illuminance`` is given.
    diffuse_horizontal_illuminance : float, optional
        Horizontal illuminance of the sky [lx] (numerical hemisphere integral).

    Notes
    -----
    Each component sky is normalised to L = Lz at the zenith, so the mixture is too.
    Directions below the horizon get 0.

    References
    ----------
    [PISMS90], [Lit94], [Mat87], [EPlus], [Kas66].
    """

    name = "asrc_cie"
    reference = ("Perez, Ineichen, Seals, Michalsky & Stewart (1990), Solar Energy 44(5), "
                 "271-289 (ASRC-CIE); Littlefair (1994), Solar Energy 53(4), 315-322")
    summary = "ASRC-CIE: CIE clear/turbid/intermediate/overcast skies mixed by Perez epsilon, Delta"
    parameters = (
        Parameter("epsilon", "", None, 1.0, 1.0e3, "Perez sky clearness (with delta)"),
        Parameter("delta", "", None, 0.0, 5.0, "Perez sky brightness (with epsilon)"),
        Parameter("dni", "W/m^2", None, 0.0, 1500.0, "direct normal irradiance (with dhi)"),
        Parameter("dhi", "W/m^2", None, 0.0, 1000.0,
                  "diffuse horizontal irradiance (with dni)", low_open=True),
        Parameter("zenith_luminance", "cd/m^2", None, 0.0, 1.0e6,
                  "luminance of the zenith; default 1000 (relative scale)"),
        Parameter("diffuse_horizontal_illuminance", "lx", None, 0.0, 2.0e5,
                  "illuminance of the sky on a horizontal plane; alternative to zenith_luminance"),
        DNI_ILLUMINANCE_PARAM,
    )

    DEFAULT_ZENITH_LUMINANCE = 1000.0

    def __init__(self, sun=None, **params):
        self._begin_cie(sun, params)
        eps, dlt = self.epsilon, self.delta
        dni, dhi = self.dni, self.dhi
        have_perez = eps is not None or dlt is not None
        have_irr = dni is not None or dhi is not None
        if have_perez and have_irr:
            raise ValueError("asrc_cie: give epsilon and delta, or dni and dhi, not both")
        if have_irr:
            if dni is None or dhi is None:
                raise ValueError("asrc_cie: dni and dhi must be given together")
            zen = self.sun.zenith_deg
            from skydome.models.analytic.perez1993 import clear_sky_limit_exceeded

            if self.sun.elevation_deg > 0.0 and bool(clear_sky_limit_exceeded(dni, dhi, zen)):
                raise ValueError(
                    f"asrc_cie: dni = {dni:g} W/m^2 with dhi = {dhi:g} W/m^2 at sun elevation "
                    f"{self.sun.elevation_deg:g} deg is beyond the clear-sky limit (direct "
                    "normal irradiance <= 1367 W/m^2 and direct normal illuminance <= "
                    "127500 lx: gendaylit's rule, see perez1993.clear_sky_limit_exceeded)")
            eps = sky_clearness(dni, dhi, zen)               # [PISMS90] eq. for epsilon
            dlt = sky_brightness(dhi, zen, self.sun.distance_au)  # [PISMS90] Delta
        elif have_perez:
            if eps is None or dlt is None:
                raise ValueError("asrc_cie: epsilon and delta must be given together")
        else:
            raise ValueError("asrc_cie needs epsilon and delta, or dni and dhi")
        # epsilon and Delta actually used (given or from dni/dhi), as Perez 1993's
        self.sky_clearness, self.sky_brightness = float(eps), float(dlt)
        if self.dni_illuminance is None and dni is not None and self.sun.elevation_deg > 0.0:
            from skydome.models.analytic.perez1993 import perez1990_luminous_efficacy

            k_dir = float(perez1990_luminous_efficacy(self.sky_clearness, self.sky_brightness,
                                                      self.sun.zenith_deg, 2.0).direct)
            self.dni_illuminance = max(float(dni) * k_dir, 0.0)   # [PISMS90] direct efficacy
        self.weights = asrc_weights(self.sky_clearness, self.sky_brightness)
        s = self.sun
        self._components = []
        for key, cls in (("clear", CIE1994Clear), ("turbid", None),
                         ("intermediate", CIE1994Intermediate), ("overcast", CIE1994Overcast)):
            w = self.weights[key]
            if w <= 0.0:
                continue
            comp = _TurbidClear(s) if cls is None else cls(sun=s, zenith_luminance=1.0)
            self._components.append((w, comp))
        self._resolve_scale(self.DEFAULT_ZENITH_LUMINANCE)

    def describe(self):
        out = super().describe()
        # Report the Perez parameters (resolved) rather than the irradiances, so that the
        # parameters round-trip through model(**params).
        p = out["parameters"]
        p["epsilon"], p["delta"] = self.sky_clearness, self.sky_brightness
        p["dni"] = None
        p["dhi"] = None
        out["weights"] = dict(self.weights)
        return out

    def _kernel(self, K, flat, scale):
        # One pass over the directions for the whole mixture (weights and zenith
        # normalisations of the clear, turbid, intermediate and overcast components).
        w = np.array([self.weights[k] for k in ("clear", "turbid", "intermediate", "overcast")])
        norms = np.ones(4)
        for _, comp in self._components:
            if isinstance(comp, CIE1994Clear):
                norms[0] = comp._norm
            elif isinstance(comp, _TurbidClear):
                norms[1] = comp._norm
            elif isinstance(comp, CIE1994Intermediate):
                norms[2] = comp._norm
        zt = math.radians(self.sun.zenith_deg)
        return K.asrc_cie(flat, self._sun_dir, w, norms, zt, scale)

    def _relative(self, d, _aligned: bool = False):
        total = np.zeros(d.shape[:-1])
        for w, comp in self._components:
            total = total + w * comp._relative(d, _aligned)
        return total
