"""Fit the ``fitted`` sky model's coefficients to its data set.

    python tools/fit_fitted.py DATASET [--out FILE] [--k-sky 32] [--k-ground 12]
        [--float16] [--gas-bands SUPPLEMENT] [--altitude-supplement SUPPLEMENT]
    python tools/fit_fitted.py --add-sun [--out FILE]

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

``--gas-bands SUPPLEMENT``: a data set of the same grid made with ``tools/fitted_dataset.py
--gas-bands`` (the reference at the gas bands' own wavelengths, 310, 330, 690, 710, 730,
770, 890 and 930 nm); its wavelengths join DATASET's as table wavelengths of their own (49
in all), fitted with the others (the same bases, per elevation node).

``--altitude-supplement SUPPLEMENT``: a data set of the same sun elevations and atmospheres
at altitudes DATASET lacks, made with ``tools/fitted_dataset.py --altitudes`` at DATASET's
table wavelengths (with ``--gas-bands``: ``--with-gas-bands``, the 20-nm and the gas bands'
together); its altitudes join DATASET's (the shipped file: the second file's 10 altitudes
and the 4, 5, 8 and 12 km supplement).

DATASET may lack some atmospheres (a data set still being generated): the fit then uses
the AOD nodes whose every albedo node is there, and says which it left out.

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


def _supplement(option: str, folder: str, ds, aods, same: dict, axis: str,
                values: np.ndarray, what: str):
    """(data set, order, joined values) of a supplement to ``ds`` along ``axis``
    ("wavelengths_nm" or "altitudes_m"): the same sun elevations, view grid and the
    attributes in ``same``, every atmosphere of the fitted AOD nodes, and no value of
    ``axis`` in common with ``values``; ``order`` sorts the concatenation ``values`` + the
    supplement's. None after printing the refusal, naming ``option``."""
    from skydome.models.fitted._dataset import DataSet

    sup = DataSet(folder, require_all=False)
    ok = (np.array_equal(sup.elevations_deg, ds.elevations_deg)
          and all(np.array_equal(getattr(sup, k), v) for k, v in same.items())
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
    ap.add_argument("--k-sky", type=int, default=32)
    ap.add_argument("--k-ground", type=int, default=12)
    ap.add_argument("--float16", action="store_true",
                    help="store coefficients and bases in float16 with a scale per row")
    ap.add_argument("--spectral-rank", type=int, default=0, metavar="K",
                    help="store the coefficients as K spectral terms per sun node (the "
                         "truncated SVD along the wavelength); 0: every wavelength's own")
    ap.add_argument("--gas-bands", default=None, metavar="SUPPLEMENT",
                    help="a --gas-bands data set of the same grid: its wavelengths added")
    ap.add_argument("--altitude-supplement", default=None, metavar="SUPPLEMENT",
                    help="a data set of the same sun elevations and atmospheres at other "
                         "altitudes (tools/fitted_dataset.py --altitudes): its altitudes "
                         "added")
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
    for name, v in (("--k-sky", a.k_sky), ("--k-ground", a.k_ground)):
        if not 1 <= v <= 256:
            print(f"error: {name} = {v} is out of range [1, 256]", file=sys.stderr)
            return 2
    if not 0 <= a.spectral_rank <= 256:
        print(f"error: --spectral-rank = {a.spectral_rank} is out of range [0, 256] (0: "
              "off)", file=sys.stderr)
        return 2
    from skydome._io import atomic_file
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
    gas = None
    if a.gas_bands is not None:
        joined = _supplement("--gas-bands", a.gas_bands, ds, aods, {"altitudes_m": alt},
                             "wavelengths_nm", wl, "the same grid as DATASET")
        if joined is None:
            return 2
        gas, order, wl = joined
        print(f"gas bands: {gas.wavelengths_nm.tolist()} nm added ({wl.size} table "
              "wavelengths)", flush=True)
    sup = None
    if a.altitude_supplement is not None:
        joined = _supplement("--altitude-supplement", a.altitude_supplement, ds, aods,
                             {"wavelengths_nm": wl}, "altitudes_m", alt,
                             "the same sun elevations and table wavelengths as DATASET "
                             "(with --gas-bands: its wavelengths too)")
        if joined is None:
            return 2
        sup, alt_order, alt = joined
        print(f"altitudes: {sup.altitudes_m.tolist()} m added ({alt.size} altitude nodes)",
              flush=True)

    def sky_wavelengths(aod, alb):
        L, sun = ds.sky(aod, alb)
        if gas is None:
            return L, sun
        Lg, sung = gas.sky(aod, alb)
        return (np.concatenate([L, Lg], axis=-1)[..., order],
                np.concatenate([sun, sung], axis=-1)[..., order])

    def sky(aod, alb):
        L, sun = sky_wavelengths(aod, alb)
        if sup is None:
            return L, sun
        La, suna = sup.sky(aod, alb)
        return (np.concatenate([L, La], axis=1)[:, alt_order],
                np.concatenate([sun, suna], axis=1)[:, alt_order])
    n_sky = _grid.N_SKY * _grid.N_PHI
    n_dir = (_grid.N_SKY + _grid.N_GROUND) * _grid.N_PHI
    shape = (aods.size, albs.size, el.size, alt.size, wl.size)
    Y = np.empty(shape + (n_dir,), dtype=np.float32)
    log_s = np.empty(shape, dtype=np.float32)
    for i, aod in enumerate(aods):
        for j, alb in enumerate(albs):
            L, _ = sky(aod, alb)                         # (e, h, rows, phi, wl)
            L = np.moveaxis(L.astype(np.float64), -1, 2).reshape(el.size, alt.size, wl.size,
                                                                   n_dir)
            s = L[..., :n_sky].mean(axis=-1)
            log_s[i, j] = np.log(s)
            Y[i, j] = np.log(np.maximum(L, 0.0) / s[..., None] + DELTA)
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
                 altitudes_m=[float(x) for x in alt])
    meta = {"dataset_grid": dgrid, "k_sky": a.k_sky, "k_ground": a.k_ground,
            "delta": DELTA, "fit_residual_rms_y": resid,
            "command": f"python tools/fit_fitted.py DATASET --k-sky {a.k_sky} "
                       f"--k-ground {a.k_ground}" + (" --float16" if a.float16 else "")
                       + (" --gas-bands SUPPLEMENT" if gas is not None else "")
                       + (" --altitude-supplement SUPPLEMENT" if sup is not None else "")
                       + (f" --spectral-rank {a.spectral_rank}" if a.spectral_rank else ""),
            "fitted": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    if a.float16:
        for key in ("coef_sky", "coef_ground", "sky_basis", "ground_basis", "coef_sky_amp",
                    "coef_ground_amp"):
            if key not in out:
                continue
            v = out[key]
            scale = np.max(np.abs(v), axis=-1).astype(np.float32)
            scale = np.where(scale > 0.0, scale, 1.0)
            out[key] = (v / scale[..., None]).astype(np.float16)
            out[key + "_scale"] = scale
    meta["float16"] = bool(a.float16)
    meta["spectral_rank"] = int(a.spectral_rank)
    meta["aod_nodes_fitted"] = [float(x) for x in aods]
    out["meta"] = np.array(json.dumps(meta))
    target = Path(a.out) if a.out else COEFFICIENT_FILE
    target.parent.mkdir(parents=True, exist_ok=True)
    with atomic_file(target) as tmp:
        np.savez_compressed(tmp, **out)
    print(f"wrote {target} ({target.stat().st_size / 1e6:.1f} MB) in "
          f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
