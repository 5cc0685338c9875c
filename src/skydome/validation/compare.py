"""Models against the measured sky: :func:`compare_measured`.

For each model and capture of the Kider et al. 2014 day (:mod:`.kider2014`), the model is
evaluated in the scanner's directions (sample 0 left out: see :data:`EXCLUDED_SAMPLES`)
and compared with the measurement:

* luminance [cd m^-2] (683 lm/W, CIE 1931 y-bar over 380-780 nm of the 5 nm spectra):
  the level error ``mean(model) / mean(measured) - 1`` and the shape error, the relative
  error per direction of each luminance normalised by its own mean; RMS / median / max of
  the absolute shape error over all directions and split into circumsolar (< 10 deg from
  the sun), horizon (altitude < 15 deg) and the rest;
* spectral radiance at 400-700 nm (spectral models only): RMS relative error over
  directions and wavelengths, level and shape separately as for luminance;
* colour: the distance in CIE 1931 xy between model and measurement, RMS and max.

The physically based models take the same atmosphere: Rayleigh (Ciddor 1996, King
factor), the AERONET aerosol of the retrieval nearest in time (tabulated measured phase
function), ozone 300 DU and the inversion's own surface albedo (see
:func:`skydome.validation.aeronet.aerosol_atmosphere`). The analytic models take the inputs
they need: Preetham and Hosek-Wilkie turbidity from the aerosol's Angstrom beta (its
optical depth at 1 um, AERONET or fitted; [PSS99] A.2 inverted), skydome's ``fitted``
model the aerosol optical depth at 550 nm and the surface albedo at 550 nm (its own
aerosol otherwise: Angstrom 1.3, Cornette-Shanks g = 0.76),
Perez 1993 DNI/DHI from the pyranometer GHI by the Erbs et al. 1982 split
(``pvlib.irradiance.erbs``), CIE 2003 the sky type of best fit to the measured luminance
shape (its level is then not a prediction and is not reported).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from skydome.validation.kider2014 import EXCLUDED_SAMPLES  # samples left out of statistics

__all__ = ["arc_directions", "MODELS", "AEROSOLS", "BANDS_NM", "band_medians", "capture_table",
           "EXCLUDED_SAMPLES", "clock_scan", "compare_measured", "ModelResult", "model_settings",
           "measured_luminance", "measured_report", "report_text"]

#: Models compared by default, in the table's order.
MODELS = ("precomputed", "montecarlo", "hillaire2020", "nishita1996", "single_scattering",
          "fitted", "preetham1999", "hosek_wilkie2012", "perez1993", "cie2003")

PHYSICAL = ("precomputed", "precomputed_accurate", "montecarlo", "hillaire2020", "nishita1996",
            "single_scattering")

#: Aerosol of the physically based models: "aeronet" (the Egbert retrieval nearest in
#: time; 2013-05-27 only) or "fitted" (tau440 and alpha fitted to the scan itself,
#: :func:`skydome.validation.fitting.fit_aerosol`)
AEROSOLS = ("aeronet", "fitted")

#: centres of the 20 nm bands whose median model / measured ratio is reported [nm]
BANDS_NM = (400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0)

#: wavelengths of the comparison: luminance and xy over 380-780 nm, spectra 400-700 nm
LUMINANCE_WL = np.arange(380.0, 781.0, 5.0)
SPECTRAL_BAND = (400.0, 700.0)


def model_settings(name: str, fast: bool = False) -> dict:
    """Settings of each physically based model in the comparison (``fast``: coarse ones for
    the tests)."""
    if name == "precomputed":
        return {"n_wavelengths": 8} if fast else {}
    if name == "precomputed_accurate":
        return {"n_wavelengths": 40, "orders": 8, "scattering_nu_size": 16, "scattering_mu_size": 256}
    if name == "montecarlo":
        return {"samples": 16 if fast else 64, "seed": 0}
    if name == "hillaire2020":
        return {"n_wavelengths": 8} if fast else {}
    if name == "nishita1996":
        return {"orders": 3} if fast else {}
    return {}


def measured_luminance(capture) -> tuple[np.ndarray, np.ndarray]:
    """(luminance [cd m^-2] (81,), xy (81, 2)) of the measured spectra over 380-780 nm."""
    from skydome.spectra import spectrum_to_xyz, xyz_to_xy

    wl = capture.wavelengths_nm
    sel = (wl >= 380.0) & (wl <= 780.0)
    xyz = spectrum_to_xyz(capture.radiance[:, sel], wl[sel])
    return xyz[:, 1], xyz_to_xy(xyz)


def _stats(err: np.ndarray) -> dict:
    a = np.abs(err)
    if a.size == 0:
        return {"rms": float("nan"), "median": float("nan"), "max": float("nan")}
    return {"rms": float(np.sqrt(np.mean(a * a))), "median": float(np.median(a)), "max": float(a.max())}


@dataclass
class ModelResult:
    """Errors of one model on one capture (relative errors as fractions; xy as distances)."""

    model: str
    capture: str
    phase: str
    luminance_level: float
    luminance_shape: dict = field(default_factory=dict)   # region -> {rms, median, max}
    spectral_level: float = float("nan")
    spectral_shape_rms: float = float("nan")
    spectral_rms: float = float("nan")
    xy_rms: float = float("nan")
    xy_max: float = float("nan")
    model_luminance: np.ndarray | None = None
    model_spectra: np.ndarray | None = None   # (81, n 400-700 nm) for spectral models
    day: str = ""
    #: RMS of the luminance error model / measured - 1 (level included) over the kept
    #: directions at least 10 deg from the sun
    luminance_rms_outside: float = float("nan")
    #: band centre [nm] -> median over the kept directions of model / measured - 1 of the
    #: radiance averaged over the band (+-10 nm); spectral models only
    band_medians: dict = field(default_factory=dict)
    aerosol: str = ""


def _regions(capture, keep):
    gamma = capture.sun_angle_deg
    el = capture.elevation_deg
    circ = (gamma < 10.0) & keep
    hor = (el < 15.0) & keep & ~circ
    rest = keep & ~circ & ~hor
    return {"all": keep, "circumsolar": circ, "horizon": hor, "rest": rest}


_ATM_CACHE: dict = {}


def atmosphere_for(capture, phase: str = "tabulated", aerosol: str = "aeronet"):
    """The atmosphere of a capture: with ``aerosol="aeronet"`` the retrieval nearest to the
    capture's mean time (on a day without one, the Egbert 2013-05-27 14:19 UTC retrieval:
    :func:`skydome.validation.fitting.base_retrieval`), with ``"fitted"`` tau440 and alpha
    fitted to the scan (:func:`skydome.validation.fitting.fit_aerosol`)."""
    from skydome.validation.aeronet import aerosol_atmosphere
    from skydome.validation.fitting import base_retrieval, fit_aerosol

    if aerosol == "fitted":
        r = fit_aerosol(capture, phase="tabulated")
        key = (capture.day, capture.label, capture.mean_time, phase, "fitted")
    else:
        r = base_retrieval(capture)
        key = (r.time, phase)
    if key not in _ATM_CACHE:
        _ATM_CACHE[key] = (aerosol_atmosphere(r, phase=phase), r)
    return _ATM_CACHE[key]


#: Models that take Henyey-Greenstein with the measured asymmetry factor when the tabulated
#: (measured) phase is asked, because their tabulated path fails the single-scattering check
#: (tests/test_validation_compare.py). Empty: precomputed evaluates tabulated phase
#: functions per table wavelength and passes it.
TABULATED_FALLBACK: tuple = ()


def model_phase(name: str, phase: str) -> str:
    """The aerosol phase model ``name`` uses in the comparison when ``phase`` is asked."""
    if phase == "tabulated" and name in TABULATED_FALLBACK:
        return "henyey_greenstein"
    return phase


def _aerosol_label(r, aerosol):
    return f"{aerosol} tau440 {r.tau440:.3f} alpha {r.alpha:.2f}"


def _build(name, capture, fast, phase, aerosol="aeronet"):
    import skydome as sd

    sun = capture.sun
    base = "precomputed" if name == "precomputed_accurate" else name
    if name in PHYSICAL:
        ph = model_phase(name, phase)
        atm, r = atmosphere_for(capture, ph, aerosol)
        label = ph if ph == "tabulated" else f"{ph} (g = {float(r.asymmetry()[1]):.3f} measured)"
        return sd.model(base, sun=sun, atmosphere=atm, **model_settings(name, fast)), label
    _, r = atmosphere_for(capture, phase, aerosol)
    src = "AERONET" if aerosol == "aeronet" else "fitted"
    if name == "preetham1999":
        beta = float(r.optical_depth(1000.0))  # Angstrom beta = tau(1 um)
        turbidity = (beta + 0.04586) / 0.04608  # [PSS99] A.2 inverted
        # the model's range is T = 2-10 ([PSS99] fit it there); a clearer sky is clipped
        clip = " clipped to 2" if turbidity < 2.0 else ""
        return sd.model("preetham1999", sun=sun, turbidity=float(np.clip(turbidity, 2.0, 10.0))), \
            f"analytic (T = {turbidity:.2f} from {src} beta{clip})"
    if name == "fitted":
        # skydome's fitted model takes the aerosol optical depth at 550 nm only (its aerosol:
        # Angstrom 1.3, Cornette-Shanks g 0.76, ssa 0.9, scale height 1.2 km, as
        # Atmosphere.earth): the capture's tau550 (AERONET or fitted), and a grey ground
        # albedo, the inversion's surface albedo at 550 nm
        aod = float(r.optical_depth(550.0))
        albedo = float(np.interp(550.0, r.albedo_wavelengths_nm, r.surface_albedo))
        return sd.model("fitted", sun=sun, aerosol_optical_depth=aod, ground_albedo=albedo), \
            f"fitted (AOD550 {aod:.3f}, Angstrom 1.3, albedo {albedo:.2f})"
    if name == "hosek_wilkie2012":
        beta = float(r.optical_depth(1000.0))
        turbidity = (beta + 0.04586) / 0.04608  # [PSS99] A.2 inverted: [HW12] use Preetham's T
        albedo = float(np.interp(550.0, r.albedo_wavelengths_nm, r.surface_albedo))
        return sd.model("hosek_wilkie2012", sun=sun, turbidity=float(np.clip(turbidity, 1.0, 10.0)),
                        albedo=albedo), \
            f"analytic (T = {turbidity:.2f} from {src} beta, albedo {albedo:.2f})"
    if name == "perez1993":
        import pvlib

        doy = capture.mean_time.timetuple().tm_yday
        split = pvlib.irradiance.erbs(capture.ghi_w_m2, sun.zenith_deg, doy)
        dni, dhi = float(split["dni"]), float(split["dhi"])
        return sd.model("perez1993", sun=sun, dni=dni, dhi=dhi, day_of_year=doy), \
            f"analytic (Erbs: DNI {dni:.0f}, DHI {dhi:.0f} W/m2)"
    if name == "cie2003":
        return None, "analytic (type by best fit)"
    raise ValueError(f"model must be one of {', '.join(MODELS + ('precomputed_accurate',))}, got {name!r}")


def _cie_best(capture, lum, keep):
    import skydome as sd

    best = None
    for t in range(1, 16):
        m = sd.model("cie2003", sun=capture.sun, sky_type=t)
        L = m.luminance(capture.directions)
        e = (L[keep] / L[keep].mean()) / (lum[keep] / lum[keep].mean()) - 1.0
        r = float(np.sqrt(np.mean(e * e)))
        if best is None or r < best[0]:
            best = (r, t, m)
    return best[2], best[1]


def arc_directions(capture, n_sub: int = 8, move: str = "from_previous") -> np.ndarray:
    """Directions along each sample's move (81, n_sub, 3).

    The scanner is a pan-tilt head: between sample i-1 and sample i it turns in azimuth and
    elevation together; if it integrated while it moved, a sample would be this mean. Sample i (i >= 1) is modelled as
    the mean over ``n_sub`` points at fractions (j + 0.5) / n_sub of the move from the
    previous sample's (azimuth, elevation) to its own, linear in both angles (the azimuth
    the short way round). Sample 0 has no previous sample: its points all lie at its own direction.
    ``move="to_next"`` takes the move from sample i to sample i + 1 instead (the last sample
    staying at its own direction).
    """
    from skydome.validation.kider2014 import _enu

    n = int(n_sub)
    if n < 1 or n > 256:
        raise ValueError(f"n_sub must be an integer in [1, 256], got {n_sub!r}")
    if move not in ("from_previous", "to_next"):
        raise ValueError(f"move must be 'from_previous' or 'to_next', got {move!r}")
    az, el = capture.azimuth_deg, capture.elevation_deg
    if move == "from_previous":
        az0, el0 = np.r_[az[0], az[:-1]], np.r_[el[0], el[:-1]]
    else:  # from this sample towards the next: the same formula with the roles swapped
        az0, el0 = np.r_[az[1:], az[-1]], np.r_[el[1:], el[-1]]
    daz = (az - az0 + 180.0) % 360.0 - 180.0
    f = (np.arange(n) + 0.5) / n
    a = az0[:, None] + daz[:, None] * f[None, :]
    e = el0[:, None] + (el - el0)[:, None] * f[None, :]
    return _enu(a, e)


def band_medians(S, wl, capture, keep) -> list[float]:
    """Per band of :data:`BANDS_NM`: the median over the kept directions (``keep``) of the
    model's mean radiance within 10 nm of the band (``S`` (n, wl) at ``wl`` [nm]) over the
    capture's mean radiance there, minus 1."""
    out = []
    for b in BANDS_NM:
        sm, mm = np.abs(wl - b) <= 10.0, np.abs(capture.wavelengths_nm - b) <= 10.0
        ratio = S[:, sm].mean(axis=1) / capture.radiance[:, mm].mean(axis=1)
        out.append(float(np.median(ratio[keep]) - 1.0))
    return out


def compare_one(name: str, capture, *, fast: bool = False, phase: str = "tabulated",
                motion: str | None = None, n_sub: int = 8, aerosol: str = "aeronet") -> ModelResult:
    """Errors of model ``name`` on one capture (see the module docstring); ``motion``:
    None (the value at the labelled direction) or a ``move`` of :func:`arc_directions`
    (each sample as the mean along that move); ``aerosol``: one of :data:`AEROSOLS`."""
    from skydome.spectra import spectrum_to_xyz, xyz_to_xy

    keep = np.ones(capture.directions.shape[0], bool)
    keep[list(EXCLUDED_SAMPLES)] = False
    lum, xy = measured_luminance(capture)
    if name == "perez1993" and not np.isfinite(capture.ghi_w_m2):
        nan = {"rms": float("nan"), "median": float("nan"), "max": float("nan")}
        return ModelResult(model=name, capture=capture.label, phase="no pyranometer record",
                           luminance_level=float("nan"), day=capture.day,
                           luminance_shape={k: dict(nan) for k in ("all", "circumsolar", "horizon", "rest")})
    model, label = _build(name, capture, fast, phase, aerosol)
    aerosol_used = "" if name in ("perez1993", "cie2003") else \
        _aerosol_label(atmosphere_for(capture, model_phase(name, phase), aerosol)[1], aerosol)
    if name == "cie2003":
        model, t = _cie_best(capture, lum, keep)
        label = f"analytic (type {t} of best fit)"
    d = arc_directions(capture, n_sub, motion) if motion else capture.directions
    spectra = None
    bands = {}
    if model.native == "spectral":
        wl = LUMINANCE_WL
        S = model.radiance(d, wl)
        if motion:
            S = S.mean(axis=1)
        bands = dict(zip(BANDS_NM, band_medians(S, wl, capture, keep)))
        xyz = spectrum_to_xyz(S, wl)
        band = (wl >= SPECTRAL_BAND[0]) & (wl <= SPECTRAL_BAND[1])
        spectra = S[:, band]
    else:
        xyz = model.xyz(d)
        if motion:
            xyz = xyz.mean(axis=1)
    L = xyz[:, 1]
    level = float(L[keep].mean() / lum[keep].mean() - 1.0) if name != "cie2003" else float("nan")
    shape = (L / L[keep].mean()) / (lum / lum[keep].mean()) - 1.0
    outside = keep & (capture.sun_angle_deg >= 10.0)
    lrms = float(np.sqrt(np.mean((L[outside] / lum[outside] - 1.0) ** 2))) \
        if name != "cie2003" else float("nan")
    res = ModelResult(model=name, capture=capture.label, phase=label, luminance_level=level,
                      luminance_shape={k: _stats(shape[m]) for k, m in _regions(capture, keep).items()},
                      model_luminance=L, model_spectra=spectra, day=capture.day,
                      luminance_rms_outside=lrms, band_medians=bands, aerosol=aerosol_used)
    if model.native != "luminance":
        dxy = np.linalg.norm(xyz_to_xy(xyz) - xy, axis=-1)[keep]
        res.xy_rms, res.xy_max = float(np.sqrt(np.mean(dxy ** 2))), float(dxy.max())
    if spectra is not None:
        mw = capture.wavelengths_nm
        msel = (mw >= SPECTRAL_BAND[0]) & (mw <= SPECTRAL_BAND[1])
        meas = capture.radiance[:, msel][keep]
        mod = spectra[keep]
        rel = mod / meas - 1.0
        res.spectral_rms = float(np.sqrt(np.mean(rel ** 2)))
        res.spectral_level = float(mod.mean() / meas.mean() - 1.0)
        srel = (mod / mod.mean()) / (meas / meas.mean()) - 1.0
        res.spectral_shape_rms = float(np.sqrt(np.mean(srel ** 2)))
    return res


def compare_measured(models=MODELS, captures=None, *, fast: bool = False,
                     phase: str = "tabulated", progress=None, day: str | None = None,
                     aerosol: str | None = None) -> list[ModelResult]:
    """Compare ``models`` with the measured captures of ``day`` (all of them by default, or
    labels).

    Parameters
    ----------
    models : sequence of str
        Names among :data:`MODELS` (and "precomputed_accurate").
    captures : sequence of str or Capture, optional
    fast : bool
        Coarse settings (tests).
    phase : {"tabulated", "henyey_greenstein", "cornette_shanks"}
        Aerosol phase function of the physically based models.
    day : str, optional
        One of :data:`skydome.validation.kider2014.DAYS` (default the first, 2013-05-27).
    aerosol : {"aeronet", "fitted"}, optional
        Default: "aeronet" on 2013-05-27, "fitted" on a day without AERONET.

    Returns
    -------
    list of ModelResult, model-major.
    """
    from skydome._validate import check_choice
    from skydome.validation.kider2014 import Capture, load_captures

    models = [models] if isinstance(models, str) else list(models)
    for m in models:
        check_choice("model", m, MODELS + ("precomputed_accurate",))
    check_choice("phase", phase, ("tabulated", "henyey_greenstein", "cornette_shanks"))
    from skydome.validation.kider2014 import DAYS, DEFAULT_DAY

    day = DEFAULT_DAY if day is None else check_choice("day", day, DAYS)
    if aerosol is None:
        aerosol = "aeronet" if day == "2013-05-27" else "fitted"
    check_choice("aerosol", aerosol, AEROSOLS)
    if aerosol == "aeronet" and day != "2013-05-27":
        raise ValueError(f"aerosol = 'aeronet' has no retrieval for day {day!r}: use 'fitted'")
    if captures is None or (captures and not isinstance(list(captures)[0], Capture)):
        captures = load_captures(captures, day=day)
    out = []
    for m in models:
        for c in captures:
            out.append(compare_one(m, c, fast=fast, phase=phase, aerosol=aerosol))
            if progress is not None:
                progress(m, c.label)
    return out


def measured_report(models, days, captures=None, *, fast: bool = False,
                    phase: str = "tabulated", aerosol: str | None = None,
                    progress=None) -> tuple[str, list[ModelResult]]:
    """The text ``skydome validate measured`` prints, and the results it comes from.

    For each of ``days`` (captures among ``captures``, all by default) the day's table
    (:func:`day_table`), then one table of every capture (:func:`capture_table`).
    ``progress(day, model, label)`` is called after each model and capture. The command
    and ``tools/validation_measured.py`` (which also saves the results for the figures)
    both call this, so the published tables are what the command prints.
    """
    from skydome.validation.kider2014 import capture_labels

    names = [models] if isinstance(models, str) else list(models)
    results = []
    for d in days:
        caps = None if captures is None else [c for c in captures if c in capture_labels(d)]
        if caps == []:
            continue
        cb = None if progress is None else (lambda m, c, d=d: progress(d, m, c))
        results += compare_measured(names, caps, fast=fast, phase=phase, day=d, aerosol=aerosol,
                                    progress=cb)
    return report_text(results, names, days), results


def report_text(results, models, days) -> str:
    """The text of :func:`measured_report` from its results (in any order): per day the
    day's table, then the table of every capture, days in the order of ``days``, models in
    the order of ``models``, captures in time order."""
    names = list(models)
    rs = sorted(results, key=lambda r: (list(days).index(r.day), names.index(r.model),
                                        r.capture))
    tables = []
    for d in days:
        rd = [r for r in rs if r.day == d]
        if rd:
            tables.append(f"Day {d} ({len(rd) // len(names)} captures), mean over captures:\n\n"
                          + day_table(rd))
    return "\n".join(tables) + "\nEvery capture:\n\n" + capture_table(rs)


def day_table(results) -> str:
    """A Markdown table: per model, the mean over captures of each error [%] (xy in 1e-3)."""
    by = {}
    for r in results:
        by.setdefault(r.model, []).append(r)
    head = ("| model | phase / inputs | level L | shape L RMS | median | max | circumsolar RMS | "
            "horizon RMS | rest RMS | spectral RMS 400-700 | spectral shape RMS | xy RMS (1e-3) |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    rows = []
    for m, rs in by.items():
        def mean(f):
            v = np.array([f(r) for r in rs], float)
            v = v[np.isfinite(v)]
            return float(np.mean(v)) if v.size else float("nan")

        def pct(x):
            return "n/a" if not np.isfinite(x) else f"{100 * x:+.1f}" if x is lvl else f"{100 * x:.1f}"

        lvl = mean(lambda r: r.luminance_level)
        phases = sorted({r.phase.split(" (")[0] for r in rs if r.phase != "no pyranometer record"})
        vals = [pct(lvl)] + [pct(mean(lambda r, k=k, s=s: r.luminance_shape[k][s]))
                             for k, s in (("all", "rms"), ("all", "median"), ("all", "max"),
                                          ("circumsolar", "rms"), ("horizon", "rms"), ("rest", "rms"))]
        vals += [pct(mean(lambda r: r.spectral_rms)), pct(mean(lambda r: r.spectral_shape_rms))]
        xyr = mean(lambda r: r.xy_rms)
        vals.append("n/a" if not np.isfinite(xyr) else f"{1000 * xyr:.1f}")
        rows.append(f"| {m} | {', '.join(phases)} | " + " | ".join(vals) + " |")
    return head + "\n".join(rows) + "\n"


def capture_table(results) -> str:
    """A Markdown table with one row per model and capture, in %: the luminance level, the
    RMS of the luminance error (level included) at least 10 deg from the sun, the shape RMS
    (all directions, circumsolar, the rest outside the circumsolar and horizon regions), the
    spectral RMS 400-700 nm, xy RMS (1e-3) and the median model / measured - 1 in each band
    of :data:`BANDS_NM`."""
    bands = " | ".join(f"{b:.0f}" for b in BANDS_NM)
    head = ("| day | capture | model | inputs | level L | L RMS >= 10 deg | shape RMS | "
            "circumsolar | rest | spectral RMS | xy (1e-3) | " + bands + " |\n"
            "|" + "---|" * (11 + len(BANDS_NM)) + "\n")

    def f(x, sign=False):
        if x is None or not np.isfinite(x):
            return "n/a"
        return f"{100 * x:+.1f}" if sign else f"{100 * x:.1f}"

    rows = []
    for r in results:
        sh = r.luminance_shape
        xy = "n/a" if not np.isfinite(r.xy_rms) else f"{1000 * r.xy_rms:.1f}"
        inputs = r.phase + (f"; {r.aerosol}" if r.aerosol else "")
        vals = [r.day, r.capture, r.model, inputs, f(r.luminance_level, True),
                f(r.luminance_rms_outside), f(sh["all"]["rms"]), f(sh["circumsolar"]["rms"]),
                f(sh["rest"]["rms"]), f(r.spectral_rms), xy]
        vals += [f(r.band_medians.get(b), True) for b in BANDS_NM]
        rows.append("| " + " | ".join(vals) + " |")
    return head + "\n".join(rows) + "\n"


def clock_scan(day: str, labels=None, offsets_min=np.arange(-60.0, 11.0, 10.0), *,
               motions=(None, "from_previous"), model: str = "hillaire2020") -> dict:
    """Shape error of ``model``'s luminance against each scan for a range of clock offsets.

    For each capture, offset [min] (added to the labels) and motion (None: the model at the
    labelled directions; "from_previous": the mean along the move from the previous sample)
    the RMS of ``ln(model / measured)`` minus its mean over the 80 kept directions (a shape
    error, free of the level). The aerosol is the AERONET retrieval nearest in time
    (:func:`skydome.validation.fitting.base_retrieval`), not fitted: a fit would follow the sun it is given.
    Returns ``{"labels", "offsets_min", "motions", "rms" (captures, motions, offsets),
    "best_min" (captures, motions)}``; ``best_min`` is the minimum of a parabola through the
    best grid offset and its neighbours.
    """
    from skydome.validation.kider2014 import capture_labels, load_captures

    labels = capture_labels(day) if labels is None else tuple(labels)
    offs = np.asarray(offsets_min, dtype=np.float64)
    rms = np.empty((len(labels), len(motions), offs.size))
    for j, off in enumerate(offs):
        for k, c in enumerate(load_captures(labels, clock_offset_min=float(off), day=day)):
            lum, _ = measured_luminance(c)
            keep = np.ones(lum.size, bool)
            keep[list(EXCLUDED_SAMPLES)] = False
            for i, mo in enumerate(motions):
                r = compare_one(model, c, motion=mo, aerosol="aeronet")
                e = np.log(r.model_luminance[keep] / lum[keep])
                rms[k, i, j] = float(np.sqrt(np.mean((e - e.mean()) ** 2)))
    best = np.empty(rms.shape[:2])
    for k in range(rms.shape[0]):
        for i in range(rms.shape[1]):
            j = int(np.argmin(rms[k, i]))
            if 0 < j < offs.size - 1:
                y0, y1, y2 = rms[k, i, j - 1:j + 2]
                den = y0 - 2 * y1 + y2
                step = offs[j + 1] - offs[j]
                best[k, i] = offs[j] + (0.5 * (y0 - y2) / den * step if den > 0 else 0.0)
            else:
                best[k, i] = offs[j]
    return {"labels": labels, "offsets_min": offs, "motions": tuple(motions), "rms": rms,
            "best_min": best}


#: elevations of the scanner's four rings [deg] (the zenith sample is the fifth "ring")
RING_ELEVATIONS_DEG = (12.1, 33.7, 53.4, 71.9, 90.0)


def ring_offsets(pairs, *, bins_deg=np.arange(10.0, 181.0, 10.0)) -> dict:
    """Each ring's error at equal angle from the sun: the scanner's per-ring response test.

    ``pairs``: sequence of (capture, model luminance (81,)). The error ``e = ln(model /
    measured)`` of every kept direction (sample 0 and directions outside ``bins_deg``, by
    default the circumsolar ones < 10 deg from the sun, left out) of all captures is fitted
    by least squares as the sum of a constant per capture (the level), a constant per bin of
    the angle from the sun (what a phase function or aerosol amount error does) and a
    constant per ring. The ring constants, centred on their sample-weighted mean, are what
    no error depending only on the angle from the sun can make: the instrument's response
    per elevation, or a model error in the vertical (the aerosol profile, the air mass
    towards the horizon). Rings are told apart because the sun moves between captures, so
    each ring meets many angles.

    Returns ``{"rings_deg", "offset" (rings,) as exp(constant) - 1, "count" (rings,),
    "rms_before", "rms_after"}`` (RMS of e about the capture constants alone, and of the
    residual of the full fit).
    """
    edges = np.asarray(bins_deg, dtype=np.float64)
    rings = np.asarray(RING_ELEVATIONS_DEG)
    nb, nr, nc = edges.size - 1, rings.size, len(pairs)
    rows_c, rows_b, rows_r, ys = [], [], [], []
    for k, (cap, model_lum) in enumerate(pairs):
        lum, _ = measured_luminance(cap)
        keep = np.ones(lum.size, bool)
        keep[list(EXCLUDED_SAMPLES)] = False
        g = cap.sun_angle_deg
        keep &= (g >= edges[0]) & (g < edges[-1])
        e = np.log(np.asarray(model_lum, dtype=np.float64) / lum)
        ring = np.argmin(np.abs(cap.elevation_deg[:, None] - rings[None, :]), axis=1)
        b = np.clip(np.digitize(g, edges) - 1, 0, nb - 1)
        idx = np.flatnonzero(keep)
        rows_c += [k] * idx.size
        rows_b += list(b[idx])
        rows_r += list(ring[idx])
        ys += list(e[idx])
    y = np.asarray(ys)
    n = y.size
    A = np.zeros((n, nc + nb + nr))
    A[np.arange(n), rows_c] = 1.0
    A[np.arange(n), nc + np.asarray(rows_b)] = 1.0
    A[np.arange(n), nc + nb + np.asarray(rows_r)] = 1.0
    x, *_ = np.linalg.lstsq(A, y, rcond=None)
    count = np.bincount(rows_r, minlength=nr)
    rc = x[nc + nb:]
    rc = rc - np.sum(rc * count) / count.sum()
    cap_only = y - np.array([y[np.asarray(rows_c) == k].mean() for k in rows_c])
    return {"rings_deg": rings, "offset": np.expm1(rc), "count": count,
            "rms_before": float(np.sqrt(np.mean(cap_only ** 2))),
            "rms_after": float(np.sqrt(np.mean((y - A @ x) ** 2)))}


def angle_profile(pairs, *, bins_deg=(10.0, 20.0, 40.0, 60.0, 80.0, 100.0, 120.0, 180.0)):
    """Median of ``model / measured - 1`` (each normalised by its mean over the kept
    directions) in bins of the angle from the sun, over all captures of ``pairs``
    (sequence of (capture, model luminance)). Returns (bin edges, medians (bins,),
    counts (bins,))."""
    edges = np.asarray(bins_deg, dtype=np.float64)
    vals = [[] for _ in range(edges.size - 1)]
    for cap, model_lum in pairs:
        lum, _ = measured_luminance(cap)
        keep = np.ones(lum.size, bool)
        keep[list(EXCLUDED_SAMPLES)] = False
        L = np.asarray(model_lum, dtype=np.float64)
        s = (L / L[keep].mean()) / (lum / lum[keep].mean()) - 1.0
        b = np.digitize(cap.sun_angle_deg, edges) - 1
        for i in np.flatnonzero(keep):
            if 0 <= b[i] < edges.size - 1:
                vals[b[i]].append(s[i])
    med = np.array([float(np.median(v)) if v else float("nan") for v in vals])
    return edges, med, np.array([len(v) for v in vals])
