"""How far the observer's sky map of ``precomputed`` is from a much finer one, per band of
elevation from the horizon: the map's rows near the horizon and the limb.

    python tools/precomputed_map_rows.py --aod A --albedo B --cases ALT:SUN,...
        [--rows G:AG:S:AS,...] [--truth G:S]

One table build of the atmosphere (``skydome.models.fitted._dataset.atmosphere``: AOD at
550 nm, Angstrom 1.3, the ground's albedo) in the fitted model's data-set configuration
(``twilight_reference=True``; table wavelengths 380-780 nm every 20 nm), then for each
observer altitude [m] and sun elevation [deg] of ``--cases`` the luminance on a grid of
directions (elevations from the observer's horizon 0.003-89 deg above and 0.01-80 deg
below it, 25 azimuths 0-180 deg from the sun's) with the sky map laid out as each entry of
``--rows`` says (G rows to the ground with the linear share AG of their mapping, S rows
above the horizon with AS: ``_multiple.map_nodes``; default: the former uniform map
48:1:192:1 and the present one), against ``--truth`` (G and S uniform rows; default
384:3072). Prints the largest relative difference per band (sky more than 5 deg from the
sun; the ground where the observer is above it) and the map's time. Cost: 1-2 min for the
tables, about 6 GB of memory, a few seconds per map (the truth's about ten).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

SKY_BANDS = ((0.0, 0.5), (0.5, 1.0), (1.0, 3.0), (3.0, 10.0), (10.0, 90.0))
GROUND_BANDS = ((0.0, 1.0), (1.0, 5.0), (5.0, 90.0))


def _parse(text, n, name):
    """Tuples of n numbers from 'a:b:...,...' or None (an error printed naming ``name``)."""
    try:
        out = [tuple(float(v) for v in item.split(":")) for item in text.split(",")]
    except ValueError:
        out = []
    if not out or any(len(t) != n for t in out):
        print(f"error: {name} = {text!r}: expected comma-separated entries of {n} numbers "
              "joined by ':'", file=sys.stderr)
        return None
    return out


def directions(theta_h):
    """(directions (n, az, 3), elevation from the horizon [deg] (n,), ground (n,))."""
    de = np.concatenate([np.geomspace(0.003, 1.0, 120), np.linspace(1.0, 10.0, 61)[1:],
                         np.linspace(10.0, 89.0, 80)])
    dg = np.concatenate([np.geomspace(0.01, 1.0, 40), np.linspace(1.0, 5.0, 21)[1:],
                         np.linspace(5.0, 80.0, 31)])
    az = np.radians(np.arange(0.0, 181.0, 7.5))
    th = np.concatenate([theta_h - np.radians(de), theta_h + np.radians(dg)])
    ground = np.concatenate([np.zeros(de.size, bool), np.ones(dg.size, bool)])
    T, A = np.meshgrid(th, az, indexing="ij")
    d = np.stack([np.sin(T) * np.sin(A), np.sin(T) * np.cos(A), np.cos(T)], -1)
    return d, np.concatenate([de, dg]), ground


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--aod", type=float, required=True)
    ap.add_argument("--albedo", type=float, required=True)
    ap.add_argument("--cases", required=True, help="ALT:SUN,... (m, deg)")
    ap.add_argument("--rows", default="48:1:192:1,64:0.15:192:0.15",
                    help="G:AG:S:AS,... the maps to measure")
    ap.add_argument("--truth", default="384:3072", help="G:S uniform rows of the reference")
    a = ap.parse_args(argv)
    cases = _parse(a.cases, 2, "--cases")
    rows = _parse(a.rows, 4, "--rows")
    truth = _parse(a.truth, 2, "--truth")
    if cases is None or rows is None or truth is None:
        return 2
    for g, ag, s_, as_ in rows:
        if g < 2 or s_ < 2 or not (0.0 < ag <= 1.0 and 0.0 < as_ <= 1.0):
            print(f"error: --rows entry {g:g}:{ag:g}:{s_:g}:{as_:g}: rows >= 2 and linear "
                  "shares in (0, 1]", file=sys.stderr)
            return 2
    import skydome as sd
    from skydome.models.fitted import _dataset
    from skydome.models.simulated import precomputed as P

    t0 = time.perf_counter()
    ref = sd.model("precomputed", sun=sd.Sun(elevation_deg=10.0, azimuth_deg=180.0),
                   atmosphere=_dataset.atmosphere(a.aod, a.albedo),
                   table_wavelengths_nm=np.arange(380.0, 781.0, 20.0),
                   twilight_reference=True, cache=False)
    print(f"tables: {time.perf_counter() - t0:.0f} s", flush=True)
    saved = (P._SLICE_GROUND, P._SLICE_GROUND_LINEAR, P._SLICE_SKY, P._SLICE_SKY_LINEAR)
    try:
        for alt, elev in cases:
            th_h = np.pi / 2 + np.arccos(ref._R / (ref._R + alt))
            d, de, ground = directions(th_h)
            sun = sd.Sun(elevation_deg=elev, azimuth_deg=0.0)
            ang = np.degrees(np.arccos(np.clip(d @ np.asarray(sun.direction), -1.0, 1.0)))

            def lum(layout):
                P._SLICE_GROUND, P._SLICE_GROUND_LINEAR, P._SLICE_SKY, P._SLICE_SKY_LINEAR = \
                    layout
                m = ref.with_sun(sun, observer_altitude_m=alt)
                m.__dict__.pop("_slice_cache", None)       # the copies share the caches
                m.__dict__.pop("_twilight_cache", None)
                t = time.perf_counter()
                return m.luminance(d), time.perf_counter() - t

            L_ref, _ = lum((int(truth[0][0]), 1.0, int(truth[0][1]), 1.0))
            for g, ag, s_, as_ in rows:
                L, dt = lum((int(g), ag, int(s_), as_))
                rel = np.abs(L / L_ref - 1.0)
                line = f"{alt:.0f} m, sun {elev:g} deg, rows {g:g}/{ag:g} + {s_:g}/{as_:g} " \
                       f"({dt:.1f} s):"
                for lo, hi in SKY_BANDS:
                    m = (ang > 5.0) & ~ground[:, None] & ((de >= lo) & (de < hi))[:, None]
                    line += f" sky {lo:g}-{hi:g} {rel[m].max() * 100:.2f} %;"
                if alt > 0.0:
                    for lo, hi in GROUND_BANDS:
                        m = (ground & (de >= lo) & (de < hi))[:, None] & np.ones(ang.shape, bool)
                        line += f" ground {lo:g}-{hi:g} {rel[m].max() * 100:.2f} %;"
                print(line, flush=True)
    finally:
        P._SLICE_GROUND, P._SLICE_GROUND_LINEAR, P._SLICE_SKY, P._SLICE_SKY_LINEAR = saved
    return 0


if __name__ == "__main__":
    sys.exit(main())
