"""On-disk cache of precomputed tables.

One folder per table set (an ``.npy`` file per array and ``meta.json``), named by a
SHA-256 hash of everything the precomputation reads: the cache format version, the table wavelengths, the atmosphere's optical properties
on them (radii, density profiles, scattering and extinction coefficients, phase functions,
ground albedo) and every table setting. A different atmosphere field or setting gives a
different key; an entry that cannot be read (truncated, corrupt, another format) is deleted
and the tables are recomputed. The arrays are memory-mapped when read, so a cached start-up
does not read the (hundreds of MB of) tables up front.

The stored 4-D table of orders 2..N is built after the precomputation, on its first read
(:meth:`._tables.Tables.build_multiple_scattering`); it is then added to the same entry as
its own file, ``multiple_scattering.npy`` (:func:`add_stored_table`: built slab by slab of
r nodes straight into a temporary file in the entry, renamed when complete), and a later
cache hit memory-maps it. An entry
without that file (not built yet, or an unreadable file, which is removed) is still a hit:
the table is built again on first use.

Folder: ``$SKYDOME_CACHE_DIR`` if set, else ``platformdirs.user_cache_dir("skydome")`` /
``precomputed``. Size limit: ``$SKYDOME_CACHE_LIMIT_BYTES`` (default 6 GB); after each
write the least recently used files are removed until the folder fits. Files are written
to a temporary name in the folder and renamed, so a reader never sees a partial file.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil

import numpy as np

# bump when the tables' meaning or layout changes (mapping, units, fields)
# 3: the mu axis of _mapping.mu_unit; 4: orders >= 3 from ray integrals, wavelength batches;
# 5: orders >= 3 batched with shared geometry, opt-in coarse grids and stored-table subset;
# 6: the stored table of orders 2..N in its own file, added on first use;
# 7: orders >= 3 at a subset of the table wavelengths; 8: their ratio to order 2 at the
# interpolation nodes kept in float16; 9: the irradiance table of orders 2..N (+ remainder)
# from the summed density (it held orders 2..N-1 and a remainder of its own)
# 10: the precomputation's ray integrals of J (orders >= 3, ground irradiance of orders >= 2)
# by Gauss-Legendre in v (7 nodes per piece; 10 midpoint nodes before)
CACHE_FORMAT = "skydome.precomputed-cache/10"
DEFAULT_LIMIT_BYTES = 6_000_000_000   # four table sets at the default settings (1.3 GB each)
_META = "meta.json"
_STORED = "multiple_scattering"       # the lazily added table's file (without .npy)


def cache_dir() -> str:
    """The cache folder (not created)."""
    env = os.environ.get("SKYDOME_CACHE_DIR")
    if env:
        return os.path.abspath(env)
    import platformdirs

    return os.path.join(platformdirs.user_cache_dir("skydome"), "precomputed")


def limit_bytes() -> int:
    """The size limit of the cache folder [bytes]."""
    env = os.environ.get("SKYDOME_CACHE_LIMIT_BYTES")
    if env is None or env == "":
        return DEFAULT_LIMIT_BYTES
    try:
        v = float(env)
    except ValueError:
        v = float("nan")
    if not (v >= 0 and np.isfinite(v)):
        raise ValueError(f"SKYDOME_CACHE_LIMIT_BYTES = {env!r} is not valid: give a size in "
                         "bytes, >= 0")
    return int(v)


def key(props, settings: dict) -> str:
    """Hex SHA-256 of the format version, the optical properties and the settings."""
    h = hashlib.sha256()
    h.update(CACHE_FORMAT.encode())
    h.update(json.dumps(settings, sort_keys=True, default=str).encode())
    for name in props._fields:
        h.update(name.encode())
        if getattr(props, name) is None:
            h.update(b"None")
            continue
        v = np.ascontiguousarray(np.asarray(getattr(props, name), dtype=None))
        if v.dtype == object:
            raise TypeError(f"optical property {name} is not numeric: cannot key the cache")
        h.update(str(v.dtype).encode() + str(v.shape).encode())
        h.update(v.tobytes())
    return h.hexdigest()


def _path(k: str) -> str:
    return os.path.join(cache_dir(), k)


def load(k: str):
    """The cached :class:`._tables.Tables` under key ``k``, or None (absent or unreadable;
    an unreadable entry is removed). The arrays are memory-mapped copy-on-write, so the
    start-up reads only the header of each file and pages come in as the tables are used."""
    from skydome.models.simulated.precomputed._tables import Tables

    path = _path(k)
    if not os.path.isdir(path):
        return None
    try:
        with open(os.path.join(path, _META)) as f:
            meta = json.load(f)
        if meta.get("cache_key") != k or meta.get("cache_format") != CACHE_FORMAT:
            raise ValueError("key mismatch")
        arrays = dict(meta["scalars"])
        for name in meta["arrays"]:
            arrays[name] = _map(os.path.join(path, name + ".npy"))
        tables = Tables.from_arrays(arrays)
    except Exception:
        _remove(path)
        return None
    if not tables.has_multiple_scattering:
        _load_stored_table(path, tables)
    try:
        os.utime(os.path.join(path, _META))   # least recently used: the meta file's mtime
    except OSError:
        pass
    return tables


def _map(file):
    return np.asarray(np.load(file, mmap_mode="c", allow_pickle=False))


def _load_stored_table(path, tables):
    """Memory-map the entry's stored table into ``tables`` where the file is there and
    matches the tables (float32, the single-scattering table's shape without its first
    axis); an unreadable or mismatched file is removed (the table is built again on use)."""
    file = os.path.join(path, _STORED + ".npy")
    if not os.path.exists(file):
        return
    try:
        ms = _map(file)
        if ms.dtype != np.float32 or ms.shape != tables.single_scattering.shape[1:]:
            raise ValueError(f"stored table of shape {ms.shape}, {ms.dtype}")
    except Exception:
        _remove(file)
        return
    tables.multiple_scattering = ms


def add_stored_table(k: str, shape, slabs):
    """Write the stored table of orders 2..N into entry ``k`` as its own file, from its
    consecutive r slabs ``slabs`` (float32; one slab in memory at a time), to a temporary
    name in the entry renamed when complete (nothing partial under the final name if the
    write is interrupted), then trim the cache to the size limit; returns the table
    memory-mapped from that file, or None where the entry is gone or cannot be written
    (the caller then builds the table in memory)."""
    from skydome._io import atomic_file

    path = _path(k)
    file = os.path.join(path, _STORED + ".npy")
    shape = tuple(int(n) for n in shape)
    try:
        with open(os.path.join(path, _META)) as f:
            meta = json.load(f)
        if meta.get("cache_key") != k or meta.get("cache_format") != CACHE_FORMAT:
            return None
        with atomic_file(file, suffix=".npy") as tmp:
            with open(tmp, "wb") as f:
                np.lib.format.write_array_header_1_0(
                    f, {"descr": np.lib.format.dtype_to_descr(np.dtype(np.float32)),
                        "fortran_order": False, "shape": shape})
                rows = 0
                for slab in slabs:
                    slab = np.ascontiguousarray(slab, dtype=np.float32)
                    if slab.shape[1:] != shape[1:]:
                        raise ValueError(f"slab of shape {slab.shape} for a table {shape}")
                    f.write(memoryview(slab).cast("B"))
                    rows += slab.shape[0]
                if rows != shape[0]:
                    raise ValueError(f"{rows} r rows written for a table {shape}")
        out = _map(file)
    except (OSError, ValueError):
        return None
    _evict(cache_dir(), limit_bytes(), keep=path)
    return out


def store(k: str, tables) -> str | None:
    """Write ``tables`` under key ``k`` (a folder of ``.npy`` files and ``meta.json``,
    written under a temporary name and renamed; the stored table of orders 2..N only where
    it is built, else :func:`add_stored_table` adds it later) and trim the cache to the
    size limit; returns the path, or None where the folder cannot be written or the tables
    alone exceed the limit (the cache is a convenience: a failure to write it is not an
    error)."""
    limit = limit_bytes()
    arrays = tables.arrays()
    if sum(a.nbytes for a in arrays.values()) > limit:
        return None
    from skydome._io import atomic_folder

    folder = cache_dir()
    path = _path(k)
    try:
        os.makedirs(folder, exist_ok=True)
        if os.path.isdir(path):
            _remove(path)
        with atomic_folder(path) as tmp:
            names, scalars = [], {}
            for name, a in arrays.items():
                if a.ndim == 0:
                    scalars[name] = a.item()
                else:
                    np.save(os.path.join(tmp, name + ".npy"), a, allow_pickle=False)
                    names.append(name)
            with open(os.path.join(tmp, _META), "w") as f:
                json.dump({"cache_key": k, "cache_format": CACHE_FORMAT, "arrays": names,
                           "scalars": scalars}, f)
    except (OSError, ValueError):   # ValueError: the cache folder is not writable
        return None
    _evict(folder, limit, keep=path)
    return path


def _size(path) -> int:
    total = 0
    for d, _, files in os.walk(path):
        for f in files:
            try:
                total += os.path.getsize(os.path.join(d, f))
            except OSError:
                pass
    return total


def _entries(folder):
    """(last use, size [bytes], path) of every cache entry, least recently used first."""
    out = []
    try:
        names = os.listdir(folder)
    except OSError:
        return out
    for n in names:
        p = os.path.join(folder, n)
        if n.startswith(".") or not os.path.isdir(p):
            continue
        try:
            used = os.stat(os.path.join(p, _META)).st_mtime
        except OSError:
            used = 0.0      # incomplete entry: first to go
        out.append((used, _size(p), p))
    return sorted(out)


def _evict(folder, limit, keep=None):
    entries = _entries(folder)
    total = sum(e[1] for e in entries)
    for _, size, p in entries:
        if total <= limit:
            break
        if p == keep:
            continue
        _remove(p)
        total -= size


def _remove(path):
    try:
        if os.path.isdir(path):
            shutil.rmtree(path)
        else:
            os.remove(path)
    except OSError:
        pass


def clear_cache() -> int:
    """Remove every cached table set (and temporary folders left by interrupted writes);
    returns the number of bytes freed."""
    folder = cache_dir()
    freed = 0
    for _, size, p in _entries(folder):
        _remove(p)
        freed += size
    try:
        names = os.listdir(folder)
    except OSError:
        names = []
    for n in names:
        if n.startswith(".") and n.endswith(".tmp"):
            p = os.path.join(folder, n)
            freed += _size(p)
            _remove(p)
    return freed
