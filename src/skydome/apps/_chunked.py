"""Rendered images as Dask chunks: a SkyImage and a few extra arrays packed as the bytes of an
.npz (a uint8 array, stored and hashed by :func:`skydome.distributed.run_chunks` like any
other chunk), and unpacked on the client."""

from __future__ import annotations

import io
import json

import numpy as np

__all__ = ["pack_image", "unpack_image", "load_chunk"]


def pack_image(img, note: str = "", **extra) -> np.ndarray:
    """``img`` (a SkyImage, or None with ``note`` saying why not) and ``extra`` arrays."""
    parts = {k: np.asarray(v) for k, v in extra.items() if v is not None}
    if img is None:
        parts["note"] = np.array(note)
    else:
        parts["data"], parts["mask"] = img.data, img.mask
        parts["kind"] = np.array(img.kind)
        if img.wavelengths_nm is not None:
            parts["wl"] = img.wavelengths_nm
        parts["metadata"] = np.array(json.dumps(img.metadata, default=str))
    buf = io.BytesIO()
    np.savez(buf, **parts)
    return np.frombuffer(buf.getvalue(), dtype=np.uint8)


def unpack_image(packed: np.ndarray, projection):
    """(SkyImage or None, note, dict of the extra arrays)."""
    from skydome.imaging.image import SkyImage

    z = dict(np.load(io.BytesIO(np.asarray(packed, dtype=np.uint8).tobytes())))
    note = str(z.pop("note")) if "note" in z else ""
    if "data" not in z:
        return None, note, z
    img = SkyImage(z.pop("data"), str(z.pop("kind")), z.pop("wl", None), z.pop("mask"),
                   projection, json.loads(str(z.pop("metadata"))))
    return img, note, z


def load_chunk(folder, key: str) -> np.ndarray:
    """A finished chunk, verified against its hash."""
    from pathlib import Path

    from skydome.distributed import _verified

    if _verified(Path(folder), key) is None:
        raise ValueError(f"chunk {key!r} in {str(folder)!r} is missing or does not match its "
                         "hash")
    return np.load(Path(folder) / f"{key}.npy")
