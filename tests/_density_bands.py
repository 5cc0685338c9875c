"""The scattering density's file of a precomputed cache entry (cache format 13, "half-bands")
read and written from its description in skydome.models.simulated.precomputed._cache
(module text, ``_write_bands``), independently of that module's reader: a .npy of uint8,
the bands of mu_s rows one after the other, each band the high bytes of its float16 values
(little-endian) compressed with zlib, then their low bytes as they are; meta.json's record
gives the on-disk float16 shape (mu_s first), each band's CRC-32 of its stored bytes, its
offset and the length of its compressed high bytes. For the tests that damage a band."""

from __future__ import annotations

import json
import os
import zlib

import numpy as np

NAME = "scattering_density"


def read(path):
    """(float16 array of the on-disk shape, meta.json) of the entry ``path``."""
    meta = json.load(open(os.path.join(path, "meta.json")))
    rec = meta["checksums"][NAME]
    raw = np.load(os.path.join(path, NAME + ".npy"))
    assert raw.dtype == np.uint8 and raw.ndim == 1
    shape = tuple(rec["shape"])
    n = int(np.prod(shape[1:]))
    out = np.empty((shape[0], n), dtype=np.uint16)
    offs, highs = rec["band_offsets"], rec["band_high_bytes"]
    for b in range(shape[0]):
        band = raw[offs[b]:offs[b + 1]].tobytes()
        assert zlib.crc32(band) == rec["band_crc32"][b]
        high = np.frombuffer(zlib.decompress(band[:highs[b]]), dtype=np.uint8)
        low = np.frombuffer(band[highs[b]:], dtype=np.uint8)
        out[b] = high.astype(np.uint16) << 8 | low
    return out.view(np.float16).reshape(shape), meta


def write(path, a, meta, new_checksums=()):
    """Write the float16 array ``a`` (on-disk shape) as the entry's density file, its bands'
    offsets and lengths into meta.json; the CRC-32 of the bands in ``new_checksums`` recorded
    again (the others keep their record, so a changed band no longer matches it)."""
    rec = meta["checksums"][NAME]
    blob, offs, highs = [], [0], []
    for b in range(a.shape[0]):
        planes = np.ascontiguousarray(a[b]).reshape(-1).view(np.uint8).reshape(-1, 2)
        high = zlib.compress(np.ascontiguousarray(planes[:, 1]).tobytes(), 1)
        band = high + np.ascontiguousarray(planes[:, 0]).tobytes()
        if b in new_checksums:
            rec["band_crc32"][b] = zlib.crc32(band)
        blob.append(band)
        highs.append(len(high))
        offs.append(offs[-1] + len(band))
    rec["band_offsets"], rec["band_high_bytes"] = offs, highs
    np.save(os.path.join(path, NAME + ".npy"), np.frombuffer(b"".join(blob), dtype=np.uint8))
    json.dump(meta, open(os.path.join(path, "meta.json"), "w"))
