"""Make the Monte Carlo reference of the sky's twilight irradiance on the ground
(tests/data/twilight_irradiance_montecarlo_550nm.npz, read by
tests/test_precomputed_twilight_irradiance.py).

    python tools/twilight_irradiance_reference.py OUT.npz [--elevations=-3.6,-5.5,-7.3]
        [--samples 50000] [--seed 41]

The ``montecarlo`` model (backward path tracing, all orders, ``next_event="segment"``: the
next event of every collision integrated along the segment before it, the earth's shadow
cut out; see tools/twilight_references.py) at 550 nm, ``Atmosphere.earth(aerosol_optical_depth
=0.2)``, sun at azimuth 180 deg, on a product quadrature of the upper hemisphere: 8
Gauss-Legendre nodes in mu = cos(zenith) over [0, 1] times 12 azimuths (midpoints over
[0, 180] deg from the sun's vertical, doubled: the sky is symmetric about it). The diffuse
horizontal irradiance is E = sum_k w_k L_k with w_k = w_mu mu 2 pi / 12, and its standard
error from the radiances' (independent per direction). On ``precomputed``'s own sky
(twilight reference configuration) this quadrature is within 0.06 % of a 48 x 96 one at
sun -5.5 and -7.3 deg.

The file holds per sun elevation the radiances and their standard errors, E and its
standard error, the paths per direction, the seed and the CPU time; the directions and
weights; the command and the provenance.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

AOD = 0.2
SUN_AZIMUTH_DEG = 180.0
N_MU, N_PHI = 8, 12


def hemisphere():
    """(directions (N_MU N_PHI, 3), weights [sr]) of the product quadrature (the sun at
    azimuth 180 deg, i.e. towards -y; azimuth measured from it)."""
    x, w = np.polynomial.legendre.leggauss(N_MU)
    mu, wm = 0.5 * (x + 1.0), 0.5 * w
    phi = (np.arange(N_PHI) + 0.5) * np.pi / N_PHI
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1.0 - M * M)
    d = np.stack([s * np.sin(P), -s * np.cos(P), M], -1).reshape(-1, 3)
    wt = (wm[:, None] * mu[:, None] * np.full(P.shape, 2.0 * np.pi / N_PHI)).reshape(-1)
    return d, wt


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--elevations", default="-3.6,-5.5,-7.3")
    ap.add_argument("--samples", type=int, default=50_000,
                    help="paths per direction and sun elevation")
    ap.add_argument("--seed", type=int, default=41)
    a = ap.parse_args(argv)
    if a.samples < 1:
        raise SystemExit(f"--samples = {a.samples} is out of range: >= 1")
    elevations = [float(x) for x in a.elevations.split(",")]
    for e in elevations:
        if not -18.0 <= e < 0.0:
            raise SystemExit(f"--elevations: {e:g} is out of range: [-18, 0) deg")
    import skydome as sd
    from skydome._io import atomic_write
    from skydome.atmosphere import Atmosphere

    d, w = hemisphere()
    wl = np.array([550.0])
    out = dict(np.load(a.out, allow_pickle=False)) if os.path.exists(a.out) else {}
    for elev in elevations:
        mc = sd.model("montecarlo", sun=sd.Sun(elevation_deg=elev, azimuth_deg=SUN_AZIMUTH_DEG),
                      atmosphere=Atmosphere.earth(aerosol_optical_depth=AOD),
                      samples=a.samples, seed=a.seed, next_event="segment")
        c0 = time.process_time()
        L, err = mc.radiance_with_error(d, wl)
        cpu = time.process_time() - c0
        E = float(w @ L[:, 0])
        E_err = float(np.sqrt(np.sum((w * err[:, 0]) ** 2)))
        k = f"{elev:g}"
        out.update({k: L, k + "_err": err, k + "_E": np.float64(E), k + "_E_err": np.float64(E_err),
                    k + "_samples": np.float64(a.samples), k + "_seed": np.int64(a.seed),
                    k + "_cpu_s": np.float64(cpu)})
        print(f"sun {elev:g} deg: E = {E:.5g} +- {100 * E_err / E:.2f} % W m^-2 nm^-1, "
              f"{cpu:.0f} s CPU", flush=True)
    out.update(directions=d, weights_sr=w, wavelengths_nm=wl,
               provenance=np.str_(
                   "skydome montecarlo (backward path tracing, all orders, next_event='segment'),"
                   f" Atmosphere.earth(aerosol_optical_depth={AOD}), sun azimuth "
                   f"{SUN_AZIMUTH_DEG:g} deg; keys '<elev>' radiance [W m^-2 sr^-1 nm^-1] "
                   "(directions, wavelengths), '<elev>_err' its standard error, '<elev>_E' "
                   "the diffuse horizontal irradiance [W m^-2 nm^-1] sum(weights_sr x "
                   "radiance), '<elev>_E_err' its standard error"),
               command=np.str_(" ".join(["python tools/twilight_irradiance_reference.py",
                                         *(argv if argv is not None else sys.argv[1:])])))
    atomic_write(a.out, lambda tmp: np.savez(tmp, **out), suffix=".npz")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
