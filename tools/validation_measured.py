"""Run the measured-sky comparison and save what docs/validation_measured.md shows.

    python tools/validation_measured.py OUT_FOLDER [--captures 10:00:00,11:00:00] [--models ...]

Writes OUT_FOLDER/validation_measured_table.md (the day's table), results.npz (per model
and capture: the model luminance in the 81 directions and its 400-700 nm spectra) and the
figures of skydome.render.plots_validation.
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
    a = ap.parse_args(argv)
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


if __name__ == "__main__":
    sys.exit(main())
