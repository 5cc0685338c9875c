"""On-disk cache of precomputed tables.

One folder per table set (an ``.npy`` file per array and ``meta.json``), named by a
SHA-256 hash of everything the precomputation reads: the cache format version, the table wavelengths, the atmosphere's optical properties
on them (radii, density profiles, scattering and extinction coefficients, phase functions,
ground albedo) and every table setting. A different atmosphere field or setting gives a
different key; an entry that cannot be read (truncated, corrupt, another format) is deleted
and the tables are recomputed. The arrays are memory-mapped when read.

**Verified on load.** ``meta.json`` records, for every array, its dtype, shape and the CRC-32
(:func:`zlib.crc32`) of its bytes, computed as the array is written; a load reads every array
once, compares its CRC-32 and checks that it holds finite values only. An entry that fails
(flipped bytes, a NaN, a missing checksum) is deleted and rebuilt, with one line on stderr
naming the entry; the stored table of orders 2..N (below) is checked the same way and, where
it fails, removed and built again on first use. Cost: the whole entry is read once per load
(CRC-32 runs at 2.2 GB/s, the finiteness check at about 10 GB/s on one core of the 2-core EPYC
of docs/performance.md; BLAKE2b at 0.74 GB/s would triple it); docs/performance.md gives the
load times measured.

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
to a temporary name in the folder and renamed, so a reader never sees a partial file. A write
that fails (a full disk, a read-only folder) is not an error: the tables are used from memory,
and the process says so once, in one line on stderr.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import sys
import zlib

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
# 11: meta.json holds every array's CRC-32, dtype and shape ("checksums"), checked on load
CACHE_FORMAT = "skydome.precomputed-cache/11"
DEFAULT_LIMIT_BYTES = 6_000_000_000   # four table sets at the default settings (1.3 GB each)
_META = "meta.json"
_STORED = "multiple_scattering"       # the lazily added table's file (without .npy)
_CHECK_BYTES = 1 << 24                # bytes per step of the load-time check (16 MiB)
_WRITE_FAILED_SAID = False            # the "could not be written" line, once per process


class DamagedEntry(ValueError):
    """A cache entry whose content does not match its recorded checksum, or is not finite."""


def _note(text: str) -> None:
    """One line on stderr."""
    try:
        print("skydome: " + " ".join(text.split()), file=sys.stderr, flush=True)
    except (OSError, ValueError):   # no stderr to write to: the note is not essential
        pass


def _write_failed(folder, exc: BaseException) -> None:
    """Say once per process that the cache could not be written (and why)."""
    global _WRITE_FAILED_SAID
    if _WRITE_FAILED_SAID:
        return
    _WRITE_FAILED_SAID = True
    if isinstance(exc, OSError):
        why = exc.strerror or " ".join(str(exc).split())
    else:
        why = "the folder is not writable"
    _note(f"the table cache in {folder} could not be written ({why}); the tables are used "
          "from memory and computed again in the next process")


def _check(a: np.ndarray, crc: int = 0) -> tuple[int, bool]:
    """(CRC-32 of the bytes of C-contiguous ``a`` continuing ``crc``, whether every value is
    finite), in one pass of :data:`_CHECK_BYTES` steps (each step still in cache for the
    second look)."""
    flat = a.reshape(-1)
    floating = np.issubdtype(a.dtype, np.floating)
    step = max(1, _CHECK_BYTES // max(1, a.itemsize))
    finite = True
    for i in range(0, flat.size, step):
        part = flat[i:i + step]
        crc = zlib.crc32(memoryview(part).cast("B"), crc)
        if floating and finite and not np.isfinite(part).all():
            finite = False
    return crc, finite


def _record(a: np.ndarray, crc: int) -> dict:
    return {"crc32": int(crc), "dtype": a.dtype.str, "shape": [int(n) for n in a.shape]}


def _verify(name: str, a: np.ndarray, rec) -> None:
    """DamagedEntry unless ``a`` matches its record ``rec`` and is finite."""
    if not isinstance(rec, dict):
        raise DamagedEntry(f"{name}.npy has no checksum")
    if a.dtype.str != rec.get("dtype") or list(a.shape) != rec.get("shape") or \
            not a.flags.c_contiguous:
        raise DamagedEntry(f"{name}.npy has shape {a.shape} {a.dtype}, recorded "
                           f"{rec.get('shape')} {rec.get('dtype')}")
    crc, finite = _check(a)
    if crc != rec.get("crc32"):
        raise DamagedEntry(f"the checksum of {name}.npy does not match")
    if not finite:
        raise DamagedEntry(f"{name}.npy holds NaN or infinite values")


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
        sums = meta.get("checksums")
        if not isinstance(sums, dict):
            raise DamagedEntry("meta.json has no checksums")
        for name in meta["arrays"]:
            arrays[name] = _map(os.path.join(path, name + ".npy"))
            _verify(name, arrays[name], sums.get(name))
        tables = Tables.from_arrays(arrays)
    except Exception as exc:
        _remove(path)
        _note(f"table cache entry {path} is damaged ({_reason(exc)}); rebuilding it")
        return None
    if not tables.has_multiple_scattering:
        _load_stored_table(path, tables, meta)
    try:
        os.utime(os.path.join(path, _META))   # least recently used: the meta file's mtime
    except OSError:
        pass
    return tables


def _map(file):
    return np.asarray(np.load(file, mmap_mode="c", allow_pickle=False))


def _reason(exc: BaseException) -> str:
    """A short reason for the note on a damaged entry."""
    if isinstance(exc, DamagedEntry):
        return str(exc)
    if isinstance(exc, FileNotFoundError):
        return f"{os.path.basename(exc.filename or '')} is missing"
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 120 else text[:117] + "..."


def _load_stored_table(path, tables, meta):
    """Memory-map the entry's stored table into ``tables`` where the file is there, matches
    the tables (float32, the single-scattering table's shape without its first axis) and its
    recorded checksum, and is finite; a file that fails is removed (the table is built again
    on use), with a note on stderr."""
    file = os.path.join(path, _STORED + ".npy")
    if not os.path.exists(file):
        return
    try:
        ms = _map(file)
        if ms.dtype != np.float32 or ms.shape != tables.single_scattering.shape[1:]:
            raise DamagedEntry(f"{_STORED}.npy has shape {ms.shape} {ms.dtype}")
        _verify(_STORED, ms, meta["checksums"].get(_STORED))
    except Exception as exc:
        _remove(file)
        _note(f"table cache entry {path} is damaged ({_reason(exc)}); its table of orders "
              "2..N is built again when used")
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
    meta_file = os.path.join(path, _META)
    shape = tuple(int(n) for n in shape)
    try:
        with open(meta_file) as f:
            meta = json.load(f)
        if meta.get("cache_key") != k or meta.get("cache_format") != CACHE_FORMAT:
            return None
        with atomic_file(file, suffix=".npy") as tmp:
            with open(tmp, "wb") as f:
                np.lib.format.write_array_header_1_0(
                    f, {"descr": np.lib.format.dtype_to_descr(np.dtype(np.float32)),
                        "fortran_order": False, "shape": shape})
                rows, crc = 0, 0
                for slab in slabs:
                    slab = np.ascontiguousarray(slab, dtype=np.float32)
                    if slab.shape[1:] != shape[1:]:
                        raise ValueError(f"slab of shape {slab.shape} for a table {shape}")
                    crc, finite = _check(slab, crc)
                    if not finite:
                        raise ValueError("the stored table holds NaN or infinite values")
                    f.write(memoryview(slab).cast("B"))
                    rows += slab.shape[0]
                if rows != shape[0]:
                    raise ValueError(f"{rows} r rows written for a table {shape}")
            # its checksum joins meta.json before the file gets its name: a file under the
            # final name always has a record (an interrupted write leaves neither, or a
            # record without its file, which is no table)
            meta.setdefault("checksums", {})[_STORED] = {
                "crc32": int(crc), "dtype": np.dtype(np.float32).str, "shape": list(shape)}
            with atomic_file(meta_file) as mtmp, open(mtmp, "w") as f:
                json.dump(meta, f)
        out = _map(file)
    except OSError as exc:
        _write_failed(path, exc)
        return None
    except ValueError:
        return None
    _evict(cache_dir(), limit_bytes(), keep=path)
    return out


class _NotFinite(Exception):
    pass


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
    from skydome._io import atomic_folder, write_npy

    folder = cache_dir()
    path = _path(k)
    try:
        os.makedirs(folder, exist_ok=True)
        if os.path.isdir(path):
            _remove(path)
        with atomic_folder(path) as tmp:
            names, scalars, sums = [], {}, {}
            for name, a in arrays.items():
                if a.ndim == 0:
                    scalars[name] = a.item()
                    continue
                a = np.ascontiguousarray(a)
                crc, finite = _check(a)
                if not finite:    # never cache a table that is not finite
                    raise _NotFinite(name)
                write_npy(os.path.join(tmp, name + ".npy"), a)
                names.append(name)
                sums[name] = _record(a, crc)
            with open(os.path.join(tmp, _META), "w") as f:
                json.dump({"cache_key": k, "cache_format": CACHE_FORMAT, "arrays": names,
                           "scalars": scalars, "checksums": sums}, f)
    except _NotFinite:
        return None
    except (OSError, ValueError) as exc:   # ValueError: the cache folder is not writable
        _write_failed(folder, exc)
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
