"""The precomputed tables as one typed record.

Every radiance and irradiance in the tables is *per unit extraterrestrial solar spectral
irradiance* (multiply by E_sun(lambda) [W m^-2 nm^-1]). Axis names: ``constituent`` (a
constituent of the atmosphere's optical properties), ``scattering`` (a constituent that
scatters, ``scattering_index`` into the constituents), ``r``, ``mu``, ``mu_s``, ``nu``
(Bruneton's coordinates, mappings in :mod:`._mapping`), ``theta``/``phi`` (the scattering
density's outgoing directions in the sun's frame) and ``wavelength`` (the table
wavelengths, innermost).

The stored 4-D table of orders 2..N (``multiple_scattering``) is built on first use from
the summed scattering density and the column table by the builder the precomputation gives
the record (:meth:`Tables.build_multiple_scattering`; the record imports no kernel):
the sky's ``radiance()`` integrates orders 2..N at the observer and never reads it; aerial
perspective, the texture/LUT export and the viewer do.

The scattering density may be held in part (the on-disk cache decodes at its load only the
mu_s rows the observer's rays reach, :meth:`Tables.set_scattering_density_part`): the
observer's sky reads those rows (:meth:`Tables.scattering_density_rows`); the first read of
``scattering_density`` itself decodes the whole table.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np


def _axes(*names, dtype="float32", optional=False):
    meta = {"axes": names, "dtype": dtype}
    return field(default=None, metadata=meta) if optional else field(metadata=meta)


def _scalar(kind, default):
    return field(default=default, metadata={"scalar": kind})


# the lazily built fields (see Tables.multiple_scattering, Tables.single_scattering,
# Tables.scattering_density)
_LAZY = "multiple_scattering"
_LAZY_SS = "single_scattering"
_LAZY_J = "scattering_density"


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
    # sky irradiance on a horizontal surface, orders 1..N and the remainder (dimensionless)
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
    # single scattering per scattering constituent, without its phase function: None until
    # first read where a builder is given (computed then from the columns and the medium,
    # see build_single_scattering; the on-disk cache does not store it)
    single_scattering: np.ndarray | None = _axes("scattering", "r", "mu", "mu_s", "nu",
                                                 "wavelength", optional=True)
    # orders 2..N (+ the geometric remainder), full radiance [sr^-1]: None until first read
    # (built then from scattering_density, see build_multiple_scattering; zeros without it)
    multiple_scattering: np.ndarray | None = _axes("r", "mu", "mu_s", "nu", "wavelength",
                                                   optional=True)
    # how the stored table is integrated: quadrature nodes per ray piece, and "full" (every
    # node) or "subset" (_precompute.stored_table_nodes, interpolated)
    stored_table_samples: int = _scalar("int", 0)
    stored_table: str = _scalar("str", "full")
    # the single-scattering table's first two r nodes (a ground observer's), kept where the
    # whole table is not (the on-disk cache): single_scattering_rows(0, 2) reads them
    single_scattering_ground: np.ndarray | None = _axes("scattering", "r", "mu", "mu_s", "nu",
                                                        "wavelength", optional=True)
    # the 4-D tables' (r, mu, mu_s, nu) node counts, and the single-scattering table's
    # quadrature nodes per ray piece (what build_single_scattering needs; 0: not recorded)
    scattering_shape: np.ndarray | None = _axes("axis", dtype="int64", optional=True)
    single_scattering_samples: int = _scalar("int", 0)

    @property
    def has_density(self) -> bool:
        """Whether the tables hold the scattering density (decoded or still to decode: this
        does not decode it)."""
        return (self.__dict__.get("_" + _LAZY_J) is not None
                or self.__dict__.get("_density_whole") is not None)

    @property
    def density_shape(self) -> tuple:
        """The scattering density's shape (scattering, theta, phi, r, mu_s, wavelength),
        without decoding it; () where the tables have none."""
        J = self.__dict__.get("_" + _LAZY_J)
        if J is not None:
            return tuple(int(n) for n in J.shape)
        return tuple(self.__dict__.get("_density_shape", ()))

    def set_scattering_density_part(self, part, first: int, whole) -> None:
        """The scattering density held in part until it is read whole (the on-disk cache,
        :func:`._cache.load`): ``part`` its mu_s rows ``first`` .. ``first +
        part.shape[4] - 1`` (C-contiguous float32, the values of the whole table; none
        where ``part.shape[4]`` is 0), and ``whole`` an object whose ``shape`` is the
        table's and whose ``read()`` returns the whole table, decoded and checked then, on
        the first read of :attr:`scattering_density` (it must not hold these tables: a
        reference cycle would keep them alive until the cyclic collector runs)."""
        self.__dict__["_" + _LAZY_J] = None
        self.__dict__["_density_part"] = (part, int(first))
        self.__dict__["_density_whole"] = whole
        self.__dict__["_density_shape"] = tuple(int(n) for n in whole.shape)

    def scattering_density_rows(self, first: int, end: int):
        """(J, j0): an array J that holds the scattering density's mu_s rows first..end-1
        (at least) as its rows ``first - j0`` .., in the whole table's values, for a kernel
        that reads only those rows (:func:`._multiple.multiple_scattering_slice`'s ``ms0``):
        the part the cache decoded (:meth:`set_scattering_density_part`) where it holds
        them, else the whole table (j0 = 0), decoded now on its first read."""
        J = self.__dict__.get("_" + _LAZY_J)
        if J is None:
            held = self.__dict__.get("_density_part")
            if held is not None:
                part, j0 = held
                if j0 <= first and end <= j0 + part.shape[4] and end > first:
                    return part, j0
            J = self.scattering_density
        return J, 0

    @property
    def table_shape(self) -> tuple:
        """(n_r, n_mu, n_mu_s, n_nu, n_wavelengths) of the 4-D tables (single scattering
        without its first axis, the stored table of orders 2..N)."""
        ss = self.__dict__.get("_" + _LAZY_SS)
        if ss is not None:
            return tuple(int(n) for n in ss.shape[1:])
        if self.scattering_shape is None:
            raise ValueError("the tables hold neither single scattering nor its shape "
                             "(scattering_shape)")
        return tuple(int(n) for n in self.scattering_shape) + (self.table_wavelengths_nm.size,)

    @property
    def has_single_scattering(self) -> bool:
        """Whether the single-scattering table is computed (or was read)."""
        return self.__dict__.get("_" + _LAZY_SS) is not None

    def build_single_scattering(self) -> np.ndarray:
        """The single-scattering table: computed now if it is not yet, by the builder that
        :meth:`set_single_scattering_builder` gave (the precomputation's step 2 on the
        columns and medium these tables hold: the same values, bit for bit). ValueError
        where it is not there and no builder was given."""
        ss = self.__dict__.get("_" + _LAZY_SS)
        if ss is not None:
            return ss
        builder = self.__dict__.get("_ss_builder")
        if builder is None:
            raise ValueError("the single-scattering table is not computed and these tables "
                             "have no builder: give one with set_single_scattering_builder")
        self.single_scattering = builder(self, None)
        return self.__dict__["_" + _LAZY_SS]

    def single_scattering_rows(self, first: int, end: int) -> np.ndarray:
        """The single-scattering table's r nodes first..end-1 (scattering, rows, mu, mu_s,
        nu, wavelength): a view of the table where it is there, else only those rows
        computed (the same values as the table's; the observer's two r nodes cost 2 / n_r
        of the table), kept for the next call with the same rows."""
        ss = self.__dict__.get("_" + _LAZY_SS)
        if ss is not None:
            return ss[:, first:end]
        ground = self.single_scattering_ground
        if ground is not None and end <= ground.shape[1]:
            return ground[:, first:end]
        rows = self.__dict__.setdefault("_ss_rows", {})
        if (first, end) not in rows:
            builder = self.__dict__.get("_ss_builder")
            if builder is None:
                return self.build_single_scattering()[:, first:end]
            if len(rows) >= 4:       # 31 MB each at the defaults: a few altitudes
                rows.clear()
            rows[(first, end)] = builder(self, (first, end))
        return rows[(first, end)]

    def single_scattering_slabs(self, step: int):
        """The single-scattering table's r nodes in slabs of ``step``: yields (first, end,
        rows), rows = the table's r nodes first..end-1 as :meth:`single_scattering_rows`
        gives them (the same values), but a slab computed here is not kept: a pass over the
        whole table (the LUT bake's) holds one slab at a time instead of the table (503 MB
        at the default sizes)."""
        if int(step) < 1:
            raise ValueError(f"step = {step!r} is not a number of r nodes >= 1")
        n_r = self.table_shape[0]
        ss = self.__dict__.get("_" + _LAZY_SS)
        builder = self.__dict__.get("_ss_builder")
        for first in range(0, n_r, int(step)):
            end = min(n_r, first + int(step))
            if ss is not None:
                yield first, end, ss[:, first:end]
            elif builder is None:
                yield first, end, self.build_single_scattering()[:, first:end]
            else:
                yield first, end, builder(self, (first, end))

    def set_single_scattering_builder(self, builder) -> None:
        """How the single-scattering table is computed when it is not there:
        ``builder(tables, rows)`` -> float32 array, the whole table (``rows`` None) or its r
        nodes ``rows = (first, end)``."""
        self.__dict__["_ss_builder"] = builder

    @property
    def kernel_phase_table(self) -> np.ndarray:
        """``phase_table``, or a zero placeholder (read by no kernel) where every phase
        function is analytic."""
        if self.phase_table is not None:
            return self.phase_table
        return np.zeros((self.phase_code.size, 2, self.table_wavelengths_nm.size))

    @property
    def has_multiple_scattering(self) -> bool:
        """Whether the stored table of orders 2..N is built (or was read)."""
        return self.__dict__.get("_" + _LAZY) is not None

    def build_multiple_scattering(self) -> np.ndarray:
        """The stored table of orders 2..N: built now if it is not yet, by the builder that
        :meth:`set_multiple_scattering_builder` gave (the precomputation's step 4,
        :func:`._precompute.attach_stored_table_builder`). Where
        :meth:`set_multiple_scattering_sink` gave a sink (the on-disk cache), the table is
        built slab by slab of r nodes straight into it and the array it returns is kept;
        without one, or where it returns None (it could not write), the table is built in
        memory. ValueError where the table is not built and no builder was given."""
        ms = self.__dict__.get("_" + _LAZY)
        if ms is not None:
            return ms
        builder = self.__dict__.get("_builder")
        if builder is None:
            raise ValueError("the stored table of orders 2..N (multiple_scattering) is not "
                             "built and these tables have no builder: give one with "
                             "set_multiple_scattering_builder")
        whole, slabs = builder
        sink = self.__dict__.get("_sink")
        reader = self.__dict__.pop("_reader", None)
        if reader is not None:
            ms = reader(self)       # the table from a file (None: unreadable, built again)
            if ms is not None:
                self.multiple_scattering = ms
                return self.__dict__["_" + _LAZY]
        if sink is not None:
            ms = sink(self.table_shape, slabs(self))
        if ms is None:
            ms = whole(self)
        self.multiple_scattering = ms
        return ms

    def set_multiple_scattering_builder(self, whole, slabs) -> None:
        """How the stored table is built on first use: ``whole(tables) -> array`` (float32,
        the single-scattering table's shape without its first axis) and
        ``slabs(tables) -> iterator`` of its consecutive r slabs (for a sink)."""
        self.__dict__["_builder"] = (whole, slabs)

    def set_multiple_scattering_reader(self, reader) -> None:
        """``reader(tables) -> array or None``: where the stored table is on disk (the
        cache), how it is read on first use (before any builder); None: it could not be,
        build it. The tables are passed in, not held by the reader: a closure over them
        would make a reference cycle, which keeps the tables' arrays (hundreds of MB) alive
        until Python's cyclic collector runs, which large arrays do not set off."""
        self.__dict__["_reader"] = reader

    def set_multiple_scattering_sink(self, sink) -> None:
        """``sink(shape, slabs) -> array or None``: called when the stored table is built,
        with its shape and an iterator of its consecutive r slabs (float32); returns the
        whole table (e.g. memory-mapped from the file the slabs went to), or None."""
        self.__dict__["_sink"] = sink

    def arrays(self) -> dict:
        """Every field as a numpy array (scalars as 0-d arrays; absent optional fields and
        the stored table of orders 2..N while it is not built left out), for ``np.savez``."""
        out = {}
        for f in dataclasses.fields(self):
            v = (self.__dict__.get("_" + f.name) if f.name in (_LAZY, _LAZY_SS)
                 else getattr(self, f.name))
            if v is not None:
                out[f.name] = np.asarray(v)
        return out

    @classmethod
    def from_arrays(cls, arrays) -> "Tables":
        """Inverse of :meth:`arrays`; ValueError naming a missing or mis-shaped field."""
        kw = {}
        for f in dataclasses.fields(cls):
            if f.name not in arrays:
                if f.default is not dataclasses.MISSING:
                    kw[f.name] = f.default
                    continue
                raise ValueError(f"table {f.name!r} is missing")
            v = np.asarray(arrays[f.name])
            if "scalar" in f.metadata:
                v = {"int": int, "str": str}[f.metadata["scalar"]](v.item() if v.ndim == 0 else v)
            elif "axes" in f.metadata:
                if v.ndim != len(f.metadata["axes"]):
                    raise ValueError(f"table {f.name!r} has {v.ndim} axes, expected "
                                     f"{len(f.metadata['axes'])} {f.metadata['axes']}")
                v = np.ascontiguousarray(v, dtype=f.metadata["dtype"])
            else:
                v = float(v)
            kw[f.name] = v
        return cls(**kw)


def _get_scattering_density(self):
    J = self.__dict__.get("_" + _LAZY_J)
    if J is None:
        whole = self.__dict__.get("_density_whole")
        if whole is not None:
            J = whole.read()      # decoded once (the reader keeps it; it is thread-safe)
            self.__dict__["_" + _LAZY_J] = J
            self.__dict__.pop("_density_part", None)
            self.__dict__.pop("_density_whole", None)
    return J


def _set_scattering_density(self, value):
    self.__dict__["_" + _LAZY_J] = value          # as given (as the plain field held it)
    self.__dict__.pop("_density_part", None)
    self.__dict__.pop("_density_whole", None)


def _get_multiple_scattering(self):
    ms = self.__dict__.get("_" + _LAZY)
    return ms if ms is not None else self.build_multiple_scattering()


def _set_multiple_scattering(self, value):
    self.__dict__["_" + _LAZY] = (None if value is None
                                  else np.ascontiguousarray(value, dtype=np.float32))


def _get_single_scattering(self):
    ss = self.__dict__.get("_" + _LAZY_SS)
    return ss if ss is not None else self.build_single_scattering()


def _set_single_scattering(self, value):
    self.__dict__["_" + _LAZY_SS] = (None if value is None
                                     else np.ascontiguousarray(value, dtype=np.float32))


# the field as a property (set after @dataclass, which took its default None for __init__):
# reading it builds the table on first use; None (the default) leaves it to be built
Tables.multiple_scattering = property(
    _get_multiple_scattering, _set_multiple_scattering,
    doc="orders 2..N (+ the geometric remainder), full radiance per unit solar irradiance "
        "[sr^-1], axes (r, mu, mu_s, nu, wavelength); built on first read")


# the scattering density: where the on-disk cache decoded a part of it (the rows the
# observer's rays reach), the whole table is decoded on its first read
Tables.scattering_density = property(
    _get_scattering_density, _set_scattering_density,
    doc="the scattering density of orders 2..N per unit number density, axes (scattering, "
        "theta, phi, r, mu_s, wavelength), or None; where the on-disk cache read only a "
        "part of it (set_scattering_density_part), decoded whole on first read")


# the same for single scattering: computed on first read where the tables do not hold it
Tables.single_scattering = property(
    _get_single_scattering, _set_single_scattering,
    doc="single scattering per scattering constituent without its phase function, per unit "
        "solar irradiance, axes (scattering, r, mu, mu_s, nu, wavelength); computed on first "
        "read where it is not held")


def axes(name: str) -> tuple:
    """The axis names of field ``name`` of :class:`Tables`."""
    for f in dataclasses.fields(Tables):
        if f.name == name:
            return f.metadata.get("axes", ())
    raise KeyError(name)
