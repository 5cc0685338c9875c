"""How far apart the ``fitted`` model's nodes may be: the interpolation of one parameter
alone, measured on the ``precomputed`` reference itself.

    python tools/fitted_node_spacing.py altitude [--aod 0.7 --albedo 0.2] [--out FILE.npz]
    python tools/fitted_node_spacing.py aod [--albedo 0.6] [--out FILE.npz]

The reference runs as in the data set (``twilight_reference=True``, no cache) at three
table wavelengths (500, 560, 620 nm; each computed independently of the others), on the
data set's view grid (skydome/models/fitted/_grid.py). Nothing of the fitted model is used
but its interpolation rules (skydome/models/fitted/_coefficients.py): the figures are the
error of interpolating the reference's own values between nodes, before any fit.

``altitude``: one atmosphere at the held-out sun elevations (-6.5 to 45 deg), observer
altitudes 0-15 km every 500 m; per sun elevation and node set, the RMS / max relative error
(560 nm, sky part of the grid) of ln L cubic in altitude (the model's rule) at altitudes off
the nodes. The node sets: the second file's above 2 km (3, 6, 10, 15 km) and refinements.
The nodes below 2 km are taken at 0.5, 1, 1.5 km here (the sweep's 500 m step).

``aod``: one albedo, AODs 0-0.1 off and on the nodes (``AOD_VALUES``), sun 0.5, 4, 8.5 and
16 deg, observer on the ground and at 2.2 km; per node set (``AOD_NODE_SETS``: the file
before the nodes at 0.0125 and 0.075, with 0.0125 alone, with both, with 0.00625 too) and
AOD off its nodes,
the RMS / max relative error (560 nm, sky part; the ground view from 2.2 km apart) of the
model's own day rule over those nodes (``_coefficients.aod_stencil``: the thin-haze form
below 0.025, through 0 and the two nodes around the AOD where the nodes double; L quadratic
in sqrt(AOD) up to 0.1); then the rules tried between 0.0125 and 0.025. ``--out`` keeps the
reference's values; a rerun with the same ``--out`` and albedo
computes only the AODs the file lacks.

Cost on the 2-core machine of docs/performance.md, with the data set running beside it: 107 s
(altitude, per atmosphere) and 410 s (aod, 11 AODs; 210 s for five more over the same
``--out``); the present ``aod`` (18 AODs) 1330 s beside two data-set workers.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

WAVELENGTHS_NM = np.array([500.0, 560.0, 620.0])
ALTITUDE_SUN_DEG = np.array([-6.5, -2.5, 0.5, 4.0, 8.5, 16.0, 28.0, 45.0])
ALTITUDE_SETS = {
    "3, 6, 10, 15 km (second file)": [3000, 6000, 10000, 15000],
    "+ 4.5 km": [3000, 4500, 6000, 10000, 15000],
    "+ 4, 5 km": [3000, 4000, 5000, 6000, 10000, 15000],
    "+ 4, 5, 8 km": [3000, 4000, 5000, 6000, 8000, 10000, 15000],
    "+ 4, 5, 8, 12 km (this file)": [3000, 4000, 5000, 6000, 8000, 10000, 12000, 15000],
    "+ 4, 8, 12 km": [3000, 4000, 6000, 8000, 10000, 12000, 15000],
}
ALTITUDE_TESTS_M = [2500.0, 3500.0, 4500.0, 5500.0, 7000.0, 9000.0, 12500.0]
#: The AOD node sets compared (the model's day rule applied over each: "aod" below).
AOD_NODE_SETS = {
    "0, 0.025, 0.05, 0.1 (the file before the node at 0.0125)": (0.0, 0.025, 0.05, 0.1),
    "0, 0.0125, 0.025, 0.05, 0.1": (0.0, 0.0125, 0.025, 0.05, 0.1),
    "0, 0.0125, 0.025, 0.05, 0.075, 0.1 (the fifth file)": (0.0, 0.0125, 0.025, 0.05, 0.075,
                                                             0.1),
    "0, 0.00625, 0.0125, 0.025, 0.05, 0.075, 0.1": (0.0, 0.00625, 0.0125, 0.025, 0.05, 0.075,
                                                    0.1),
}
#: The AODs off the nodes where each set is measured.
AOD_TESTS = (0.003, 0.0045, 0.006, 0.00625, 0.009, 0.0125, 0.018, 0.03, 0.0375, 0.045, 0.06,
             0.07, 0.09)
AOD_VALUES = tuple(sorted(set(AOD_TESTS) | {0.0, 0.00625, 0.0125, 0.025, 0.05, 0.075, 0.1}))
#: ``aod --hazy``: the node sets and AODs above 0.1 (ln L quadratic in sqrt(AOD) over the
#: nodes from 0.1 up; the sets' nodes below 0.1 are not read there); the shipped file's
#: sweep at albedo 0.2 (docs/models.md, "fitted", "The AOD nodes at 0.35 and 0.75").
AOD_NODE_SETS_HAZY = {
    "0.1, 0.25, 0.5, 1 (the file before)": (0.0, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.25, 0.5,
                                            1.0),
    "+ 0.15": (0.0, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.25, 0.5, 1.0),
    "+ 0.15, 0.75": (0.0, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.25, 0.5, 0.75, 1.0),
    "+ 0.15, 0.35, 0.75 (this file)": (0.0, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.25,
                                       0.35, 0.5, 0.75, 1.0),
}
AOD_TESTS_HAZY = (0.12, 0.135, 0.165, 0.18, 0.2, 0.22, 0.3, 0.35, 0.42, 0.6, 0.7, 0.85,
                  0.9)
AOD_VALUES_HAZY = tuple(sorted(set(AOD_TESTS_HAZY) | {0.1, 0.15, 0.25, 0.5, 0.75, 1.0}))
AOD_SUN_DEG = (0.5, 4.0, 8.5, 16.0)
AOD_ALTITUDES_M = (0.0, 2200.0)


def _stats(e):
    return 100.0 * float(np.sqrt(np.mean(e ** 2))), 100.0 * float(np.max(np.abs(e)))


def altitude(aod: float, albedo: float, out: str | None) -> None:
    from skydome.models.fitted import _coefficients as C
    from skydome.models.fitted import _dataset, _grid

    alts = np.arange(0.0, 15001.0, 500.0)
    t0 = time.perf_counter()
    c = _dataset.compute_chunk(aod, albedo, ALTITUDE_SUN_DEG, alts, twilight_reference=True,
                               wavelengths=WAVELENGTHS_NM)
    print(f"reference: AOD {aod:g}, albedo {albedo:g}, {alts.size} altitudes x "
          f"{ALTITUDE_SUN_DEG.size} suns in {time.perf_counter() - t0:.0f} s")
    if out:
        np.savez(out, chunk=c, elevations_deg=ALTITUDE_SUN_DEG, altitudes_m=alts)
    y = np.log(np.maximum(c[:, :, :_grid.N_SKY, :, 1].astype(np.float64), 1e-30))
    at = {float(h): k for k, h in enumerate(alts)}
    print("\nln L cubic in altitude, RMS / max [%] at "
          + ", ".join(f"{h / 1000:g}" for h in ALTITUDE_TESTS_M) + " km:")
    for i, el in enumerate(ALTITUDE_SUN_DEG):
        for name, upper in ALTITUDE_SETS.items():
            nodes = np.array([0.0, 500.0, 1000.0, 1500.0, 2000.0] + upper, dtype=float)
            cells = []
            for x in ALTITUDE_TESTS_M:
                if x in nodes:
                    cells.append("   node   ")
                    continue
                yi = sum(w * y[i, at[float(nodes[p])]] for p, w in C.stencil(nodes, x, 3))
                r, m = _stats(np.exp(yi - y[i, at[x]]) - 1.0)
                cells.append(f"{r:4.1f}/{m:5.1f}")
            print(f"sun {el:5.1f} deg  {name:30s} " + " ".join(cells))


def _print_row(label: str, e: np.ndarray) -> None:
    """One row of relative errors ``e`` (sun, observer, direction): RMS / max of the sky part
    per sun and observer, then the ground view from 2.2 km."""
    from skydome.models.fitted import _grid

    n = _grid.N_SKY
    cells = [f"{r:4.1f}/{m:4.1f}" for i in range(len(AOD_SUN_DEG))
             for r, m in [_stats(e[i, j, :n]) for j in range(len(AOD_ALTITUDES_M))]]
    r, m = _stats(e[:, 1, n:])
    print(f"  {label} " + " ".join(cells) + f"   ground {r:.1f}/{m:.1f}")


def apply_aod_rule(L: dict, nodes, x: float) -> np.ndarray:
    """The model's day rule in AOD (``_coefficients.aod_stencil`` and ``thin_haze_form``)
    applied to the reference's own values ``L[node]`` over the AOD ``nodes``, at ``x``."""
    from skydome.models.fitted import _coefficients as C

    nodes = np.asarray(nodes, dtype=float)
    st, how = C.aod_stencil(nodes, x)
    return C.apply_aod_stencil(nodes, x, st, how, lambda i: L[float(nodes[i])])


def aod(albedo: float, out: str | None, hazy: bool = False) -> None:
    from skydome.models.fitted import _dataset

    t0 = time.perf_counter()
    L = {}
    if out and os.path.exists(out):
        # a rerun reads the AODs that the file already holds (same albedo, suns, altitudes,
        # wavelengths: the file records them) and computes the others
        z = np.load(out)
        if float(z["albedo"]) == albedo:
            L = {float(k[3:]): z[k].astype(np.float64) for k in z.files if k.startswith("aod")}
    values, tests, sets = ((AOD_VALUES_HAZY, AOD_TESTS_HAZY, AOD_NODE_SETS_HAZY) if hazy
                           else (AOD_VALUES, AOD_TESTS, AOD_NODE_SETS))
    for a in values:
        if a in L:
            continue
        L[a] = _dataset.compute_chunk(a, albedo, AOD_SUN_DEG, AOD_ALTITUDES_M,
                                      twilight_reference=True,
                                      wavelengths=WAVELENGTHS_NM)[:, :, :-1, :, 1]
        L[a] = L[a].astype(np.float64)
    print(f"reference: albedo {albedo:g}, AOD {list(values)} in "
          f"{time.perf_counter() - t0:.0f} s")
    if out:
        np.savez(out, albedo=albedo, **{f"aod{a:g}": v for a, v in L.items()})

    print("\nRMS / max [%], sky part, per sun (" + ", ".join(f"{e:g}" for e in AOD_SUN_DEG)
          + " deg) x observer (ground, 2.2 km); then the ground view from 2.2 km:")
    for name, nodes in sets.items():
        print(f"nodes {name}:")
        for x in tests:
            if np.any(np.isclose(nodes, x)):
                continue
            _print_row(f"AOD {x:<7g}", apply_aod_rule(L, nodes, x) / L[x] - 1.0)
    if hazy:
        return
    # the candidates between the second and third node of the set with 0.0125 (rows
    # "form t in [1, 2]": the thin-haze form through 0, 0.0125, 0.025 read beyond its middle
    # node; "form 0, 0.025, 0.05": the file before's form)
    from skydome.models.fitted import _coefficients as C
    print("between 0.0125 and 0.025, other rules:")
    for name, f in (("form t in [1, 2]", lambda x: C.thin_haze_form(
                        L[0.0], L[0.0125], L[0.025], x / 0.0125).reshape(L[0.0].shape)),
                    ("form 0, 0.025, 0.05", lambda x: C.thin_haze_form(
                        L[0.0], L[0.025], L[0.05], x / 0.025).reshape(L[0.0].shape))):
        for x in [v for v in AOD_TESTS if 0.0125 < v < 0.025]:
            _print_row(f"{name:20s} AOD {x:<7g}", f(x) / L[x] - 1.0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("what", choices=("altitude", "aod"))
    ap.add_argument("--aod", type=float, default=0.7)
    ap.add_argument("--albedo", type=float, default=None,
                    help="ground albedo (default 0.2 for altitude, 0.6 for aod)")
    ap.add_argument("--out", default=None, help="keep the reference's values (.npz)")
    ap.add_argument("--hazy", action="store_true",
                    help="aod: the AODs above 0.1 (AOD_NODE_SETS_HAZY) instead of below")
    a = ap.parse_args(argv)
    albedo = a.albedo if a.albedo is not None else (0.2 if a.what == "altitude" else 0.6)
    if not 0.0 <= albedo <= 1.0:
        print(f"error: --albedo = {albedo:g} is out of range [0, 1]", file=sys.stderr)
        return 2
    if not 0.0 <= a.aod <= 1.0:
        print(f"error: --aod = {a.aod:g} is out of range [0, 1]", file=sys.stderr)
        return 2
    if a.what == "altitude":
        altitude(a.aod, albedo, a.out)
    else:
        aod(albedo, a.out, a.hazy)
    return 0


if __name__ == "__main__":
    sys.exit(main())
