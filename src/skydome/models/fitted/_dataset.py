"""The data set of the ``fitted`` model: one chunk per atmosphere, computed by the
``precomputed`` reference, and its reader.

A chunk (one atmosphere: aerosol optical depth at 550 nm and ground albedo) is the array
(n_elevations, n_altitudes, N_SKY + N_GROUND + 1, N_PHI, n_wavelengths) float32:

* rows 0 .. N_SKY + N_GROUND - 1: the radiance per unit extraterrestrial irradiance
  [sr^-1] (``PrecomputedSky.radiance_table``) on the view grid of :mod:`._grid`, sun at
  azimuth 180 deg, at each (sun elevation, observer altitude) node (the held-out grid: at
  the centres of the view grid's cells, N_SKY + N_GROUND - 2 rows of N_PHI - 1);
* the last row, azimuth column 0: the sun's disc radiance over E_sun / Omega_sun
  (``sun_radiance`` divided by the extraterrestrial solar radiance; the transmittance
  along the path to the sun times the fraction of the disc above the horizon).

The reference runs with ``cache=False`` (a chunk is computed once; the table cache would
hold a 1.3 GB entry per atmosphere) and its table wavelengths set to
:data:`._grid.WAVELENGTHS_NM` (the fitting wavelengths, every 20 nm) or, for a held-out set
that measures the model between them, to :func:`wavelengths_nm` of a finer step (10 nm:
300, 310, ..., 1100 nm; the 20-nm wavelengths are every other one of them). The reference
computes every order at every table wavelength, each independently of the others (its
default ``high_order_wavelengths=None``), so its values at the shared wavelengths do not
depend on the step.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from skydome.models.fitted import _grid

#: Angstrom exponent of the aerosol (Atmosphere.earth's default).
ANGSTROM_ALPHA = 1.3


def atmosphere(aod: float, albedo: float):
    """The reference atmosphere of a data-set node: ``Atmosphere.earth`` with the aerosol
    optical depth ``aod`` at 550 nm (Angstrom exponent 1.3) and the grey ground albedo
    ``albedo``; every other constituent at its default (ozone 300 DU, water 1.42 cm)."""
    from skydome.atmosphere import Atmosphere

    return Atmosphere.earth(aerosol_optical_depth=float(aod), angstrom_alpha=ANGSTROM_ALPHA,
                            ground_albedo=float(albedo))


def wavelengths_nm(step_nm: float = 20.0) -> np.ndarray:
    """The table wavelengths of a data set [nm]: 300 to 1100 nm every ``step_nm`` (20, the
    fitting wavelengths :data:`._grid.WAVELENGTHS_NM`, or a divisor of 20: 10, 5, 4, 2, 1,
    which keeps every fitting wavelength among them)."""
    step = float(step_nm)
    n = 20.0 / step if step > 0 else 0.0
    if step not in (20.0, 10.0, 5.0, 4.0, 2.0, 1.0) or abs(n - round(n)) > 1e-12:
        raise ValueError(f"wavelength step = {step_nm!r} nm is out of range: one of 20, 10, "
                         "5, 4, 2, 1 nm (a divisor of the fitting wavelengths' 20 nm)")
    if step == 20.0:
        return _grid.WAVELENGTHS_NM.copy()
    k = int(round(800.0 / step))
    return 300.0 + step * np.arange(k + 1, dtype=np.float64)


def gas_band_wavelengths_nm() -> np.ndarray:
    """The table wavelengths of a gas-band supplement [nm]
    (:data:`._grid.GAS_BAND_WAVELENGTHS_NM`: between the 20-nm ones where the gases absorb);
    ``precomputed`` computes each table wavelength independently of the others, so a
    supplement's values are those a 10-nm set would hold there."""
    return _grid.GAS_BAND_WAVELENGTHS_NM.copy()


def chunk_key(aod: float, albedo: float) -> str:
    return f"aod{aod:.3f}_albedo{albedo:.3f}"


def compute_chunk(aod: float, albedo: float, elevations_deg, altitudes_m,
                  midpoints: bool = False, twilight_reference: bool = False,
                  wavelengths=None) -> np.ndarray:
    """One atmosphere's chunk (module docstring), by the ``precomputed`` model; with
    ``midpoints`` on the centres of the view grid's cells (the held-out grid); with
    ``twilight_reference`` in ``precomputed``'s twilight reference configuration (its
    ``twilight_reference=True``, validated to sun -12 deg; about 4x the CPU);
    ``wavelengths`` [nm]: the table wavelengths (default :data:`._grid.WAVELENGTHS_NM`)."""
    import skydome as sd

    el = np.asarray(elevations_deg, dtype=np.float64)
    alt = np.asarray(altitudes_m, dtype=np.float64)
    wl = (_grid.WAVELENGTHS_NM if wavelengths is None
          else np.asarray(wavelengths, dtype=np.float64))
    extra = {"twilight_reference": True} if twilight_reference else {}
    ref = sd.model("precomputed", sun=sd.Sun(elevation_deg=float(el[0]), azimuth_deg=180.0),
                   atmosphere=atmosphere(aod, albedo), table_wavelengths_nm=wl, cache=False,
                   **extra)
    n_dir = _grid.N_SKY + _grid.N_GROUND - (2 if midpoints else 0)
    n_phi = _grid.N_PHI - (1 if midpoints else 0)
    out = np.zeros((el.size, alt.size, n_dir + 1, n_phi, wl.size), dtype=np.float32)
    from skydome.spectra import solar_irradiance

    e_sun = solar_irradiance(wl)
    for j, h in enumerate(alt):
        d = _grid.directions(float(h), 180.0, midpoints)
        for i, e in enumerate(el):
            sun = sd.Sun(elevation_deg=float(e), azimuth_deg=180.0)
            m = ref.with_sun(sun, observer_altitude_m=float(h))
            out[i, j, :n_dir] = m.radiance_table(d)
            out[i, j, n_dir, 0] = m.sun_radiance(wl) * sun.solid_angle_sr / (
                e_sun * sun.irradiance_scale)
    return out


class DataSet:
    """A data-set folder written by tools/fitted_dataset.py: ``grid.json`` (the nodes) and
    one verified chunk per atmosphere (:mod:`skydome.distributed`)."""

    def __init__(self, folder, require_all: bool = True, grid: str = "fit"):
        """``require_all=False``: a data set still being generated (its ``grid.json`` may
        be missing: the grid is then the one named ``grid``, one of
        :data:`._grid.GRID_NAMES`); :attr:`present` lists the atmospheres whose chunk is
        there."""
        self.folder = Path(folder)
        gj = self.folder / "grid.json"
        if gj.is_file() or require_all:
            meta = json.loads(gj.read_text())
        else:
            meta = _grid_meta(grid)
        self.meta = meta
        self.elevations_deg = np.array(meta["elevations_deg"])
        self.altitudes_m = np.array(meta["altitudes_m"])
        self.atmospheres = [tuple(a) for a in meta["atmospheres"]]
        self.wavelengths_nm = np.array(meta["wavelengths_nm"])
        self.midpoints = meta["view_grid"].get("directions") == "cell centres"
        self.present = [(a, b) for a, b in self.atmospheres
                        if (self.folder / (chunk_key(a, b) + ".npy.sha256")).is_file()]
        if not gj.is_file() and self.present:
            # still being generated: its wavelengths from a chunk's last axis (the gas
            # bands' 11 of --gas-bands, the 52 of --with-gas-bands, the earlier files' 8 and
            # 49, the Chappuis band's 3 of --wavelengths 570,590,610, else 300-1100 nm
            # evenly spaced, as --wavelength-step writes them)
            n = np.load(self.folder / (chunk_key(*self.present[0]) + ".npy"),
                        mmap_mode="r").shape[-1]
            known = {v.size: v for v in (_grid.GAS_BAND_WAVELENGTHS_NM,
                                         _grid.TABLE_WAVELENGTHS_NM,
                                         _grid.V7_GAS_BAND_WAVELENGTHS_NM,
                                         _grid.V7_TABLE_WAVELENGTHS_NM,
                                         _grid.CHAPPUIS_WAVELENGTHS_NM)}
            self.wavelengths_nm = (known[n].copy() if n in known
                                   else np.linspace(300.0, 1100.0, n))

    def chunk(self, aod: float, albedo: float) -> np.ndarray:
        """The chunk of one atmosphere (verified against its recorded hash)."""
        from skydome.distributed import assemble_chunks

        return assemble_chunks(self.folder, [chunk_key(aod, albedo)])

    def sky(self, aod, albedo):
        """(radiance (n_e, n_h, N_SKY + N_GROUND, N_PHI, n_wl) [sr^-1], sun factor
        (n_e, n_h, n_wl))."""
        c = self.chunk(aod, albedo)
        return c[:, :, :-1], c[:, :, -1, 0]


def _grid_meta(grid: str) -> dict:
    """The grid.json of a data set of the named grid (as write_grid records it), for a
    data set whose generation has not finished."""
    el, alt, atm, mid = _grid.grid(grid)
    atm = [[float(a), float(b)] for a, b in atm]
    return {"elevations_deg": [float(x) for x in el], "altitudes_m": [float(x) for x in alt],
            "atmospheres": atm, "wavelengths_nm": [float(x) for x in _grid.WAVELENGTHS_NM],
            "view_grid": {"n_sky": _grid.N_SKY, "n_ground": _grid.N_GROUND,
                          "n_phi": _grid.N_PHI, "a_phi": _grid.A_PHI,
                          "directions": "cell centres" if mid else "nodes"},
            "reference": f"precomputed (grid.json not written yet: the {grid} grid assumed)"}


def write_grid(folder, elevations_deg, altitudes_m, atmospheres,
               midpoints: bool = False, twilight_reference: bool = False,
               wavelengths=None) -> None:
    """Record the data set's nodes in ``folder/grid.json`` (atomically); ``wavelengths``
    [nm]: its table wavelengths (default :data:`._grid.WAVELENGTHS_NM`)."""
    from skydome._io import atomic_file

    wl = _grid.WAVELENGTHS_NM if wavelengths is None else np.asarray(wavelengths)

    meta = {"elevations_deg": [float(x) for x in elevations_deg],
            "altitudes_m": [float(x) for x in altitudes_m],
            "atmospheres": [[float(a), float(b)] for a, b in atmospheres],
            "wavelengths_nm": [float(x) for x in wl],
            "view_grid": {"n_sky": _grid.N_SKY, "n_ground": _grid.N_GROUND,
                          "n_phi": _grid.N_PHI, "a_phi": _grid.A_PHI,
                          "directions": "cell centres" if midpoints else "nodes"},
            "reference": ("precomputed (" + ("twilight_reference=True" if twilight_reference
                                             else "defaults")
                          + ", cache=False, table_wavelengths_nm as above)"),
            "written": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    Path(folder).mkdir(parents=True, exist_ok=True)
    with atomic_file(Path(folder) / "grid.json") as tmp:
        Path(tmp).write_text(json.dumps(meta, indent=1))
