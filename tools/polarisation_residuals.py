"""Does the scanner's response to polarised light explain the measured sky's angular error?

    python tools/polarisation_residuals.py OUT_FOLDER [--models hillaire2020,precomputed]
        [--samples 20000] [--captures DAY/LABEL,...]

Prints every figure of docs/validation_measured.md, "The scanner's response to polarised
light". Per capture of both days (all 20 by default): the published comparison's model
luminance in the 81 directions (``compare.compare_one(model, capture, aerosol="fitted")``,
the rows of the "aerosol fitted to each scan" blocks), the sky's degree of linear
polarisation P from the polarised ``montecarlo`` model at the capture's fitted aerosol
(450, 550, 650 nm) and the angle chi of the single-scattering E-vector in the pan-tilt
head's frame (``skydome.validation.scanner_polarisation``). Then, per day and jointly,
with y = ln(measured / model) in the kept directions at least 10 deg from the sun:

(a) correlation of y (less its capture mean) with P cos 2 chi and P sin 2 chi (each less
    its capture mean);
(b) the fit y = c_capture + m P cos 2 chi + n P sin 2 chi, per day and jointly, its
    diattenuation sqrt(m^2 + n^2) and axis; (m, n) fitted to each capture alone; the
    cross-validation (fit on one day, applied
    to the other, only the capture constants refitted); the same fit with a constant per
    10 deg bin of the angle from the sun added (whether (m, n) survive once the pattern
    by angle is taken out), and with a constant per ring of the scan as well;
(c) the median shape error by angle from the sun (``compare.angle_profile``) and the mean
    luminance RMS >= 10 deg, before and after the model is multiplied by
    1 + m P cos 2 chi + n P sin 2 chi (what the instrument would read);
(d) 10-20 deg from the sun: the median shape error against the median fitted term;
(e) per band (450, 550, 650 nm, +-10 nm means): the fit with P at that wavelength.

Aerosol fits, model runs and P are cached in OUT_FOLDER (rerun to print again cheaply).
"""

from __future__ import annotations

import argparse
import pickle
import sys
import time
from pathlib import Path

import numpy as np

P_WAVELENGTHS = (450.0, 550.0, 650.0)
LUMINANCE_P_WL = 550.0
ANGLE_BINS = (10.0, 20.0, 40.0, 60.0, 80.0, 100.0, 120.0, 180.0)


def _data(out: Path, models, captures, samples):
    """Per (model, day, label): the capture, the model's luminance and 400-700 nm spectra;
    per (day, label): P (81, 3) and its error, chi (81,). Cached in OUT."""
    from skydome.validation import compare, fitting
    from skydome.validation import scanner_polarisation as sp
    from skydome.validation.kider2014 import DAYS, capture_labels, load_captures

    out.mkdir(parents=True, exist_ok=True)
    fits, cache = out / "fits.pkl", out / "polarisation_cache.pkl"
    if fits.exists():
        with open(fits, "rb") as f:
            fitting._FIT_CACHE.update(pickle.load(f))
    store = {"model": {}, "pol": {}}
    if cache.exists():
        with open(cache, "rb") as f:
            store = pickle.load(f)
    labs = (captures.split(",") if captures else
            [f"{d}/{lab}" for d in DAYS for lab in capture_labels(d)])
    caps = {}
    for lab in labs:
        day, label = lab.split("/")
        c = load_captures([label], day=day)[0]
        caps[(day, label)] = c
        t, cpu = time.time(), time.process_time()
        fitting.fit_aerosol(c)
        with open(fits, "wb") as f:
            pickle.dump(dict(fitting._FIT_CACHE), f)
        for m in models:
            if (m, day, label) not in store["model"]:
                r = compare.compare_one(m, c, aerosol="fitted")
                store["model"][(m, day, label)] = (r.model_luminance, r.model_spectra)
        if (day, label, samples) not in store["pol"]:
            atm, _ = compare.atmosphere_for(c, "tabulated", "fitted")
            P, Pe = sp.degree_montecarlo(c, atm, P_WAVELENGTHS, samples=samples)
            chi = sp.single_scattering_angle(c.azimuth_deg, c.elevation_deg, c.sun.direction)
            store["pol"][(day, label, samples)] = (P, Pe, chi)
        with open(cache, "wb") as f:
            pickle.dump(store, f)
        print(f"  {day} {label}: {time.time() - t:.0f} s wall, {time.process_time() - cpu:.0f} s CPU",
              file=sys.stderr, flush=True)
    return caps, store


def _keep(c):
    from skydome.validation.compare import EXCLUDED_SAMPLES

    k = c.sun_angle_deg >= 10.0
    k[list(EXCLUDED_SAMPLES)] = False
    return k


def _terms(store, day, label, samples, iw):
    from skydome.validation.scanner_polarisation import response_terms

    P, _, chi = store["pol"][(day, label, samples)]
    return response_terms(P[:, iw], chi)


def _groups(caps, store, model, keys, samples, iw=1, band=None):
    """(y, X, Y) per capture of ``keys``: y = ln(measured / model) in the kept directions
    >= 10 deg from the sun (luminance, or the +-10 nm band mean at ``band`` nm)."""
    from skydome.validation.compare import LUMINANCE_WL, SPECTRAL_BAND, measured_luminance

    out = []
    for day, label in keys:
        c = caps[(day, label)]
        L, S = store["model"][(model, day, label)]
        if band is None:
            meas, mod = measured_luminance(c)[0], L
        else:
            wl = LUMINANCE_WL[(LUMINANCE_WL >= SPECTRAL_BAND[0]) & (LUMINANCE_WL <= SPECTRAL_BAND[1])]
            mod = S[:, np.abs(wl - band) <= 10.0].mean(axis=1)
            meas = c.radiance[:, np.abs(c.wavelengths_nm - band) <= 10.0].mean(axis=1)
        k = _keep(c)
        X, Y = _terms(store, day, label, samples, iw)
        out.append((np.log(meas[k] / mod[k]), X[k], Y[k]))
    return out


def _demeaned_corr(groups):
    """Pearson correlation of y with X and with Y, each less its group mean."""
    y = np.concatenate([g[0] - g[0].mean() for g in groups])
    X = np.concatenate([g[1] - g[1].mean() for g in groups])
    Y = np.concatenate([g[2] - g[2].mean() for g in groups])
    return float(np.corrcoef(y, X)[0, 1]), float(np.corrcoef(y, Y)[0, 1])


def _apply(groups, m, n):
    """RMS of y about refitted group constants before and after subtracting m X + n Y."""
    b = np.concatenate([g[0] - g[0].mean() for g in groups])
    a = []
    for y, X, Y in groups:
        r = y - m * X - n * Y
        a.append(r - r.mean())
    a = np.concatenate(a)
    return float(np.sqrt(np.mean(b ** 2))), float(np.sqrt(np.mean(a ** 2)))


def _fit_with_bins(caps, keys, groups, rings=False):
    """(m, n) fitted together with a constant per capture and per 10 deg bin of the angle
    from the sun (10-180 deg); with ``rings`` also a constant per ring of the scan
    (compare.RING_ELEVATIONS_DEG, as compare.ring_offsets)."""
    from skydome.validation.compare import RING_ELEVATIONS_DEG

    edges = np.arange(10.0, 181.0, 10.0)
    nb, nk = edges.size - 1, len(groups)
    nr = len(RING_ELEVATIONS_DEG) if rings else 0
    ys, A_rows = [], []
    for k, ((day, label), (y, X, Y)) in enumerate(zip(keys, groups)):
        c = caps[(day, label)]
        g = c.sun_angle_deg[_keep(c)]
        b = np.clip(np.digitize(g, edges) - 1, 0, nb - 1)
        A = np.zeros((y.size, nk + nb + nr + 2))
        A[:, k] = 1.0
        A[np.arange(y.size), nk + b] = 1.0
        if rings:
            el = c.elevation_deg[_keep(c)]
            ring = np.argmin(np.abs(el[:, None] - np.asarray(RING_ELEVATIONS_DEG)[None, :]), axis=1)
            A[np.arange(y.size), nk + nb + ring] = 1.0
        A[:, -2], A[:, -1] = X, Y
        ys.append(y)
        A_rows.append(A)
    y, A = np.concatenate(ys), np.vstack(A_rows)
    x, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ x
    cov = np.linalg.pinv(A.T @ A) * float(r @ r) / max(y.size - np.linalg.matrix_rank(A), 1)
    return float(x[-2]), float(x[-1]), float(np.sqrt(cov[-2, -2])), float(np.sqrt(cov[-1, -1]))


def _profile_and_rms(caps, store, model, keys, samples, mn=None):
    """(median shape error per angle bin, mean L RMS >= 10 deg, median fitted term per
    bin) with the model as published or multiplied by 1 + m X + n Y."""
    from skydome.validation.compare import angle_profile, measured_luminance

    pairs, rms, terms = [], [], [[] for _ in range(len(ANGLE_BINS) - 1)]
    for day, label in keys:
        c = caps[(day, label)]
        L = store["model"][(model, day, label)][0]
        X, Y = _terms(store, day, label, samples, 1)
        t = np.zeros_like(L) if mn is None else mn[0] * X + mn[1] * Y
        Lc = L * (1.0 + t)
        pairs.append((c, Lc))
        lum = measured_luminance(c)[0]
        k = _keep(c)
        rms.append(np.sqrt(np.mean((Lc[k] / lum[k] - 1.0) ** 2)))
        b = np.digitize(c.sun_angle_deg, ANGLE_BINS) - 1
        for i in np.flatnonzero(k):
            if 0 <= b[i] < len(terms):
                terms[b[i]].append(t[i])
    _, med, _ = angle_profile(pairs, bins_deg=ANGLE_BINS)
    tmed = np.array([np.median(v) if v else np.nan for v in terms])
    return med, float(np.mean(rms)), tmed


def _pct(v, sign=True):
    return " / ".join("(none)" if not np.isfinite(x) else (f"{100 * x:+.1f}" if sign else f"{100 * x:.1f}")
                      for x in v)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--models", default="hillaire2020")
    ap.add_argument("--samples", type=int, default=20000,
                    help="montecarlo paths per direction and wavelength for P")
    ap.add_argument("--captures", default=None, help="DAY/LABEL,... (default: all 20)")
    a = ap.parse_args(argv)
    if a.samples < 100:
        raise SystemExit(f"--samples must be >= 100, got {a.samples}")
    from skydome.validation import scanner_polarisation as sp

    models = a.models.split(",")
    t0, cpu0 = time.time(), time.process_time()
    caps, store = _data(Path(a.out), models, a.captures, a.samples)
    days = list(dict.fromkeys(d for d, _ in caps))
    keys_of = {d: [k for k in caps if k[0] == d] for d in days}
    keys_of["both days"] = list(caps)
    S = a.samples

    print(f"Degree of linear polarisation P (montecarlo, {S} paths, aerosol fitted), kept "
          "directions:")
    for d in days:
        P = np.concatenate([store["pol"][(dd, lab, S)][0][_keep(caps[(dd, lab)])]
                            for dd, lab in keys_of[d]])
        Pe = np.concatenate([store["pol"][(dd, lab, S)][1][_keep(caps[(dd, lab)])]
                             for dd, lab in keys_of[d]])
        g = np.concatenate([caps[k].sun_angle_deg[_keep(caps[k])] for k in keys_of[d]])
        ring = (g >= 80.0) & (g < 100.0)
        print(f"  {d}: max over directions " + " / ".join(f"{x:.2f}" for x in P.max(axis=0))
              + f" at {'/'.join(f'{w:.0f}' for w in P_WAVELENGTHS)} nm; median 80-100 deg from "
              "the sun " + " / ".join(f"{x:.2f}" for x in np.median(P[ring], axis=0))
              + "; median 10-20 deg " + " / ".join(
                  f"{x:.2f}" for x in np.median(P[(g >= 10) & (g < 20)], axis=0))
              + f"; median standard error {np.median(Pe):.3f}")
        ss = np.concatenate([sp.single_scattering_degree(caps[k].azimuth_deg, caps[k].elevation_deg,
                                                         caps[k].sun.direction, 0.0279)[_keep(caps[k])]
                             for k in keys_of[d]])
        print(f"  {d}: single-scattering Rayleigh degree (rho 0.0279) max {ss.max():.2f}, "
              f"median 80-100 deg {np.median(ss[ring]):.2f}; montecarlo / single scattering at "
              f"550 nm, median over the kept directions {np.median(P[:, 1] / np.maximum(ss, 1e-6)):.2f}")

    for model in models:
        print(f"\n== {model}, aerosol fitted to each scan (the published rows' model luminance) ==")
        fits = {}
        print("\n(a) correlation of ln(measured / model) with P cos 2chi and P sin 2chi "
              "(each less its capture mean), kept directions >= 10 deg from the sun:")
        for d in keys_of:
            gr = _groups(caps, store, model, keys_of[d], S)
            rx, ry = _demeaned_corr(gr)
            print(f"  {d:10s}: r(X) {rx:+.2f}, r(Y) {ry:+.2f}  ({sum(g[0].size for g in gr)} directions, "
                  f"{len(gr)} captures)")
        print("\n(b) fit ln(measured / model) = c_capture + m P cos 2chi + n P sin 2chi "
              "(P at 550 nm):")
        for d in keys_of:
            gr = _groups(caps, store, model, keys_of[d], S)
            f = sp.fit_response(gr)
            fits[d] = f
            print(f"  {d:10s}: m {f.m:+.3f} +- {f.sm:.3f}, n {f.n:+.3f} +- {f.sn:.3f}; "
                  f"diattenuation {f.diattenuation:.3f}, axis {f.axis_deg:+.0f} deg from the "
                  f"vertical; RMS of ln about the capture means {100 * f.rms_before:.1f} -> "
                  f"{100 * f.rms_after:.1f} %")
        print("  per capture alone (m / n):")
        for d in days:
            parts = []
            for key, g in zip(keys_of[d], _groups(caps, store, model, keys_of[d], S)):
                f = sp.fit_response([g])
                parts.append(f"{key[1][:5]} {f.m:+.2f}/{f.n:+.2f}")
            print(f"    {d}: " + ", ".join(parts))
        if len(days) == 2:
            print("  cross-validation (fit on one day, applied to the other; capture constants refitted):")
            for src, dst in ((days[0], days[1]), (days[1], days[0])):
                b, aft = _apply(_groups(caps, store, model, keys_of[dst], S), fits[src].m, fits[src].n)
                print(f"    fit on {src}, applied to {dst}: RMS {100 * b:.1f} -> {100 * aft:.1f} %")
        print("  with a constant per 10 deg bin of the angle from the sun as well:")
        for d in keys_of:
            gr = _groups(caps, store, model, keys_of[d], S)
            m, n, sm, sn = _fit_with_bins(caps, keys_of[d], gr)
            print(f"    {d:10s}: m {m:+.3f} +- {sm:.3f}, n {n:+.3f} +- {sn:.3f} "
                  f"(diattenuation {np.hypot(m, n):.3f})")
        print("  with a constant per 10 deg bin of the angle from the sun and per ring as well:")
        for d in keys_of:
            gr = _groups(caps, store, model, keys_of[d], S)
            m, n, sm, sn = _fit_with_bins(caps, keys_of[d], gr, rings=True)
            print(f"    {d:10s}: m {m:+.3f} +- {sm:.3f}, n {n:+.3f} +- {sn:.3f} "
                  f"(diattenuation {np.hypot(m, n):.3f})")

        print("\n(c) median shape error [%] by angle from the sun "
              + "/".join(f"{ANGLE_BINS[i]:.0f}-{ANGLE_BINS[i + 1]:.0f}" for i in range(len(ANGLE_BINS) - 1))
              + " deg; mean L RMS >= 10 deg:")
        for d in days:
            med0, rms0, _ = _profile_and_rms(caps, store, model, keys_of[d], S)
            print(f"  {d} as published:            {_pct(med0)}; {100 * rms0:.1f} %")
            for name, f in ((f"fit on {d}", fits[d]), ("joint fit", fits["both days"])) + tuple(
                    (f"fit on {o}", fits[o]) for o in days if o != d):
                med, rms, _ = _profile_and_rms(caps, store, model, keys_of[d], S, (f.m, f.n))
                print(f"  {d} corrected, {name:18s}: {_pct(med)}; {100 * rms:.1f} %")

        print("\n(d) 10-20 deg from the sun: median shape error against the median fitted "
              "term m P cos 2chi + n P sin 2chi there (and its largest size anywhere):")
        for d in days:
            med0, _, _ = _profile_and_rms(caps, store, model, keys_of[d], S)
            _, _, tmed = _profile_and_rms(caps, store, model, keys_of[d], S, (fits[d].m, fits[d].n))
            tall = np.concatenate([
                (fits[d].m * _terms(store, dd, lab, S, 1)[0] + fits[d].n * _terms(store, dd, lab, S, 1)[1])[
                    _keep(caps[(dd, lab)])] for dd, lab in keys_of[d]])
            print(f"  {d}: shape error {100 * med0[0]:+.1f} %, fitted term {100 * tmed[0]:+.2f} % "
                  f"(term by bin: {_pct(tmed)}; largest |term| {100 * np.abs(tall).max():.1f} %)")

        print("\n(e) per band (+-10 nm means), P at the band's wavelength, fit per day:")
        for iw, w in enumerate(P_WAVELENGTHS):
            parts = []
            for d in keys_of:
                gr = _groups(caps, store, model, keys_of[d], S, iw=iw, band=w)
                f = sp.fit_response(gr)
                rx, ry = _demeaned_corr(gr)
                parts.append(f"{d}: m {f.m:+.3f}, n {f.n:+.3f}, r {rx:+.2f}/{ry:+.2f}, RMS "
                             f"{100 * f.rms_before:.1f} -> {100 * f.rms_after:.1f} %")
            print(f"  {w:.0f} nm: " + "; ".join(parts))
    print(f"\n({time.time() - t0:.0f} s wall, {time.process_time() - cpu0:.0f} s CPU)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
