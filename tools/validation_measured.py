"""Run the measured-sky comparison and save what docs/validation_measured.md shows.

    python tools/validation_measured.py OUT_FOLDER [--day 2013-09-24] [--aerosol fitted]
        [--captures 10:00:00,11:00:00] [--models ...]
    python tools/validation_measured.py OUT_FOLDER --clock [--day 2013-09-24]

Writes OUT_FOLDER/validation_measured_table.md (the day's table, then every capture, as
``skydome validate measured`` prints them), results_MODEL.pkl (per model
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
    ap.add_argument("--day", default="2013-05-27")
    ap.add_argument("--aerosol", default=None,
                    help="aeronet or fitted (default: aeronet where there is one)")
    ap.add_argument("--clock", action="store_true",
                    help="the clock scan (validation.compare.clock_scan), not the table")
    ap.add_argument("--figures", default=None, help="only make the figures from OUT's results into this folder")
    a = ap.parse_args(argv)
    if a.figures:
        return figures(Path(a.out), Path(a.figures))
    if a.clock:
        return clock(Path(a.out), a.day)
    from skydome.validation.compare import MODELS, capture_table, compare_measured, day_table

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    models = a.models.split(",") if a.models else list(MODELS)
    caps = a.captures.split(",") if a.captures else None
    results = []
    for m in models:
        t = time.time()
        rs = compare_measured([m], caps, fast=a.fast, day=a.day, aerosol=a.aerosol)
        results += rs
        print(f"{m}: {time.time() - t:.0f} s for {len(rs)} captures", flush=True)
        with open(out / f"results_{m}.pkl", "wb") as f:
            pickle.dump(rs, f)
    text = day_table(results) + "\n" + capture_table(results)
    (out / "validation_measured_table.md").write_text(text, encoding="utf-8")
    print(text)
    return 0


def clock(out: Path, day: str) -> int:
    """Shape error against the clock offset, at the labelled directions and along the moves."""
    import numpy as np

    from skydome.validation.compare import clock_scan

    out.mkdir(parents=True, exist_ok=True)
    r = clock_scan(day, offsets_min=np.arange(-70.0, 21.0, 10.0))
    np.savez(out / f"clock_{day}.npz", labels=np.array(r["labels"]), offsets=r["offsets_min"],
             rms=r["rms"], best=r["best_min"])
    for lab, b, rr in zip(r["labels"], r["best_min"], r["rms"]):
        print(f"{day} {lab} best offset [min]: point {b[0]:+.1f} move {b[1]:+.1f}; "
              f"least shape RMS: point {rr[0].min():.3f} move {rr[1].min():.3f}")
    return 0


def figures(results_dir: Path, fig_dir: Path) -> int:
    import numpy as np

    from skydome.imaging import plots_validation as pv
    from skydome.validation.compare import LUMINANCE_WL, SPECTRAL_BAND, measured_luminance
    from skydome.validation.kider2014 import load_captures

    results = []
    for p in sorted(results_dir.glob("results_*.pkl")):
        with open(p, "rb") as f:
            results += pickle.load(f)
    labels = list(dict.fromkeys(r.capture for r in results))
    day = getattr(results[0], "day", "") or "2013-05-27"
    caps = {c.label: c for c in load_captures(labels, day=day)}
    order = ["precomputed", "montecarlo", "hillaire2020", "nishita1996", "single_scattering",
             "preetham1999", "hosek_wilkie2012", "perez1993", "cie2003"]
    panels = []
    for lab in labels:
        lum, _ = measured_luminance(caps[lab])
        models = {r.model: r.model_luminance for r in results
                  if r.capture == lab and r.model_luminance is not None}
        models = {m: models[m] for m in order if m in models and m != "cie2003"}
        panels.append((caps[lab], lum, models))
    pv.plot_luminance_vs_scattering_angle(panels, fig_dir / "validation_measured_scattering_angle.png",
                                          title="Kider et al. 2014, 2013-05-27: luminance in the 81 directions")
    lab = "12:00:00" if "12:00:00" in labels else labels[0]
    wl = LUMINANCE_WL[(LUMINANCE_WL >= SPECTRAL_BAND[0]) & (LUMINANCE_WL <= SPECTRAL_BAND[1])]
    spec = {r.model: r.model_spectra for r in results if r.capture == lab and r.model_spectra is not None}
    pv.plot_spectra(caps[lab], wl, spec, fig_dir / "validation_measured_spectra.png")
    lum, _ = measured_luminance(caps[lab])
    maps = {r.model: r.model_luminance for r in results if r.capture == lab and r.model_luminance is not None}
    maps = {m: maps[m] for m in order if m in maps}
    pv.plot_error_maps(caps[lab], lum, maps, fig_dir / "validation_measured_error_maps.png")
    # the scanner's motion: hillaire2020 at the labelled directions and along each move
    from skydome.validation.compare import compare_one

    point = compare_one("hillaire2020", caps[lab])
    arc = compare_one("hillaire2020", caps[lab], motion="from_previous")
    pv.plot_scan_order(caps[lab], lum, {"hillaire2020 at the labelled directions": point.model_luminance,
                                        "hillaire2020 along each move": arc.model_luminance},
                       fig_dir / "validation_measured_scan_order.png",
                       title=f"capture {lab}: point sampling and the mean along the scanner's move")
    return 0


if __name__ == "__main__":
    sys.exit(main())
