"""Polarisation maps as files (``skydome polarisation``): the figure is
:func:`skydome.imaging.plots.plot_polarisation_maps`, the numbers per pixel :func:`write_map_csv`.
The physics is in :mod:`skydome.effects.polarisation_maps`."""

from __future__ import annotations

import numpy as np

__all__ = ["run_polarisation", "write_map_csv"]


def run_polarisation(out, sun, *, method: str = "montecarlo", csv=None, size: int = 48,
                     samples: int = 2000, seed: int = 0, wavelength_nm: float = 550.0,
                     turbidity: float = 2.5) -> tuple[float, float]:
    """Compute the polarisation maps, write the figure ``out`` (and the numbers to ``csv``),
    and return the largest degree of polarisation in the sky with its angle from the sun
    [deg]. If the CSV cannot be written, a figure this call created is removed again."""
    import os

    from skydome._validate import check_int
    from skydome.effects.polarisation_maps import polarisation_maps
    from skydome.imaging.plots import plot_polarisation_maps
    from skydome.imaging.projections import Fisheye

    size = check_int("size", size, 4, 4096)
    kw = dict(samples=samples, seed=seed) if method == "montecarlo" else {}
    pmap = polarisation_maps(method, sun, *Fisheye(size).directions(), wavelength_nm=wavelength_nm,
                             turbidity=turbidity, **kw)
    existed = os.path.exists(out)
    plot_polarisation_maps(pmap, out)
    if csv is not None:
        try:
            write_map_csv(pmap, csv)
        except BaseException:
            if not existed and os.path.exists(out):
                os.unlink(out)
            raise
    sky = pmap.mask & (pmap.dirs[..., 2] > 0)
    i = int(np.nanargmax(np.where(sky, pmap.dop, -1.0)))
    cos = float(np.clip(pmap.dirs.reshape(-1, 3)[i] @ sun.direction, -1.0, 1.0))
    return float(pmap.dop.flat[i]), float(np.degrees(np.arccos(cos)))


def write_map_csv(pmap, path) -> None:
    """Write the sky-disc pixels of ``pmap`` as CSV (atomically): row, col, elevation and
    azimuth [deg], I, Q, U, V, their standard errors, degree and angle [deg] of
    polarisation."""
    from pathlib import Path

    from skydome._io import atomic_file

    from skydome.transport.geometry import angles_from_direction

    path = Path(path)
    rr, cc = np.nonzero(pmap.mask)
    el, az = angles_from_direction(pmap.dirs[rr, cc])
    s, e = pmap.stokes[rr, cc], pmap.stderr[rr, cc]
    cols = [rr, cc, el, az] + [s[:, i] for i in range(4)] + [e[:, i] for i in range(4)] + \
        [pmap.dop[rr, cc], pmap.aop[rr, cc]]
    header = (f"# skydome polarisation map: method {pmap.method}, sun elevation "
              f"{pmap.sun.elevation_deg:g} deg azimuth {pmap.sun.azimuth_deg:g} deg, "
              f"{pmap.wavelength_nm:g} nm; Stokes in W m^-2 sr^-1 nm^-1, frame: reference axis "
              "towards increasing elevation, angle counter-clockwise seen facing the sky\n"
              "row,col,elevation_deg,azimuth_deg,I,Q,U,V,I_err,Q_err,U_err,V_err,dop,aop_deg\n")
    with atomic_file(path) as tmp, open(tmp, "w") as f:
        f.write(header)
        np.savetxt(f, np.column_stack(cols), delimiter=",",
                   fmt=["%d", "%d"] + ["%.4f"] * 2 + ["%.6e"] * 8 + ["%.5f", "%.3f"])


# ---------------------------------------------------------------------------------------
# Solar meridian and neutral points
# ---------------------------------------------------------------------------------------
