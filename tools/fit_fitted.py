"""Fit the ``fitted`` sky model's coefficients to its data set.

    python tools/fit_fitted.py DATASET [--out FILE] [--k-sky 32] [--k-ground 12]
        [--float16] [--gas-bands SUPPLEMENT] [--altitude-supplement SUPPLEMENT]
        [--elevation-supplement SUPPLEMENT]
    python tools/fit_fitted.py --add-sun [--out FILE]
    python tools/fit_fitted.py DATASET --extend FILE [--out FILE2]
    python tools/fit_fitted.py DATASET --replace FILE [--out FILE2]

DATASET is a folder written by ``tools/fitted_dataset.py --grid fit``. The fit (the
representation is described in skydome/models/fitted/_coefficients.py):

1. per node and wavelength, s = the mean radiance over the sky part of the view grid and
   y = ln(L / s + DELTA);
2. per sun-elevation node, the mean of y and its leading singular vectors over every
   atmosphere, altitude and wavelength of that node (a randomised SVD, Halko, Martinsson &
   Tropp 2011, alg. 4.4 with 2 power iterations, in float32, with a fixed seed so that a
   rerun gives the same file), the sky and the ground apart;
3. the coefficients: y minus the mean, projected on the basis;
4. the sun (:func:`add_sun`, no data set needed): the columns of every constituent along
   the ray to the top over (observer radius, sun zenith cosine), computed from the
   atmosphere's profiles by the reference's own column kernel and table sizes, with the
   rows' profiles and the radii (skydome/models/fitted/_sun.py; the model takes the
   extinction spectra from its atmosphere); the data set's sun factor is not used (the
   reference's sun_radiance is the check: tests/test_fitted_sun.py). The shipped file
   still holds the former ``log_sun_transmittance`` (read by no code).

With ``--float16`` the coefficients and the bases are stored in float16, each row of
coefficients (one node and wavelength) and each basis vector divided by its largest
magnitude (the scales in float32): half the file, for the rounding error measured in
docs/models.md ("fitted").

``--wavelength-supplement SUPPLEMENT`` (``--gas-bands``, its name in earlier files'
commands): a data set of the same grid made with ``tools/fitted_dataset.py --gas-bands``
(the reference at the gas bands' own wavelengths, 310, 330, 570, 590, 610, 690, 710, 730,
770, 890 and 930 nm) or ``--wavelengths`` (some of them: the shipped file's 570, 590 and
610 nm); its wavelengths join DATASET's as table wavelengths of their own, fitted with the
others (the same bases, per elevation node).

Every supplement option is repeatable, and the supplements join in the order of the
command line, each to the data set joined so far: it must hold that state's values of the
two other axes. The shipped file: ``DATASET --elevation-supplement SUN
--wavelength-supplement CHAPPUIS`` (the 49-wavelength data set of the seventh file's 28 sun
nodes, its 0.5-deg supplement at the same 49 wavelengths, then 570, 590 and 610 nm at all
29 sun nodes).

``--altitude-supplement SUPPLEMENT``: a data set of the same sun elevations and atmospheres
at altitudes DATASET lacks, made with ``tools/fitted_dataset.py --altitudes`` at DATASET's
table wavelengths (with ``--gas-bands``: ``--with-gas-bands``, the 20-nm and the gas bands'
together); its altitudes join DATASET's (the shipped file: the second file's 10 altitudes
and the 4, 5, 8 and 12 km supplement).

``--elevation-supplement SUPPLEMENT``: likewise a data set of the same altitudes (with
``--altitude-supplement``: its altitudes too), table wavelengths and atmospheres at sun
elevations DATASET lacks, made with ``tools/fitted_dataset.py --elevations``; its elevations
join DATASET's (the shipped file: the 28 sun nodes of the sixth file's data set and the
0.5-deg supplement).

DATASET may lack some atmospheres (a data set still being generated): the fit then uses
the AOD nodes whose every albedo node is there, and says which it left out.

``--extend FILE``: add the AOD nodes of DATASET (every albedo node of FILE there) that FILE
lacks, on FILE's own means, bases and spectral vectors: steps 1 and 3 only, the
coefficients of the new nodes the least-squares projection of their y on FILE's bases (as
stored: float16 bases as the model reads them), then on its spectral vectors; every node of
FILE keeps its arrays bit for bit (DATASET must hold FILE's sun elevations, altitudes, table
wavelengths and view grid). It prints the projection's RMS residual of y at the new nodes
beside FILE's fit residual. The shipped file is the full fit of the ``fit-v4`` grid (30
atmospheres) extended with the AOD nodes 0.35 and 0.75 (their six chunks made with
``tools/fitted_dataset.py --atmospheres``).

``--replace FILE``: the same projection for the AOD nodes of DATASET (every albedo node there)
that FILE already has, whose arrays it replaces (the scale, the coefficients), every other
node and FILE's means, bases and spectral vectors kept bit for bit: the nodes of a
corrected reference (the reference's ``observer_columns``, docs/models.md) without a new
basis. It prints the projection's RMS residual of y at the replaced nodes beside FILE's fit
residual.

``--add-sun``: only step 4, into an existing FILE: its other arrays are written back
unchanged (same dtypes, same compression), the sun's arrays added or replaced.

Writes FILE (default: the package's skydome/models/fitted/data/fitted_coefficients.npz)
atomically and prints the fit residual on the fitting nodes (RMS of y; the accuracy of the
model is measured on held-out nodes by tools/fitted_accuracy.py, not here).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def randomized_basis(X: np.ndarray, k: int, seed: int = 29) -> np.ndarray:
    """The k leading right singular vectors of X (rows are samples): (k, n_cols)."""
    rng = np.random.default_rng(seed)
    omega = rng.standard_normal((X.shape[1], k + 10)).astype(X.dtype)
    Y = X @ omega
    for _ in range(2):
        Q, _ = np.linalg.qr(Y)
        Z, _ = np.linalg.qr(X.T @ Q)
        Y = X @ Z
    Q, _ = np.linalg.qr(Y)
    _, _, vt = np.linalg.svd(Q.T @ X, full_matrices=False)
    return vt[:k]


def log_ratio(L: np.ndarray, n_sky: int, delta: float):
    """(ln s, y) of one atmosphere's radiance ``L`` (e, h, rows, phi, wl) as the fit takes
    it (step 1): s (e, h, wl) the mean over the sky part, y (e, h, wl, rows x phi) = ln(L / s
    + delta)."""
    e, h, rows, phi, w = L.shape
    L = np.moveaxis(L.astype(np.float64), -1, 2).reshape(e, h, w, rows * phi)
    s = L[..., :n_sky].mean(axis=-1)
    return np.log(s), np.log(np.maximum(L, 0.0) / s[..., None] + delta)


def _float16_rows(v: np.ndarray):
    """(v / scale in float16, scale in float32): one scale per row (the last axis), its
    largest magnitude (1 for a row of zeros)."""
    scale = np.max(np.abs(v), axis=-1).astype(np.float32)
    scale = np.where(scale > 0.0, scale, 1.0)
    return (v / scale[..., None]).astype(np.float16), scale


def write_file(target: Path, arrays: dict, meta: dict) -> None:
    """Write a coefficient file: ``arrays`` and ``meta`` (as JSON), atomically
    (np.savez_compressed: deterministic, no time stamps)."""
    from skydome._io import atomic_file

    target.parent.mkdir(parents=True, exist_ok=True)
    with atomic_file(target) as tmp:
        np.savez_compressed(tmp, **dict(arrays, meta=np.array(json.dumps(meta))))


def extend(file: Path, dataset: str, out: Path, replace: bool = False) -> int:
    """``--extend``: FILE with DATASET's AOD nodes that it lacks added; with ``replace``
    (``--replace``), the AOD nodes of DATASET that FILE has projected again and their
    arrays replaced (module docstring)."""
    from skydome.models.fitted import _coefficients, _grid
    from skydome.models.fitted._dataset import DataSet

    t0 = time.perf_counter()
    with np.load(file, allow_pickle=False) as z:
        arr = {k: z[k] for k in z.files}
    meta = json.loads(str(arr["meta"]))
    ds = DataSet(dataset, require_all=False)
    albs = arr["albedo_nodes"]
    present = set(ds.present)
    new = sorted({a for a, _ in ds.atmospheres
                  if np.any(np.isclose(arr["aod_nodes"], a)) == replace
                  and all((a, float(b)) in present for b in albs)})
    same = (np.array_equal(ds.elevations_deg, arr["elevation_nodes_deg"])
            and np.array_equal(ds.altitudes_m, arr["altitude_nodes_m"])
            and np.array_equal(ds.wavelengths_nm, arr["wavelengths_nm"])
            and not ds.midpoints)
    if not same or not new:
        print(f"error: {'--replace' if replace else '--extend'} = {file}: DATASET = "
              f"{dataset} "
              + (f"holds no AOD node that the file {'has' if replace else 'lacks'} with "
                 f"every albedo node "
                 f"{albs.tolist()}" if same else
                 "is not of the file's grid (sun elevations, altitudes, table wavelengths, "
                 "view-grid nodes)"), file=sys.stderr)
        return 2
    n_sky = _grid.N_SKY * _grid.N_PHI
    delta = float(meta["delta"])
    spectral = "coef_sky_amp" in arr
    ne, nh, nw = (arr[k].size for k in ("elevation_nodes_deg", "altitude_nodes_m",
                                         "wavelengths_nm"))
    parts = (("sky", slice(0, n_sky)), ("ground", slice(n_sky, None)))
    # the bases as the model reads them (_coefficients.load: float16 times its scale) and,
    # per sun node, their least-squares projector (B B^T)^-1 B (orthonormal before the
    # rounding), formed once
    model = _coefficients.load(str(file))
    bases, proj = {}, {}
    for part, _ in parts:
        B = model[f"{part}_basis"].astype(np.float64)
        bases[part] = B
        proj[part] = np.stack([np.linalg.solve(b @ b.T, b) for b in B])
    added = {"sky": [], "ground": [], "log_scale": []}
    sq = {"sky": 0.0, "ground": 0.0}
    cnt = {"sky": 0, "ground": 0}
    trunc = {"sky": [0.0, 0.0], "ground": [0.0, 0.0]}     # spectral: residual^2, total^2
    for aod in new:
        per_alb = {"sky": [], "ground": [], "log_scale": []}
        for alb in albs:
            L, _ = ds.sky(aod, float(alb))
            log_s, Y = log_ratio(L, n_sky, delta)
            per_alb["log_scale"].append(log_s.astype(np.float32))
            for part, cols in parts:
                B = bases[part]
                coef = np.empty((ne, nh, nw, B.shape[1]))
                for e in range(ne):
                    X = Y[e, :, :, cols].reshape(nh * nw, -1) - arr[f"{part}_mean"][e]
                    C = X @ proj[part][e].T
                    R = X - C @ B[e]
                    sq[part] += float(np.sum(R ** 2))
                    cnt[part] += R.size
                    coef[e] = C.reshape(nh, nw, -1)
                if spectral:
                    spec = arr[f"coef_{part}_spec"].astype(np.float64)      # (e, K, W)
                    m = arr[f"coef_{part}_spec_mean"].astype(np.float64)    # (e, W)
                    # rows (h, t) along the wavelength, on the file's spectral vectors
                    Xw = np.moveaxis(coef, 2, -1) - m[:, None, None, :]     # (e, h, T, W)
                    amp = np.einsum("ehtw,ekw->ehkt", Xw, spec)             # (e, h, K, T)
                    back = np.einsum("ehkt,ekw->ehtw", amp, spec)
                    trunc[part][0] += float(np.sum((Xw - back) ** 2))
                    trunc[part][1] += float(np.sum(coef ** 2))
                    per_alb[part].append(amp)
                else:
                    per_alb[part].append(coef)
            print(f"projected AOD {aod:g} albedo {float(alb):g}", flush=True)
        for k in per_alb:
            added[k].append(np.stack(per_alb[k]))
    resid = {p: float(np.sqrt(sq[p] / cnt[p])) for p in sq}
    for p in ("sky", "ground"):
        print(f"{p}: RMS residual of y at the {'replaced' if replace else 'new'} nodes "
              f"{resid[p]:.4f} (the file's fit on "
              f"its nodes: {meta['fit_residual_rms_y'][p]:.4f})"
              + (f"; relative RMS of the spectral terms' truncation there "
                 f"{np.sqrt(trunc[p][0] / max(trunc[p][1], 1e-300)):.2e}" if spectral
                 else ""), flush=True)
    out_arr = dict(arr)
    if replace:
        # the replaced nodes' rows in FILE's AOD axis; every other row kept bit for bit
        rows = [int(np.flatnonzero(np.isclose(arr["aod_nodes"], x))[0]) for x in new]

        def join(key, values):
            out_arr[key] = arr[key].copy()
            out_arr[key][rows] = values.astype(arr[key].dtype)
    else:
        aods = np.concatenate([arr["aod_nodes"], np.array(new)])
        order = np.argsort(aods, kind="stable")
        out_arr["aod_nodes"] = aods[order]

        def join(key, values):
            old = arr[key]
            out_arr[key] = np.concatenate([old, values.astype(old.dtype)])[order]

    join("log_scale", np.stack(added["log_scale"]))
    for part in ("sky", "ground"):
        key = f"coef_{part}_amp" if spectral else f"coef_{part}"
        v = np.stack(added[part])
        if key + "_scale" in arr:
            v, scale = _float16_rows(v)
            join(key + "_scale", scale)
        join(key, v)
    if replace:
        # cumulative: a file reprojected in steps (a data set generated over several
        # runs) records every node reprojected and each step's residual
        before = [float(x) for x in meta.get("aod_nodes_reprojected", [])]
        meta["aod_nodes_reprojected"] = sorted(set(before) | {float(x) for x in new})
        steps = meta.get("reprojection_steps", [])
        steps.append({"aod_nodes": [float(x) for x in new], "residual_rms_y": resid})
        meta["reprojection_steps"] = steps
        meta["reprojection_residual_rms_y"] = resid
        meta["command_replace"] = "python tools/fit_fitted.py DATASET --replace FILE"
    else:
        meta["aod_nodes_projected"] = [float(x) for x in new]
        meta["projection_residual_rms_y"] = resid
        meta["command_extend"] = "python tools/fit_fitted.py DATASET --extend FILE"
    write_file(out, out_arr, meta)
    print(f"wrote {out} ({out.stat().st_size / 1e6:.1f} MB; AOD nodes "
          f"{out_arr['aod_nodes'].tolist()}) in {time.perf_counter() - t0:.0f} s")
    return 0


def add_sun(arrays: dict) -> dict:
    """``arrays`` (a coefficient file's arrays, ``wavelengths_nm`` among them) with the
    sun's arrays of :func:`skydome.models.fitted._sun.derive` added or replaced."""
    from skydome.models.fitted import _sun

    out = {k: v for k, v in arrays.items() if k not in _sun.SUN_KEYS}
    out.update(_sun.derive(arrays["wavelengths_nm"]))
    return out


def add_sun_to_file(target: Path) -> None:
    """Add (replace) the sun's arrays in the coefficient file ``target``, every other array
    written back as it was (np.savez_compressed: deterministic, no time stamps)."""
    from skydome._io import atomic_file

    with np.load(target, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    out = add_sun(arrays)
    with atomic_file(target) as tmp:
        np.savez_compressed(tmp, **out)


#: The axis of the data set along which each supplement option joins.
SUPPLEMENT_AXES = {"--wavelength-supplement": "wavelengths_nm", "--gas-bands": "wavelengths_nm",
                   "--altitude-supplement": "altitudes_m",
                   "--elevation-supplement": "elevations_deg"}
#: Per axis (the data set's attribute): its index in a chunk's radiance (e, h, rows, phi,
#: wl) and sun factor (e, h, wl), and its name in messages.
AXES = {"wavelengths_nm": (-1, "table wavelengths"), "altitudes_m": (1, "altitudes"),
        "elevations_deg": (0, "sun elevations")}


class _Supplement(argparse.Action):
    """Appends (option, folder) to ``supplements``: the supplements in command-line order."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, getattr(namespace, self.dest) + [(option_string, values)])


def _supplement(option: str, folder: str, ds, aods, same: dict, axis: str,
                values: np.ndarray, what: str):
    """(data set, order, joined values) of a supplement to ``ds`` along ``axis``
    ("wavelengths_nm", "altitudes_m" or "elevations_deg"): the same view grid and the
    attributes in ``same``, every atmosphere of the fitted AOD nodes, and no value of
    ``axis`` in common with ``values``; ``order`` sorts the concatenation ``values`` + the
    supplement's. None after printing the refusal, naming ``option``."""
    from skydome.models.fitted._dataset import DataSet

    sup = DataSet(folder, require_all=False)
    ok = (all(np.array_equal(getattr(sup, k), v) for k, v in same.items())
          and all(x in sup.present for x in ds.present if x[0] in set(aods.tolist())))
    if not ok or sup.midpoints != ds.midpoints:
        print(f"error: {option} = {folder}: not {what}, or an atmosphere missing",
              file=sys.stderr)
        return None
    new = getattr(sup, axis)
    if np.isin(new, values).any():
        print(f"error: {option} = {folder}: its {axis.split('_')[0]} overlap DATASET's",
              file=sys.stderr)
        return None
    order = np.argsort(np.concatenate([values, new]), kind="stable")
    return sup, order, np.concatenate([values, new])[order]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dataset", nargs="?")
    ap.add_argument("--add-sun", action="store_true",
                    help="only add (replace) the sun's arrays in FILE (--out, default the "
                         "shipped file); no data set")
    ap.add_argument("--out", default=None)
    ap.add_argument("--extend", default=None, metavar="FILE",
                    help="add DATASET's AOD nodes that FILE lacks on FILE's own bases "
                         "(written to --out, default FILE)")
    ap.add_argument("--replace", default=None, metavar="FILE",
                    help="project DATASET's AOD nodes that FILE has on FILE's own bases "
                         "again and replace their arrays (a data set of a corrected "
                         "reference at some nodes; written to --out, default FILE)")
    ap.add_argument("--k-sky", type=int, default=32)
    ap.add_argument("--k-ground", type=int, default=12)
    ap.add_argument("--float16", action="store_true",
                    help="store coefficients and bases in float16 with a scale per row")
    ap.add_argument("--spectral-rank", type=int, default=0, metavar="K",
                    help="store the coefficients as K spectral terms per sun node (the "
                         "truncated SVD along the wavelength); 0: every wavelength's own")
    for option, text in (
            ("--wavelength-supplement", "a data set of the same sun elevations, altitudes "
             "and atmospheres at other table wavelengths (tools/fitted_dataset.py "
             "--wavelengths or --gas-bands): its wavelengths added"),
            ("--gas-bands", "the same as --wavelength-supplement (the name in the commands "
             "of earlier files)"),
            ("--altitude-supplement", "a data set of the same sun elevations, wavelengths "
             "and atmospheres at other altitudes (tools/fitted_dataset.py --altitudes): its "
             "altitudes added"),
            ("--elevation-supplement", "a data set of the same altitudes, wavelengths and "
             "atmospheres at other sun elevations (tools/fitted_dataset.py --elevations): "
             "its elevations added")):
        ap.add_argument(option, dest="supplements", action=_Supplement, default=[],
                        metavar="SUPPLEMENT", help=text + "; repeatable, joined in the "
                        "order given")
    a = ap.parse_args(argv)
    if a.add_sun:
        from skydome.models.fitted._coefficients import COEFFICIENT_FILE

        target = Path(a.out) if a.out else COEFFICIENT_FILE
        t0 = time.perf_counter()
        add_sun_to_file(target)
        print(f"added the sun's arrays to {target} ({target.stat().st_size / 1e6:.2f} MB) "
              f"in {time.perf_counter() - t0:.1f} s")
        return 0
    if a.dataset is None:
        ap.error("DATASET is required (unless --add-sun)")
    if a.extend is not None and a.replace is not None:
        print("error: --extend and --replace exclude each other", file=sys.stderr)
        return 2
    for option, file in (("--extend", a.extend), ("--replace", a.replace)):
        if file is None:
            continue
        if not Path(file).is_file():
            print(f"error: {option} = {file}: no such coefficient file", file=sys.stderr)
            return 2
        return extend(Path(file), a.dataset, Path(a.out) if a.out else Path(file),
                      replace=option == "--replace")
    for name, v in (("--k-sky", a.k_sky), ("--k-ground", a.k_ground)):
        if not 1 <= v <= 256:
            print(f"error: {name} = {v} is out of range [1, 256]", file=sys.stderr)
            return 2
    if not 0 <= a.spectral_rank <= 256:
        print(f"error: --spectral-rank = {a.spectral_rank} is out of range [0, 256] (0: "
              "off)", file=sys.stderr)
        return 2
    from skydome.models.fitted import _grid
    from skydome.models.fitted._coefficients import COEFFICIENT_FILE, DELTA, \
        spectral_factors
    from skydome.models.fitted._dataset import DataSet

    t0 = time.perf_counter()
    ds = DataSet(a.dataset, require_all=False)
    albs = np.array(sorted({x for _, x in ds.atmospheres}))
    present = set(ds.present)
    aods_all = sorted({x for x, _ in ds.atmospheres})
    aods = np.array([x for x in aods_all if all((x, b) in present for b in albs)])
    if aods.size < len(aods_all):
        print(f"AOD nodes left out (an albedo chunk missing): "
              f"{sorted(set(aods_all) - set(aods.tolist()))}", flush=True)
    if aods.size < 2:
        print("error: fewer than two complete AOD nodes in the data set", file=sys.stderr)
        return 2
    el, alt, wl = ds.elevations_deg, ds.altitudes_m, ds.wavelengths_nm
    # the supplements joined to DATASET, in order: (data set, axis of the chunk's arrays,
    # order of the joined values); a chunk's radiance (e, h, rows, phi, wl) and sun factor
    # (e, h, wl) share the elevation (0), altitude (1) and wavelength (-1) axes
    joins = []
    # each supplement joins the data set as joined so far, in the order of the command
    # line: it must hold that state's values of the two other axes
    state = {"wavelengths_nm": wl, "altitudes_m": alt, "elevations_deg": el}
    for option, folder in a.supplements:
        axis = SUPPLEMENT_AXES[option]
        same = {k: v for k, v in state.items() if k != axis}
        what = ("the " + " and ".join(AXES[k][1] for k in same) + " of DATASET"
                + (" with the supplements before it" if joins else ""))
        joined = _supplement(option, folder, ds, aods, same, axis, state[axis], what)
        if joined is None:
            return 2
        sup, order, state[axis] = joined
        joins.append((sup, AXES[axis][0], order))
        print(f"{option}: {getattr(sup, axis).tolist()} added ({state[axis].size} "
              f"{axis.split('_')[0]})", flush=True)
    wl, alt, el = state["wavelengths_nm"], state["altitudes_m"], state["elevations_deg"]

    def sky(aod, alb):
        L, sun = ds.sky(aod, alb)
        for part, axis, order in joins:
            Lp, sunp = part.sky(aod, alb)
            L = np.take(np.concatenate([L, Lp], axis=axis), order, axis=axis)
            sun = np.take(np.concatenate([sun, sunp], axis=axis), order, axis=axis)
        return L, sun
    n_sky = _grid.N_SKY * _grid.N_PHI
    n_dir = (_grid.N_SKY + _grid.N_GROUND) * _grid.N_PHI
    shape = (aods.size, albs.size, el.size, alt.size, wl.size)
    Y = np.empty(shape + (n_dir,), dtype=np.float32)
    log_s = np.empty(shape, dtype=np.float32)
    for i, aod in enumerate(aods):
        for j, alb in enumerate(albs):
            L, _ = sky(aod, alb)                         # (e, h, rows, phi, wl)
            log_s[i, j], Y[i, j] = log_ratio(L, n_sky, DELTA)
            print(f"read AOD {aod:g} albedo {alb:g}", flush=True)
    out = {"aod_nodes": aods, "albedo_nodes": albs, "elevation_nodes_deg": el,
           "altitude_nodes_m": alt, "wavelengths_nm": wl}
    resid = {}
    for part, cols, k in (("sky", slice(0, n_sky), a.k_sky),
                          ("ground", slice(n_sky, n_dir), a.k_ground)):
        n_c = cols.stop - cols.start
        means = np.empty((el.size, n_c), dtype=np.float32)
        bases = np.empty((el.size, k, n_c), dtype=np.float32)
        coef = np.empty(shape + (k,), dtype=np.float32)
        sq, cnt = 0.0, 0
        for e in range(el.size):
            X = Y[:, :, e, :, :, cols]                             # (a, b, h, wl, n_c)
            Xf = X.reshape(-1, n_c)
            mean = Xf.mean(axis=0, dtype=np.float64).astype(np.float32)
            B = randomized_basis(Xf - mean, k)
            C = (Xf - mean) @ B.T
            means[e], bases[e] = mean, B
            coef[:, :, e] = C.reshape(X.shape[:-1] + (k,))
            R = Xf - mean - C @ B
            sq += float(np.sum(R.astype(np.float64) ** 2))
            cnt += R.size
        resid[part] = float(np.sqrt(sq / cnt))
        out[f"{part}_mean"], out[f"{part}_basis"], out[f"coef_{part}"] = means, bases, coef
        print(f"{part}: {k} terms, RMS residual of y on the fitting nodes {resid[part]:.4f}",
              flush=True)
    out["log_scale"] = log_s
    if a.spectral_rank:
        if a.spectral_rank > wl.size:
            print(f"error: --spectral-rank = {a.spectral_rank} is out of range [0, "
                  f"{wl.size}] (the data set's table wavelengths)", file=sys.stderr)
            return 2
        for part in ("sky", "ground"):
            amp, spec, mean, rel = spectral_factors(out.pop(f"coef_{part}"),
                                                    a.spectral_rank)
            out[f"coef_{part}_amp"] = amp
            out[f"coef_{part}_spec"] = spec
            out[f"coef_{part}_spec_mean"] = mean
            print(f"{part}: coefficients as {a.spectral_rank} spectral terms per sun node, "
                  f"relative RMS of the truncation {rel:.2e}", flush=True)
    out = add_sun(out)
    dgrid = dict(ds.meta, wavelengths_nm=[float(x) for x in wl],
                 altitudes_m=[float(x) for x in alt], elevations_deg=[float(x) for x in el])
    meta = {"dataset_grid": dgrid, "k_sky": a.k_sky, "k_ground": a.k_ground,
            "delta": DELTA, "fit_residual_rms_y": resid,
            "command": f"python tools/fit_fitted.py DATASET --k-sky {a.k_sky} "
                       f"--k-ground {a.k_ground}" + (" --float16" if a.float16 else "")
                       + "".join(f" {opt} SUPPLEMENT" for opt, _ in a.supplements)
                       + (f" --spectral-rank {a.spectral_rank}" if a.spectral_rank else ""),
            "fitted": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    if a.float16:
        for key in ("coef_sky", "coef_ground", "sky_basis", "ground_basis", "coef_sky_amp",
                    "coef_ground_amp"):
            if key not in out:
                continue
            out[key], out[key + "_scale"] = _float16_rows(out[key])
    meta["float16"] = bool(a.float16)
    meta["spectral_rank"] = int(a.spectral_rank)
    meta["aod_nodes_fitted"] = [float(x) for x in aods]
    target = Path(a.out) if a.out else COEFFICIENT_FILE
    write_file(target, out, meta)
    print(f"wrote {target} ({target.stat().st_size / 1e6:.1f} MB) in "
          f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
