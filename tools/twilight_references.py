"""Make the deep-twilight Monte Carlo references of tests/test_precomputed_twilight.py.

    python tools/twilight_references.py OUT.npz [--samples 20000000] [--seed 21]
        [--elevations=-8,-10,-12] [--next-event vertex|segment]

The ``montecarlo`` model (backward path tracing, all orders, next-event estimation towards
the sun; no variance reduction) at 550 nm on the five directions of
``benchmarks/twilight_reference.py --test-set`` (10 deg up towards the sun and opposite it,
30 deg up at 90 deg from it, 50 deg up opposite it, the zenith), sun at azimuth 180 deg,
``Atmosphere.earth(aerosol_optical_depth=0.2)``: the same sky and directions as
tests/data/twilight_montecarlo_550nm.npz (sun -4 and -6 deg), for deeper suns. The file
holds per sun elevation the radiance, its standard error, the paths per direction, the
seed and the CPU time, and the command and provenance (written by
``benchmarks/twilight_reference.py reference``, which this runs; a second run with another
seed is pooled with ``--merge``).

Cost: most twilight paths never see the sun. With the default vertex estimator, at 550 nm,
10^6 paths per direction gave a relative standard error of 5-17 % at sun -8 deg and 34-92 %
at -12 deg (largest low opposite the sun); 0.7 million paths per CPU second at -8 deg, 0.23
million at -12 deg. ``--next-event segment`` (montecarlo's ``next_event="segment"``: the
next event of every collision integrated along the segment before it, the earth's shadow
cut out) costs more per path (about 0.04-0.07 million paths per CPU second) but gave 7-43 %
at -12 deg with 2 x 10^4 paths per direction, some 2000 times less variance per path: the
references of tests/data/twilight_montecarlo_550nm_segment.npz (sun -8, -10, -12 deg) were
made with it (each file's ``command`` says how).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--samples", type=int, default=20_000_000,
                    help="paths per direction and sun elevation")
    ap.add_argument("--seed", type=int, default=21)
    ap.add_argument("--elevations", default="-8,-10,-12")
    ap.add_argument("--next-event", default="vertex", choices=("vertex", "segment"),
                    help="montecarlo's next_event (segment: for deep twilight)")
    ap.add_argument("--merge", action="store_true",
                    help="pool with the paths already in OUT (use another --seed)")
    a = ap.parse_args(argv)
    if a.samples < 1:
        raise SystemExit(f"--samples = {a.samples} is out of range: >= 1")
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import twilight_reference

    args = ["reference", "--test-set", "--wavelengths", "550", f"--elevations={a.elevations}",
            "--samples", str(a.samples), "--seed", str(a.seed), "--next-event", a.next_event,
            "--out", a.out]
    args += ["--merge"] if a.merge else []
    # the file's ``command`` records the equivalent benchmarks/twilight_reference.py call
    sys.argv = ["benchmarks/twilight_reference.py"] + args
    twilight_reference.main(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
