"""Broadband closure: a physically based model's global horizontal irradiance against the
Kider et al. 2014 pyranometer, capture by capture (docs/validation_measured.md).

The model sees the sun at the middle of the pyranometer's window (SPA; the labels' time,
which the pyranometer's record fits, see ``pyranometer_clock_offset_min``) and the AERONET
atmosphere of :func:`skydome.validation.aeronet.aerosol_atmosphere`
with the absorbing gases of :mod:`skydome.atmosphere.gases`. Its spectral global horizontal
irradiance (direct + diffuse) is computed at the Bird & Riordan 1986 table wavelengths in
the band (where the gas coefficients are given; linear between them) and integrated against
the ASTM G173 extraterrestrial spectrum at 1 nm: per unit extraterrestrial irradiance the
model's response is interpolated linearly between those wavelengths, then multiplied by
the 1 nm spectrum and summed (trapezoidal rule).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skydome._validate import check_choice, check_number

__all__ = ["BAND_NM", "PYRANOMETER_CLOCK_OFFSET_MIN", "ClosureResult", "closure_wavelengths", "broadband_ghi", "closure",
           "closure_table"]

#: the pyranometer's band [nm] (a thermopile pyranometer's 285-2800 nm, from 300 nm where
#: the gas table starts: below it the ground irradiance is under 0.01 % of the total)
BAND_NM = (300.0, 2800.0)

#: the pyranometer's clock offset [min]: its record fits the labels (EDT) as they are, not
#: the scanner's -40 min (docs/validation_measured.md, "Broadband closure")
PYRANOMETER_CLOCK_OFFSET_MIN = 0.0

#: models the closure runs
CLOSURE_MODELS = ("precomputed", "hillaire2020")


def closure_wavelengths(band_nm=BAND_NM) -> np.ndarray:
    """The Bird & Riordan 1986 wavelengths within ``band_nm`` plus its ends [nm]."""
    from skydome.atmosphere.gases import absorption_table

    wl = absorption_table()[0]
    lo, hi = band_nm
    inner = wl[(wl > lo) & (wl < hi)]
    return np.concatenate([[lo], inner, [hi]])


@dataclass
class ClosureResult:
    """One capture: measured and modelled GHI [W m^-2] and the relative error."""

    capture: str
    model: str
    sun_elevation_deg: float
    measured_w_m2: float
    model_w_m2: float
    direct_w_m2: float
    diffuse_w_m2: float

    @property
    def error(self) -> float:
        return self.model_w_m2 / self.measured_w_m2 - 1.0


def _label_sun(label: str, offset_min: float):
    """The SPA sun at the middle of the scan window labelled ``label`` (EDT) + ``offset_min``."""
    from datetime import datetime, timedelta

    from skydome.sun import Sun
    from skydome.validation import kider2014 as k

    h, m, s = (int(x) for x in label.split(":"))
    t = datetime(*k.DATE, h, m, s, tzinfo=k.EDT) + timedelta(minutes=offset_min,
                                                              seconds=k.SCAN_DURATION_S / 2.0)
    return Sun.from_location(k.SITE_LATITUDE_DEG, k.SITE_LONGITUDE_DEG, t)


def _model(name, sun, atmosphere, wl, fast):
    import skydome as sd

    if name == "precomputed":
        kw = {"table_wavelengths_nm": wl}
        if fast:
            kw.update(orders=4, scattering_mu_size=64, scattering_mu_s_size=32, scattering_nu_size=8,
                      sphere_samples=16)
        return sd.model("precomputed", sun=sun, atmosphere=atmosphere, **kw)
    return sd.model("hillaire2020", sun=sun, atmosphere=atmosphere, n_wavelengths=wl.size)


def _components(sky, wl):
    """(direct, diffuse) horizontal spectral irradiance at ``wl`` [W m^-2 nm^-1]."""
    if hasattr(sky, "irradiance_components"):
        return sky.irradiance_components(wl)
    from skydome.illuminance import sky_irradiance, sun_irradiance

    return np.asarray(sun_irradiance(sky, wl)), np.asarray(sky_irradiance(sky, wl))


def broadband_ghi(sky, band_nm=BAND_NM) -> tuple[float, float]:
    """(direct, diffuse) broadband horizontal irradiance [W m^-2] of a spectral model over
    ``band_nm``: the model's response at :func:`closure_wavelengths`, per unit
    extraterrestrial irradiance, interpolated linearly onto a 1 nm grid and integrated
    against the ASTM G173 spectrum there."""
    from skydome.spectra import solar_irradiance

    wl = closure_wavelengths(band_nm)
    scale = sky.sun.irradiance_scale
    e0 = solar_irradiance(wl) * scale
    fine = np.arange(band_nm[0], band_nm[1] + 0.5, 1.0)
    e0_fine = solar_irradiance(fine) * scale
    out = []
    for e in _components(sky, wl):
        per_unit = np.asarray(e, dtype=np.float64).reshape(-1) / e0
        out.append(float(np.trapezoid(np.interp(fine, wl, per_unit) * e0_fine, fine)))
    return out[0], out[1]


def closure(captures, model: str = "precomputed", *, precipitable_water_cm: float = 1.42,
            gas_reference_airmass: float = 1.5, fast: bool = False,
            band_nm=BAND_NM,
            pyranometer_clock_offset_min: float | None = PYRANOMETER_CLOCK_OFFSET_MIN) -> list[ClosureResult]:
    """Model against pyranometer GHI for each capture that has a pyranometer record.

    Parameters
    ----------
    captures : list of :class:`skydome.validation.kider2014.Capture`
    model : {"precomputed", "hillaire2020"}
    precipitable_water_cm : float
        Water vapour column [cm] in [0, 10] (default 1.42, the US Standard Atmosphere's; not
        measured that day).
    gas_reference_airmass : float
        Air mass in [1, 40] at which the gas band models are matched (:mod:`skydome.atmosphere.gases`).
    fast : bool
        precomputed at coarse table sizes (the tests' setting).
    band_nm : (float, float)
        Integration band [nm] within 300-4000.
    pyranometer_clock_offset_min : float or None
        Offset [min] in [-120, 120] of the pyranometer's clock: the model's sun is at the
        middle of the labelled window plus this offset (default
        :data:`PYRANOMETER_CLOCK_OFFSET_MIN`, 0: the labels, which the pyranometer's record
        fits). None: the capture's own sun (the scanner's clock correction,
        :data:`skydome.validation.kider2014.CLOCK_OFFSETS_MIN`).
    """
    from skydome.validation.aeronet import aerosol_atmosphere, egbert_20130527, nearest_retrieval

    check_choice("model", model, CLOSURE_MODELS)
    w = check_number("precipitable_water_cm", precipitable_water_cm, 0.0, 10.0, "cm")
    m = check_number("gas_reference_airmass", gas_reference_airmass, 1.0, 40.0)
    lo = check_number("band_nm[0]", band_nm[0], 300.0, 4000.0, "nm")
    hi = check_number("band_nm[1]", band_nm[1], 300.0, 4000.0, "nm")
    if hi <= lo:
        raise ValueError(f"band_nm = {tuple(band_nm)} must increase")
    if pyranometer_clock_offset_min is not None:
        off = check_number("pyranometer_clock_offset_min", pyranometer_clock_offset_min,
                           -120.0, 120.0, "min")
    wl = closure_wavelengths((lo, hi))
    retrievals = egbert_20130527()
    atmospheres: dict = {}
    out = []
    for c in captures:
        if not np.isfinite(c.ghi_w_m2):
            continue
        r = nearest_retrieval(retrievals, c.mean_time)
        if r.time not in atmospheres:
            atmospheres[r.time] = aerosol_atmosphere(r, precipitable_water_cm=w,
                                                     gas_reference_airmass=m)
        sun = c.sun if pyranometer_clock_offset_min is None else _label_sun(c.label, off)
        sky = _model(model, sun, atmospheres[r.time], wl, fast)
        direct, diffuse = broadband_ghi(sky, (lo, hi))
        out.append(ClosureResult(c.label, model, float(sun.elevation_deg), float(c.ghi_w_m2),
                                 direct + diffuse, direct, diffuse))
    return out


def closure_table(results) -> str:
    """The :func:`closure` results as a Markdown table, a capture a row."""
    lines = ["| capture | sun elevation [deg] | measured [W m^-2] | model [W m^-2] | direct | "
             "diffuse | error |", "|---|---|---|---|---|---|---|"]
    lines += [f"| {r.capture} | {r.sun_elevation_deg:.1f} | {r.measured_w_m2:.1f} | "
              f"{r.model_w_m2:.1f} | {r.direct_w_m2:.1f} | {r.diffuse_w_m2:.1f} | "
              f"{100 * r.error:+.1f} % |" for r in results]
    return "\n".join(lines)
