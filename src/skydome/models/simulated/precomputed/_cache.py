"""On-disk cache of precomputed tables.

One folder per table set (an ``.npy`` file per array and ``meta.json``), named by a
SHA-256 hash of everything the precomputation reads: the cache format version, the table wavelengths, the atmosphere's optical properties
on them (radii, density profiles, scattering and extinction coefficients, phase functions,
ground albedo) and every table setting. A different atmosphere field or setting gives a
different key; an entry that cannot be read (truncated, corrupt, another format) is deleted
and the tables are recomputed. The arrays are memory-mapped when read.

**Stored in the precision the sky needs.** Tables of at least :data:`HALF_MIN_BYTES` are
stored as float16 with a power-of-two scale per row of wavelengths (``<name>.npy`` and its
int8 exponents ``<name>.exp.npy``; relative rounding <= 2^-11 = 4.9e-4 per value, and no
underflow within 2^28 of the row's largest value) and decoded to float32 when read; the
single-scattering table is not stored where the entry can compute it again (it is, from the
columns and the medium the entry holds, bit for bit: the observer's two r nodes for the
sky's radiance, the whole table on first use for aerial perspective and the exports),
except its first two r nodes (``single_scattering_ground``, a ground observer's, as they
are). A
model whose tables are stored serves the decoded values from then on, so that a cache hit
serves what the first build did. docs/performance.md gives the sizes and the accuracy cost.

**Verified on load.** ``meta.json`` records, for every array, its dtype, shape and the CRC-32
(:func:`zlib.crc32`) of its bytes, computed as the array is written; a load reads every array
once, compares its CRC-32 and checks that it holds finite values only. An entry that fails
(flipped bytes, a NaN, a missing checksum) is deleted and rebuilt, with one line on stderr
naming the entry; the stored table of orders 2..N (below) is checked the same way and, where
it fails, removed and built again on first use. Cost: the whole entry is read once per load
(CRC-32 runs at 2.2 GB/s, the finiteness check at about 10 GB/s on one core of the 2-core EPYC
of docs/performance.md; BLAKE2b at 0.74 GB/s would triple it); docs/performance.md gives the
load times measured. A half-precision table's finiteness is found on its float16 bits as they
are decoded (:func:`_decode_half_checked`), in the same pass. The scattering density is
checked in bands instead (below).

**The scattering density read in part.** A model that renders the observer's sky reads the
scattering density only at the sun cosines its own rays reach (:mod:`._reach`: about a
fifth of the default table's mu_s rows with the sun at 30 deg), so :func:`load` decodes
only those rows where the caller names them (``density_rows``) and the whole table on its
first read (:class:`_HalfTable`, :meth:`._tables.Tables.set_scattering_density_part`:
aerial perspective, the stored table's build, the exports, another sun's rows). Its float16
file and exponents are stored in bands of mu_s rows (format 13, "half-bands" in
``meta.json``'s "encoded"; :func:`_write_bands`): the mu_s axis first on disk, one row per
band, each band's bytes contiguous and with its own CRC-32 (the records' ``band_crc32``),
so that the load reads, checks and decodes only the bands of its rows (7 of 48 at the
defaults with the sun at 30 deg), not the whole file. Each band is stored as the high bytes
of its float16 values (sign, exponent, two mantissa bits: mostly repetition in a smooth
table) compressed with zlib, then their low bytes as they are (near noise: zlib saves 4 %
of them); the file is a .npy of those bytes (uint8) and the record gives each band's offset
and the length of its compressed part (``band_offsets``, ``band_high_bytes``). Lossless:
the default density's 132 MB of float16 take about 80 MB. The in-memory table is
as before (the kernels index J[c, theta, phi, r, mu_s, wavelength]); the values decoded are
the same bits. A damaged band the load reads rebuilds the entry before anything is served,
as any other file; the other bands are checked (CRC-32, finiteness) when the whole table is
first decoded, and damage found there is said in one line on stderr naming the entry, the
entry removed and the whole table served from the precomputation again (the caller's
``rebuild_density`` of :func:`load`: what a fresh model serves), so that it does not reach
the caller as an error.

The stored 4-D table of orders 2..N is built after the precomputation, on its first read
(:meth:`._tables.Tables.build_multiple_scattering`); it is then added to the same entry as
its own file (:func:`add_stored_table`: built slab by slab of r nodes straight into a
temporary file in the entry, renamed when complete): a table of at least
:data:`HALF_MIN_BYTES`, as the default one, in half precision with its float16 values'
two byte planes compressed losslessly (``multiple_scattering.packed``, :func:`_write_half` with ``packed``:
126 MB of float16 in 66 MB; read, checked and decoded whole on its first use,
:func:`_read_packed`), a smaller one as it is (``multiple_scattering.npy``, memory-mapped
by a later cache hit). An entry holding the half table uncompressed
(``multiple_scattering.npy`` in float16, as this format first wrote it) is still read. An entry
without that file (not built yet, or an unreadable file, which is removed) is still a hit:
the table is built again on first use.

Folder: ``$SKYDOME_CACHE_DIR`` if set, else ``platformdirs.user_cache_dir("skydome")`` /
``precomputed``. Size limit: ``$SKYDOME_CACHE_LIMIT_BYTES`` (default 1.5 GB); after each
write the least recently used files are removed until the folder fits. Files are written
to a temporary name in the folder and renamed, so a reader never sees a partial file. A write
that fails (a full disk, a read-only folder) is not an error: the tables are used from memory,
and the process says so once, in one line on stderr. Within :func:`background_writes` (the
command line's model construction) a new entry's tables are encoded at once and its files
written on a (non-daemon) thread while the caller goes on; :func:`wait_for_writes` waits
for it, and every later load, store and clear does so first.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import shutil
import struct
import sys
import threading
import weakref
import zlib

import numpy as np

from skydome._io import write_npy

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
# 12: the large tables in half precision (float16 and a power-of-two scale per row of
# wavelengths, "encoded"; the scattering density's Rayleigh constituent as a quadratic form);
# the single-scattering table not stored where it can be computed again from the entry (it
# is, on use: the observer's two r nodes, or the whole table), but for its first two r nodes
# 13: the scattering density's float16 file and its exponents in bands of mu_s rows (the
# mu_s axis first on disk, "half-bands"), a CRC-32 per band, so that a part of its rows is
# read and checked alone; each band's high bytes compressed (zlib), its low bytes as they are
# 14 (never released) and 15: the view rays' piece from their start to their lowest point
# integrated on two halves, each dense at its own end (transport._quadrature.ray_nodes): the
# tables' values change
# 16: the irradiance table's mu_s axis on the 4-D tables' sun mapping (_mapping.mu_s_unit),
# read geometrically between its nodes (_lookup.irradiance_lookup_acc): its nodes move
CACHE_FORMAT = "skydome.precomputed-cache/16"
# five table sets at the default settings: 0.24 GB each with the stored table of orders
# 2..N (packed; 0.30 GB before), 0.17 GB without it (1.28 GB each in format 11)
DEFAULT_LIMIT_BYTES = 1_500_000_000
# tables of at least this many bytes are stored in half precision (_HALF) or left out
# where the entry can compute them again (_RECOMPUTED); smaller ones exactly as they are
HALF_MIN_BYTES = 8 << 20
_HALF = ("scattering_density", "multiple_scattering")
_RECOMPUTED = ("single_scattering",)
_GROUND = "single_scattering_ground"    # its first two r nodes, stored as they are
_EXP = ".exp"                          # the file of a half table's row exponents
_DENSITY = "scattering_density"
_BANDS = "half-bands"                  # "encoded" of a half table stored in bands of mu_s rows
_QUAD = ".quadratic"                   # its constituents stored as a quadratic form
# largest residual of that form, relative to the largest value of each (r, mu_s, wavelength)
# column, for a constituent to be stored as one (float32 rounding: about 1e-6)
QUADRATIC_TOL = 1e-5
_COLUMNS = 2048                        # columns of J per step of the fit and its evaluation
# the largest scaled value of a row is in [2^HALF_TOP, 2^(HALF_TOP + 1)): below float16's
# largest finite value (65504 < 2^16) after rounding, and 2^28 above its smallest normal
HALF_TOP = 14
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


def _half_exponents(rows: np.ndarray) -> np.ndarray:
    """The int8 exponent e of each row of ``rows`` (n, n_wavelengths): its largest absolute
    value divided by 2^e lies in [2^HALF_TOP, 2^(HALF_TOP + 1)) (e clipped to [-127, 127], so
    that 2^-e is a finite float32; 0 for a row of zeros)."""
    m = np.max(np.abs(rows), axis=1)
    e = np.zeros(m.shape, dtype=np.int32)
    pos = m > 0
    e[pos] = np.frexp(m[pos])[1] - 1 - HALF_TOP      # frexp: m = f 2^x, f in [0.5, 1)
    return np.clip(e, -127, 127).astype(np.int8)


def _pow2(e: np.ndarray) -> np.ndarray:
    """2^e as float32 (exact: a power of two, |e| <= 127), for broadcasting over a row."""
    return np.ldexp(np.float32(1.0), e.astype(np.int32))[..., None]


def _encode_half(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(float16 values, int8 exponents) of the float32 rows (n, n_wavelengths): value =
    h 2^e, h rounded to nearest (relative error <= 2^-11 where |h| >= 2^-14)."""
    e = _half_exponents(rows)
    return np.ascontiguousarray((rows * _pow2(-e)).astype(np.float16)), e


def _decode_half(h: np.ndarray, e: np.ndarray, out: np.ndarray) -> None:
    """``out`` (n, n_wavelengths) float32 = h 2^e (exact: a float16 times a power of two)."""
    np.multiply(h, _pow2(e), out=out, dtype=np.float32)


# float32's exponent bias less float16's (127 - 15): a float16's exponent and mantissa bits
# moved into float32's fields give a float32 of value h 2^-112, exactly (subnormal float16
# values included: both formats' subnormals scale the mantissa by 2^(1 - bias))
_BIAS_SHIFT = 112
# a float16 of all-ones exponent (inf, NaN) moved so has the float32 exponent field 31, i.e.
# |value| >= 2^(31 - 127); every finite float16 (<= 65504 < 2^16) gives |value| < 2^-96
_NOT_FINITE_MOVED = np.float32(2.0 ** -96)
_BITS = np.int32(-0x70002000)   # 0x8FFFE000: the sign bit and the moved exponent, mantissa


def _decode_half_checked(h: np.ndarray, e: np.ndarray, out: np.ndarray) -> bool:
    """``out`` (n, n_wavelengths) float32 = h 2^e, bit for bit what :func:`_decode_half`
    gives, and whether every value of ``h`` is finite, in fewer passes. (Any leading axes:
    ``h`` (..., n_wavelengths), ``e`` (...), ``out`` C-contiguous, as the rows of a part
    of a table are.)

    NumPy's float16 -> float32 cast runs at about 2.3 ns per value on the 2-core EPYC of
    docs/performance.md (no F16C): the scattering density's 66 M values took 0.25 s. Here
    the float16 bits are widened with their sign (int16 -> int32), shifted into float32's
    fields and masked (``out`` then holds h 2^-112 exactly, inf and NaN showing as values
    of magnitude >= 2^-96, one reduction each way), and each row multiplied by the power of
    two 2^(112 + e): one rounding of the exact product h 2^e, as in :func:`_decode_half`,
    where 112 + e <= 127 (e <= 15; a chunk with a larger e, which no table of radiance per
    unit irradiance has, is decoded by :func:`_decode_half` and checked after)."""
    if e.size and int(e.max()) > 127 - _BIAS_SHIFT:
        _decode_half(h, e, out)
        return bool(np.isfinite(out).all())
    w = out.view(np.int32)
    np.copyto(w, h.view(np.int16), casting="unsafe")     # sign-extended to 32 bits
    np.left_shift(w, 13, out=w)
    np.bitwise_and(w, _BITS, out=w)
    finite = bool(out.max() < _NOT_FINITE_MOVED) and bool(out.min() > -_NOT_FINITE_MOVED)
    np.multiply(out, np.ldexp(np.float32(1.0), e.astype(np.int32) + _BIAS_SHIFT)[..., None],
                out=out)
    return finite


def _npy_header(f, dtype, shape) -> None:
    np.lib.format.write_array_header_1_0(
        f, {"descr": np.lib.format.dtype_to_descr(np.dtype(dtype)), "fortran_order": False,
            "shape": tuple(int(n) for n in shape)})


# A half table "packed" (the stored table of orders 2..N, ``<name>.packed``): its float16
# values split into their two byte planes, each compressed losslessly with zlib. The high
# byte (sign, exponent, two mantissa bits) of a smooth table is mostly repetition: the
# default stored table's 63 MB of high bytes take 14.9 MB at level 1; its low bytes (eight
# mantissa bits, near noise) 51 MB of 63 (docs/performance.md). The file: _PACK_MAGIC, then
# chunks, each a header (_PACK_HEAD: values, compressed high bytes, compressed low bytes)
# and its two planes; every value decoded is the float16 written (bit for bit).
_PACK = ".packed"
_PACK_MAGIC = b"skydome-half-packed-1\n"
_PACK_HEAD = struct.Struct("<QQQ")
_PACK_LEVEL = 1                       # zlib level: the table's build takes 7 s; level 1 adds
                                      # about 1 s of compression to it, level 6 about 4 s


def _byte_planes(h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(high bytes, low bytes) of the float16 values ``h`` (C-contiguous), each a
    contiguous uint8 array: the planes the packed files store (the bytes of a
    little-endian float16, the order of the entry's "<f2" records)."""
    b = h.reshape(-1).view(np.uint8).reshape(-1, 2)       # little-endian: [low, high]
    return np.ascontiguousarray(b[:, 1]), np.ascontiguousarray(b[:, 0])


def _pack_chunk(h: np.ndarray) -> list:
    """The packed bytes of the float16 values ``h`` (C-contiguous): [header, high, low]."""
    high, low = _byte_planes(h)
    hi = zlib.compress(high, _PACK_LEVEL)
    lo = zlib.compress(low, _PACK_LEVEL)
    return [_PACK_HEAD.pack(high.size, len(hi), len(lo)), hi, lo]


def _unpack_chunk(f, n_max: int, crc: int, label: str):
    """(float16 values, crc) of the next chunk of the open packed file ``f`` (named
    ``label`` in the errors), the CRC-32 of
    its bytes as stored continued from ``crc``; DamagedEntry where it cannot be read back
    (truncated, a wrong length, more than ``n_max`` values, a zlib stream that fails)."""
    head = f.read(_PACK_HEAD.size)
    if len(head) != _PACK_HEAD.size:
        raise DamagedEntry(f"{label} is truncated")
    n, n_hi, n_lo = _PACK_HEAD.unpack(head)
    if not 0 < n <= n_max or n_hi > 2 * n + 1024 or n_lo > 2 * n + 1024:
        raise DamagedEntry(f"{label} has a chunk of a wrong size")
    hi, lo = f.read(n_hi), f.read(n_lo)
    if len(hi) != n_hi or len(lo) != n_lo:
        raise DamagedEntry(f"{label} is truncated")
    crc = zlib.crc32(lo, zlib.crc32(hi, zlib.crc32(head, crc)))
    b = np.empty((n, 2), dtype=np.uint8)
    try:
        for plane, data in ((1, hi), (0, lo)):
            raw = zlib.decompress(data)
            if len(raw) != n:
                raise DamagedEntry(f"{label} has a chunk of a wrong length")
            b[:, plane] = np.frombuffer(raw, dtype=np.uint8)
    except zlib.error as exc:
        raise DamagedEntry(f"{label} cannot be decompressed ({exc})") from None
    return b.view(np.float16).reshape(-1), crc


def _read_packed(path: str, name: str, sums: dict) -> np.ndarray:
    """The float32 table ``name`` of the entry ``path`` from its packed file
    (:func:`_write_half` with ``packed``) and row exponents: every chunk read, its CRC-32 continued, its
    planes decompressed and decoded (:func:`_decode_half_checked`) into the table; the file's
    CRC-32, length and every value's finiteness checked. DamagedEntry where a check fails."""
    rec = sums.get(name)
    if not isinstance(rec, dict) or "packed_bytes" not in rec:
        raise DamagedEntry(f"{name}{_PACK} has no checksum")
    exps = _map(os.path.join(path, name + _EXP + ".npy"))
    _verify(name + _EXP, exps, sums.get(name + _EXP))
    shape = tuple(int(n) for n in rec.get("shape", ()))
    if rec.get("dtype") != np.dtype(np.float16).str or tuple(exps.shape) != shape[:-1]:
        raise DamagedEntry(f"{name}{_PACK} has shape {shape}, its exponents {exps.shape}")
    nl = shape[-1]
    out = np.empty(shape, dtype=np.float32)
    flat, e_flat = out.reshape(-1, nl), exps.reshape(-1)
    n_rows = flat.shape[0]
    crc, row, finite = 0, 0, True
    with open(os.path.join(path, name + _PACK), "rb") as f:
        if f.read(len(_PACK_MAGIC)) != _PACK_MAGIC:
            raise DamagedEntry(f"{name}{_PACK} is not a packed table")
        while row < n_rows:
            h, crc = _unpack_chunk(f, (n_rows - row) * nl, crc, name + _PACK)
            if h.size % nl:
                raise DamagedEntry(f"{name}{_PACK} has a chunk of a wrong length")
            k = h.size // nl
            finite = _decode_half_checked(h.reshape(k, nl), e_flat[row:row + k],
                                          flat[row:row + k]) and finite
            row += k
        if f.tell() - len(_PACK_MAGIC) != rec["packed_bytes"] or f.read(1):
            raise DamagedEntry(f"{name}{_PACK} is longer than its record")
    if crc != rec.get("crc32"):
        raise DamagedEntry(f"the checksum of {name}{_PACK} does not match")
    if not finite:
        raise DamagedEntry(f"{name}{_PACK} holds NaN or infinite values")
    return out


def _write_half(file: str, exp_file: str, name: str, slabs, shape,
                packed: bool = False) -> dict:
    """Write the float32 table ``name`` of ``shape`` given as consecutive ``slabs`` along its
    first axis to ``file`` (float16: ``<name>.npy``) and ``exp_file`` (int8 row exponents:
    ``<name>.exp.npy``); returns their checksum records. Each slab (C-contiguous float32)
    receives the decoded values in place (what a later read gives): a slab that is a view of
    the table makes the table serve them. _NotFinite where a value is not finite (or too
    large for the format). ``packed``: the float16 values packed instead
    (:func:`_pack_chunk`, a ``<name>.packed`` file, read by :func:`_read_packed`) in chunks
    of :data:`_CHECK_BYTES` of float32 rows, the record's CRC-32 that of the packed file's
    bytes after its magic line, as stored, and its ``packed_bytes`` their count."""
    nl = int(shape[-1])
    exps = np.empty(int(np.prod(shape[:-1])), dtype=np.int8)
    done, crc, size = 0, 0, 0
    with open(file, "wb") as f:
        if packed:
            f.write(_PACK_MAGIC)
        else:
            _npy_header(f, np.float16, shape)
        for slab in slabs:
            if slab.dtype != np.float32 or not slab.flags.c_contiguous:
                raise ValueError(f"a slab of {name} is not C-contiguous float32")
            flat = slab.reshape(-1, nl)
            step = max(1, _CHECK_BYTES // (4 * nl))
            for i in range(0, flat.shape[0], step):
                h, e = _encode_rows(flat[i:i + step], name)
                for part in (_pack_chunk(h) if packed
                             else [memoryview(h.reshape(-1)).cast("B")]):
                    crc = zlib.crc32(part, crc)
                    size += len(part)
                    f.write(part)
                exps[done:done + e.size] = e
                done += e.size
    if done != exps.size:
        raise ValueError(f"{done} rows written for a table {tuple(shape)}")
    exps = exps.reshape(tuple(shape[:-1]))
    write_npy(exp_file, exps)
    rec = {"crc32": int(crc), "dtype": np.dtype(np.float16).str,
           "shape": [int(n) for n in shape]}
    if packed:
        rec["packed_bytes"] = int(size)
    return {name: rec, name + _EXP: _record(exps, zlib.crc32(memoryview(exps.reshape(-1))))}


def _encode_rows(rows: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(float16 values, int8 exponents) of the float32 ``rows`` (n, n_wavelengths)
    (:func:`_encode_half`), ``rows`` receiving the decoded values in place (what a later
    read gives: :func:`_decode_half_checked`, the reader's decoding); _NotFinite where a
    value is not finite (NaN and inf, and values too large for the format, encode to NaN or
    inf)."""
    h, e = _encode_half(rows)
    if not _decode_half_checked(h, e, rows):
        raise _NotFinite(name)
    return h, e


def _encode_threads() -> int:
    """Threads of the encoding of a large table (:func:`_encode_table`): the cores this
    process may use, at most 4."""
    try:
        n = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        n = os.cpu_count() or 1
    return max(1, min(4, n))


class _Encoded:
    """A float32 table encoded in half precision in memory (:func:`_encode_table`): its
    float16 chunks in file order and its int8 row exponents, written by
    :func:`_write_encoded`."""

    def __init__(self, shape, chunks, exps):
        self.shape, self.chunks, self.exps = tuple(int(n) for n in shape), chunks, exps


def _encode_table(name: str, slabs, shape, block: int = 1) -> _Encoded:
    """Encode the float32 table ``name`` of ``shape`` given as consecutive C-contiguous
    ``slabs`` along its first axis, each receiving the decoded values in place
    (:func:`_encode_rows`), in steps of :data:`_CHECK_BYTES` shared out between
    :func:`_encode_threads` threads (NumPy's casts and reductions release the interpreter
    lock: the scattering density's aerosol constituent took 0.9-1.2 s on one thread of the
    2-core EPYC of docs/performance.md). The same chunks, values and exponents as
    :func:`_write_half` writes; held in memory (half the table's float32 size) until
    :func:`_write_encoded` writes them. _NotFinite as there. ``block``: each chunk holds a
    whole number of blocks of that many rows (the mu_s axis, for a table written in bands:
    :func:`_write_encoded`)."""
    nl = int(shape[-1])
    block = max(1, int(block))
    parts = []
    for slab in slabs:
        if slab.dtype != np.float32 or not slab.flags.c_contiguous:
            raise ValueError(f"a slab of {name} is not C-contiguous float32")
        flat = slab.reshape(-1, nl)
        if flat.shape[0] % block:
            raise ValueError(f"a slab of {name} is not whole blocks of {block} rows")
        step = max(1, _CHECK_BYTES // (4 * nl * block)) * block
        parts += [flat[i:i + step] for i in range(0, flat.shape[0], step)]
    n = min(_encode_threads(), len(parts))
    if n <= 1:
        out = [_encode_rows(p, name) for p in parts]
    else:
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(max_workers=n) as pool:
            out = list(pool.map(lambda p: _encode_rows(p, name), parts))
    rows = sum(p.shape[0] for p in parts)
    if rows != int(np.prod(shape[:-1])):
        raise ValueError(f"{rows} rows encoded for a table {tuple(shape)}")
    exps = (np.concatenate([e for _, e in out]) if out else np.empty(0, dtype=np.int8))
    return _Encoded(shape, [h for h, _ in out], exps.reshape(tuple(shape[:-1])))


def _write_encoded(file: str, exp_file: str, name: str, enc: _Encoded,
                   banded: bool = False) -> dict:
    """Write the encoded table ``enc`` (:func:`_encode_table`) to ``file`` and ``exp_file``
    as :func:`_write_half` does (the same bytes); returns their checksum records. Each chunk
    is let go once written (``enc.chunks`` is empty after), so that the memory they hold
    shrinks as the write goes on. ``banded``: in bands of mu_s rows instead
    (:func:`_write_bands`)."""
    if banded:
        return _write_bands(file, exp_file, name, enc)
    crc = 0
    with open(file, "wb") as f:
        _npy_header(f, np.float16, enc.shape)
        chunks, enc.chunks = enc.chunks, []
        chunks.reverse()
        while chunks:
            h = chunks.pop()
            data = memoryview(h.reshape(-1)).cast("B")
            crc = zlib.crc32(data, crc)
            f.write(data)
            del data, h
    write_npy(exp_file, enc.exps)
    rec = {"crc32": int(crc), "dtype": np.dtype(np.float16).str,
           "shape": [int(n) for n in enc.shape]}
    return {name: rec,
            name + _EXP: _record(enc.exps, zlib.crc32(memoryview(enc.exps.reshape(-1))))}


def _band_shape(shape) -> tuple:
    """The on-disk shape of a table of ``shape`` (..., mu_s, wavelength) stored in bands of
    mu_s rows: (mu_s, ..., wavelength), the mu_s axis first, so that each mu_s row (a
    band) is contiguous in the file. One row per band (2.7 MB of the default density's
    float16 file): the rows a render reads are consecutive, so their bands are consecutive
    in the file whatever the band's width, and a wider band would only add rows to read,
    check and decode (docs/performance.md, "The scattering density stored in mu_s
    bands")."""
    shape = tuple(int(n) for n in shape)
    return (shape[-2],) + shape[:-2] + (shape[-1],)


def _write_bands(file: str, exp_file: str, name: str, enc: _Encoded) -> dict:
    """Write the encoded table ``enc`` (logical shape (..., mu_s, wavelength); its chunks
    whole blocks of mu_s rows, :func:`_encode_table` with ``block``) in bands of mu_s rows:
    ``file`` float16 of shape :func:`_band_shape` and ``exp_file`` its int8 exponents
    (mu_s, ...), the bytes of band b those of the table's rows [..., b, :] in the table's
    order. Returns their records: dtype, on-disk shape and a CRC-32 per band
    (``band_crc32``). The same values as :func:`_write_encoded`'s, moved."""
    shape = enc.shape
    n_ms, nl = shape[-2], shape[-1]
    disk = _band_shape(shape)
    chunks, enc.chunks = enc.chunks, []
    blocks = [h.reshape(-1, n_ms, nl) for h in chunks]
    exps = np.ascontiguousarray(np.moveaxis(enc.exps, -1, 0))      # (mu_s, ...)

    def packed(b):
        """Band b's stored bytes: its values' high bytes zlib-compressed, then their low
        bytes as they are (:data:`_PACK` in the module's text)."""
        v = np.concatenate([h[:, b, :].reshape(-1) for h in blocks]) if blocks else \
            np.empty(0, np.float16)
        high, low = _byte_planes(v)
        return zlib.compress(high, _PACK_LEVEL), low.tobytes()

    # zlib releases the interpreter lock: the bands are compressed on the encoding's threads
    n = min(_encode_threads(), n_ms)
    if n <= 1:
        bands = [packed(b) for b in range(n_ms)]
    else:
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(max_workers=n) as pool:
            bands = list(pool.map(packed, range(n_ms)))
    del blocks, chunks
    crcs, offsets, highs = [], [0], []
    for hi, lo in bands:
        crcs.append(int(zlib.crc32(lo, zlib.crc32(hi))))
        highs.append(len(hi))
        offsets.append(offsets[-1] + len(hi) + len(lo))
    with open(file, "wb") as f:
        # an honest .npy of the stored bytes (uint8), which meta.json's record describes
        _npy_header(f, np.uint8, (offsets[-1],))
        for hi, lo in bands:
            f.write(hi)
            f.write(lo)
    del bands
    write_npy(exp_file, exps)
    exp_crcs = [int(zlib.crc32(memoryview(exps[b].reshape(-1)))) for b in range(n_ms)]
    return {name: {"dtype": np.dtype(np.float16).str, "shape": [int(n) for n in disk],
                   "band_crc32": crcs, "band_offsets": offsets, "band_high_bytes": highs},
            name + _EXP: {"dtype": exps.dtype.str, "shape": [int(n) for n in exps.shape],
                          "band_crc32": exp_crcs}}


def _read_half(path: str, name: str, sums: dict, out=None) -> np.ndarray:
    """The float32 table ``name`` of the entry ``path`` decoded from its half-precision
    files, checked as it is read (CRC-32 of both files, finite values) in steps of
    :data:`_CHECK_BYTES`, through file reads (no mapping: only the decoded table is
    resident); DamagedEntry where a check fails. ``out``: a C-contiguous float32 array of
    the table's shape to decode into (else a new one)."""
    with _HalfTable(path, name, sums) as t:
        return t.decode(out=out)


def _read_at(f, view, pos: int) -> int:
    """Read into ``view`` from offset ``pos`` of the open file ``f``; the bytes read.
    ``os.preadv`` where there is one (no file position: a process forked meanwhile shares
    the file's), else a seek and a read."""
    if hasattr(os, "preadv"):
        return os.preadv(f.fileno(), [view], pos)
    f.seek(pos)                                   # pragma: no cover - no preadv
    return f.readinto(view)                       # pragma: no cover


class _HalfTable:
    """A half-precision table of an entry (``<name>.npy``, float16, and its row exponents
    ``<name>.exp.npy``; for the scattering density, with ``quad``, its "quadratic" record,
    also the constituents stored as a quadratic form, ``<name>.quadratic.npy``), its files
    held: the float16 file open and read at offsets (:func:`_read_at`), the small files
    memory-mapped. Held, they stay readable when the entry
    is removed meanwhile (the cache's eviction and ``clear_cache`` unlink files; its writers
    replace files by renaming), so that what was checked at the load is what is decoded
    later. Opening checks the float16 file's header, the coefficients' CRC-32 and, for a
    table stored whole, the exponents'.

    ``banded`` (the scattering density, "half-bands"): the float16 file and the exponents
    are stored in bands of mu_s rows (:func:`_write_bands`: the mu_s axis first on disk),
    each with its own CRC-32, so that :meth:`decode` with ``rows`` reads, checks (CRC-32 of
    the band's float16 bytes and exponents, finiteness of its values as they are decoded)
    and decodes only the bands of the mu_s rows first..end-1; without ``rows``, every band.
    A table stored whole (the stored table of orders 2..N) is decoded whole, the CRC-32 of
    the whole float16 file and the finiteness of every value checked in the same pass. The
    values decoded are the same bits either way (each value is decoded alone: a float16
    times the power of two of its row, :func:`_decode_half_checked`; a quadratic form's
    value is its own column's product, :func:`_quadratic_eval`).

    :meth:`read` (the whole table, once; thread-safe) is what
    :meth:`._tables.Tables.set_scattering_density_part` calls on the first read of the whole
    table: it checks every band again, so that a band outside the rows decoded at the load
    is checked there. Where a check fails there (a damaged band not read at the load, or a
    file changed in place since), :meth:`read` says so on stderr in one line naming the
    entry, removes the entry (where it is still the one whose files are held) and returns
    the table ``rebuild()`` gives (the precomputation's, for the model's atmosphere and
    settings: what a fresh model serves); without ``rebuild``, DamagedEntry."""

    def __init__(self, path: str, name: str, sums: dict, quad=None, banded: bool = False,
                 rebuild=None):
        self.path, self.name, self.sums = path, name, sums
        self.banded, self.rebuild = bool(banded), rebuild
        self._lock = threading.Lock()
        self._whole = None
        self._f = None
        if quad is None:
            self.ks = []
        else:
            self.ks = [int(k) for k in quad["constituents"]]
        self.exps = _map(os.path.join(path, name + _EXP + ".npy"))
        rec = sums.get(name)
        if not isinstance(rec, dict):
            raise DamagedEntry(f"{name}.npy has no checksum")
        erec = sums.get(name + _EXP)
        if self.banded:
            # the exponents are checked band by band, as their bands are decoded
            for r, file, a in ((rec, name, None), (erec, name + _EXP, self.exps)):
                crcs = r.get("band_crc32") if isinstance(r, dict) else None
                if not isinstance(crcs, list) or not crcs:
                    raise DamagedEntry(f"{file}.npy has no checksum")
                if a is not None and (a.dtype.str != r.get("dtype") or not a.flags.c_contiguous
                                      or list(a.shape) != r.get("shape")
                                      or len(crcs) != a.shape[0]):
                    raise DamagedEntry(f"{file}.npy has shape {a.shape} {a.dtype}, recorded "
                                       f"{r.get('shape')} {r.get('dtype')}")
        else:
            _verify(name + _EXP, self.exps, erec)
        self.rec = rec
        self.coef = None
        f = open(os.path.join(path, name + ".npy"), "rb")
        try:
            version = np.lib.format.read_magic(f)
            read = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                    else np.lib.format.read_array_header_2_0)
            shape, fortran, dtype = read(f)
            if self.banded:
                # the file: the bands' stored bytes (uint8, _write_bands); the record: the
                # float16 table's on-disk shape and where each band lies
                offs, highs = rec.get("band_offsets"), rec.get("band_high_bytes")
                rshape = rec.get("shape")
                if (dtype != np.uint8 or fortran or not isinstance(offs, list)
                        or not isinstance(highs, list) or not isinstance(rshape, list)
                        or len(rshape) < 2 or len(offs) != len(rec["band_crc32"]) + 1
                        or len(highs) != rshape[0] or len(offs) != rshape[0] + 1
                        or offs[0] != 0 or any(b < a for a, b in zip(offs, offs[1:]))
                        or tuple(shape) != (offs[-1],)
                        or rec.get("dtype") != np.dtype(np.float16).str
                        or tuple(rshape[:-1]) != self.exps.shape):
                    raise DamagedEntry(f"{name}.npy has shape {shape} {dtype}, recorded "
                                       f"{rshape} {rec.get('dtype')}")
                shape = rshape
            elif (dtype != np.float16 or fortran or list(shape) != rec.get("shape")
                    or rec.get("dtype") != np.dtype(np.float16).str
                    or tuple(shape[:-1]) != self.exps.shape):
                raise DamagedEntry(f"{name}.npy has shape {shape} {dtype}, recorded "
                                   f"{rec.get('shape')} {rec.get('dtype')}")
            self.offset = f.tell()
            shape = tuple(int(n) for n in shape)
            # the table's own shape (..., mu_s, wavelength): a banded file's first axis is mu_s
            self.half_shape = (shape[1:-1] + (shape[0], shape[-1]) if self.banded else shape)
            if quad is None:
                self.shape = self.half_shape
            else:
                self.shape = tuple(int(n) for n in quad["shape"])
                coef = _map(os.path.join(path, name + _QUAD + ".npy"))
                _verify(name + _QUAD, coef, sums.get(name + _QUAD))
                if coef.shape != (len(self.ks), 6) + self.shape[3:]:
                    raise DamagedEntry(f"{name}{_QUAD}.npy has shape {coef.shape}")
                self.coef = coef
            self.rest = [k for k in range(self.shape[0]) if k not in self.ks]
            if self.shape[1:] != self.half_shape[1:] or len(self.rest) != self.half_shape[0]:
                raise DamagedEntry(f"{name}.npy has shape {self.half_shape}, the table "
                                   f"{self.shape}")
        except BaseException:
            f.close()
            raise
        self._f = f

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        f, self._f = self._f, None
        if f is not None:
            f.close()

    def __del__(self):
        self.close()

    def read(self) -> np.ndarray:
        """The whole table, decoded and checked on the first call, then the same array; the
        files are let go once it is decoded. A check that fails: see the class's text."""
        with self._lock:
            if self._whole is None:
                try:
                    if self._f is None:
                        raise DamagedEntry(f"{self.name}.npy of {self.path} is closed")
                    # the small files again, as they are mapped now
                    if not self.banded:
                        _verify(self.name + _EXP, self.exps, self.sums.get(self.name + _EXP))
                    if self.coef is not None:
                        _verify(self.name + _QUAD, self.coef,
                                self.sums.get(self.name + _QUAD))
                    self._whole = self.decode()
                except DamagedEntry as exc:
                    self._whole = self._repair(exc)
                self.close()
            return self._whole

    def _repair(self, exc: DamagedEntry) -> np.ndarray:
        """:meth:`read`'s way out of a failed check: the note, the entry removed (where its
        file is still the one held: not where the entry was written again since), the
        table from ``rebuild`` (DamagedEntry ``exc`` without it)."""
        same = False
        if self._f is not None:
            try:
                held = os.fstat(self._f.fileno())
                now = os.stat(os.path.join(self.path, self.name + ".npy"))
                same = (held.st_ino, held.st_dev) == (now.st_ino, now.st_dev)
            except OSError:
                pass
        self.close()
        if same:
            _remove(self.path)
        _note(f"table cache entry {self.path} is damaged ({_reason(exc)}); "
              + ("rebuilding it" if self.rebuild is not None else "it is removed"))
        if self.rebuild is None:
            raise exc
        J = self.rebuild()
        if J is None or tuple(J.shape) != self.shape:
            raise exc
        return J

    def decode(self, rows=None, out=None) -> np.ndarray:
        """The table decoded (float32), or with ``rows`` = (first, end) only its mu_s rows
        first..end-1 (the table's shape with that axis end - first long; a banded table
        only); every value of the float16 file that is decoded checked (CRC-32, finite).
        ``out``: a C-contiguous float32 array of that shape to decode into (else a new
        one)."""
        shape = self.shape
        if rows is not None:
            if not self.banded:
                raise ValueError(f"{self.name}.npy is not stored in bands of rows")
            lo, hi = int(rows[0]), int(rows[1])
            if not 0 <= lo <= hi <= shape[-2]:
                raise ValueError(f"rows {rows} of an axis of {shape[-2]}")
            shape = shape[:-2] + (hi - lo, shape[-1])
        if out is None:
            out = np.empty(shape, dtype=np.float32)
        elif out.shape != shape or out.dtype != np.float32 or not out.flags.c_contiguous:
            raise DamagedEntry(f"{self.name}.npy has shape {shape}, expected {out.shape}")
        rest = self.rest
        run = self._bands if self.banded else self._pass
        if not rest:
            run(None, rows)          # the checks of the (empty) float16 file
        elif rest == list(range(rest[0], rest[-1] + 1)):
            run(out[rest[0]:rest[0] + len(rest)], rows)
        else:
            out[rest] = run(None, rows)
        if self.ks:
            for j, k in enumerate(self.ks):
                coef = self.coef[j]
                if rows is not None:
                    coef = np.ascontiguousarray(coef[..., lo:hi, :])
                _quadratic_eval(coef, out[k])
        return out

    def _length(self, pos: int) -> None:
        size = os.fstat(self._f.fileno()).st_size
        if size < pos:
            raise DamagedEntry(f"{self.name}.npy is truncated")
        if size > pos:
            raise DamagedEntry(f"{self.name}.npy is longer than its shape")

    def _pass(self, out, rows=None):
        """One pass over the float16 file of a table stored whole, in steps of
        :data:`_CHECK_BYTES`: its CRC-32, the finiteness of every value and the values
        decoded into ``out`` (a new array where None). Returns ``out``. (``rows``: None
        always; :meth:`decode` refuses rows of a table stored whole.)"""
        name, shape = self.name, self.half_shape
        nl = shape[-1]
        n_rows = int(np.prod(shape[:-1]))
        step = max(1, _CHECK_BYTES // (2 * nl))
        if out is None:
            out = np.empty(shape, dtype=np.float32)
        e_flat = self.exps.reshape(-1)
        flat = out.reshape(-1, nl)
        buf = np.empty(min(step, max(n_rows, 1)) * nl, dtype=np.float16)
        self._length(self.offset + 2 * n_rows * nl)
        pos = self.offset
        crc, finite = 0, True
        for i in range(0, n_rows, step):
            k = min(step, n_rows - i)
            b = buf[:k * nl]
            view = memoryview(b).cast("B")
            if _read_at(self._f, view, pos) != b.nbytes:
                raise DamagedEntry(f"{name}.npy is truncated")
            pos += b.nbytes
            crc = zlib.crc32(view, crc)
            finite = _decode_half_checked(b.reshape(k, nl), e_flat[i:i + k],
                                          flat[i:i + k]) and finite
        if crc != self.rec.get("crc32"):
            raise DamagedEntry(f"the checksum of {name}.npy does not match")
        if not finite:
            raise DamagedEntry(f"{name}.npy holds NaN or infinite values")
        return out

    def _bands(self, out, rows):
        """The bands of mu_s rows ``rows`` (first, end; None: every band) of a banded
        table: read in one pass (consecutive bands are consecutive in the file), each
        band's CRC-32 and its exponents' checked, the values decoded into ``out`` (the
        table's shape with the mu_s axis end - first long; a new array where None), their
        finiteness checked as they are decoded. Returns ``out``."""
        name, shape = self.name, self.half_shape
        n_ms, nl = shape[-2], shape[-1]
        lo, hi = (0, n_ms) if rows is None else (int(rows[0]), int(rows[1]))
        n = hi - lo
        if out is None:
            out = np.empty(shape[:-2] + (n, nl), dtype=np.float32)
        outer = int(np.prod(shape[:-2]))
        band = outer * nl                                  # values per band
        offs, highs = self.rec["band_offsets"], self.rec["band_high_bytes"]
        self._length(self.offset + offs[-1])
        buf = np.empty((n, outer, nl), dtype=np.float16)
        if n == 0 or outer == 0:
            return out
        raw = bytearray(offs[hi] - offs[lo])
        view = memoryview(raw)
        got, pos = 0, self.offset + offs[lo]
        while got < len(raw):                              # one read, in steps of 1 GiB
            k = _read_at(self._f, view[got:got + (1 << 30)], pos + got)
            if k <= 0:
                raise DamagedEntry(f"{name}.npy is truncated")
            got += k
        crcs, e_crcs = self.rec["band_crc32"], self.sums[name + _EXP]["band_crc32"]
        planes = buf.view(np.uint8).reshape(n, band, 2)

        def unpack(j):
            a, b = offs[lo + j] - offs[lo], offs[lo + j + 1] - offs[lo]
            if zlib.crc32(view[a:b]) != crcs[lo + j]:
                raise DamagedEntry(f"the checksum of {name}.npy does not match "
                                   f"(mu_s row {lo + j})")
            if zlib.crc32(memoryview(self.exps[lo + j].reshape(-1)).cast("B")) != \
                    e_crcs[lo + j]:
                raise DamagedEntry(f"the checksum of {name}{_EXP}.npy does not match "
                                   f"(mu_s row {lo + j})")
            # the band's high bytes (zlib) and low bytes (as they are) into its values
            m = a + highs[lo + j]
            try:
                high = zlib.decompress(view[a:m])
            except zlib.error as exc:
                raise DamagedEntry(f"{name}.npy cannot be decompressed (mu_s row "
                                   f"{lo + j}: {exc})") from None
            if len(high) != band or b - m != band:
                raise DamagedEntry(f"{name}.npy has a band of a wrong length "
                                   f"(mu_s row {lo + j})")
            planes[j, :, 1] = np.frombuffer(high, dtype=np.uint8)
            planes[j, :, 0] = np.frombuffer(view[m:b], dtype=np.uint8)

        # CRC-32 and zlib release the interpreter lock: many bands (a whole read) on the
        # encoding's threads (0.42 s on one thread for the default density's 48, 2 cores)
        n_threads = min(_encode_threads(), n // 8)
        if n_threads <= 1:
            for j in range(n):
                unpack(j)
        else:
            from concurrent.futures import ThreadPoolExecutor

            with ThreadPoolExecutor(max_workers=n_threads) as pool:
                list(pool.map(unpack, range(n)))
        # decoded into ``out`` in its own order (contiguous), reading the bands across:
        # (outer, n, nl) views of the band-major buffer and exponents
        h = buf.transpose(1, 0, 2)
        e = self.exps[lo:hi].reshape(n, outer).T
        flat = out.reshape(outer, n, nl)
        step = max(1, _CHECK_BYTES // (4 * nl * n))
        finite = True
        for i in range(0, outer, step):
            finite = _decode_half_checked(h[i:i + step], e[i:i + step],
                                          flat[i:i + step]) and finite
        if not finite:
            raise DamagedEntry(f"{name}.npy holds NaN or infinite values")
        return out


def _quadratic_basis(n_th: int, n_ph: int) -> np.ndarray:
    """(n_th n_ph, 6) float64: 1, o_x, o_z, o_x^2, o_z^2, o_x o_z at the scattering density's
    outgoing directions o = (sin th cos ph, sin th sin ph, cos th) in the sun's frame (th, ph
    on [0, pi], the grid of ``_precompute._DensityQuadrature``). A phase function of degree
    <= 2 in the cosine (Rayleigh's, [BN08] eq. 2 with depolarisation; isotropic) gives
    J(o) = int P(o . i) L(i) di = a0 int L + a1 o . int L i + a2 o^T (int L i i^T) o: a
    quadratic form in o, exactly for any quadrature of the incident directions; the incident
    field is mirror-symmetric about the sun's vertical plane (o_y -> -o_y), so the terms odd
    in o_y vanish and o_y^2 = 1 - o_x^2 - o_z^2."""
    th = np.linspace(0.0, np.pi, n_th)[:, None]
    ph = np.linspace(0.0, np.pi, n_ph)[None, :]
    ox = (np.sin(th) * np.cos(ph)).ravel()
    oz = np.broadcast_to(np.cos(th), (n_th, n_ph)).ravel()
    return np.stack([np.ones_like(ox), ox, oz, ox * ox, oz * oz, ox * oz], axis=1)


def _quadratic_fit(J: np.ndarray) -> tuple[list, np.ndarray]:
    """(constituents, coefficients): the scattering constituents of J (scattering, theta,
    phi, r, mu_s, wavelength) that are a quadratic form in the outgoing direction
    (:func:`_quadratic_basis`) to :data:`QUADRATIC_TOL` in every (r, mu_s, wavelength)
    column, and their least-squares coefficients, float32 (n, 6, r, mu_s, wavelength).
    In float32 (one product for the coefficients, the residual a block of columns at a
    time): its rounding, about 1e-6 of a column's largest value, is well within the
    tolerance."""
    nsc, n_th, n_ph = J.shape[:3]
    B64 = _quadratic_basis(n_th, n_ph)
    B = B64.astype(np.float32)
    Bp = np.linalg.pinv(B64).astype(np.float32)
    ks, coefs = [], []
    for k in range(nsc):
        A = J[k].reshape(n_th * n_ph, -1)
        C = Bp @ A
        ok = True
        for c0 in range(0, A.shape[1], _COLUMNS):
            a = A[:, c0:c0 + _COLUMNS]
            r = B @ C[:, c0:c0 + _COLUMNS]
            np.subtract(r, a, out=r)
            np.abs(r, out=r)
            if not np.all(r.max(axis=0) <= QUADRATIC_TOL * np.abs(a).max(axis=0)):
                ok = False
                break
        if ok:
            ks.append(k)
            coefs.append(C.reshape((6,) + J.shape[3:]))
    return ks, (np.stack(coefs) if coefs else np.zeros((0, 6) + J.shape[3:], np.float32))


def _quadratic_eval(coef: np.ndarray, out: np.ndarray) -> None:
    """``out`` (theta, phi, r, mu_s, wavelength), C-contiguous float32 = the quadratic form
    of ``coef`` (6, r, mu_s, wavelength) at the outgoing directions."""
    B = _quadratic_basis(out.shape[0], out.shape[1]).astype(np.float32)
    # one float32 product (6 terms per value: rounding about 1e-7 of the largest term, far
    # below QUADRATIC_TOL), written straight into the table
    np.matmul(B, np.asarray(coef, dtype=np.float32).reshape(6, -1),
              out=out.reshape(B.shape[0], -1))


def _encode_store_half(name: str, a: np.ndarray):
    """Encode the table ``name`` (float32 ``a``, the tables' own array) for the entry in
    half precision: for the scattering density, the constituents that are a quadratic form
    in the outgoing direction as its coefficients (float32, ``<name>.quadratic.npy``) and
    the others as float16 (:func:`_encode_table`); every other table all as float16. ``a``
    receives the values a later read gives. Returns (coefficients with their CRC-32 or
    None, the encoded rest, the "quadratic" record of meta.json: {name: {"constituents",
    "shape"}} or {}), for :func:`_write_store_half`."""
    ks, coef = _quadratic_fit(a) if name == _DENSITY else ([], None)
    quad, extra = None, {}
    if ks:
        crc, finite = _check(coef)
        if not finite:
            raise _NotFinite(name)
        quad = (coef, crc)
        extra[name] = {"constituents": ks, "shape": [int(n) for n in a.shape]}
        for j, k in enumerate(ks):
            _quadratic_eval(coef[j], a[k])
    rest = [k for k in range(a.shape[0]) if k not in ks]
    # the density in bands of mu_s rows (_write_bands): chunks of whole mu_s blocks
    block = a.shape[-2] if name == _DENSITY and a.ndim >= 2 else 1
    enc = _encode_table(name, [a[k:k + 1] for k in rest], (len(rest),) + a.shape[1:],
                        block=block)
    return quad, enc, extra


def _write_store_half(folder: str, name: str, encoded) -> dict:
    """Write what :func:`_encode_store_half` encoded into ``folder``; returns the files'
    checksum records."""
    quad, enc, _ = encoded
    recs = {}
    if quad is not None:
        coef, crc = quad
        write_npy(os.path.join(folder, name + _QUAD + ".npy"), coef)
        recs[name + _QUAD] = _record(coef, crc)
    recs.update(_write_encoded(os.path.join(folder, name + ".npy"),
                               os.path.join(folder, name + _EXP + ".npy"), name, enc,
                               banded=_encoding(name) == _BANDS))
    return recs


def _encoding(name: str) -> str:
    """The "encoded" record of a table stored in half precision by :func:`store`: the
    scattering density in bands of mu_s rows, every other table whole."""
    return _BANDS if name == _DENSITY else "half"


def _store_half(folder: str, name: str, a: np.ndarray) -> tuple[dict, dict]:
    """Write the table ``name`` (float32 ``a``, the tables' own array) into ``folder`` in
    half precision (:func:`_encode_store_half`, then :func:`_write_store_half`). ``a``
    receives the values a later read gives. Returns (checksum records of the files, the
    "quadratic" record of meta.json: {name: {"constituents", "shape"}} or {})."""
    encoded = _encode_store_half(name, a)
    return _write_store_half(folder, name, encoded), encoded[2]


def _read_table(path: str, name: str, sums: dict, quad, rows=None, banded=False,
                rebuild=None):
    """The half-precision table ``name`` of the entry ``path``, decoded (:func:`_read_half`)
    and, where ``quad`` (its "quadratic" record) says so, its quadratic-form constituents
    evaluated from their coefficients. With ``rows`` (first, end; a ``banded`` table): (the
    table's mu_s rows first..end-1 decoded, its :class:`_HalfTable`, files held, for the
    whole table later, ``rebuild`` its way out of damage found then), the bands of those
    rows checked (and the coefficients and the float16 file's header)."""
    t = _HalfTable(path, name, sums, quad, banded=banded, rebuild=rebuild)
    if rows is None:
        with t:
            return t.decode()
    try:
        return t.decode(rows), t
    except BaseException:
        t.close()
        raise


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


# Tables read in this process, while any model holds them: a second model of the same
# atmosphere (a timelapse's next frame, a loop over sun positions) gets the same arrays
# instead of reading and decoding the entry again (about 0.35 s and 0.55 GB for the default
# entry). Keyed on the entry's folder and its files' identity (inode, size, modification
# time; the meta file's time is the entry's last use and is left out), so an entry changed
# on disk since (rewritten, damaged, a stored table added) is read again.
_LOADED: "weakref.WeakValueDictionary" = weakref.WeakValueDictionary()
_LOADED_LOCK = threading.Lock()


def _signature(path: str):
    """The identity of the entry's files, or None where it cannot be read."""
    try:
        with os.scandir(path) as it:
            sig = []
            for e in it:
                st = e.stat(follow_symlinks=False)
                sig.append((e.name, st.st_ino, st.st_size,
                            0 if e.name == _META else st.st_mtime_ns))
    except OSError:
        return None
    return (path, tuple(sorted(sig)))


def _touch(path: str) -> None:
    try:
        os.utime(os.path.join(path, _META))   # least recently used: the meta file's mtime
    except OSError:
        pass


def load(k: str, density_rows=None, rebuild_density=None):
    """The cached :class:`._tables.Tables` under key ``k``, or None (absent or unreadable;
    an unreadable entry is removed). The arrays are memory-mapped copy-on-write, so the
    start-up reads only the header of each file and pages come in as the tables are used.
    Where tables of the same entry, unchanged on disk, are still held in this process, they
    are returned (the same object).

    ``density_rows(scalars, shape) -> (first, end)`` (optional): the mu_s rows of the
    scattering density (of ``shape``; ``scalars``: the entry's scalars, its radii and
    ``mu_s_min``) that the caller reads first, e.g. those an observer's rays reach
    (:func:`._reach.density_mu_s_rows`). Where the entry holds the density in half
    precision, only those rows are decoded at the load (the default entry's 527 MB in
    float32: the rows a ground observer's sky needs are about a fifth of them), and the
    whole table on its first read (:meth:`._tables.Tables.set_scattering_density_part`).

    What is checked when: at the load, every file of the entry but the density's float16
    file and exponents whole (the CRC-32 of every byte, the finiteness of every value),
    and of those two the bands of the rows decoded (the density is stored in bands of
    mu_s rows, each with its CRC-32, :func:`_write_bands`; the finiteness of their values
    as they are decoded): damage there rebuilds the entry before the model serves anything
    from it. The other bands are read and checked when the whole table is first decoded
    (:meth:`_HalfTable.read`); the files of the density stay held (open or mapped) by the
    tables until then. Damage found there (a band not read at the load, or a file changed
    in place since) is said in one line on stderr, the entry removed and the whole table
    served from ``rebuild_density()`` (the caller's: the precomputation's table for the
    same atmosphere and settings, the values a fresh model serves); without it,
    DamagedEntry."""
    from skydome.models.simulated.precomputed._tables import Tables

    wait_for_writes()
    path = _path(k)
    if not os.path.isdir(path):
        return None
    sig = _signature(path)
    if sig is not None:
        with _LOADED_LOCK:
            held = _LOADED.get(sig)
        if held is not None:
            _touch(path)
            return held
    part = None
    try:
        with open(os.path.join(path, _META)) as f:
            meta = json.load(f)
        if meta.get("cache_key") != k or meta.get("cache_format") != CACHE_FORMAT:
            raise ValueError("key mismatch")
        arrays = dict(meta["scalars"])
        sums = meta.get("checksums")
        if not isinstance(sums, dict):
            raise DamagedEntry("meta.json has no checksums")
        half = meta.get("encoded", {})
        quad = meta.get("quadratic", {})
        for name in meta["arrays"]:
            if name.rsplit(".", 1)[0] in half and "." in name:
                continue                 # read with its table (exponents, coefficients)
            if name in half:
                rows = None
                if name == _DENSITY and density_rows is not None:
                    rows = _rows_asked(density_rows, meta, name)
                banded = half[name] == _BANDS
                if rows is None or not banded:
                    arrays[name] = _read_table(path, name, sums, quad.get(name),
                                               banded=banded)
                else:
                    part = (int(rows[0]),) + _read_table(path, name, sums, quad.get(name),
                                                         rows=rows, banded=banded,
                                                         rebuild=rebuild_density)
                continue
            arrays[name] = _map(os.path.join(path, name + ".npy"))
            _verify(name, arrays[name], sums.get(name))
        tables = Tables.from_arrays(arrays)
        if part is not None:
            first, rows_part, whole = part
            tables.set_scattering_density_part(rows_part, first, whole)
    except Exception as exc:
        if part is not None:
            part[2].close()
        _remove(path)
        _note(f"table cache entry {path} is damaged ({_reason(exc)}); rebuilding it")
        return None
    if not tables.has_multiple_scattering:
        _load_stored_table(path, tables, meta)
    _touch(path)
    if sig is not None and sig == _signature(path):   # nothing removed meanwhile
        with _LOADED_LOCK:
            _LOADED[sig] = tables
    return tables


def _rows_asked(density_rows, meta, name):
    """``density_rows(scalars, shape)`` for the entry's table ``name`` (its shape from its
    records), or None (the whole table) where it cannot say: an error there is the caller's,
    not the entry's, and must not remove the entry."""
    try:
        quad = meta.get("quadratic", {}).get(name)
        shape = quad["shape"] if quad is not None else meta["checksums"][name]["shape"]
        shape = tuple(int(n) for n in shape)
        first, end = (int(x) for x in density_rows(dict(meta["scalars"]), shape))
    except Exception:
        return None
    if not 0 <= first <= end <= shape[-2]:
        return None
    return first, end


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
    the tables (float32, the 4-D tables' shape) and its recorded checksum, and is finite; a
    file that fails is removed (the table is built again on use), with a note on stderr. A
    table in half precision is read and checked on its first use instead
    (:meth:`._tables.Tables.set_multiple_scattering_reader`): the sky's radiance does not
    read it."""
    packed = meta.get("encoded", {}).get(_STORED) == "half-packed"
    file = os.path.join(path, _STORED + (_PACK if packed else ".npy"))
    if not os.path.exists(file):
        return

    def failed(exc):
        _remove(file)
        _remove(os.path.join(path, _STORED + _EXP + ".npy"))
        _note(f"table cache entry {path} is damaged ({_reason(exc)}); its table of orders "
              "2..N is built again when used")

    if _STORED in meta.get("encoded", {}):
        def reader(t):
            try:
                ms = (_read_packed if packed else _read_half)(path, _STORED,
                                                               meta["checksums"])
                if ms.shape != t.table_shape:
                    raise DamagedEntry(f"{_STORED}.npy has shape {ms.shape}")
            except Exception as exc:
                failed(exc)
                return None
            return ms

        tables.set_multiple_scattering_reader(reader)
        return
    try:
        ms = _map(file)
        if ms.dtype != np.float32 or ms.shape != tables.table_shape:
            raise DamagedEntry(f"{_STORED}.npy has shape {ms.shape} {ms.dtype}")
        _verify(_STORED, ms, meta["checksums"].get(_STORED))
    except Exception as exc:
        failed(exc)
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

    wait_for_writes()
    path = _path(k)
    file = os.path.join(path, _STORED + ".npy")
    meta_file = os.path.join(path, _META)
    shape = tuple(int(n) for n in shape)
    try:
        with open(meta_file) as f:
            meta = json.load(f)
        if meta.get("cache_key") != k or meta.get("cache_format") != CACHE_FORMAT:
            return None
        if 4 * int(np.prod(shape)) >= HALF_MIN_BYTES:
            return _add_half_table(path, meta, shape, slabs)
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


def _add_half_table(path, meta, shape, slabs):
    """:func:`add_stored_table` in half precision: the table's two files and its records in
    ``meta.json`` (written before the table's file gets its name), then the cache trimmed;
    returns the decoded table (what a later read gives)."""
    from skydome._io import atomic_file

    file = os.path.join(path, _STORED + _PACK)
    exp_file = os.path.join(path, _STORED + _EXP + ".npy")
    out = np.empty(shape, dtype=np.float32)

    def into_out():         # each slab copied into the table, decoded there in place
        row = 0
        for slab in slabs:
            part = out[row:row + slab.shape[0]]
            part[...] = slab
            row += slab.shape[0]
            yield part

    try:
        with atomic_file(file, suffix=_PACK) as tmp, \
                atomic_file(exp_file, suffix=".npy") as etmp:
            recs = _write_half(tmp, etmp, _STORED, into_out(), shape, packed=True)
            meta.setdefault("checksums", {}).update(recs)
            meta.setdefault("encoded", {})[_STORED] = "half-packed"
            with atomic_file(os.path.join(path, _META)) as mtmp, open(mtmp, "w") as f:
                json.dump(meta, f)
    except OSError as exc:
        _write_failed(path, exc)
        return None
    except (ValueError, _NotFinite):
        return None
    _evict(cache_dir(), limit_bytes(), keep=path)
    return out


class _NotFinite(Exception):
    pass


# entries being written on background threads (store with background writes), and the lock
# of that list
_PENDING: list = []
_PENDING_LOCK = threading.Lock()
_BACKGROUND = False


@contextlib.contextmanager
def background_writes():
    """Meanwhile (in this process), :func:`store` encodes a new entry's tables at once (the
    tables then serve the values a later read gives, as before) and writes its files on a
    background thread, so that the caller goes on (e.g. renders) while they are written.
    The thread is not a daemon: the interpreter waits for it before it exits, so the entry
    is written, or (an error, a signal) none is (the files go to a temporary folder renamed
    when complete). Every later :func:`load`, :func:`store`, :func:`add_stored_table` and
    :func:`clear_cache` waits for it first; :func:`wait_for_writes` waits explicitly (the
    command line does, when its command ends)."""
    global _BACKGROUND
    before = _BACKGROUND
    _BACKGROUND = True
    try:
        yield
    finally:
        _BACKGROUND = before


def wait_for_writes() -> None:
    """Wait for every entry being written on a background thread (:func:`background_writes`)."""
    while True:
        with _PENDING_LOCK:
            pending = [t for t in _PENDING if t is not threading.current_thread()]
        if not pending:
            return
        for t in pending:
            t.join()
            with _PENDING_LOCK:
                if t in _PENDING:
                    _PENDING.remove(t)


def store(k: str, tables, background: bool | None = None) -> str | None:
    """Write ``tables`` under key ``k`` (a folder of ``.npy`` files and ``meta.json``,
    written under a temporary name and renamed; the stored table of orders 2..N only where
    it is built, else :func:`add_stored_table` adds it later) and trim the cache to the
    size limit; returns the path, or None where the folder cannot be written or the tables
    alone exceed the limit (the cache is a convenience: a failure to write it is not an
    error).

    The large tables are encoded first (:func:`_encode_store_half`; the tables' own arrays
    then hold the decoded values), then the files written. ``background`` (default: within
    :func:`background_writes`): the files are written on a thread and the path the entry
    will have is returned at once (a failure is said on stderr, as without)."""
    wait_for_writes()
    background = _BACKGROUND if background is None else bool(background)
    limit = limit_bytes()
    arrays = tables.arrays()
    half = set()
    for name in list(arrays):
        a = arrays[name]
        if a.nbytes < HALF_MIN_BYTES:
            continue
        if name in _RECOMPUTED and tables.single_scattering_samples > 0 and tables.has_density:
            del arrays[name]             # computed again from the entry when used
            # but a ground observer's two r nodes kept (exactly): the sky's radiance at the
            # ground reads them, without computing them or loading their kernel
            arrays[_GROUND] = np.ascontiguousarray(a[:, :2])
        elif name in _HALF + _RECOMPUTED and a.dtype == np.float32 and a.ndim >= 2:
            half.add(name)
    if sum(a.nbytes // (2 if n in half else 1) for n, a in arrays.items()) > limit:
        return None
    folder = cache_dir()
    path = _path(k)
    order, plain = list(arrays), {}
    try:
        # in this thread: the checks of the tables stored as they are (never cache a table
        # that is not finite), the cache folder, then the encoding; the tables' own arrays
        # receive the decoded values, so that this model serves what a later cache hit
        # reads (a C-contiguous float32 array: arrays() gives the table itself, not a copy)
        for name, a in arrays.items():
            if name in half:
                continue
            if a.ndim == 0:           # a scalar of meta.json (ascontiguousarray would make
                plain[name] = (a, None)   # it 1-d)
                continue
            a = np.ascontiguousarray(a)
            plain[name] = (a, _checked_crc(name, a))
        os.makedirs(folder, exist_ok=True)
        if not os.access(folder, os.W_OK | os.X_OK):
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), folder)
        encoded = {name: _encode_store_half(name, getattr(tables, name)) for name in half}
    except _NotFinite:
        return None
    except (OSError, ValueError) as exc:   # ValueError: the cache folder is not writable
        _write_failed(folder, exc)
        return None

    def write():
        return _write_entry(folder, path, k, order, plain, encoded, half, limit)

    if not background:
        return write()
    from skydome._io import _install_handler

    _install_handler()     # the SIGTERM clean-up of the temporary folder (main thread only)
    t = threading.Thread(target=write, name="skydome-cache-write", daemon=False)
    with _PENDING_LOCK:
        _PENDING.append(t)
    t.start()
    return path


def _checked_crc(name: str, a: np.ndarray) -> int:
    """The CRC-32 of C-contiguous ``a``; _NotFinite where a value is not finite."""
    crc, finite = _check(a)
    if not finite:
        raise _NotFinite(name)
    return crc


def _write_entry(folder, path, k, order, plain, encoded, half, limit) -> str | None:
    """:func:`store`'s files: the tables ``plain`` ({name: (array, CRC-32)}) as they are
    and the ``encoded`` ones (:func:`_encode_store_half`), in the order of the names
    ``order``, into a temporary folder renamed to ``path``, then the cache trimmed; the
    path, or None (see :func:`store`)."""
    from skydome._io import atomic_folder

    try:
        os.makedirs(folder, exist_ok=True)
        if os.path.isdir(path):
            _remove(path)
        with atomic_folder(path) as tmp:
            names, scalars, sums, quadratic = [], {}, {}, {}
            for name in order:
                if name in encoded:
                    recs = _write_store_half(tmp, name, encoded[name])
                    sums.update(recs)
                    names += list(recs)
                    quadratic.update(encoded[name][2])
                    continue
                a, crc = plain[name]
                if a.ndim == 0:
                    scalars[name] = a.item()
                    continue
                write_npy(os.path.join(tmp, name + ".npy"), a)
                names.append(name)
                sums[name] = _record(a, crc)
            with open(os.path.join(tmp, _META), "w") as f:
                json.dump({"cache_key": k, "cache_format": CACHE_FORMAT, "arrays": names,
                           "scalars": scalars, "checksums": sums,
                           "encoded": {n: _encoding(n) for n in sorted(half)},
                           "quadratic": quadratic}, f)
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
    wait_for_writes()
    with _LOADED_LOCK:
        _LOADED.clear()
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
