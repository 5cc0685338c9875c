"""Run the measured-sky comparison and save what docs/validation_measured.md shows.

    python tools/validation_measured.py OUT_FOLDER [--captures 10:00:00,11:00:00] [--models ...]

Writes OUT_FOLDER/validation_measured_table.md (the day's table), results.npz (per model
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
    ap.add_argument("--figures", default=None, help="only make the figures from OUT's results into this folder")
    a = ap.parse_args(argv)
    if a.figures:
        return figures(Path(a.out), Path(a.figures))
    from skydome.validation.compare import MODELS, compare_measured, day_table

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    models = a.models.split(",") if a.models else list(MODELS)
    caps = a.captures.split(",") if a.captures else None
    results = []
    for m in models:
        t = time.time()
        rs = compare_measured([m], caps, fast=a.fast)
        results += rs
        print(f"{m}: {time.time() - t:.0f} s for {len(rs)} captures", flush=True)
        with open(out / f"results_{m}.pkl", "wb") as f:
            pickle.dump(rs, f)
    (out / "validation_measured_table.md").write_text(day_table(results), encoding="utf-8")
    print(day_table(results))
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
    caps = {c.label: c for c in load_captures(labels)}
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
