"""Where the ``fitted`` model's error next to the horizon comes from: the fit at the nodes,
the interpolation between the parameter nodes, or the view grid's angular interpolation.

    python tools/fitted_horizon_diagnosis.py reference OUT.npz --aod A --albedo B
        --suns E1,E2,... --altitudes H1,H2,...
    python tools/fitted_horizon_diagnosis.py measure REF.npz [REF.npz ...]
        [--rows N] [--json OUT.json]

``reference`` computes the reference of one atmosphere as the data set does
(``precomputed`` with ``twilight_reference=True``, ``cache=False``, the 20-nm table
wavelengths, the atmosphere of ``_dataset.atmosphere``; one table build for every sun and
altitude): the radiance per unit extraterrestrial irradiance at every (sun elevation,
altitude) pair of the lists, both on the view grid's nodes and at the centres of its cells
(where the held-out grid measures the model). Cost: about 6 GB of memory for the table
build, 1-1.5 min wall per atmosphere on 2 cores for a few dozen (sun, altitude) pairs.

``measure`` compares the package's ``fitted`` model (its coefficient file and its present
interpolation in ``_coefficients.py``) with those references, in luminance (the sky above
the horizon more than 5 deg from the sun; the reference's spectrum integrated as
tools/fitted_accuracy.py integrates it) and per configuration prints, RMS / max:

* ``nodes``: the model's table at the view grid's nodes against the reference there: the
  fit's residual where the sun, altitude, AOD and albedo are all nodes, that plus the
  interpolation between the parameter nodes where one of them is not;
* ``centres``: the model at the cells' centres (what the held-out grid measures);
* ``angular alone``: the reference's own node values interpolated to the centres as the
  lookup does (in the grid's mapped coordinates the Catmull-Rom spline along the rows, at a
  centre (-p[k-1] + 9 p[k] + 9 p[k+1] - p[k+2]) / 16, the row beyond the sky's first and
  last on the line through its two end rows; the mean of the two azimuth columns) against
  the reference computed there: the view grid's share, which no interpolation between
  parameter nodes can remove;

each also for the first ``--rows`` rows above the horizon, and where the largest centre
error sits (the row counted from the horizon, 0 the first; azimuth from the sun; angle
from the sun). Where the sun is not an elevation node and the reference holds every sun
node of the model's stencil around it at the same altitude (``--suns`` with them, e.g.
0,0.25,0.5,1,2 for 0.25 deg), also

* ``elevation alone``: the reference's own values at those sun nodes, interpolated in
  elevation as the model does (y = ln(L / s + DELTA) and ln s, s the mean of the sky part
  of the grid per wavelength, cubic over the four nodes of
  ``_coefficients.elevation_stencil``, in ln(e + c) where the stencil reads the node 0 deg
  from above and ``_coefficients.elevation_log_offset`` gives c for the reference's AOD), at
  the view grid's nodes against the reference computed at that sun: the share of the sun
  elevation interval, which no fit at the nodes can remove.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def _floats(text: str, name: str):
    """The comma-separated numbers of ``text``, or None (an error printed, naming ``name``)."""
    try:
        v = np.array([float(x) for x in text.split(",") if x.strip()])
    except ValueError:
        v = np.array([])
    if v.size == 0 or not np.all(np.isfinite(v)):
        print(f"error: {name} = {text!r} is not a comma-separated list of numbers",
              file=sys.stderr)
        return None
    return v


def compute_reference(aod: float, albedo: float, suns, altitudes) -> dict:
    """The reference of one atmosphere at every (sun, altitude) pair, on the view grid's
    nodes and at its cells' centres (module docstring); the model construction of
    ``_dataset.compute_chunk``, both direction sets from one table build."""
    import skydome as sd
    from skydome.models.fitted import _dataset, _grid

    wl = _grid.WAVELENGTHS_NM
    ref = sd.model("precomputed", sun=sd.Sun(elevation_deg=float(suns[0]), azimuth_deg=180.0),
                   atmosphere=_dataset.atmosphere(aod, albedo), table_wavelengths_nm=wl,
                   cache=False, twilight_reference=True)
    out = {"aod": aod, "albedo": albedo, "suns": np.asarray(suns, float),
           "altitudes": np.asarray(altitudes, float), "wavelengths_nm": wl}
    for tag, mid in (("nodes", False), ("centres", True)):
        n_dir = _grid.N_SKY + _grid.N_GROUND - (2 if mid else 0)
        n_phi = _grid.N_PHI - (1 if mid else 0)
        arr = np.zeros((len(suns), len(altitudes), n_dir, n_phi, wl.size), np.float32)
        for j, h in enumerate(altitudes):
            d = _grid.directions(float(h), 180.0, mid)
            for i, e in enumerate(suns):
                m = ref.with_sun(sd.Sun(elevation_deg=float(e), azimuth_deg=180.0),
                                 observer_altitude_m=float(h))
                arr[i, j] = m.radiance_table(d)
        out[tag] = arr
    return out


def _luminance_matrix(wl):
    """(n_wl, n_default): the table values [sr^-1] to the solar-weighted spectrum on the
    default wavelengths (as tools/fitted_accuracy.py integrates the reference)."""
    from skydome.spectra import default_wavelengths, interpolation_matrix, solar_irradiance

    dwl = default_wavelengths()
    return interpolation_matrix(wl, dwl) * solar_irradiance(dwl)[None, :], dwl


def ref_luminance(L, wl):
    from skydome.spectra import luminance_from_spectrum

    M, dwl = _luminance_matrix(wl)
    return luminance_from_spectrum(L.astype(np.float64) @ M, dwl)


def compare(ref: dict, aod=None, albedo=None, rows: int = 3) -> list[dict]:
    """Per (sun, altitude) of a reference: the model's luminance errors (module docstring).
    ``aod``, ``albedo``: the model's (default the reference's)."""
    import skydome as sd
    from skydome.models.fitted import _grid

    aod = float(ref["aod"]) if aod is None else aod
    albedo = float(ref["albedo"]) if albedo is None else albedo
    wl = ref["wavelengths_nm"]
    n_sky_c, n_sky_n = _grid.N_SKY - 1, _grid.N_SKY
    t = np.linspace(0.0, 1.0, _grid.N_PHI)
    t = 0.5 * (t[1:] + t[:-1])
    phi_c = 180.0 * (_grid.A_PHI * t + (1.0 - _grid.A_PHI) * t * t)
    out = []
    for i, e in enumerate(ref["suns"]):
        sun = sd.Sun(elevation_deg=float(e), azimuth_deg=180.0)
        for j, h in enumerate(ref["altitudes"]):
            m = sd.model("fitted", sun=sun, aerosol_optical_depth=aod, ground_albedo=albedo,
                         observer_altitude_m=float(h))
            dn = _grid.directions(float(h), 180.0)
            dc = _grid.directions(float(h), 180.0, midpoints=True)
            yn_ref = ref_luminance(ref["nodes"][i, j], wl)[:n_sky_n]
            yc_ref = ref_luminance(ref["centres"][i, j], wl)[:n_sky_c]
            yn_fit = m.xyz_table()[:n_sky_n, :, 1]
            yc_fit = m.luminance(dc[:n_sky_c])
            # the lookup at a cell's centre: the spline at f = 1/2 along the rows (the
            # straight-line rows beyond the ends), then the mean of the two columns
            ext = np.vstack([2.0 * yn_ref[:1] - yn_ref[1:2], yn_ref,
                             2.0 * yn_ref[-1:] - yn_ref[-2:-1]])
            col = (-ext[:-3] + 9.0 * ext[1:-2] + 9.0 * ext[2:-1] - ext[3:]) / 16.0
            yc_ang = np.maximum(0.5 * (col[:, :-1] + col[:, 1:]), 0.0)
            gn = np.degrees(np.arccos(np.clip(dn[:n_sky_n] @ sun.direction, -1, 1)))
            gc = np.degrees(np.arccos(np.clip(dc[:n_sky_c] @ sun.direction, -1, 1)))
            kn, kc = (gn > 5.0) & (yn_ref > 0), (gc > 5.0) & (yc_ref > 0)
            r = {"aod": aod, "albedo": albedo, "sun": float(e), "alt": float(h)}
            cases = [("nodes", yn_fit / np.where(yn_ref > 0, yn_ref, 1) - 1, kn),
                     ("centres", yc_fit / np.where(yc_ref > 0, yc_ref, 1) - 1, kc),
                     ("angular", yc_ang / np.where(yc_ref > 0, yc_ref, 1) - 1, kc)]
            ye = elevation_alone(ref, i, j)
            if ye is not None:
                cases.append(("elevation", ye / np.where(yn_ref > 0, yn_ref, 1) - 1, kn))
            for tag, rel, keep in cases:
                a = np.abs(np.where(keep, rel, 0.0))
                r[tag] = (float(np.sqrt(np.sum(a ** 2) / keep.sum())), float(a.max()))
                near = keep[:rows]
                r[tag + " low"] = (float(np.sqrt(np.sum(a[:rows] ** 2) / max(near.sum(), 1))),
                                   float(a[:rows].max()))
                if tag == "centres":
                    k = np.unravel_index(np.argmax(a), a.shape)
                    r["where"] = (int(k[0]), float(phi_c[k[1]]), float(gc[k]),
                                  float(rel[k]))
                    r["err"] = np.where(keep, rel, np.nan)
            out.append(r)
    return out


def elevation_alone(ref: dict, i: int, j: int):
    """The reference's luminance at its sun ``i`` and altitude ``j`` on the view grid's
    sky nodes, interpolated from its sun nodes as the model interpolates in elevation
    (module docstring); None where the sun is a node or the stencil's nodes are missing."""
    from skydome.models.fitted import _coefficients as C
    from skydome.models.fitted import _grid

    nodes = _grid.SUN_ELEVATION_NODES_DEG
    e = float(ref["suns"][i])
    if np.any(np.isclose(nodes, e)):
        return None
    st = C.elevation_stencil(nodes, e, C.elevation_log_offset(float(ref["aod"])))
    at = {float(x): k for k, x in enumerate(ref["suns"])}
    if any(float(nodes[p]) not in at for p, _ in st):
        return None
    y = ln_s = 0.0
    n_sky = _grid.N_SKY
    for p, w in st:
        L = ref["nodes"][at[float(nodes[p])], j].astype(np.float64)      # (rows, phi, wl)
        s = L[:n_sky].mean(axis=(0, 1))
        y = y + w * np.log(np.maximum(L, 0.0) / s + C.DELTA)
        ln_s = ln_s + w * np.log(s)
    L = np.maximum(np.exp(ln_s) * (np.exp(y) - C.DELTA), 0.0)
    return ref_luminance(L, ref["wavelengths_nm"])[:n_sky]


def _fmt(p):
    return f"{100 * p[0]:.2f} / {100 * p[1]:.1f}"


def print_table(results, rows: int = 3) -> None:
    print(f"| AOD, albedo | sun | altitude | nodes | centres | angular alone | elevation "
          f"alone | centres, rows 0-{rows - 1} | angular alone, rows 0-{rows - 1} | "
          f"elevation alone, rows 0-{rows - 1} | max at (row, azimuth from sun, from sun, "
          f"error) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        w = r["where"]
        el = [_fmt(r[k]) if k in r else "-" for k in ("elevation", "elevation low")]
        print(f"| {r['aod']:g}, {r['albedo']:g} | {r['sun']:g} | {r['alt']:g} | "
              f"{_fmt(r['nodes'])} | {_fmt(r['centres'])} | {_fmt(r['angular'])} | "
              f"{el[0]} | {_fmt(r['centres low'])} | {_fmt(r['angular low'])} | {el[1]} | "
              f"{w[0]}, {w[1]:.0f}, {w[2]:.0f} deg, {100 * w[3]:+.1f} % |", flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("reference", help="compute one atmosphere's reference")
    r.add_argument("out")
    r.add_argument("--aod", type=float, required=True)
    r.add_argument("--albedo", type=float, required=True)
    r.add_argument("--suns", required=True, help="sun elevations [deg], comma-separated")
    r.add_argument("--altitudes", required=True, help="observer altitudes [m]")
    m = sub.add_parser("measure", help="measure the package's model against references")
    m.add_argument("refs", nargs="+")
    m.add_argument("--rows", type=int, default=3,
                   help="the rows above the horizon reported apart (default 3)")
    m.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    from skydome.models.fitted import _grid

    if a.cmd == "reference":
        suns = _floats(a.suns, "--suns")
        alts = _floats(a.altitudes, "--altitudes")
        if suns is None or alts is None:
            return 2
        for name, v, (lo, hi) in (("--aod", [a.aod], _grid.AOD_RANGE),
                                  ("--albedo", [a.albedo], _grid.ALBEDO_RANGE),
                                  ("--suns", suns, _grid.SUN_ELEVATION_RANGE_DEG),
                                  ("--altitudes", alts, _grid.ALTITUDE_RANGE_M)):
            bad = [x for x in v if not lo <= x <= hi]
            if bad:
                print(f"error: {name} = {bad[0]:g} is out of range [{lo:g}, {hi:g}]",
                      file=sys.stderr)
                return 2
        out = compute_reference(a.aod, a.albedo, suns, alts)
        np.savez(a.out, **out)
        print(f"wrote {a.out}")
        return 0
    if a.rows < 1 or a.rows > _grid.N_SKY - 1:
        print(f"error: --rows = {a.rows} is out of range [1, {_grid.N_SKY - 1}]",
              file=sys.stderr)
        return 2
    results = []
    for p in a.refs:
        if not Path(p).is_file():
            print(f"error: {p} is not a file", file=sys.stderr)
            return 2
        with np.load(p) as z:
            ref = {k: z[k] for k in z.files}
        results += compare(ref, rows=a.rows)
    print_table(results, a.rows)
    if a.json:
        Path(a.json).write_text(json.dumps(
            [{k: v for k, v in r.items() if k != "err"} for r in results], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
