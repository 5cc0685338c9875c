"""The atmosphere: planet, top of the atmosphere, constituents and ground.

An :class:`Atmosphere` is a spherical shell (planet radius, top altitude) filled with
constituents. Each :class:`Constituent` has a reference scattering and absorption
coefficient as a function of wavelength (at sea level, or at the peak of an elevated
layer), a :mod:`density profile <skydome.atmosphere.profiles>` and a phase function. Every
physically based model in skydome takes the same object, so a comparison between
models changes only the method.

Presets: :meth:`Atmosphere.earth` (survey physics: Rayleigh eq. 8 with H0 = 7994 m,
aerosols from turbidity or optical depth with H = 1200 m, ozone) and
:meth:`Atmosphere.bruneton2017` (the demo atmosphere of Bruneton's reference
implementation, for comparisons). :meth:`Atmosphere.custom` builds one from explicit
coefficients, so that any other program's or paper's atmosphere can be reproduced.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from skydome._validate import as_wavelengths, check_number
from skydome.atmosphere._constituent import (PHASE_CODES, PHASE_TABLE_ANGLES,  # noqa: F401
                                           Constituent, OpticalProperties,
                                           SpectralCoefficient, TabulatedPhase,
                                           fold_absorbers)
from skydome.atmosphere.profiles import (DensityProfile, ExponentialProfile, GaussianLayerProfile,
                                         TentProfile, UniformProfile)
from skydome.constants import DOBSON_UNIT, EARTH_RADIUS, H_MIE, H_RAYLEIGH, N_S_SURVEY

__all__ = ["Atmosphere", "Constituent", "OpticalProperties", "fold_absorbers", "SpectralCoefficient", "TabulatedPhase",
           "ExponentialProfile", "TentProfile", "UniformProfile", "GaussianLayerProfile",
           "ozone_cross_section"]


# ---------------------------------------------------------------------------------------------
def ozone_cross_section(wavelength_nm) -> np.ndarray:
    """Ozone absorption cross section [m^2].

    From 365 nm: Serdyuchenko et al. 2014 at 233 K (10 nm bin means from 360-830 nm, placed
    at the bin centres; linear interpolation; the 830 nm bin held beyond). The Huggins band
    below: Bird & Riordan 1986's a_o (300-350 nm, :func:`skydome.atmosphere.gases.
    ozone_cross_section_br86`), log-linear from their 350 nm value to the 365 nm bin, their
    300 nm value held below 300 nm (an underestimate there: the Hartley band keeps rising)."""
    from skydome.atmosphere.gases import ozone_cross_section_br86
    from skydome.data import load_table
    from skydome.spectra import resample

    wl = np.asarray(wavelength_nm, dtype=np.float64)
    _, t = load_table("ozone_cross_section_233k")
    lo, hi = 350.0, t[0, 0] + 5.0
    upper = resample(wl, t[:, 0] + 5.0, t[:, 1], "hold")
    huggins = ozone_cross_section_br86(np.minimum(wl, lo))
    s_lo, s_hi = float(ozone_cross_section_br86(lo)), float(t[0, 1])
    f = np.clip((wl - lo) / (hi - lo), 0.0, 1.0)
    bridge = np.exp((1.0 - f) * np.log(s_lo) + f * np.log(s_hi))
    return np.where(wl >= hi, upper, np.where(wl <= lo, huggins, bridge))


@dataclass(frozen=True, eq=False)
class Atmosphere:
    """A spherical-shell atmosphere.

    Parameters
    ----------
    constituents : sequence of Constituent
    planet_radius_m : float
        Radius of the ground sphere [m], in [1e3, 1e8]; Earth 6360 km.
    top_altitude_m : float
        Altitude of the top of the atmosphere above the ground [m], in [100, 1e6]; 100 km
        by default so that twilight (sun down to -18 deg) is lit correctly.
    ground_albedo : float or spectral
        Lambertian ground reflectance in [0, 1].
    name : str
    """

    constituents: tuple = ()
    planet_radius_m: float = EARTH_RADIUS
    top_altitude_m: float = 100e3
    ground_albedo: Any = 0.1
    name: str = "custom"

    def __post_init__(self):
        cons = tuple(self.constituents)
        for c in cons:
            if not isinstance(c, Constituent):
                raise TypeError(f"constituents must be Constituent objects, got {type(c).__name__}")
        names = [c.name for c in cons]
        if len(set(names)) != len(names):
            raise ValueError(f"constituent names must be unique, got {names}")
        object.__setattr__(self, "constituents", cons)
        object.__setattr__(self, "planet_radius_m",
                           check_number("planet_radius_m", self.planet_radius_m, 1e3, 1e8, "m"))
        object.__setattr__(self, "top_altitude_m",
                           check_number("top_altitude_m", self.top_altitude_m, 100.0, 1e6, "m"))
        if isinstance(self.ground_albedo, (int, float)) and not isinstance(self.ground_albedo, bool):
            check_number("ground_albedo", self.ground_albedo, 0.0, 1.0)
        object.__setattr__(self, "ground_albedo", SpectralCoefficient.make(self.ground_albedo, "ground_albedo"))

    # -- presets -------------------------------------------------------------------------------
    @classmethod
    def earth(cls, turbidity: float | None = None, *, aerosol_optical_depth: float | None = None,
              angstrom_alpha: float = 1.3, aerosol_g: float = 0.76,
              aerosol_single_scattering_albedo: float = 0.9,
              aerosol_phase: str = "cornette_shanks",
              aerosol_scale_height_m: float = H_MIE,
              rayleigh_scale_height_m: float = H_RAYLEIGH,
              refractive_index: str | float = "survey",
              number_density_m3: float = N_S_SURVEY,
              depolarisation: float = 0.0,
              ozone_du: float = 300.0,
              precipitable_water_cm: float = 1.42,
              mixed_gases: bool = True,
              gas_reference_airmass: float = 1.5,
              ground_albedo: Any = 0.1,
              planet_radius_m: float = EARTH_RADIUS,
              top_altitude_m: float = 100e3) -> "Atmosphere":
        """Earth's clear atmosphere with the survey's physics.

        Parameters
        ----------
        turbidity : float, optional
            Preetham turbidity T in [1, 32]; sets the Angstrom beta = 0.04608 T - 0.04586
            ([PSS99] A.2). Default 2.5 when no aerosol optical depth is given.
        aerosol_optical_depth : float, optional
            Vertical aerosol optical depth at 550 nm, in [0, 10] (instead of turbidity).
        angstrom_alpha : float
            Angstrom exponent, default 1.3.
        aerosol_g, aerosol_single_scattering_albedo, aerosol_phase, aerosol_scale_height_m
            Aerosol phase asymmetry (0.76), albedo (0.9), phase function
            ("cornette_shanks", survey eq. 11) and scale height (1200 m, survey sec. 4).
        rayleigh_scale_height_m : float
            H0 = 7994 m (survey eq. 7).
        refractive_index, number_density_m3, depolarisation
            Rayleigh coefficient inputs (survey eqs. 5, 6, 8): n = 1.000278, N_s = 2.545e25
            m^-3, no King correction (reproduces Table 1).
        ozone_du : float
            Total ozone column [DU] in [0, 1000] on a 10-25-40 km tent profile (Bruneton
            2017); 0 disables ozone. Cross sections: Serdyuchenko et al. 2014 from 365 nm,
            the Huggins band below from Bird & Riordan 1986 (:func:`ozone_cross_section`).
        precipitable_water_cm : float
            Water vapour column [cm] in [0, 10] on a 2 km exponential profile (default 1.42,
            the US Standard Atmosphere's: Anderson et al. 1986, AFGL-TR-86-0110); 0 disables
            water vapour. Bird & Riordan 1986 band coefficients
            (:mod:`skydome.atmosphere.gases`).
        mixed_gases : bool
            O2 (A and B bands) and CO2 absorption with the air density (Bird & Riordan 1986),
            default True.
        gas_reference_airmass : float
            Air mass in [1, 40] at which the water-vapour and mixed-gas band models are
            matched by Beer's law (default 1.5; :mod:`skydome.atmosphere.gases`).
        ground_albedo : float or spectral, in [0, 1].
        """
        from skydome.atmosphere.aerosols import (aerosol_optical_depth as _aod,
                                                 angstrom_beta_from_turbidity)
        from skydome.atmosphere.rayleigh import rayleigh_scattering_coefficient

        if turbidity is not None and aerosol_optical_depth is not None:
            raise ValueError("give either turbidity or aerosol_optical_depth, not both")
        alpha = check_number("angstrom_alpha", angstrom_alpha, -1.0, 4.0)
        if aerosol_optical_depth is not None:
            aod = check_number("aerosol_optical_depth", aerosol_optical_depth, 0.0, 10.0)
            beta = aod * (550.0 / 1000.0) ** alpha  # Angstrom beta = tau(1 um)
        else:
            beta = angstrom_beta_from_turbidity(2.5 if turbidity is None else turbidity)
        h_m = check_number("aerosol_scale_height_m", aerosol_scale_height_m, 10.0, 1e5, "m")
        ssa = check_number("aerosol_single_scattering_albedo", aerosol_single_scattering_albedo, 0.0, 1.0)
        ozone = check_number("ozone_du", ozone_du, 0.0, 1000.0, "DU")
        water = check_number("precipitable_water_cm", precipitable_water_cm, 0.0, 10.0, "cm")
        m_ref = check_number("gas_reference_airmass", gas_reference_airmass, 1.0, 40.0)
        if not isinstance(mixed_gases, (bool, np.bool_)):
            raise TypeError(f"mixed_gases must be True or False, got {mixed_gases!r}")
        check_number("rayleigh_scale_height_m", rayleigh_scale_height_m, 10.0, 1e5, "m")
        # validate Rayleigh inputs once, here
        rayleigh_scattering_coefficient(550.0, refractive_index=refractive_index,
                                        number_density_m3=number_density_m3,
                                        depolarisation=depolarisation)
        top = check_number("top_altitude_m", top_altitude_m, 100.0, 1e6, "m")

        def rayleigh_beta(wl):
            return rayleigh_scattering_coefficient(wl, refractive_index=refractive_index,
                                                   number_density_m3=number_density_m3,
                                                   depolarisation=depolarisation)

        aero_profile = ExponentialProfile(h_m)
        column = aero_profile.column(top)

        def aerosol_extinction(wl):
            # sea-level extinction so that the vertical column gives the Angstrom depth
            return _aod(wl, beta, alpha) / column

        constituents = [
            Constituent("rayleigh", scattering=rayleigh_beta, absorption=0.0,
                        profile=ExponentialProfile(rayleigh_scale_height_m), phase="rayleigh",
                        depolarisation=depolarisation),
            Constituent("aerosol", scattering=lambda wl: ssa * aerosol_extinction(wl),
                        absorption=lambda wl: (1.0 - ssa) * aerosol_extinction(wl),
                        profile=aero_profile, phase=aerosol_phase, g=aerosol_g),
        ]
        if ozone > 0:
            constituents.append(cls.ozone_layer(ozone, top))
        constituents.extend(cls.gas_constituents(water, bool(mixed_gases), top, m_ref,
                                                 rayleigh_scale_height_m))
        return cls(tuple(constituents), planet_radius_m=planet_radius_m, top_altitude_m=top,
                   ground_albedo=ground_albedo,
                   name=f"earth(beta={beta:.4g}, alpha={alpha:g}, ozone={ozone:g} DU, "
                        f"water={water:g} cm, mixed_gases={bool(mixed_gases)})")

    @staticmethod
    def gas_constituents(precipitable_water_cm: float = 1.42, mixed_gases: bool = True,
                         top_altitude_m: float = 100e3, gas_reference_airmass: float = 1.5,
                         air_scale_height_m: float = H_RAYLEIGH) -> list:
        """The absorbing gases besides ozone: water vapour (``precipitable_water_cm`` [cm],
        none when 0) and the mixed gases O2 / CO2 (with the air's ``air_scale_height_m``)
        (:mod:`skydome.atmosphere.gases`)."""
        from skydome.atmosphere import gases

        out = []
        if precipitable_water_cm > 0:
            out.append(gases.water_vapour(precipitable_water_cm, top_altitude_m,
                                          reference_airmass=gas_reference_airmass))
        if mixed_gases:
            out.append(gases.mixed_gases(top_altitude_m, scale_height_m=air_scale_height_m,
                                         reference_airmass=gas_reference_airmass))
        return out

    @staticmethod
    def ozone_layer(ozone_du: float = 300.0, top_altitude_m: float = 100e3) -> Constituent:
        """An absorbing ozone constituent of ``ozone_du`` Dobson units on the 10-25-40 km
        tent profile: peak number density = column / 15 km (Bruneton 2017)."""
        ozone = check_number("ozone_du", ozone_du, 0.0, 1000.0, "DU")
        profile = TentProfile(25e3, 15e3)
        peak_density = ozone * DOBSON_UNIT / profile.column(top_altitude_m)  # [m^-3]
        return Constituent("ozone", scattering=0.0,
                           absorption=lambda wl: peak_density * ozone_cross_section(wl),
                           profile=profile, phase="isotropic")

    @classmethod
    def bruneton2017(cls) -> "Atmosphere":
        """The demo atmosphere of Bruneton's 2017 reference implementation
        (precomputed_atmospheric_scattering, atmosphere/demo/demo.cc): radii 6360/6420 km,
        Rayleigh 1.24062e-6 lambda^-4 m^-1 (lambda in um), H = 8 km; aerosol Angstrom beta
        5.328e-3, alpha 0, H = 1.2 km, albedo 0.9, Cornette-Shanks g = 0.8; ozone 300 DU on
        the 10-25-40 km tent; ground albedo 0.1."""
        mie_ext = 5.328e-3 / 1200.0
        return cls(
            (Constituent("rayleigh", scattering=lambda wl: 1.24062e-6 * (np.asarray(wl) / 1000.0) ** -4.0,
                         profile=ExponentialProfile(8000.0), phase="rayleigh"),
             Constituent("aerosol", scattering=0.9 * mie_ext, absorption=0.1 * mie_ext,
                         profile=ExponentialProfile(1200.0), phase="cornette_shanks", g=0.8),
             cls.ozone_layer(300.0, 60e3)),
            planet_radius_m=EARTH_RADIUS, top_altitude_m=60e3, ground_albedo=0.1, name="bruneton2017")

    @classmethod
    def blender(cls, sky_type: str = "multiple_scattering", *, air_density: float = 1.0,
                aerosol_density: float = 1.0, ozone_density: float = 1.0) -> "Atmosphere":
        """Blender's own atmosphere: ``"multiple_scattering"`` (Blender 5's default Sky
        Texture, intern/sky/source/sky_multiple_scattering.cpp) or ``"nishita"`` (Blender
        2.90-4.x, sky_nishita.cpp), with the node's air, aerosol (dust) and ozone density
        factors in [0, 10]. Constants, sources and the two profiles replaced by ones of
        equal column: :mod:`skydome.atmosphere.blender`."""
        from skydome.atmosphere.blender import blender_atmosphere

        return blender_atmosphere(cls, sky_type, air_density, aerosol_density, ozone_density)

    @classmethod
    def volcanic_ash(cls, optical_depth_550: float = 1.0, *, median_radius_um: float = 0.45,
                     geometric_std: float = 1.15, refractive_index: Any = 1.5 - 0.001j,
                     layer_altitude_m: float = 20e3, layer_width_m: float = 3e3,
                     background_turbidity: float = 2.0, **earth_kwargs) -> "Atmosphere":
        """Earth plus a stratospheric layer of narrow log-normal volcanic ash (Lorenz-Mie,
        :mod:`skydome.atmosphere.mie`): the blue sun and blue moon of the survey's section
        5.6 (Krakatoa 1883). Parameters: vertical optical depth of the layer at 550 nm
        (0, 20]; median radius [um] and geometric standard deviation of the number
        distribution; complex refractive index (ash 1.5 - 0.001i); Gaussian layer centre
        and width [m]; turbidity of the ordinary aerosol below; other keywords go to
        :meth:`earth`."""
        return cls._mie_layered("volcanic_ash", locals())

    @classmethod
    def forest_fire_smoke(cls, optical_depth_550: float = 1.0, *, median_radius_um: float = 0.5,
                          geometric_std: float = 1.15, refractive_index: Any = 1.5 - 0.01j,
                          layer_altitude_m: float = 10e3, layer_width_m: float = 2e3,
                          background_turbidity: float = 2.0, **earth_kwargs) -> "Atmosphere":
        """Earth plus an elevated layer of uniform smoke droplets (Lorenz-Mie): the blue
        sun of 1950 September after the Alberta forest fires (Wilson, MNRAS 111, 1951;
        survey section 5.6). Same parameters as :meth:`volcanic_ash`."""
        return cls._mie_layered("forest_fire_smoke", locals())

    @classmethod
    def _mie_layered(cls, kind: str, args: dict) -> "Atmosphere":
        """The body of :meth:`volcanic_ash` and :meth:`forest_fire_smoke` (``args``: their
        arguments): :func:`skydome.atmosphere.mie.layered_mie_atmosphere` of this class."""
        from skydome.atmosphere.mie import layered_mie_atmosphere

        kw = {k: v for k, v in args.items() if k not in ("cls", "earth_kwargs")}
        return layered_mie_atmosphere(cls, kind, **kw, **args["earth_kwargs"])

    @classmethod
    def custom(cls, *, rayleigh_scattering, rayleigh_scale_height_m: float = H_RAYLEIGH,
               mie_scattering=0.0, mie_extinction=None, mie_scale_height_m: float = H_MIE,
               mie_phase: str = "cornette_shanks", mie_g: float = 0.76,
               ozone_absorption=None, ozone_profile: DensityProfile | None = None,
               planet_radius_m: float = EARTH_RADIUS, top_altitude_m: float = 100e3,
               ground_albedo: Any = 0.1, depolarisation: float = 0.0,
               name: str = "custom") -> "Atmosphere":
        """An atmosphere from explicit sea-level coefficients (each a number, a
        (wavelengths_nm, values) table or a callable of wavelength in nm, in m^-1).

        ``mie_extinction`` defaults to ``mie_scattering`` (single-scattering albedo 1); it
        must not be smaller than the scattering at any wavelength (checked when used).
        """
        ray = SpectralCoefficient.make(rayleigh_scattering, "rayleigh_scattering")
        mie_s = SpectralCoefficient.make(mie_scattering, "mie_scattering")
        mie_e = mie_s if mie_extinction is None else SpectralCoefficient.make(mie_extinction, "mie_extinction")

        def mie_abs(wl):
            s, e = mie_s(wl), mie_e(wl)
            if np.any(e < s * (1.0 - 1e-12)):
                raise ValueError("mie_extinction must be >= mie_scattering at every wavelength")
            return np.maximum(e - s, 0.0)

        cons = [Constituent("rayleigh", scattering=ray, profile=ExponentialProfile(rayleigh_scale_height_m),
                            phase="rayleigh", depolarisation=depolarisation),
                Constituent("aerosol", scattering=mie_s, absorption=mie_abs,
                            profile=ExponentialProfile(mie_scale_height_m), phase=mie_phase, g=mie_g)]
        if ozone_absorption is not None:
            cons.append(Constituent("ozone", absorption=ozone_absorption,
                                    profile=ozone_profile or TentProfile(25e3, 15e3), phase="isotropic"))
        return cls(tuple(cons), planet_radius_m=planet_radius_m, top_altitude_m=top_altitude_m,
                   ground_albedo=ground_albedo, name=name)

    # -- derived quantities --------------------------------------------------------------------
    @property
    def top_radius_m(self) -> float:
        return self.planet_radius_m + self.top_altitude_m

    def constituent(self, name: str) -> Constituent:
        for c in self.constituents:
            if c.name == name:
                return c
        raise KeyError(f"no constituent named {name!r}; have {[c.name for c in self.constituents]}")

    def optical_properties(self, wavelengths_nm, fold: bool = False) -> OpticalProperties:
        """Evaluate every coefficient on a wavelength grid [nm] for the kernels.

        With ``fold`` the purely absorbing constituents that share an earlier constituent's
        density profile are folded into it (:func:`fold_absorbers`; exact): what every
        physically based model hands its kernels, so that, for example, the uniformly mixed
        gases cost nothing beyond Rayleigh's constituent. Without it (the default) there is
        one row per entry of :attr:`constituents`, in order.
        """
        if not isinstance(fold, (bool, np.bool_)):
            raise TypeError(f"fold must be True or False, got {fold!r}")
        wl = as_wavelengths(wavelengths_nm)
        nc, nl = len(self.constituents), wl.size
        sca = np.zeros((nc, nl))
        ext = np.zeros((nc, nl))
        code = np.zeros(nc, dtype=np.int64)
        p0 = np.zeros(nc)
        p1 = np.zeros(nc)
        ph = np.zeros(nc, dtype=np.int64)
        pp = np.zeros(nc)
        for i, c in enumerate(self.constituents):
            sca[i] = c.scattering(wl)
            ext[i] = sca[i] + c.absorption(wl)
            code[i], p0[i], p1[i] = c.profile.kernel_params()
            ph[i] = PHASE_CODES[c.phase]
            pp[i] = c.phase_param()
        albedo = self.ground_albedo(wl)
        if np.any(albedo > 1.0):
            raise ValueError(f"ground_albedo = {albedo.max():g} is out of range [0, 1]")
        table = None
        if np.any(ph == PHASE_CODES["tabulated"]):
            table = np.zeros((nc, PHASE_TABLE_ANGLES, nl))
            for i, c in enumerate(self.constituents):
                if c.phase == "tabulated":
                    table[i] = c.phase_table.on_grid(wl, PHASE_TABLE_ANGLES)
        props = OpticalProperties(wl, self.planet_radius_m, self.top_radius_m, code, p0, p1, sca, ext,
                                  ph, pp, albedo, table)
        return fold_absorbers(props)[0] if fold else props

    def extinction(self, altitude_m, wavelengths_nm) -> np.ndarray:
        """Total extinction coefficient [m^-1] at altitudes (...) and wavelengths: (..., nl)."""
        wl = as_wavelengths(wavelengths_nm)
        h = np.asarray(altitude_m, dtype=np.float64)[..., None]
        total = np.zeros(h.shape[:-1] + (wl.size,))
        for c in self.constituents:
            total = total + c.profile.density(h) * (c.scattering(wl) + c.absorption(wl))
        return total

    def vertical_optical_depth(self, wavelengths_nm) -> dict[str, np.ndarray]:
        """Vertical optical depth from the ground to the top per constituent (nl,)."""
        wl = as_wavelengths(wavelengths_nm)
        return {c.name: c.profile.column(self.top_altitude_m) * (c.scattering(wl) + c.absorption(wl))
                for c in self.constituents}

    def describe(self) -> dict[str, Any]:
        """A JSON-friendly summary (for image metadata)."""
        return {"name": self.name, "planet_radius_m": self.planet_radius_m,
                "top_altitude_m": self.top_altitude_m,
                "ground_albedo": self.ground_albedo.description,
                "constituents": [{"name": c.name, "scattering": c.scattering.description,
                                  "absorption": c.absorption.description,
                                  "profile": repr(c.profile), "phase": c.phase, "g": c.g,
                                  **({"phase_table": c.phase_table.description}
                                     if c.phase_table is not None else {})}
                                 for c in self.constituents]}
