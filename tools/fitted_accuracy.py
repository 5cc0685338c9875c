"""Measure the ``fitted`` model on its held-out grid, against the ``precomputed`` reference.

    python tools/fitted_accuracy.py HELDOUT [--supplement SUP ...] [--elevations DEG,...]
        [--figure docs/figures/fitted_heldout.png] [--json OUT.json] [--coefficients FILE]
        [--per-atmosphere] [--where N]
    python tools/fitted_accuracy.py DATASET --nodes [--albedo A] [--aod A] [--where N]
        [--coefficients FILE]

HELDOUT is a folder written by ``tools/fitted_dataset.py --grid heldout``: the reference's
spectral skies (computed by ``precomputed`` itself, never by the fitted model) at parameter
values that are not fitting nodes (AOD and albedo off the nodes, sun elevations and
altitudes between them) and at directions in the centres of the view grid's cells. For
each regime (sun above 20 deg, 0-20 deg, 0 to -6 deg, -6 to -12 deg; observer on the
ground, at 0.4-4.5 km, at 15 km) it prints the luminance RMS and largest relative error and the spectral ones
(every table wavelength 300-1100 nm) over the sky more than 5 deg from the sun, the same
luminance figures for ``hosek_wilkie2012`` (observer on the ground, sun above the horizon;
turbidity from the AOD by Preetham's beta = 0.04608 T - 0.04586 and Angstrom's law with
alpha 1.3), the ground seen from above (below the horizon) and the sun's transmittance.

``--supplement SUP`` (repeatable): a held-out set of the same altitudes, atmospheres and
wavelengths at other sun elevations (``tools/fitted_dataset.py --grid heldout --elevations``);
its elevations join HELDOUT's (the present held-out grid: the sixth file's held-out set,
whose sun 0.5 deg is now a node, and the 0.25 and 0.75 deg supplement). Of the joined sun
elevations, those that are sun nodes of the measured file are left out (they are not held
out), and with ``--elevations`` only those listed are measured (the same points for two
files: for instance the present file and the sixth on 0.25 and 0.75 deg).

``--nodes``: DATASET is a ``--grid fit`` data set; the luminance error at its nodes (every
sun elevation and altitude, every view-grid node of the sky more than 5 deg from the sun),
each point classed by whether its parameters are nodes of the measured file: the
representation's own error (the truncated angular basis) at the file's nodes, and the
interpolation's in sun elevation, altitude or AOD at a finer grid's nodes between them
(the angular interpolation, which the held-out grid's cell centres add, is not in it);
``--where N`` lists the N largest errors of each regime with where they lie (the
atmosphere, the sun, the altitude, the view-grid row and column, the elevation and the
angle from the sun); on a held-out set too (the view grid's cell centres there).
``--coefficients``: measure that file instead of the package's
(for instance the previous coefficients on the same held-out grid).

A held-out set made with ``--wavelength-step 10`` also holds the reference at the
wavelengths between the model's 20-nm table wavelengths (310, 330, ..., 1090 nm, computed
by ``precomputed`` at those wavelengths, not interpolated). The spectral columns of the
main table are then the table wavelengths only (as for a 20-nm set), and a second table
gives per regime the spectral RMS and max at the in-between wavelengths, for the model and
for its wavelength interpolation alone (the reference's own values at the table
wavelengths interpolated as the model interpolates: the part of the error that no fit of
the table wavelengths can remove), with the worst in-between wavelengths;
``--spectral-figure`` draws the RMS per wavelength. The luminance reference is integrated
from every wavelength of the set.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

REGIMES = (("sun > 20 deg", 20.0, 90.0), ("sun 0-20 deg", 0.0, 20.0),
           ("sun 0 to -6 deg", -6.0, 0.0), ("sun -6 to -12 deg", -12.0, -6.0))
HEIGHTS = (("ground", 0.0, 0.0), ("0.4-4.5 km", 1.0, 14000.0), ("15 km", 15000.0, 15000.0))
#: The two atmosphere classes of the tables: clear (AOD <= 0.1) and hazy.
CLASSES = (("clear", 0.0, 0.1), ("hazy", 0.1, 1.0))


def turbidity_from_aod(aod: float) -> float:
    """Preetham turbidity with the AOD at 550 nm: beta = AOD (0.55)^1.3 (Angstrom, alpha
    1.3), beta = 0.04608 T - 0.04586 ([PSS99] A.2)."""
    beta = aod * 0.55 ** 1.3
    return (beta + 0.04586) / 0.04608


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("heldout")
    ap.add_argument("--figure", default=None)
    ap.add_argument("--json", default=None)
    ap.add_argument("--coefficients", default=None,
                    help="coefficient file to measure (default: the package's)")
    ap.add_argument("--nodes", action="store_true",
                    help="measure at the fitting nodes of a --grid fit data set")
    ap.add_argument("--albedo", type=float, default=None,
                    help="with --nodes: only the atmospheres of this albedo (default all)")
    ap.add_argument("--aod", type=float, default=None,
                    help="with --nodes: only the atmospheres of this AOD (default all)")
    ap.add_argument("--where", type=int, default=0, metavar="N",
                    help="also list the N largest luminance errors of each regime with "
                         "where they lie (atmosphere, sun, altitude, view-grid row and "
                         "column, elevation, angle from the sun)")
    ap.add_argument("--per-atmosphere", action="store_true",
                    help="also the luminance RMS / max per held-out atmosphere, regime and "
                         "observer (which atmospheres the regimes' figures come from)")
    ap.add_argument("--supplement", action="append", default=[], metavar="SUP",
                    help="a held-out set at other sun elevations (same altitudes, "
                         "atmospheres and wavelengths): its elevations joined (repeatable)")
    ap.add_argument("--elevations", default=None, metavar="DEG,...",
                    help="measure only these of the held-out sun elevations (default: every "
                         "one that is not a sun node of the measured file)")
    ap.add_argument("--spectral-figure", default=None,
                    help="figure of the spectral RMS per wavelength (a set with wavelengths "
                         "between the table wavelengths)")
    a = ap.parse_args(argv)
    import skydome as sd
    from skydome.models.fitted import _coefficients, _grid
    if a.coefficients is not None:
        if not Path(a.coefficients).is_file():
            print(f"error: --coefficients = {a.coefficients} is not a file", file=sys.stderr)
            return 2
        _coefficients.COEFFICIENT_FILE = Path(a.coefficients)
    if not 0 <= a.where <= 10000:
        print(f"error: --where = {a.where} is out of range [0, 10000]", file=sys.stderr)
        return 2
    if a.nodes:
        return _at_nodes(a.heldout, a.albedo, a.aod, a.where)
    from skydome.models.fitted._dataset import DataSet
    from skydome.spectra import default_wavelengths, interpolation_matrix, \
        luminance_from_spectrum, solar_irradiance

    ds = DataSet(a.heldout, require_all=False, grid="heldout")
    try:
        ds = _HeldOut(ds, [DataSet(f, require_all=False, grid="heldout")
                           for f in a.supplement], a.elevations,
                      _coefficients.load()["elevation_nodes_deg"])
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    lo_aod, hi_aod = _grid.AOD_RANGE
    atmospheres = [x for x in ds.present if lo_aod <= x[0] <= hi_aod]
    left = sorted(set(ds.atmospheres) - set(atmospheres))
    if left:
        print(f"held-out atmospheres left out (no chunk, or outside the model's AOD range "
              f"[{lo_aod:g}, {hi_aod:g}]): {left}")
    if not ds.midpoints:
        print("error: HELDOUT must be made with --grid heldout", file=sys.stderr)
        return 2
    from skydome.models.fitted import interpolate_spectrum

    wl = ds.wavelengths_nm
    # the model's table wavelengths among the set's, and the ones between them
    table_wl = _coefficients.load()["wavelengths_nm"]      # the measured file's
    node = np.isin(np.round(wl, 6), np.round(table_wl, 6))
    between = ~node
    if not node.all() and not np.isin(np.round(table_wl, 6), np.round(wl, 6)).all():
        print("error: HELDOUT's wavelengths do not include the model's table wavelengths "
              f"({', '.join(f'{x:g}' for x in table_wl)} nm)", file=sys.stderr)
        return 2
    # per regime, per wavelength: sum of squares, count and largest relative error of the
    # sky more than 5 deg from the sun, for the model and for the interpolation alone
    per_wl: dict = {}

    def add_wl(key, rel, mask):
        s = per_wl.setdefault(key, [np.zeros(wl.size), np.zeros(wl.size), np.zeros(wl.size)])
        r = np.where(mask, rel, 0.0)
        s[0] += np.sum(r * r, axis=0)
        s[1] += np.sum(mask, axis=0)
        s[2] = np.maximum(s[2], np.max(np.abs(r), axis=0))

    dwl = default_wavelengths()
    to_default = interpolation_matrix(wl, dwl) * solar_irradiance(dwl)[None, :]
    e_table = solar_irradiance(wl)
    acc: dict = {}

    def add(key, err):
        acc.setdefault(key, []).append(np.abs(np.ravel(err)))

    sun_err = []
    examples = []
    largest = _Largest(a.where)
    for aod, alb in atmospheres:
        L_all, sunf = ds.sky(aod, alb)
        for i, el in enumerate(ds.elevations_deg):
            for j, h in enumerate(ds.altitudes_m):
                sun = sd.Sun(elevation_deg=float(el), azimuth_deg=180.0)
                d = _grid.directions(float(h), 180.0, midpoints=True)
                n_sky = _grid.N_SKY - 1
                ref = L_all[i, j].astype(np.float64)                    # (78, 63, n_wl)
                gamma = np.degrees(np.arccos(np.clip(d @ sun.direction, -1, 1)))
                keep = gamma > 5.0
                sky = np.zeros(keep.shape, bool)
                sky[:n_sky] = True
                m = sd.model("fitted", sun=sun, aerosol_optical_depth=aod, ground_albedo=alb,
                             observer_altitude_m=float(h))
                y_ref = luminance_from_spectrum(ref @ to_default, dwl)
                y_fit = m.luminance(d)
                s_ref = ref * e_table
                s_fit = m.radiance(d, wl)
                rel_y = (y_fit - y_ref) / y_ref
                pos = s_ref > 0
                rel_s = np.where(pos, (s_fit - s_ref) / np.where(pos, s_ref, 1.0), 0.0)
                reg = next(r for r, lo, hi in REGIMES if lo <= el <= hi)
                hgt = next(r for r, lo, hi in HEIGHTS if lo <= h <= hi)
                cls = next(r for r, lo, hi in CLASSES if lo <= aod <= hi)
                hgt = (cls, hgt)
                sel = sky & keep
                add((reg, hgt, "fitted", "Y"), rel_y[sel])
                add(("atmosphere", (aod, alb), reg, hgt[1]), rel_y[sel])
                largest.add(reg, rel_y, sel, d, sun.direction,
                            (aod, alb, float(el), float(h), hgt[1]))
                rs, ps = rel_s[sel], pos[sel]
                add((reg, hgt, "fitted", "spectral"), rs[:, node][ps[:, node]])
                if between.any():
                    add((reg, hgt, "fitted", "spectral between"),
                        rs[:, between][ps[:, between]])
                    # the interpolation alone: the reference's own table-wavelength values
                    # interpolated to every wavelength as the model does
                    s_int = interpolate_spectrum(ref[..., node][sel], wl[node],
                                                 wl) * e_table
                    r_int = np.where(ps, (s_int - s_ref[sel]) / np.where(ps, s_ref[sel], 1.0),
                                     0.0)
                    add((reg, hgt, "interpolation", "spectral between"),
                        r_int[:, between][ps[:, between]])
                    add_wl((reg, "fitted"), rs, ps)
                    add_wl((reg, "interpolation"), r_int, ps)
                if h > 0:
                    add((reg, hgt, "fitted", "ground Y"), rel_y[~sky])
                if h == 0 and el >= 0:
                    hw = sd.model("hosek_wilkie2012", sun=sun,
                                  turbidity=turbidity_from_aod(aod), albedo=alb)
                    y_hw = hw.luminance(d)
                    add((reg, hgt, "hosek_wilkie2012", "Y"),
                        ((y_hw - y_ref) / y_ref)[sky & keep])
                # the sun: the reference's factor against the model's transmittance x vis
                t_ref = sunf[i, j]
                t_fit = m.sun_radiance(wl) * sun.solid_angle_sr / e_table
                if t_ref[wl == 560.0][0] > 1e-3:
                    e_t = np.abs(t_fit / np.where(t_ref > 0, t_ref, 1.0) - 1.0)
                    e_t = np.where(t_ref > 0, e_t, 0.0)
                    sun_err.append((float(el), float(h), aod,
                                    float(np.max(e_t[(wl >= 400) & node])),
                                    float(np.max(e_t[(wl >= 400) & between], initial=0.0))))
                if (aod, alb) == atmospheres[0] and h in (0.0, 15000.0) and \
                        el in (45.0, 4.0, -4.5, -9.0, -9.5):
                    examples.append((el, h, y_ref, rel_y))
    rows = []
    print(f"held-out grid: {len(atmospheres)} atmospheres "
          f"{atmospheres}, sun {list(ds.elevations_deg)} deg, altitude "
          f"{list(ds.altitudes_m)} m; relative errors more than 5 deg from the sun")
    for cls, _, _ in CLASSES:
        print(f"\n{cls}:\n")
        print("| sun | observer | model | luminance RMS | luminance max | spectral RMS | "
              "spectral max | ground view luminance RMS / max |")
        print("|---|---|---|---|---|---|---|---|")
        for reg, _, _ in REGIMES:
            for hgt, _, _ in HEIGHTS:
                for model in ("fitted", "hosek_wilkie2012"):
                    row = _row(acc, reg, (cls, hgt), model)
                    if row is None:
                        continue
                    rows.append(row)
                    cells = [f"{100 * row['Y_rms']:.2f} %", f"{100 * row['Y_max']:.1f} %"]
                    cells += ([f"{100 * row['S_rms']:.2f} %", f"{100 * row['S_max']:.1f} %"]
                              if "S_rms" in row else ["-", "-"])
                    cells.append(f"{100 * row['G_rms']:.2f} / {100 * row['G_max']:.1f} %"
                                 if "G_rms" in row else "-")
                    print(f"| {reg[4:]} | {hgt} | {model} | " + " | ".join(cells) + " |")
    largest.print("per regime, the sky more than 5 deg from the sun",
                  [r for r, _, _ in REGIMES], "observer")
    if sun_err:
        se = np.array([x[3] for x in sun_err])
        print(f"sun transmittance (400-1100 nm, where it exceeds 1e-3 at 560 nm): largest "
              f"relative error {100 * se.max():.2f} %, median {100 * np.median(se):.2f} % "
              f"over {se.size} held-out nodes (the table wavelengths)")
        if between.any():
            sb = np.array([x[4] for x in sun_err])
            hi = np.array([x[0] for x in sun_err]) >= 4.0
            print(f"  between the table wavelengths: largest {100 * sb.max():.2f} %, median "
                  f"{100 * np.median(sb):.2f} %; with the sun at 4 deg or higher: largest "
                  f"{100 * sb[hi].max(initial=0.0):.2f} %, median "
                  f"{100 * np.median(sb[hi]) if hi.any() else 0.0:.2f} %")
    per_atm = []
    for key, parts in acc.items():
        if key[0] == "atmosphere":
            e = np.concatenate(parts)
            per_atm.append({"aod": key[1][0], "albedo": key[1][1], "regime": key[2],
                            "observer": key[3], "Y_rms": float(np.sqrt(np.mean(e * e))),
                            "Y_max": float(e.max(initial=0.0))})
    if a.per_atmosphere:
        print("\nper atmosphere, luminance RMS / max (the regimes as above):\n")
        heads = [f"{r[4:]}, {h}" for r, _, _ in REGIMES for h, _, _ in HEIGHTS]
        print("| AOD, albedo | " + " | ".join(heads) + " |")
        print("|---|" + "---|" * len(heads))
        look = {(x["aod"], x["albedo"], x["regime"], x["observer"]): x for x in per_atm}
        for aod, alb in atmospheres:
            cells = []
            for r, _, _ in REGIMES:
                for h, _, _ in HEIGHTS:
                    x = look.get((aod, alb, r, h))
                    cells.append("-" if x is None else
                                 f"{100 * x['Y_rms']:.2f} / {100 * x['Y_max']:.1f}")
            print(f"| {aod:g}, {alb:g} | " + " | ".join(cells) + " |")
    spectral = _between_tables(acc, per_wl, wl, between) if between.any() else {}
    if a.json:
        Path(a.json).write_text(json.dumps({"rows": rows, "sun": sun_err,
                                            "between": spectral,
                                            "per_atmosphere": per_atm}, indent=1))
    if a.spectral_figure and spectral:
        _spectral_figure(a.spectral_figure, spectral, wl, node)
    if a.figure and examples:
        _figure(a.figure, examples, atmospheres[0])
    return 0


class _Largest:
    """The ``n`` largest relative errors per group (``--where``), with where they lie."""

    def __init__(self, n: int):
        self.n = n
        self.pts: dict = {}

    def add(self, group, signed, keep, d, sun_dir, what):
        """``signed`` (rows, columns): model / reference - 1 over the view grid ``d`` (rows,
        columns, 3); only where ``keep``; ``what``: (AOD, albedo, sun, altitude, label)."""
        if not self.n:
            return
        rows, cols = np.nonzero(keep)
        err = signed[rows, cols]
        top = np.argsort(np.abs(err))[::-1][:self.n]
        v = d[rows[top], cols[top]]
        ang = np.degrees(np.arccos(np.clip(v @ sun_dir, -1.0, 1.0)))
        up = np.degrees(np.arcsin(np.clip(v[:, 2], -1.0, 1.0)))
        pts = self.pts.setdefault(group, [])
        pts += [(abs(float(err[t])), float(err[t])) + tuple(what[:4])
                + (int(rows[t]), int(cols[t]), float(u), float(g), what[4])
                for t, u, g in zip(top, up, ang)]
        pts.sort(key=lambda x: -x[0])
        del pts[self.n:]

    def print(self, title, groups, label):
        if not self.n:
            return
        print(f"\nthe {self.n} largest luminance errors {title} (model / reference - 1; row "
              "and column of the view grid: the row 0 the sky's lowest, at the horizon (from "
              "above: the limb), the column 0 towards the sun's azimuth; elevation above the "
              "horizontal)")
        for g in groups:
            if g not in self.pts:
                continue
            print(f"\n{g}:\n")
            print(f"| error | AOD | albedo | sun | altitude | row | column | elevation | "
                  f"from the sun | {label} |")
            print("|---|---|---|---|---|---|---|---|---|---|")
            for _, e, a_, b_, el, h, r, k, u, gm, lab in self.pts[g]:
                print(f"| {100 * e:+.2f} % | {a_:g} | {b_:g} | {el:g} deg | {h:g} m | {r} | "
                      f"{k} | {u:.2f} deg | {gm:.2f} deg | {lab} |")


class _HeldOut:
    """A held-out set joined with supplements at other sun elevations (``--supplement``),
    reduced to the measured sun elevations: the attributes of
    :class:`skydome.models.fitted._dataset.DataSet` that the held-out measure reads."""

    def __init__(self, ds, supplements, elevations, file_nodes):
        self.altitudes_m, self.wavelengths_nm = ds.altitudes_m, ds.wavelengths_nm
        self.midpoints, self.atmospheres = ds.midpoints, ds.atmospheres
        self.parts = [ds] + list(supplements)
        for sup in supplements:
            same = (np.array_equal(sup.altitudes_m, ds.altitudes_m)
                    and np.array_equal(sup.wavelengths_nm, ds.wavelengths_nm)
                    and sup.midpoints == ds.midpoints
                    and set(sup.atmospheres) == set(ds.atmospheres))
            if not same:
                raise ValueError(f"--supplement = {sup.folder}: not the altitudes, "
                                 "wavelengths, atmospheres and view grid of HELDOUT")
        joined = np.concatenate([p.elevations_deg for p in self.parts])
        if np.unique(np.round(joined, 9)).size < joined.size:
            raise ValueError(f"--supplement: sun elevations {joined.tolist()} deg overlap "
                             "between the held-out sets")
        self.present = [x for x in ds.present
                        if all(x in sup.present for sup in supplements)]
        if elevations is not None:
            try:
                want = np.array([float(x) for x in elevations.split(",")])
            except ValueError:
                raise ValueError(f"--elevations = {elevations!r} is not a list of sun "
                                 "elevations in deg") from None
            bad = [float(e) for e in want if not np.isclose(joined, e).any()]
            if bad or not want.size:
                raise ValueError(f"--elevations = {elevations!r}: {bad} not among the "
                                 f"held-out sun elevations {sorted(joined.tolist())} deg")
            keep = np.isclose(joined[:, None], want[None, :]).any(axis=1)
        else:
            keep = ~np.isclose(joined[:, None], np.asarray(file_nodes)[None, :]).any(axis=1)
            if not keep.all():
                print(f"held-out sun elevations left out (sun nodes of the measured file): "
                      f"{joined[~keep].tolist()} deg")
        order = np.argsort(joined, kind="stable")
        self.index = order[keep[order]]
        self.elevations_deg = joined[self.index]

    def sky(self, aod, alb):
        Ls, suns = zip(*(p.sky(aod, alb) for p in self.parts))
        return (np.concatenate(Ls, axis=0)[self.index],
                np.concatenate(suns, axis=0)[self.index])


def _at_nodes(folder, albedo, aod=None, where=0) -> int:
    """The luminance error on a ``--grid fit`` data set (module docstring, ``--nodes``),
    each point classed by which of its parameters are nodes of the measured coefficient
    file: all of them (the representation's own error), or the sun elevation, the altitude
    or the AOD between the file's nodes (that interpolation's error on top of it; a data
    set of a finer grid than the file's holds such points)."""
    import skydome as sd
    from skydome.models.fitted import _coefficients, _grid
    from skydome.models.fitted._dataset import DataSet
    from skydome.spectra import default_wavelengths, interpolation_matrix, \
        luminance_from_spectrum, solar_irradiance

    ds = DataSet(folder, require_all=False)
    if ds.midpoints:
        print("error: with --nodes DATASET must be made with --grid fit", file=sys.stderr)
        return 2
    atms = [x for x in ds.present if (albedo is None or abs(x[1] - albedo) < 1e-9)
            and (aod is None or abs(x[0] - aod) < 1e-9)]
    if not atms:
        print(f"error: --albedo = {albedo}, --aod = {aod}: no computed atmosphere of the "
              f"data set has them (computed: {ds.present})", file=sys.stderr)
        return 2
    c = _coefficients.load()

    def is_node(nodes, x):
        return bool(np.any(np.abs(np.asarray(nodes, dtype=np.float64) - x) < 1e-9))

    wl = ds.wavelengths_nm
    # the file's table wavelengths that are the data set's (a file fitted with the gas
    # bands' supplement has 49, a 20-nm data set 41)
    sel = np.isin(np.round(c["wavelengths_nm"], 6), np.round(wl, 6))
    if int(sel.sum()) != wl.size:
        print("error: DATASET's wavelengths are not all table wavelengths of the file",
              file=sys.stderr)
        return 2
    dwl = default_wavelengths()
    to_default = interpolation_matrix(wl, dwl) * solar_irradiance(dwl)[None, :]
    n_sky = _grid.N_SKY
    acc: dict = {}
    largest = _Largest(where)
    for aod, alb in atms:
        L_all, _ = ds.sky(aod, alb)
        cls = next(r for r, lo, hi in CLASSES if lo <= aod <= hi)
        a_node = is_node(c["aod_nodes"], aod) and is_node(c["albedo_nodes"], alb)
        for i, el in enumerate(ds.elevations_deg):
            sun = sd.Sun(elevation_deg=float(el), azimuth_deg=180.0)
            reg = next(r for r, lo, hi in REGIMES if lo <= el <= hi)
            e_node = is_node(c["elevation_nodes_deg"], el)
            for j, h in enumerate(ds.altitudes_m):
                h_node = is_node(c["altitude_nodes_m"], h)
                kind = ("at nodes" if a_node and e_node and h_node else
                        "+".join(n for n, ok in (("AOD", a_node), ("sun", e_node),
                                                 ("altitude", h_node)) if not ok)
                        + " between nodes")
                d = _grid.directions(float(h), 180.0)
                keep = np.degrees(np.arccos(np.clip(d @ sun.direction, -1, 1))) > 5.0
                keep[n_sky:] = False
                y_ref = luminance_from_spectrum(L_all[i, j].astype(np.float64) @ to_default,
                                                dwl)
                keep &= y_ref > 0.0           # (no light: nothing to compare)
                fit = _coefficients.radiance_grid(c, aod, alb, float(el), float(h))[..., sel]
                y_fit = luminance_from_spectrum(fit @ to_default, dwl)
                hgt = next(r for r, lo, hi in HEIGHTS if lo <= h <= hi)
                signed = y_fit / y_ref - 1.0
                rel = np.abs(signed[keep])
                acc.setdefault((cls, reg, hgt, kind), []).append(rel)
                acc.setdefault((cls, reg, hgt, kind, aod), []).append(rel)
                largest.add(reg, signed, keep, d, sun.direction,
                            (aod, alb, float(el), float(h), kind))
    print(f"on the data set's nodes: atmospheres {atms}, sun {list(ds.elevations_deg)} "
          f"deg, altitude {list(ds.altitudes_m)} m; coefficient file "
          f"{_coefficients.COEFFICIENT_FILE.name} (AOD nodes "
          f"{[float(x) for x in c['aod_nodes']]}, sun {len(c['elevation_nodes_deg'])} "
          f"nodes, altitude {[float(x) for x in c['altitude_nodes_m']]} m); luminance, "
          f"the sky more than 5 deg from the sun")
    print("| class | sun | observer | points | luminance RMS | luminance max | "
          "worst AOD (RMS) |")
    print("|---|---|---|---|---|---|---|")
    kinds = sorted({k[3] for k in acc}, key=lambda k: (k != "at nodes", k))
    for cls, _, _ in CLASSES:
        for reg, _, _ in REGIMES:
            for hgt, _, _ in HEIGHTS:
                for kind in kinds:
                    v = acc.get((cls, reg, hgt, kind))
                    if v is None:
                        continue
                    n = len(v)
                    v = np.concatenate(v)
                    per = {k[4]: float(np.sqrt(np.mean(np.concatenate(x) ** 2)))
                           for k, x in acc.items()
                           if len(k) == 5 and k[:4] == (cls, reg, hgt, kind)}
                    worst = max(per, key=per.get)
                    print(f"| {cls} | {reg[4:]} | {hgt} | {kind} ({n}) | "
                          f"{100 * np.sqrt(np.mean(v ** 2)):.2f} % | {100 * v.max():.1f} % | "
                          f"{worst:g} ({100 * per[worst]:.2f} %) |", flush=True)
    largest.print("per regime at the data set's nodes, the sky more than 5 deg from the sun",
                  [r for r, _, _ in REGIMES], "points")
    return 0


def _between_tables(acc, per_wl, wl, between):
    """Print the spectral errors at the wavelengths between the table wavelengths, per
    regime (every atmosphere and observer together); returns them for the JSON file."""
    out = {"wavelengths_nm": [float(x) for x in wl], "regimes": {}}
    print(f"\nspectral, sky more than 5 deg from the sun, at the {int(between.sum())} "
          f"wavelengths between the table wavelengths ({wl[between][0]:g}, "
          f"{wl[between][1]:g}, ..., {wl[between][-1]:g} nm) against the reference computed "
          "there; 'interpolation alone': the reference's own table-wavelength values "
          "interpolated as the model does:\n")
    print("| sun | table wavelengths: RMS / max | between: RMS / max | interpolation "
          "alone, between: RMS / max | worst between (interpolation alone: RMS) |")
    print("|---|---|---|---|---|")
    for reg, _, _ in REGIMES:
        cells = []
        for model, name in (("fitted", "spectral"), ("fitted", "spectral between"),
                            ("interpolation", "spectral between")):
            v = [np.concatenate(x) for k, x in acc.items()
                 if k[0] == reg and k[2] == model and k[3] == name]
            if not v:
                cells.append("-")
                continue
            v = np.concatenate(v)
            cells.append(f"{100 * np.sqrt(np.mean(v ** 2)):.2f} / {100 * v.max():.1f} %")
        curves = {}
        for model in ("fitted", "interpolation"):
            s = per_wl.get((reg, model))
            if s is None:
                continue
            rms = np.sqrt(s[0] / np.maximum(s[1], 1))
            curves[model] = {"rms": [float(x) for x in rms], "max": [float(x) for x in s[2]]}
        if not curves:
            continue
        rms_i = np.array(curves["interpolation"]["rms"])
        worst = np.argsort(np.where(between, rms_i, -1.0))[::-1][:4]
        cells.append(", ".join(f"{wl[k]:g} nm {100 * rms_i[k]:.1f} %" for k in worst))
        out["regimes"][reg] = curves
        print(f"| {reg[4:]} | " + " | ".join(cells) + " |")
    print("\nper wavelength, RMS [%] (model / interpolation alone), every regime:\n")
    print("| nm | " + " | ".join(r[4:] for r in out["regimes"]) + " |")
    print("|---|" + "---|" * len(out["regimes"]))
    for k in np.flatnonzero(between):
        print(f"| {wl[k]:g} | " + " | ".join(
            f"{100 * c['fitted']['rms'][k]:.2f} / {100 * c['interpolation']['rms'][k]:.2f}"
            for c in out["regimes"].values()) + " |")
    return out


def _spectral_figure(path, spectral, wl, node):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from skydome._io import atomic_file

    regs = list(spectral["regimes"])
    fig, ax = plt.subplots(1, len(regs), figsize=(4.2 * len(regs), 3.6), squeeze=False,
                           sharey=True)
    for k, reg in enumerate(regs):
        c = spectral["regimes"][reg]
        a = ax[0, k]
        a.semilogy(wl, 100 * np.maximum(c["fitted"]["rms"], 1e-4), "-", color="0.6", lw=0.8)
        a.semilogy(wl[~node], 100 * np.maximum(np.array(c["fitted"]["rms"])[~node], 1e-4),
                   "o", ms=3.5, color="C0", label="fitted, between")
        a.semilogy(wl[node], 100 * np.maximum(np.array(c["fitted"]["rms"])[node], 1e-4),
                   "s", ms=3, color="C2", label="fitted, table wavelengths")
        a.semilogy(wl[~node], 100 * np.maximum(np.array(c["interpolation"]["rms"])[~node],
                                               1e-4),
                   "x", ms=4, color="C3", label="interpolation alone")
        a.set_title(reg, fontsize=9)
        a.set_xlabel("wavelength [nm]")
        a.grid(True, which="both", lw=0.3)
    ax[0, 0].set_ylabel("spectral RMS, sky > 5 deg from sun [%]")
    ax[0, 0].legend(fontsize=7)
    fig.suptitle("fitted vs precomputed at 10-nm wavelengths (held-out grid)", fontsize=10)
    fig.tight_layout()
    with atomic_file(path) as tmp:
        fig.savefig(tmp, dpi=90)
    plt.close(fig)


def _row(acc, reg, key, model):
    """RMS and largest relative error of one cell of the table (None: no data)."""
    y = acc.get((reg, key, model, "Y"))
    if y is None:
        return None
    y = np.concatenate(y)
    row = {"regime": reg, "class": key[0], "observer": key[1], "model": model,
           "Y_rms": float(np.sqrt(np.mean(y ** 2))), "Y_max": float(y.max())}
    for tag, name in (("S", "spectral"), ("G", "ground Y")):
        v = acc.get((reg, key, model, name))
        if v is not None:
            v = np.concatenate(v)
            row.update({f"{tag}_rms": float(np.sqrt(np.mean(v ** 2))),
                        f"{tag}_max": float(v.max())})
    return row


def _figure(path, examples, atm):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from skydome._io import atomic_file
    from skydome.models.fitted import _grid

    els = sorted({e[0] for e in examples}, reverse=True)
    hs = sorted({e[1] for e in examples})
    n = len(els)
    # per altitude two rows: the reference's luminance, the model's error
    fig, ax = plt.subplots(2 * len(hs), n, figsize=(3.0 * n, 2.8 * 2 * len(hs)),
                           squeeze=False)
    t = np.linspace(0.0, 1.0, _grid.N_PHI)
    t = 0.5 * (t[1:] + t[:-1])
    phi = 180.0 * (_grid.A_PHI * t + (1.0 - _grid.A_PHI) * t * t)
    for el, h, y_ref, rel in examples:
        k, r0 = els.index(el), 2 * hs.index(h)
        th = np.degrees(np.arccos(np.clip(_grid.directions(h, 180.0, True)[:, 0, 2], -1, 1)))
        order = np.argsort(th)           # the sky rows run from the horizon up: sort them
        th, y_ref, rel = th[order], y_ref[order], rel[order]
        im = ax[r0, k].pcolormesh(phi, th, np.log10(np.maximum(y_ref, 1e-9)),
                                  shading="auto", cmap="magma")
        fig.colorbar(im, ax=ax[r0, k], label="log10 cd/m2")
        im = ax[r0 + 1, k].pcolormesh(phi, th, 100 * rel, shading="auto", cmap="RdBu_r",
                                      vmin=-5, vmax=5)
        fig.colorbar(im, ax=ax[r0 + 1, k], label="fitted - ref [%]")
        for r in (r0, r0 + 1):
            ax[r, k].invert_yaxis()
            ax[r, k].axhline(np.degrees(_grid.horizon_zenith_rad(h)), color="k", lw=0.5)
            ax[r, k].set_ylabel("view zenith [deg]")
        ax[r0 + 1, k].set_xlabel("azimuth from sun [deg]")
        ax[r0, k].set_title(f"sun {el:g} deg, {h / 1000:g} km", fontsize=9)
    fig.suptitle(f"fitted vs precomputed at held-out nodes (AOD {atm[0]:g}, albedo "
                 f"{atm[1]:g}): reference luminance (top), error (bottom)", fontsize=10)
    fig.tight_layout()
    with atomic_file(path) as tmp:
        fig.savefig(tmp, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
