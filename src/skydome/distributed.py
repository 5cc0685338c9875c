"""Scale-out on Dask (dask.distributed): chunked, resumable jobs.

A job is a list of chunks, each a pure function of its inputs that returns a NumPy array.
Every chunk is written by the worker that computed it, atomically (temporary file + rename),
as ``<folder>/<key>.npy`` with its SHA-256 in ``<key>.npy.sha256``. A rerun with the same
folder verifies the finished chunks (hash of the file against the recorded one) and computes
only the missing or corrupt ones; a worker lost mid-run has its chunk rescheduled by the
scheduler (dask.distributed's own fault tolerance), and the atomic write means a chunk file
is either whole or absent. Memory is bounded by the chunk size: results stay on disk, the
client only collects hashes.

The embedded default needs no set-up: a ``LocalCluster`` on this machine (processes, one
thread each). ``scheduler="tcp://HOST:8786"`` runs the same job on an existing cluster (the
folder must then be on storage every worker sees).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

__all__ = ["Chunk", "JobReport", "run_chunks", "assemble_chunks"]


@dataclass(frozen=True)
class Chunk:
    """One task: ``func(*args)`` -> numpy array, stored as ``<key>.npy``."""

    key: str
    func: Callable
    args: tuple


@dataclass
class JobReport:
    """What a run did: chunks computed now, verified from an earlier run, recomputed because
    their file did not match its hash; the hash of every chunk."""

    computed: list
    verified: list
    repaired: list
    hashes: dict


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _verified(folder: Path, key: str) -> str | None:
    p = folder / f"{key}.npy"
    s = folder / f"{key}.npy.sha256"
    if not (p.exists() and s.exists()):
        return None
    want = s.read_text().strip()
    return want if _sha256(p) == want else None


def _compute_and_store(folder: str, key: str, func, args) -> tuple[str, str]:
    """Run on a worker: compute, write the chunk atomically, then its hash; return both."""
    import io

    folder_p = Path(folder)
    arr = np.ascontiguousarray(func(*args))
    buf = io.BytesIO()
    np.save(buf, arr)
    data = buf.getvalue()
    digest = hashlib.sha256(data).hexdigest()
    for name, payload in ((f"{key}.npy", data), (f"{key}.npy.sha256", digest.encode())):
        fd, tmp = tempfile.mkstemp(dir=folder_p, prefix=f".{name}.", suffix=".part")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(payload)
            os.replace(tmp, folder_p / name)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
    return key, digest


def run_chunks(chunks: Sequence[Chunk], folder, *, scheduler: str | None = None,
               n_workers: int = 2, client=None, progress: bool = False) -> JobReport:
    """Compute the chunks that ``folder`` does not already hold (verified by hash).

    Parameters
    ----------
    chunks : sequence of Chunk
        Keys must be unique file-name stems.
    folder : str or Path
        Where the chunks are written (created if missing).
    scheduler : str, optional
        Address of a running dask.distributed scheduler ("tcp://HOST:8786"); default: a local
        cluster of ``n_workers`` processes with one thread each, closed at the end.
    client : distributed.Client, optional
        Use this client (its cluster) instead.
    progress : bool
        Show a progress bar (dask.distributed's).
    """
    keys = [c.key for c in chunks]
    if len(set(keys)) != len(keys):
        raise ValueError("chunk keys must be unique")
    for k in keys:
        if not k or "/" in k or k.startswith("."):
            raise ValueError(f"chunk key {k!r} is not a plain file-name stem")
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    verified, repaired, todo, hashes = [], [], [], {}
    for c in chunks:
        h = _verified(folder, c.key)
        if h is not None:
            verified.append(c.key)
            hashes[c.key] = h
        else:
            if (folder / f"{c.key}.npy").exists():
                repaired.append(c.key)
            todo.append(c)
    if todo:
        from distributed import Client, LocalCluster, as_completed

        own = None
        if client is None:
            if scheduler is not None:
                own = client = Client(scheduler)
            else:
                cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1,
                                       processes=True, dashboard_address=None)
                own = client = Client(cluster)
        try:
            futures = [client.submit(_compute_and_store, str(folder), c.key, c.func, c.args,
                                     key=f"skydome-{folder.name}-{c.key}", pure=False)
                       for c in todo]
            if progress:
                from distributed import progress as _progress

                _progress(futures)
            for fut in as_completed(futures):
                k, h = fut.result()
                hashes[k] = h
        finally:
            if own is not None:
                cl = own.cluster
                own.close()
                if cl is not None and scheduler is None:
                    cl.close()
    computed = [c.key for c in todo]
    return JobReport(computed, verified, repaired, hashes)


def assemble_chunks(folder, keys) -> np.ndarray:
    """The chunks' arrays concatenated along the first axis (hours), each verified."""
    folder = Path(folder)
    parts = []
    for k in keys:
        if _verified(folder, k) is None:
            raise ValueError(f"chunk {k!r} in {str(folder)!r} is missing or does not match its "
                             "hash")
        parts.append(np.load(folder / f"{k}.npy"))
    return np.concatenate(parts, axis=0)
