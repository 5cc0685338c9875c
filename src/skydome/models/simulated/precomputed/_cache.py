"""On-disk cache of precomputed tables.

One ``.npz`` file per table set, named by a SHA-256 hash of everything the precomputation
reads: the cache format version, the table wavelengths, the atmosphere's optical properties
on them (radii, density profiles, scattering and extinction coefficients, phase functions,
ground albedo) and every table setting. A different atmosphere field or setting gives a
different key; a file that cannot be read (truncated, corrupt, another format) is deleted
and the tables are recomputed.

Folder: ``$SKYDOME_CACHE_DIR`` if set, else ``platformdirs.user_cache_dir("skydome")`` /
``precomputed``. Size limit: ``$SKYDOME_CACHE_LIMIT_BYTES`` (default 2 GB); after each
write the least recently used files are removed until the folder fits. Files are written
to a temporary name in the folder and renamed, so a reader never sees a partial file.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile

import numpy as np

# bump when the tables' meaning or layout changes (mapping, units, fields)
CACHE_FORMAT = "skydome.precomputed-cache/2"
DEFAULT_LIMIT_BYTES = 2_000_000_000
_SUFFIX = ".npz"


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
    return os.path.join(cache_dir(), k + _SUFFIX)


def load(k: str):
    """The cached :class:`._tables.Tables` under key ``k``, or None (absent or unreadable;
    an unreadable file is removed)."""
    from skydome.models.simulated.precomputed._tables import Tables

    path = _path(k)
    if not os.path.exists(path):
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            if str(z["cache_key"]) != k or str(z["cache_format"]) != CACHE_FORMAT:
                raise ValueError("key mismatch")
            tables = Tables.from_arrays({n: z[n] for n in z.files})
    except Exception:
        _remove(path)
        return None
    try:
        os.utime(path)      # least recently used: the access time is the file's mtime
    except OSError:
        pass
    return tables


def store(k: str, tables) -> str | None:
    """Write ``tables`` under key ``k`` atomically and trim the folder to the size limit;
    returns the path, or None where the folder cannot be written or the tables alone exceed
    the limit (the cache is a convenience: a failure to write it is not an error)."""
    limit = limit_bytes()
    arrays = tables.arrays()
    size = sum(a.nbytes for a in arrays.values())
    if size > limit:
        return None
    folder = cache_dir()
    tmp = None
    try:
        os.makedirs(folder, exist_ok=True)
        fd, tmp = tempfile.mkstemp(suffix=".tmp", prefix=".", dir=folder)
        with os.fdopen(fd, "wb") as f:
            np.savez(f, cache_key=np.array(k), cache_format=np.array(CACHE_FORMAT), **arrays)
        path = _path(k)
        os.replace(tmp, path)
        tmp = None
    except OSError:
        return None
    finally:
        if tmp is not None:
            _remove(tmp)
    _evict(folder, limit, keep=path)
    return path


def _entries(folder):
    out = []
    try:
        names = os.listdir(folder)
    except OSError:
        return out
    for n in names:
        if n.endswith(_SUFFIX) and not n.startswith("."):
            p = os.path.join(folder, n)
            try:
                st = os.stat(p)
            except OSError:
                continue
            out.append((st.st_mtime, st.st_size, p))
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
        os.remove(path)
    except OSError:
        pass


def clear_cache() -> int:
    """Remove every cached table set; returns the number of bytes freed."""
    freed = 0
    for _, size, p in _entries(cache_dir()):
        _remove(p)
        freed += size
    return freed
