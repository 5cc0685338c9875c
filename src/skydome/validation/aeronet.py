"""AERONET almucantar inversions (.pfn, Version 2) and the aerosol optics they give.

:func:`read_pfn` reads the total-mode phase functions (4 wavelengths x 83 angles), the
aerosol optical depth at 440 nm, the Angstrom exponent 440-870 nm and the surface albedo
that the inversion assumed, per wavelength (columns ``albedo_440`` ... ``albedo-1020``:
their values on 2013-05-27, 0.03 / 0.09 / 0.43 / 0.43, are the red edge of vegetation, a
ground reflectance, not the aerosol's single scattering albedo, which Version 2 ships in
separate ``.ssa`` files that this data set lacks). :class:`AeronetRetrieval` turns one
retrieval into the optics of a skydome aerosol constituent: spectral extinction
``tau(lambda) = tau440 (lambda / 440)^-alpha`` (Angstrom 1929), a grey single scattering
albedo (:data:`DEFAULT_SSA`, assumed), and the measured phase function as a
:class:`skydome.atmosphere.TabulatedPhase` interpolated linearly in wavelength between
442/674/871/1020 nm (the 442 nm table held below 442 nm, the 1020 nm one above).

The file shipped with skydome (``data/aeronet_egbert_20130527.pfn``, provenance and
licence in its sidecar ``.pfn.txt``) is Egbert, Ontario, 2013-05-27, about 370 km from
the Kider et al. 2014 site; AERONET times are UTC.

References
----------
Dubovik, O., King, M. D., "A flexible inversion algorithm for retrieval of aerosol optical
properties from Sun and sky radiance measurements", J. Geophys. Res. 105(D16), 2000.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

#: Aerosol single scattering albedo used with a .pfn retrieval (which carries none): 0.95,
#: within the 0.93-0.98 of the continental urban-industrial / mixed models of Dubovik et al.
#: 2002 (J. Atmos. Sci. 59, 590-608, Table 1, 440-1020 nm) and typical of eastern North
#: America (GSFC 0.98-0.97); an assumption, stated in docs/validation_measured.md.
DEFAULT_SSA = 0.95

__all__ = ["DEFAULT_SSA", "AeronetRetrieval", "read_pfn", "egbert_20130527", "aerosol_atmosphere"]

_COL = re.compile(r"^([0-9.]+)\[(\d+)nm\]$")


@dataclass(frozen=True, eq=False)
class AeronetRetrieval:
    """One AERONET almucantar retrieval.

    Attributes
    ----------
    time : datetime (UTC)
    theta_deg : ndarray (83,)
        Scattering angles of the phase functions [deg], 0-180.
    phase_wavelengths_nm : ndarray (4,)
        442, 674, 871, 1020 nm.
    phase : ndarray (83, 4)
        Total-mode phase function as AERONET gives it (normalised to 4 pi over the sphere).
    tau440 : float
        Aerosol optical depth at 440 nm (measured).
    alpha : float
        Angstrom exponent 440-870 nm.
    albedo_wavelengths_nm, surface_albedo : ndarray (4,)
        Surface albedo the inversion assumed at 440, 675, 870, 1020 nm.
    ssa : float
        Aerosol single scattering albedo used (:data:`DEFAULT_SSA` unless given).
    """

    time: datetime
    theta_deg: np.ndarray
    phase_wavelengths_nm: np.ndarray
    phase: np.ndarray
    tau440: float
    alpha: float
    albedo_wavelengths_nm: np.ndarray
    surface_albedo: np.ndarray
    ssa: float = DEFAULT_SSA

    def optical_depth(self, wavelength_nm) -> np.ndarray:
        """Vertical aerosol optical depth, ``tau440 (lambda / 440)^-alpha`` [-]."""
        wl = np.asarray(wavelength_nm, dtype=np.float64)
        return self.tau440 * (wl / 440.0) ** (-self.alpha)

    def single_scattering_albedo(self, wavelength_nm) -> np.ndarray:
        """Aerosol single scattering albedo (grey: ``ssa``)."""
        return np.full(np.shape(wavelength_nm), self.ssa, dtype=np.float64)

    def ground_albedo(self, wavelength_nm) -> np.ndarray:
        """The inversion's surface albedo, linear in wavelength between its four, end
        values held beyond."""
        return np.interp(np.asarray(wavelength_nm, dtype=np.float64), self.albedo_wavelengths_nm,
                         self.surface_albedo)

    def phase_table(self):
        """The measured phase function as a TabulatedPhase (normalised to 1 over the sphere)."""
        from skydome.atmosphere import TabulatedPhase

        return TabulatedPhase(self.theta_deg, self.phase, self.phase_wavelengths_nm, normalise=True,
                              description=f"AERONET {self.time:%Y-%m-%d %H:%M} UTC")

    def asymmetry(self) -> np.ndarray:
        """Asymmetry factor g = <cos theta> of the phase function at its four wavelengths."""
        t = np.radians(self.theta_deg)
        w = self.phase * np.sin(t)[:, None]
        return np.trapezoid(w * np.cos(t)[:, None], t, axis=0) / np.trapezoid(w, t, axis=0)


def read_pfn(path) -> list[AeronetRetrieval]:
    """Read every retrieval of an AERONET Version 2 ``.pfn`` file (phase functions, total
    mode). Raises ValueError if the columns it needs are missing."""
    lines = Path(path).read_text(encoding="utf-8", errors="replace").splitlines()
    hi = next((i for i, ln in enumerate(lines) if ln.startswith("Date(dd-mm-yyyy)")), None)
    if hi is None:
        raise ValueError(f"path {str(path)!r} is not an AERONET .pfn file (no Date(dd-mm-yyyy) header)")
    header = [h.strip() for h in lines[hi].split(",")]
    angle_cols: dict[int, list[tuple[float, int]]] = {}
    for j, h in enumerate(header):
        m = _COL.match(h)
        if m:
            angle_cols.setdefault(int(m.group(2)), []).append((float(m.group(1)), j))
    need = ["alpha440-870", "tau440(measured)", "albedo_440", "albedo_675", "albedo_870", "albedo-1020"]
    missing = [n for n in need if n not in header]
    if missing or len(angle_cols) != 4:
        raise ValueError(f"path {str(path)!r} lacks AERONET columns {missing or 'phase functions'}")
    wls = sorted(angle_cols)
    theta = np.array([a for a, _ in angle_cols[wls[0]]])
    out = []
    for ln in lines[hi + 1:]:
        parts = [p.strip() for p in ln.split(",")]
        if len(parts) < len(header) - 1:
            continue
        d, t = parts[0], parts[1]
        day, mon, yr = (int(x) for x in d.split(":"))
        hh, mm, ss = (int(x) for x in t.split(":"))
        phase = np.array([[float(parts[j]) for _, j in angle_cols[w]] for w in wls]).T
        out.append(AeronetRetrieval(
            time=datetime(yr, mon, day, hh, mm, ss, tzinfo=timezone.utc), theta_deg=theta.copy(),
            phase_wavelengths_nm=np.array(wls, dtype=np.float64), phase=phase,
            tau440=float(parts[header.index("tau440(measured)")]),
            alpha=float(parts[header.index("alpha440-870")]),
            albedo_wavelengths_nm=np.array([440.0, 675.0, 870.0, 1020.0]),
            surface_albedo=np.array([float(parts[header.index(n)]) for n in need[2:]])))
    return out


def egbert_20130527() -> list[AeronetRetrieval]:
    """The five retrievals of Egbert, Ontario, 2013-05-27 shipped with skydome."""
    from skydome.data import DATA_DIR

    return read_pfn(DATA_DIR / "aeronet_egbert_20130527.pfn")


def nearest_retrieval(retrievals, time: datetime) -> AeronetRetrieval:
    """The retrieval closest in time to ``time`` (timezone-aware)."""
    return min(retrievals, key=lambda r: abs((r.time - time).total_seconds()))


def aerosol_atmosphere(retrieval: AeronetRetrieval, *, phase: str = "tabulated",
                       ozone_du: float = 300.0, ground_albedo=None,
                       aerosol_scale_height_m: float = 1200.0,
                       precipitable_water_cm: float = 1.42, mixed_gases: bool = True,
                       gas_reference_airmass: float = 1.5, asymmetry: float | None = None):
    """Earth's atmosphere with the retrieval's aerosol.

    Rayleigh: Ciddor 1996 refractive index of standard air (15 degC, 101325 Pa), number
    density p / (k T) = 2.5469e25 m^-3, depolarisation 0.0279 (Young 1980) with its King
    factor and phase function, scale height 7994 m. Aerosol: extinction from tau440 and
    alpha on an exponential profile of ``aerosol_scale_height_m`` (1200 m, survey sec. 4;
    AERONET gives no profile), single scattering albedo ``retrieval.ssa``, and ``phase``:
    "tabulated" (the measured phase function, default) or "henyey_greenstein" /
    "cornette_shanks" with the measured asymmetry factor at 674 nm, or ``asymmetry`` in
    [0, 0.95] when given (the phase fit of :func:`skydome.validation.fitting.fit_aerosol_phase`;
    refused with "tabulated"). Ozone ``ozone_du`` on
    the 10-25-40 km tent (300 DU: not measured that day; a typical mid-latitude column).
    Ground albedo: ``ground_albedo`` or, by default, the inversion's surface albedo (at
    Egbert; the Ithaca roof's is unknown). Water vapour ``precipitable_water_cm`` (1.42 cm,
    the US Standard Atmosphere's: the inversion file holds no water column and none was
    measured at the site) and the mixed gases, as :meth:`Atmosphere.earth`.
    """
    from skydome._validate import check_choice
    from skydome.atmosphere import Atmosphere, Constituent, ExponentialProfile
    from skydome.atmosphere.rayleigh import rayleigh_scattering_coefficient

    check_choice("phase", phase, ("tabulated", "henyey_greenstein", "cornette_shanks"))
    if asymmetry is not None:
        from skydome._validate import check_number

        if phase == "tabulated":
            raise ValueError("asymmetry must be None with phase='tabulated' (the table sets "
                             f"it), got {asymmetry!r}")
        asymmetry = check_number("asymmetry", asymmetry, 0.0, 0.95)
    n_air = 101325.0 / (1.380649e-23 * 288.15)  # [m^-3] ideal gas at 15 degC
    rho = 0.0279  # depolarisation ratio (Young 1980, Appl. Opt. 19, 3427)

    def ray(wl):
        return rayleigh_scattering_coefficient(wl, refractive_index="ciddor1996",
                                               number_density_m3=n_air, depolarisation=rho)

    prof = ExponentialProfile(aerosol_scale_height_m)
    column = prof.column(100e3)

    def ext(wl):
        return retrieval.optical_depth(wl) / column

    kw = {"phase": phase}
    if phase == "tabulated":
        kw["phase_table"] = retrieval.phase_table()
    else:
        kw["g"] = float(retrieval.asymmetry()[1]) if asymmetry is None else float(asymmetry)
    cons = (Constituent("rayleigh", scattering=ray, profile=ExponentialProfile(7994.0),
                        phase="rayleigh", depolarisation=rho),
            Constituent("aerosol", scattering=lambda wl: retrieval.single_scattering_albedo(wl) * ext(wl),
                        absorption=lambda wl: (1.0 - retrieval.single_scattering_albedo(wl)) * ext(wl),
                        profile=prof, **kw),
            Atmosphere.ozone_layer(ozone_du, 100e3),
            *Atmosphere.gas_constituents(precipitable_water_cm, mixed_gases, 100e3,
                                         gas_reference_airmass, 7994.0))
    if ground_albedo is None:
        ground_albedo = retrieval.ground_albedo
    return Atmosphere(cons, ground_albedo=ground_albedo,
                      name=f"aeronet({retrieval.time:%H:%M} UTC, tau440={retrieval.tau440:.3f}, "
                           f"alpha={retrieval.alpha:.3f}, {phase}"
                           + ("" if asymmetry is None else f", g={asymmetry:.3f}") + ")")
