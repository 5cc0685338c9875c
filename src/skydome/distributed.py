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

Errors, before any work: a scheduler address that is not ``tcp://HOST:PORT`` or
``HOST:PORT`` (PORT 1-65535; ``tls://``, ``ws://``, ``wss://`` and ``inproc://`` addresses
as Dask writes them are taken too) is refused with a ValueError naming ``scheduler``, and a
scheduler that does not answer within ``connect_timeout_s`` (default
:data:`CONNECT_TIMEOUT_S`) raises :class:`SchedulerError` (a ValueError) naming it, before
the chunk folder is made. A run that fails leaves the folder as it found it: one it created
is removed (with the chunks it wrote), an existing one keeps its verified chunks; only an
interruption (Ctrl-C) keeps a new folder, whose chunks a rerun reuses.
"""

from __future__ import annotations

import hashlib
import logging
import os
import re
import shutil
import socket
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

__all__ = ["Chunk", "JobReport", "run_chunks", "assemble_chunks", "check_scheduler",
           "SchedulerError", "CONNECT_TIMEOUT_S"]

#: Seconds to wait for a scheduler given by address to answer (``connect_timeout_s``).
CONNECT_TIMEOUT_S = 10.0

_HOST = r"(?:[A-Za-z0-9](?:[A-Za-z0-9-]{0,61}[A-Za-z0-9])?(?:\.[A-Za-z0-9](?:[A-Za-z0-9-]{0,61}" \
        r"[A-Za-z0-9])?)*|\[[0-9A-Fa-f:.]+\])"
_ADDRESS = re.compile(r"^(?:(tcp|tls|ws|wss)://)?(" + _HOST + r"):([0-9]{1,5})$")
_VALID = "tcp://HOST:PORT or HOST:PORT with PORT in 1-65535"


class SchedulerError(ValueError):
    """The Dask scheduler given by address did not answer."""


def check_scheduler(scheduler, name: str = "scheduler") -> str | None:
    """``scheduler`` as given (None: a local cluster) if it is a Dask scheduler address:
    ``tcp://HOST:PORT`` or ``HOST:PORT`` (PORT 1-65535; also ``tls://``, ``ws://``,
    ``wss://`` and ``inproc://`` addresses); else ValueError naming ``name``, the value and
    the valid form. Checks the syntax only (no connection)."""
    if scheduler is None:
        return None
    if not isinstance(scheduler, str):
        raise TypeError(f"{name} must be a string ({_VALID}), got {scheduler!r}")
    text = scheduler.strip()
    if text.startswith("inproc://") and len(text) > len("inproc://"):
        return text
    m = _ADDRESS.match(text)
    if m is None:
        raise ValueError(f"{name} = {scheduler!r} is not a Dask scheduler address: give "
                         f"{_VALID}")
    port = int(m.group(3))
    if not 1 <= port <= 65535:
        raise ValueError(f"{name} = {scheduler!r}: port {port} is out of range [1, 65535] "
                         f"(give {_VALID})")
    return text


def _connect(scheduler: str, timeout_s: float):
    """A Client of the scheduler at ``scheduler``, or SchedulerError after ``timeout_s``."""
    from distributed import Client

    try:
        return Client(scheduler, timeout=timeout_s)
    except (OSError, TimeoutError) as exc:
        raise SchedulerError(
            f"scheduler = {scheduler!r}: no Dask scheduler answered within {timeout_s:g} s "
            f"({' '.join(str(exc).split()) or type(exc).__name__}); check the address, or "
            "leave the scheduler option out to run on this machine") from None


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
        # the writer named in the temporary (pid@host), so that a run can tell an orphan
        # of a worker killed while writing from a live writer's (_remove_orphans)
        fd, tmp = tempfile.mkstemp(dir=folder_p, suffix=".part",
                                   prefix=f".{name}.{os.getpid()}@{socket.gethostname()}.")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(payload)
            os.replace(tmp, folder_p / name)
        except OSError as exc:      # a full disk: ENOSPC naming the chunk, not its temporary
            if os.path.exists(tmp):
                os.unlink(tmp)
            if exc.errno is None or exc.filename not in (None, tmp):
                raise
            raise OSError(exc.errno, exc.strerror or os.strerror(exc.errno),
                          str(folder_p / name)) from None
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
    return key, digest


def _pid_alive(pid: int) -> bool:
    """Whether process ``pid`` of this host exists (one of another user's counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        pass
    return True


def _remove_orphans(folder: Path, keys) -> list[str]:
    """Remove the temporaries of the chunk files of ``keys`` (``.KEY.npy.PID@HOST.*.part``,
    :func:`_compute_and_store`) whose writer was a process of this host that is no longer
    alive: what a worker killed while writing (SIGKILL, the out-of-memory killer) leaves.
    A temporary of a live process, or of another host's, is kept. The names removed."""
    host = socket.gethostname()
    prefixes = [f".{k}.npy{x}." for k in keys for x in ("", ".sha256")]
    removed = []
    for p in folder.glob(".*.part"):
        found = [n for n in prefixes if p.name.startswith(n)]
        if not found:
            continue
        prefix = max(found, key=len)          # ".K.npy.sha256." before ".K.npy."
        writer = p.name[len(prefix):].rsplit(".", 2)[0]          # PID@HOST
        pid, _, whose = writer.partition("@")
        if whose != host or not pid.isdigit() or _pid_alive(int(pid)):
            continue
        try:
            p.unlink()
            removed.append(p.name)
        except FileNotFoundError:
            pass
    return removed


def worker_environment(n_workers: int) -> dict:
    """The environment of a local cluster's worker processes: numba's thread count
    (``NUMBA_NUM_THREADS``) set to this process's cores divided among the ``n_workers``
    workers (at least 1), unless the caller has set it. Otherwise every worker's parallel
    kernels would start a thread per core, ``n_workers`` times the cores in all."""
    if "NUMBA_NUM_THREADS" in os.environ:
        return {}
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cores = os.cpu_count() or 1
    return {"NUMBA_NUM_THREADS": str(max(1, cores // max(1, int(n_workers))))}


def run_chunks(chunks: Sequence[Chunk], folder, *, scheduler: str | None = None,
               n_workers: int = 2, client=None, progress: bool = False,
               connect_timeout_s: float = CONNECT_TIMEOUT_S) -> JobReport:
    """Compute the chunks that ``folder`` does not already hold (verified by hash).

    Parameters
    ----------
    chunks : sequence of Chunk
        Keys must be unique file-name stems.
    folder : str or Path
        Where the chunks are written (created if missing).
    scheduler : str, optional
        Address of a running dask.distributed scheduler ("tcp://HOST:8786"); default: a local
        cluster of ``n_workers`` processes with one thread each (and numba's threads of
        :func:`worker_environment`), closed at the end. Checked
        before any work (:func:`check_scheduler`).
    client : distributed.Client, optional
        Use this client (its cluster) instead.
    progress : bool
        Show a progress bar (dask.distributed's).
    connect_timeout_s : float
        Seconds to wait for ``scheduler`` to answer (0 < t <= 3600), then
        :class:`SchedulerError`; nothing is written then.

    A run that fails (an exception) removes ``folder`` if it made it; Ctrl-C keeps it (a
    rerun reuses its chunks).
    """
    from skydome._validate import check_number

    scheduler = check_scheduler(scheduler)
    connect_timeout_s = check_number("connect_timeout_s", connect_timeout_s, 0.0, 3600.0,
                                     "s", low_open=True)
    keys = [c.key for c in chunks]
    if len(set(keys)) != len(keys):
        raise ValueError("chunk keys must be unique")
    for k in keys:
        if not k or "/" in k or k.startswith("."):
            raise ValueError(f"chunk key {k!r} is not a plain file-name stem")
    folder = Path(folder)
    created = not folder.exists()
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
    if not todo:
        folder.mkdir(parents=True, exist_ok=True)
    else:
        from distributed import Client, LocalCluster, as_completed

        own = None
        if client is None:
            if scheduler is not None:
                own = client = _connect(scheduler, connect_timeout_s)   # before any write
            else:
                # the workers' own logging off: a failed chunk (a full disk) reaches the
                # caller as the chunk's exception, not as a log record on stderr as well.
                # No dashboard; the scheduler's HTTP routes (which Dask starts even so, by
                # default on port 8787 of every interface, with a warning where another
                # cluster holds that port) on a free loopback port
                cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1,
                                       processes=True, dashboard_address=None,
                                       scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                                       silence_logs=logging.CRITICAL,
                                       env=worker_environment(n_workers))
                own = client = Client(cluster)
        futures, failed = [], False
        try:
            folder.mkdir(parents=True, exist_ok=True)
            futures = [client.submit(_compute_and_store, str(folder), c.key, c.func, c.args,
                                     key=f"skydome-{folder.name}-{c.key}", pure=False)
                       for c in todo]
            if progress:
                from distributed import progress as _progress

                _progress(futures)
            for fut in as_completed(futures):
                k, h = fut.result()
                hashes[k] = h
        except Exception:
            failed = True
            for fut in futures:
                fut.cancel()
            raise
        finally:
            if own is not None:
                cl = own.cluster
                own.close()
                if cl is not None and scheduler is None:
                    cl.close()
            if failed and created:   # leave the folder as it was found: not there
                shutil.rmtree(folder, ignore_errors=True)
    if todo:
        # a worker killed while writing a chunk (the chunk was computed again elsewhere)
        # leaves its temporary: removed once every chunk is in place
        _remove_orphans(folder, [c.key for c in todo])
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
