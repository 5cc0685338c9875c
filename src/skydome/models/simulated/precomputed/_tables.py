"""The precomputed tables as one typed record.

Every radiance and irradiance in the tables is *per unit extraterrestrial solar spectral
irradiance* (multiply by E_sun(lambda) [W m^-2 nm^-1]). Axis names: ``constituent`` (a
constituent of the atmosphere's optical properties), ``scattering`` (a constituent that
scatters, ``scattering_index`` into the constituents), ``r``, ``mu``, ``mu_s``, ``nu``
(Bruneton's coordinates, mappings in :mod:`._mapping`), ``theta``/``phi`` (the scattering
density's outgoing directions in the sun's frame) and ``wavelength`` (the table
wavelengths, innermost).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np


def _axes(*names, dtype="float32", optional=False):
    meta = {"axes": names, "dtype": dtype}
    return field(default=None, metadata=meta) if optional else field(metadata=meta)


@dataclass
class Tables:
    """The arrays of one precomputation ([Bru17] Model::Precompute), with their axes in
    each field's ``metadata["axes"]`` (see :func:`axes`). The 4-D tables are float32; the
    small tables and coefficients stay float64 (column differences of short paths)."""

    table_wavelengths_nm: np.ndarray = _axes("wavelength", dtype="float64")
    # column density of each constituent from (r, mu) to the top [m] (reference density)
    columns: np.ndarray = _axes("constituent", "r", "mu", dtype="float64")
    # extinction coefficient at reference density [m^-1]
    beta_e: np.ndarray = _axes("constituent", "wavelength", dtype="float64")
    # single scattering per scattering constituent, without its phase function
    single_scattering: np.ndarray = _axes("scattering", "r", "mu", "mu_s", "nu", "wavelength")
    # orders 2..N (+ the geometric remainder), full radiance [sr^-1]
    multiple_scattering: np.ndarray = _axes("r", "mu", "mu_s", "nu", "wavelength")
    # sky irradiance on a horizontal surface, orders 1..N-1 (dimensionless)
    irradiance: np.ndarray = _axes("r", "mu_s", "wavelength", dtype="float64")
    phase_code: np.ndarray = _axes("scattering", dtype="int64")
    phase_param: np.ndarray = _axes("scattering", dtype="float64")
    ground_albedo: np.ndarray = _axes("wavelength", dtype="float64")
    scattering_coefficient: np.ndarray = _axes("scattering", "wavelength", dtype="float64")
    planet_radius_m: float
    top_radius_m: float
    mu_s_min: float
    sun_angular_radius_rad: float
    precompute_seconds: float
    # orders >= 2 only: the scattering density of orders 2..N per unit number density, and
    # the density profiles of the constituents (for the observer's own sky map)
    scattering_density: np.ndarray | None = _axes("scattering", "theta", "phi", "r", "mu_s",
                                                  "wavelength", optional=True)
    profile_code: np.ndarray | None = _axes("constituent", dtype="int64", optional=True)
    profile_p0: np.ndarray | None = _axes("constituent", dtype="float64", optional=True)
    profile_p1: np.ndarray | None = _axes("constituent", dtype="float64", optional=True)
    scattering_index: np.ndarray | None = _axes("scattering", dtype="int64", optional=True)
    # tabulated phase functions only: the atmosphere's table (skydome.transport._phase,
    # uniform in the scattering angle over [0, pi]) on the table wavelengths [sr^-1]
    phase_table: np.ndarray | None = _axes("scattering", "angle", "wavelength", dtype="float64",
                                           optional=True)

    @property
    def has_density(self) -> bool:
        return self.scattering_density is not None

    @property
    def kernel_phase_table(self) -> np.ndarray:
        """``phase_table``, or a zero placeholder (read by no kernel) where every phase
        function is analytic."""
        if self.phase_table is not None:
            return self.phase_table
        return np.zeros((self.phase_code.size, 2, self.table_wavelengths_nm.size))

    def arrays(self) -> dict:
        """Every field as a numpy array (scalars as 0-d arrays; absent optional fields left
        out), for ``np.savez``."""
        out = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if v is not None:
                out[f.name] = np.asarray(v)
        return out

    @classmethod
    def from_arrays(cls, arrays) -> "Tables":
        """Inverse of :meth:`arrays`; ValueError naming a missing or mis-shaped field."""
        kw = {}
        for f in dataclasses.fields(cls):
            if f.name not in arrays:
                if f.default is None:
                    kw[f.name] = None
                    continue
                raise ValueError(f"table {f.name!r} is missing")
            v = np.asarray(arrays[f.name])
            if "axes" in f.metadata:
                if v.ndim != len(f.metadata["axes"]):
                    raise ValueError(f"table {f.name!r} has {v.ndim} axes, expected "
                                     f"{len(f.metadata['axes'])} {f.metadata['axes']}")
                v = np.ascontiguousarray(v, dtype=f.metadata["dtype"])
            else:
                v = float(v)
            kw[f.name] = v
        return cls(**kw)


def axes(name: str) -> tuple:
    """The axis names of field ``name`` of :class:`Tables`."""
    for f in dataclasses.fields(Tables):
        if f.name == name:
            return f.metadata.get("axes", ())
    raise KeyError(name)
