"""Run the measured-sky comparison and save what docs/validation_measured.md shows.

    python tools/validation_measured.py OUT_FOLDER [--day 2013-09-24|all] [--aerosol fitted]
        [--captures 10:00:00,11:00:00] [--models ...]
    python tools/validation_measured.py OUT_FOLDER --clock [--day 2013-09-24]
    python tools/validation_measured.py OUT_FOLDER --colour [--captures DAY/LABEL,...]
        [--fit-cache FITS.pkl]
    python tools/validation_measured.py OUT_FOLDER --figures FIG_FOLDER
    python tools/validation_measured.py docs/validation_measured.md --update-doc [--models fitted]
        [--day 2013-05-27] [--fit-cache FITS.pkl]

``--update-doc`` reruns every block of the page between ``<!-- begin: skydome validate
measured OPTIONS -->`` and ``<!-- end -->`` with those options and puts what the command
prints there; with ``--models`` only those models' rows are rerun and replaced (the other
rows stay), e.g. after a change of the fitted model's coefficients; with ``--day`` only the
blocks of that day are rerun. The page is written after each block, so a long rerun lands
block by block; ``--fit-cache FILE`` keeps the aerosol fits (the costly part) between runs
of groups of models.

``--clock`` prints, per capture, the best clock offset of the point and move models and,
last, the median over the captures of each: the median of the point model is what
``kider2014.CLOCK_OFFSETS_MIN`` takes for 2013-05-27.

Writes OUT_FOLDER/validation_measured_table.md (each day's table, then every capture,
exactly as ``skydome validate measured`` prints them with the same options: both call
``skydome.validation.compare.measured_report``), results.pkl (per model
and capture: the model luminance in the 81 directions and its 400-700 nm spectra) and the
figures of skydome.imaging.plots_validation.
"""

from __future__ import annotations

import argparse
import pickle
import sys
import time
from pathlib import Path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--captures", default=None)
    ap.add_argument("--models", default=None)
    ap.add_argument("--fast", action="store_true")
    ap.add_argument("--day", default=None,
                    help="2013-05-27 (default), 2013-09-24 or all; with --update-doc: only "
                         "that day's blocks")
    ap.add_argument("--phase", default="tabulated")
    ap.add_argument("--aerosol", default=None,
                    help="aeronet or fitted (default: aeronet where there is one)")
    ap.add_argument("--clock", action="store_true",
                    help="the clock scan (validation.compare.clock_scan), not the table")
    ap.add_argument("--point-only", action="store_true",
                    help="with --clock: the point model only (not the mean along the moves)")
    ap.add_argument("--shape", action="store_true",
                    help="the shape-error study: ring offsets of OUT's results.pkl and "
                         "hillaire2020 "
                         "refitted with other aerosol profiles, ground albedo, observer altitude")
    ap.add_argument("--phase-fit", action="store_true",
                    help="the phase-function test: hillaire2020 with tau440 and alpha fitted "
                         "(measured phase) against tau440, alpha and a Henyey-Greenstein g "
                         "fitted together, on --captures DAY/LABEL,... (default: every capture "
                         "of both days)")
    ap.add_argument("--colour", action="store_true",
                    help="the colour study: per capture (--captures DAY/LABEL,..., default all), "
                         "hillaire2020's band medians with the AERONET aerosol (2013-05-27), "
                         "with the Angstrom exponent held at 1.3 and tau440 fitted, and with "
                         "both fitted; the precipitable water from the scan's 940 nm band")
    ap.add_argument("--figures", default=None, help="only make the figures from OUT's results into this folder")
    ap.add_argument("--update-doc", action="store_true",
                    help="OUT is a Markdown page: rerun its marked command blocks in place")
    ap.add_argument("--fit-cache", default=None,
                    help="with --update-doc: a pickle keeping the aerosol fits between runs")
    a = ap.parse_args(argv)
    if a.update_doc:
        return update_doc(Path(a.out), a.models, None if a.day in (None, "all") else a.day,
                          a.fit_cache)
    a.day = a.day or "2013-05-27"
    if a.figures:
        return figures(Path(a.out), Path(a.figures))
    if a.clock:
        return clock(Path(a.out), a.day, a.point_only)
    if a.shape:
        return shape(Path(a.out), a.captures)
    if a.phase_fit:
        return phase_fit(Path(a.out), a.captures)
    if a.colour:
        return colour(Path(a.out), a.captures, a.fit_cache)
    from skydome.validation import fitting
    from skydome.validation.compare import compare_measured, report_text

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    models = a.models.split(",") if a.models else [
        "precomputed", "hillaire2020", "nishita1996", "single_scattering", "fitted",
        "preetham1999", "hosek_wilkie2012", "perez1993", "cie2003"]
    caps = a.captures.split(",") if a.captures else None
    days = ["2013-05-27", "2013-09-24"] if a.day == "all" else [a.day]
    t0 = time.time()
    # the aerosol fits of an earlier, interrupted run of the same folder (the fit is the
    # costly part of a rerun; the precomputed tables come from the table cache)
    fits = out / "fits.pkl"
    if fits.exists():
        with open(fits, "rb") as f:
            fitting._FIT_CACHE.update(pickle.load(f))

    def progress(m, c):
        print(f"{time.time() - t0:7.0f} s  {m} {c}", file=sys.stderr, flush=True)

    from skydome.validation.kider2014 import capture_labels

    # model by model, saving after each: the text is report_text of all results, the same
    # function measured_report (the command) formats them with, so the table is what
    # `skydome validate measured` prints with these options
    results, done = [], []
    for m in models:
        for d in days:
            cd = None if caps is None else [c for c in caps if c in capture_labels(d)]
            if cd == []:
                continue
            results += compare_measured([m], cd, fast=a.fast, phase=a.phase, day=d,
                                        aerosol=a.aerosol, progress=progress)
        done.append(m)
        with open(out / "results.pkl", "wb") as f:
            pickle.dump(results, f)
        with open(fits, "wb") as f:
            pickle.dump(dict(fitting._FIT_CACHE), f)
        text = report_text(results, done, days)
        name = "validation_measured_table.md" if done == models else "partial_table.md"
        (out / name).write_text(text, encoding="utf-8")
    print(text)
    print(f"{time.time() - t0:.0f} s", file=sys.stderr)
    return 0


_BEGIN = "<!-- begin: skydome validate measured"
_END = "<!-- end -->"


def _block_options(line: str) -> dict:
    """The options of a begin marker: ``--day``, ``--aerosol``, ``--models``, ``--phase``,
    ``--captures`` (the command's, with its defaults)."""
    raw = line[len(_BEGIN):].replace("-->", "").split()
    words = []
    for w in raw:  # a list may run on to the next line after a comma
        if words and words[-1].endswith(","):
            words[-1] += w
        else:
            words.append(w)
    opts = {"day": "2013-05-27", "aerosol": "auto", "models": None, "phase": "tabulated",
            "captures": None}
    for k, v in zip(words[::2], words[1::2]):
        if not k.startswith("--") or k[2:] not in opts:
            raise SystemExit(f"unknown option {k!r} in {line.strip()!r}")
        opts[k[2:]] = v
    return opts


def _replace_rows(old: str, new: str, models) -> str:
    """``old`` with the table rows of ``models`` replaced by ``new``'s (same tables)."""
    def model_of(row):
        cells = [c.strip() for c in row.strip("|").split("|")]
        return cells[2] if row.startswith("| 2013-") else cells[0]

    new_rows = [ln for ln in new.splitlines() if ln.startswith("| ") and model_of(ln) in models]
    out, it = [], iter(new_rows)
    for ln in old.splitlines():
        if ln.startswith("| ") and not ln.startswith("| model") and not ln.startswith("| day") \
                and model_of(ln) in models:
            out.append(next(it))
        else:
            out.append(ln)
    if next(it, None) is not None:
        raise SystemExit("the rerun gave more rows than the page holds: rerun the whole block")
    return "\n".join(out) + "\n"


def update_doc(page: Path, models, day=None, fit_cache=None) -> int:
    """Rerun each marked block of ``page`` (see the module docstring; only the blocks of
    ``day`` when given) and write the page back after each block."""
    from skydome._io import atomic_write
    from skydome.validation import fitting
    from skydome.validation.compare import measured_report
    from skydome.validation.kider2014 import DAYS

    only = models.split(",") if models else None
    if fit_cache and Path(fit_cache).exists():
        with open(fit_cache, "rb") as f:
            fitting._FIT_CACHE.update(pickle.load(f))
    lines = page.read_text(encoding="utf-8").splitlines(keepends=True)
    out, i = [], 0

    def write(rest):
        atomic_write(page, lambda tmp: Path(tmp).write_text("".join(out) + "".join(rest),
                                                            encoding="utf-8"))
        if fit_cache:
            with open(fit_cache, "wb") as f:
                pickle.dump(dict(fitting._FIT_CACHE), f)

    while i < len(lines):
        out.append(lines[i])
        if not lines[i].startswith(_BEGIN):
            i += 1
            continue
        k = i
        while "-->" not in lines[k]:  # the marker may span lines
            k += 1
            out.append(lines[k])
        o = _block_options(" ".join(ln.strip() for ln in lines[i:k + 1]))
        i = k
        j = i + 1
        while not lines[j].startswith(_END):
            j += 1
        old = "".join(lines[i + 1:j])
        names = (o["models"].split(",") if o["models"] else
                 ["precomputed", "hillaire2020", "nishita1996", "single_scattering", "fitted",
                  "preetham1999", "hosek_wilkie2012", "perez1993", "cie2003"])
        run = [m for m in names if only is None or m in only]
        if day is not None and o["day"] not in (day, "all"):
            run = []
        if run:
            days = list(DAYS) if o["day"] == "all" else [o["day"]]
            caps = o["captures"].split(",") if o["captures"] else None
            print(f"rerunning {o} for {', '.join(run)}", file=sys.stderr)
            text, _ = measured_report(run, days, caps, phase=o["phase"],
                                      aerosol=None if o["aerosol"] == "auto" else o["aerosol"])
            # a block of only the models rerun is replaced whole (also a new, empty one)
            new = text if only is None or set(names) <= set(only) else \
                _replace_rows(old, text, set(run))
            out.append(new if new.endswith("\n") else new + "\n")
            write(lines[j:])
        else:
            out.append(old)
        i = j
    write([])
    return 0


def clock(out: Path, day: str, point_only: bool = False) -> int:
    """Shape error against the clock offset, at the labelled directions and (unless
    ``point_only``) along the moves."""
    import numpy as np

    from skydome.validation.compare import clock_scan

    out.mkdir(parents=True, exist_ok=True)
    motions = (None,) if point_only else (None, "from_previous")
    names = ("point", "move")[:len(motions)]
    r = clock_scan(day, offsets_min=np.arange(-70.0, 21.0, 10.0), motions=motions)
    np.savez(out / f"clock_{day}.npz", labels=np.array(r["labels"]), offsets=r["offsets_min"],
             rms=r["rms"], best=r["best_min"])
    for lab, b, rr in zip(r["labels"], r["best_min"], r["rms"]):
        print(f"{day} {lab} best offset [min]: " + " ".join(
            f"{n} {b[i]:+.1f}" for i, n in enumerate(names)) + "; least shape RMS: " +
            " ".join(f"{n} {rr[i].min():.3f}" for i, n in enumerate(names)))
    med = np.median(r["rms"], axis=0)
    for i, name in enumerate(names):
        print(f"{day} median shape RMS, {name}: " + ", ".join(
            f"{o:+.0f}: {v:.3f}" for o, v in zip(r["offsets_min"], med[i])))
    best = np.median(r["best_min"], axis=0)
    print(f"{day} median of the per-capture best offsets [min]: " + " ".join(
        f"{n} {best[i]:+.1f}" for i, n in enumerate(names)))
    return 0


#: the variants of the shape study: (name, aerosol_atmosphere keywords, model keywords)
SHAPE_VARIANTS = (
    ("as published (H 1.2 km, Egbert albedo, sea level)", {}, {}),
    ("aerosol scale height 2.5 km", {"aerosol_scale_height_m": 2500.0}, {}),
    ("grey ground albedo 0.2", {"ground_albedo": 0.2}, {}),
    ("observer 250 m up (the site)", {}, {"observer_altitude_m": 250.0}),
)


def shape(out: Path, captures) -> int:
    """The shape error one step further: (1) per-ring offsets at equal angle from the sun
    (compare.ring_offsets) of every model in OUT/results.pkl; (2) hillaire2020 with the
    aerosol refitted under each of SHAPE_VARIANTS on a few captures: luminance RMS >= 10 deg,
    shape RMS and the median shape error per bin of the angle from the sun."""
    import numpy as np

    from skydome.validation import compare
    from skydome.validation.aeronet import aerosol_atmosphere
    from skydome.validation.fitting import fit_aerosol
    from skydome.validation.kider2014 import load_captures

    import skydome as sd

    lines = []
    pk = out / "results.pkl"
    if pk.exists():
        with open(pk, "rb") as f:
            results = pickle.load(f)
        caps = {}
        for d in dict.fromkeys(r.day for r in results):
            caps.update({(d, c.label): c for c in load_captures(
                list(dict.fromkeys(r.capture for r in results if r.day == d)), day=d)})
        lines.append("Ring offsets at equal angle from the sun (exp(constant) - 1, %; "
                     "rings 12.1 / 33.7 / 53.4 / 71.9 / 90 deg), RMS of ln before / after:")
        for m in dict.fromkeys(r.model for r in results):
            for d in [None] + list(dict.fromkeys(r.day for r in results)):
                pairs = [(caps[(r.day, r.capture)], r.model_luminance) for r in results
                         if r.model == m and (d is None or r.day == d)
                         and r.model_luminance is not None and m != "cie2003"]
                if not pairs:
                    continue
                ro = compare.ring_offsets(pairs)
                offs = " / ".join(f"{100 * v:+.1f}" for v in ro["offset"])
                lines.append(f"  {m:18s} {d or 'both days':10s} {offs}   "
                             f"{ro['rms_before']:.3f} / {ro['rms_after']:.3f}")
                e, med, n = compare.angle_profile(pairs)
                lines.append("      by angle from the sun " + ", ".join(
                    f"{e[i]:.0f}-{e[i + 1]:.0f}: {100 * med[i]:+.1f}" for i in range(med.size)))
    labs = (captures.split(",") if captures else
            ["2013-05-27/12:00:00", "2013-09-24/13:20:00"])
    if captures == "none":  # the ring offsets of OUT's results only
        labs = []
    lines.append("")
    lines.append("hillaire2020, aerosol refitted per variant:")
    for lab in labs:
        day, label = lab.split("/")
        c = load_captures([label], day=day)[0]
        for name, akw, mkw in SHAPE_VARIANTS:
            t = time.time()
            r = fit_aerosol(c, atmosphere_kw=akw, model_kw=mkw)
            m = sd.model("hillaire2020", sun=c.sun, atmosphere=aerosol_atmosphere(r, **akw), **mkw)
            L = m.xyz(c.directions)[:, 1]
            lum, _ = compare.measured_luminance(c)
            keep = np.ones(lum.size, bool)
            keep[list(compare.EXCLUDED_SAMPLES)] = False
            outside = keep & (c.sun_angle_deg >= 10.0)
            lrms = float(np.sqrt(np.mean((L[outside] / lum[outside] - 1.0) ** 2)))
            sh = (L / L[keep].mean()) / (lum / lum[keep].mean()) - 1.0
            srms = float(np.sqrt(np.mean(sh[keep] ** 2)))
            e, med, _ = compare.angle_profile([(c, L)])
            prof = ", ".join(f"{e[i]:.0f}-{e[i + 1]:.0f}: {100 * med[i]:+.1f}"
                             for i in range(med.size))
            ro = compare.ring_offsets([(c, L)])
            lines.append(f"  {day} {label} {name}: tau440 {r.tau440:.3f} alpha {r.alpha:.2f}; "
                         f"L RMS >= 10 deg {100 * lrms:.1f} %, shape RMS {100 * srms:.1f} %; "
                         f"by angle {prof}; rings " +
                         " / ".join(f"{100 * v:+.1f}" for v in ro["offset"]) +
                         f" ({time.time() - t:.0f} s)")
            print(lines[-1], flush=True)
    (out / "shape_study.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))
    return 0


def _errors(c, L):
    """L RMS >= 10 deg, shape RMS (log), band medians and the profile by angle of ``L``."""
    import numpy as np

    from skydome.validation import compare

    lum, _ = compare.measured_luminance(c)
    keep = np.ones(lum.size, bool)
    keep[list(compare.EXCLUDED_SAMPLES)] = False
    outside = keep & (c.sun_angle_deg >= 10.0)
    lrms = float(np.sqrt(np.mean((L[outside] / lum[outside] - 1.0) ** 2)))
    e = np.log(L[keep] / lum[keep])
    srms = float(np.sqrt(np.mean((e - e.mean()) ** 2)))
    _, med, _ = compare.angle_profile([(c, L)])
    return lrms, srms, med


def phase_fit(out: Path, captures) -> int:
    """Per capture: hillaire2020 with (a) tau440 and alpha fitted, measured (tabulated)
    phase function, as the tables; (b) tau440, alpha and a Henyey-Greenstein g fitted
    together (fitting.fit_aerosol_phase). Prints the fitted values, the luminance RMS
    >= 10 deg from the sun, the log-shape RMS, the band medians 400-700 nm and the median
    shape error by angle from the sun (compare.angle_profile) of each; saves
    OUT/phase_fit.pkl."""
    import numpy as np

    import skydome as sd
    from skydome.validation import compare, fitting
    from skydome.validation.aeronet import aerosol_atmosphere
    from skydome.validation.kider2014 import DAYS, capture_labels, load_captures

    out.mkdir(parents=True, exist_ok=True)
    labs = (captures.split(",") if captures else
            [f"{d}/{lab}" for d in DAYS for lab in capture_labels(d)])
    rows = []
    wl = compare.LUMINANCE_WL
    for lab in labs:
        day, label = lab.split("/")
        c = load_captures([label], day=day)[0]
        t, cpu = time.time(), time.process_time()
        res = {}
        r0 = fitting.fit_aerosol(c)
        r1, g = fitting.fit_aerosol_phase(c)
        for name, atm, fit in (("measured phase", aerosol_atmosphere(r0), (r0.tau440, r0.alpha, float("nan"))),
                               ("HG, g fitted", aerosol_atmosphere(r1, phase="henyey_greenstein", asymmetry=g),
                                (r1.tau440, r1.alpha, g))):
            m = sd.model("hillaire2020", sun=c.sun, atmosphere=atm)
            S = m.radiance(c.directions, wl)
            from skydome.spectra import spectrum_to_xyz

            L = spectrum_to_xyz(S, wl)[:, 1]
            lrms, srms, med = _errors(c, L)
            keep = np.ones(L.size, bool)
            keep[list(compare.EXCLUDED_SAMPLES)] = False
            bands = compare.band_medians(S, wl, c, keep)
            res[name] = {"fit": fit, "lrms": lrms, "srms": srms, "profile": med, "bands": bands}
        rows.append((day, label, res))
        for name, v in res.items():
            print(f"{day} {label} {name:14s} tau440 {v['fit'][0]:.3f} alpha {v['fit'][1]:.2f} "
                  f"g {v['fit'][2]:.3f}; L RMS >= 10 deg {100 * v['lrms']:.1f} %, log-shape RMS "
                  f"{100 * v['srms']:.1f} %; bands " + " / ".join(f"{100 * x:+.1f}" for x in v["bands"])
                  + "; by angle 10-20/20-40/40-60/60-80/80-100/100-120/120-180: "
                  + " / ".join(f"{100 * x:+.1f}" for x in v["profile"]), flush=True)
        print(f"    ({time.time() - t:.0f} s wall, {time.process_time() - cpu:.0f} s CPU)", flush=True)
        with open(out / "phase_fit.pkl", "wb") as f:
            pickle.dump(rows, f)
    return 0


#: the Angstrom exponent held fixed in the colour study (the issue's run and skydome's
#: fitted model take 1.3)
FIXED_ALPHA = 1.3
#: precipitable water of the colour study's water-band estimate [cm]
PW_GRID_CM = (0.5, 1.42, 3.0)


def _fit_tau_fixed_alpha(c, alpha):
    """tau440 fitted to the scan as fitting.fit_aerosol does (same residual, directions and
    wavelengths), the Angstrom exponent held at ``alpha``."""
    import dataclasses

    import numpy as np
    from scipy.optimize import least_squares

    import skydome as sd
    from skydome.validation import fitting
    from skydome.validation.aeronet import aerosol_atmosphere

    base, wl, d, meas = fitting._fit_data(c)

    def resid(p):
        r = dataclasses.replace(base, tau440=float(np.exp(p[0])), alpha=float(alpha))
        m = sd.model("hillaire2020", sun=c.sun, atmosphere=aerosol_atmosphere(r),
                     n_wavelengths=wl.size)
        return (np.log(np.maximum(m.radiance(d, wl), 1e-30)) - meas).ravel()

    lo, hi = np.log(fitting.TAU440_RANGE[0]), np.log(fitting.TAU440_RANGE[1])
    sol = least_squares(resid, [float(np.clip(np.log(base.tau440), lo, hi))], bounds=([lo], [hi]),
                        diff_step=2e-3, x_scale=[0.3], xtol=1e-3, ftol=1e-4, max_nfev=20)
    return dataclasses.replace(base, tau440=float(np.exp(sol.x[0])), alpha=float(alpha))


def _band_medians(c, r, **atm_kw):
    """hillaire2020's band medians (model / measured - 1 of the +-10 nm means, median over
    the kept directions) at compare.BANDS_NM, computed as the tables do."""
    import numpy as np

    import skydome as sd
    from skydome.validation import compare
    from skydome.validation.aeronet import aerosol_atmosphere

    # as the tables (compare.compare_one): the comparison's wavelengths, default settings
    wl = compare.LUMINANCE_WL
    m = sd.model("hillaire2020", sun=c.sun, atmosphere=aerosol_atmosphere(r, **atm_kw))
    S = m.radiance(c.directions, wl)
    keep = np.ones(S.shape[0], bool)
    keep[list(compare.EXCLUDED_SAMPLES)] = False
    return compare.band_medians(S, wl, c, keep)


def _water_from_band(c, r):
    """The precipitable water [cm] at which hillaire2020 (aerosol ``r``) reproduces the
    scan's 940 nm band depth: the median over the kept directions of (model / measured) of
    the 930-950 nm mean over the 865-885 nm mean, at PW_GRID_CM, interpolated in ln PW to 1
    (None outside the grid); also that ratio at the models' 1.42 cm."""
    import numpy as np

    import skydome as sd
    from skydome.validation import compare
    from skydome.validation.aeronet import aerosol_atmosphere

    band, cont = np.arange(930.0, 950.1, 5.0), np.arange(865.0, 885.1, 5.0)
    wl = np.concatenate([cont, band])
    keep = np.ones(c.directions.shape[0], bool)
    keep[list(compare.EXCLUDED_SAMPLES)] = False
    mw = c.wavelengths_nm
    meas = (c.radiance[:, (mw >= 929.0) & (mw <= 951.0)].mean(axis=1)
            / c.radiance[:, (mw >= 864.0) & (mw <= 886.0)].mean(axis=1))
    q = []
    for pw in PW_GRID_CM:
        m = sd.model("hillaire2020", sun=c.sun,
                     atmosphere=aerosol_atmosphere(r, precipitable_water_cm=pw),
                     n_wavelengths=wl.size)
        S = m.radiance(c.directions, wl)
        mod = S[:, cont.size:].mean(axis=1) / S[:, :cont.size].mean(axis=1)
        q.append(float(np.median((mod / meas)[keep])))
    q = np.array(q)
    x = np.log(PW_GRID_CM)
    pw = None
    if q.min() <= 1.0 <= q.max():  # q falls as the water rises
        pw = float(np.exp(np.interp(0.0, np.log(q[::-1]), x[::-1])))
    return pw, float(q[1])


def colour(out: Path, captures, fit_cache=None) -> int:
    """The colour study (docs/validation_measured.md, "Why the colour error changes sign"):
    per capture, hillaire2020's band medians 400-700 nm with (a) the AERONET aerosol
    (2013-05-27 only), (b) the Angstrom exponent held at FIXED_ALPHA and tau440 fitted to
    the scan, (c) tau440 and alpha fitted (fitting.fit_aerosol); and the precipitable water
    that the scan's 940 nm band asks for (:func:`_water_from_band`). Prints one line per
    capture; saves OUT/colour.pkl."""
    from skydome.validation import fitting
    from skydome.validation.kider2014 import DAYS, capture_labels, load_captures

    out.mkdir(parents=True, exist_ok=True)
    if fit_cache and Path(fit_cache).exists():
        with open(fit_cache, "rb") as f:
            fitting._FIT_CACHE.update(pickle.load(f))
    labs = (captures.split(",") if captures else
            [f"{d}/{lab}" for d in DAYS for lab in capture_labels(d)])
    rows = []
    for lab in labs:
        day, label = lab.split("/")
        c = load_captures([label], day=day)[0]
        t, cpu = time.time(), time.process_time()
        runs = []
        if day == "2013-05-27":
            runs.append(("AERONET", fitting.base_retrieval(c)))
        runs.append((f"alpha {FIXED_ALPHA} fixed", _fit_tau_fixed_alpha(c, FIXED_ALPHA)))
        runs.append(("fitted", fitting.fit_aerosol(c)))
        res = [(name, r.tau440, r.alpha, _band_medians(c, r)) for name, r in runs]
        pw, q142 = _water_from_band(c, runs[-1][1])
        rows.append((day, label, res, pw, q142))
        for name, tau, alpha, b in res:
            print(f"{day} {label} {name:16s} tau440 {tau:.3f} alpha {alpha:.2f}; bands 400..700 "
                  + " / ".join(f"{100 * x:+.1f}" for x in b), flush=True)
        print(f"{day} {label} 940 nm band: precipitable water "
              + ("outside 0.5-3 cm" if pw is None else f"{pw:.2f} cm")
              + f"; model / measured band depth at 1.42 cm {q142:.3f}"
              f"  ({time.time() - t:.0f} s wall, {time.process_time() - cpu:.0f} s CPU)", flush=True)
        with open(out / "colour.pkl", "wb") as f:
            pickle.dump(rows, f)
        (out / "colour_table.md").write_text(colour_table(rows), encoding="utf-8")
        if fit_cache:
            with open(fit_cache, "wb") as f:
                pickle.dump(dict(fitting._FIT_CACHE), f)
    return 0


def colour_table(rows) -> str:
    """The colour study's rows (:func:`colour`) as one Markdown table per day: per capture
    and aerosol, tau440, alpha, hillaire2020's band medians [%], their 700 - 400 nm
    difference and, on the fitted row, the precipitable water of the 940 nm band."""
    out = []
    for day in dict.fromkeys(r[0] for r in rows):
        out.append(f"{day}:\n")
        out.append("| capture | aerosol | tau440 | alpha | 400 | 450 | 500 | 550 | 600 | 650 | "
                   "700 | 700 - 400 | water, 940 nm band [cm] |")
        out.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for d, label, res, pw, _ in rows:
            if d != day:
                continue
            for name, tau, alpha, b in res:
                w = ("" if name != "fitted" else
                     "outside 0.5-3" if pw is None else f"{pw:.2f}")
                out.append(f"| {label[:5]} | {name} | {tau:.3f} | {alpha:.2f} | "
                           + " | ".join(f"{100 * x:+.1f}" for x in b)
                           + f" | {100 * (b[-1] - b[0]):+.1f} | {w} |")
        out.append("")
    return "\n".join(out)


def figures(results_dir: Path, fig_dir: Path) -> int:
    """The figures of docs/validation_measured.md from RESULTS_DIR/results*.pkl (one run of
    both days): luminance against the angle from the sun (six captures of both days), the
    spectra and the shape error maps of 2013-05-27 12:00 and 2013-09-24 13:20, the scan
    order of 2013-05-27 12:00 (hillaire2020 point and move, computed here)."""
    from skydome.imaging import plots_validation as pv
    from skydome.validation.compare import LUMINANCE_WL, SPECTRAL_BAND, measured_luminance
    from skydome.validation.kider2014 import load_captures

    results = []
    for p in sorted(results_dir.glob("results*.pkl")):
        with open(p, "rb") as f:
            results += pickle.load(f)
    caps = {}
    for d in dict.fromkeys(r.day for r in results):
        labs = list(dict.fromkeys(r.capture for r in results if r.day == d))
        caps.update({(d, c.label): c for c in load_captures(labs, day=d)})
    aer = sorted({r.aerosol.split(" ")[0] for r in results if r.aerosol})
    order = ["precomputed", "montecarlo", "hillaire2020", "nishita1996", "fitted",
             "single_scattering", "preetham1999", "hosek_wilkie2012", "perez1993", "cie2003"]

    def lum_of(key, skip=()):
        got = {r.model: r.model_luminance for r in results
               if (r.day, r.capture) == key and r.model_luminance is not None}
        return {m: got[m] for m in order if m in got and m not in skip}

    want = [("2013-05-27", "09:30:00"), ("2013-05-27", "11:00:00"), ("2013-05-27", "12:00:00"),
            ("2013-05-27", "13:30:00"), ("2013-09-24", "07:50:00"), ("2013-09-24", "13:20:00")]
    keys = [k for k in want if k in caps] or list(caps)[:6]
    panels = []
    for k in keys:
        lum, _ = measured_luminance(caps[k])
        sel = lum_of(k, skip=("cie2003", "preetham1999", "perez1993", "hillaire2020",
                              "single_scattering", "hosek_wilkie2012"))
        panels.append((caps[k], lum, sel))
    pv.plot_luminance_vs_scattering_angle(
        panels, fig_dir / "validation_measured_scattering_angle.png",
        title=f"Kider et al. 2014 ({', '.join(k[0] + ' ' + k[1][:5] for k in keys)}), aerosol "
              f"{'/'.join(aer)}: luminance in the 81 directions")
    wl = LUMINANCE_WL[(LUMINANCE_WL >= SPECTRAL_BAND[0]) & (LUMINANCE_WL <= SPECTRAL_BAND[1])]
    for k, suffix in ((("2013-05-27", "12:00:00"), ""), (("2013-09-24", "13:20:00"), "_20130924")):
        if k not in caps:
            continue
        spec = {r.model: r.model_spectra for r in results
                if (r.day, r.capture) == k and r.model_spectra is not None}
        spec = {m: spec[m] for m in order if m in spec}
        pv.plot_spectra(caps[k], wl, spec, fig_dir / f"validation_measured_spectra{suffix}.png",
                        title=f"{k[0]} {k[1]}, aerosol {'/'.join(aer)}")
        lum, _ = measured_luminance(caps[k])
        pv.plot_error_maps(caps[k], lum, lum_of(k),
                           fig_dir / f"validation_measured_error_maps{suffix}.png",
                           title=f"{k[0]} {k[1]}, aerosol {'/'.join(aer)}: luminance shape error "
                                 "(sun: star)")
    # the scanner's motion: hillaire2020 at the labelled directions and as the mean along
    # each move (compare.arc_directions), 2013-05-27 12:00, the results' aerosol
    k = ("2013-05-27", "12:00:00")
    if k in caps:
        from skydome.validation.compare import compare_one

        a = "fitted" if aer == ["fitted"] else "aeronet"
        lum, _ = measured_luminance(caps[k])
        point = compare_one("hillaire2020", caps[k], aerosol=a)
        arc = compare_one("hillaire2020", caps[k], aerosol=a, motion="from_previous")
        pv.plot_scan_order(caps[k], lum, {"hillaire2020 at the labelled directions": point.model_luminance,
                                          "hillaire2020, mean along each move": arc.model_luminance},
                           fig_dir / "validation_measured_scan_order.png",
                           title=f"{k[0]} {k[1]}, aerosol {a}: point sampling and the mean along "
                                 "the scanner's move")
    return 0


if __name__ == "__main__":
    sys.exit(main())
