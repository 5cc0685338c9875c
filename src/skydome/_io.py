"""Atomic output: one writer for files and one for folders.

Every file skydome writes goes through :func:`atomic_file` (or :func:`atomic_write`), every
folder of results through :func:`atomic_folder`. Both write to a hidden temporary beside the
target and rename it into place, so a reader sees either the old content or the new, never
a partial one.

* **Permissions.** A new file gets ``0o666 & ~umask`` and a new folder ``0o777 & ~umask``,
  as :func:`open` and :func:`os.mkdir` would give (not the ``0o600`` of :func:`tempfile.mkstemp`);
  replacing an existing file keeps that file's mode.
* **Clean-up.** The temporary is removed on any exception (a full disk, a bad value found
  late), on ``KeyboardInterrupt`` (SIGINT) and on SIGTERM: while a temporary exists, a
  SIGTERM handler removes every live temporary and then terminates the process the way the
  signal's previous disposition would (default: killed by SIGTERM). Python runs signal
  handlers between bytecodes, so a SIGTERM that arrives inside a long compiled kernel takes
  effect when the kernel returns.

* **Other writers.** A writer that makes its own temporary (a memory-mapped matrix, a Zarr
  folder written chunk by chunk) registers it with :func:`temporary` for the same SIGTERM
  clean-up.
* **Errors.** A failed write raises :class:`OSError` with its errno (ENOSPC on a full disk)
  and the name of the file it was writing: :func:`write_exr` turns OpenEXR's RuntimeError
  into one, and :func:`write_npy` replaces ``np.save`` to a file name, whose short write on
  a full disk is an OSError without an errno. A command line reports such an error as one
  line (``could not write 'FILE': No space left on device``) and exit code 2.

Only the standard library is imported here (numpy and OpenEXR inside the writers that need
them).
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import signal
import stat
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable, Iterator

__all__ = ["atomic_file", "atomic_write", "atomic_folder", "atomic_files", "check_output_file",
           "check_output_folder", "current_umask", "temporary", "write_exr", "write_npy"]

# live temporaries: path -> [True for a folder, False for a file; open registrations]
_LIVE: dict[str, list] = {}
_LOCK = threading.Lock()
_PREVIOUS_HANDLER = None
_INSTALLED = False


def current_umask() -> int:
    """The process's umask (read from /proc where available, which changes nothing)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    with _LOCK:  # fallback: set and restore
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


def _remove(path: str, is_dir: bool) -> None:
    try:
        if is_dir:
            shutil.rmtree(path, ignore_errors=True)
        elif os.path.lexists(path):
            os.unlink(path)
    except OSError:
        pass


#: pauses [s] after removing the live temporaries on SIGTERM where other threads run, each
#: followed by the removal of any that came back: a write already under way on another thread (Zarr's I/O runs on its own
#: event-loop thread while the main thread, here, handles the signal) can recreate a removed
#: folder's chunk path after the removal; it was seen, under load, as a left
#: `.a.zarr.part/c/8/0/0`. The main thread issues no new writes meanwhile.
_SIGTERM_SETTLE_S = (0.02, 0.1, 0.3)


def _on_sigterm(signum, frame):  # pragma: no cover - exercised in a child process by the tests
    live = [(path, is_dir) for path, (is_dir, _) in list(_LIVE.items())]
    for path, is_dir in live:
        _remove(path, is_dir)
    # with no other thread nothing can write meanwhile; else every pause, removing what came
    # back after each (0.42 s in all)
    others = threading.active_count() > 1
    for pause in _SIGTERM_SETTLE_S if live and others else ():
        time.sleep(pause)
        for path, is_dir in live:
            if os.path.lexists(path):
                _remove(path, is_dir)
    _LIVE.clear()
    prev = _PREVIOUS_HANDLER
    if callable(prev):
        prev(signum, frame)
        return
    signal.signal(signum, signal.SIG_DFL)
    os.kill(os.getpid(), signum)


def _install_handler() -> None:
    """Install the SIGTERM clean-up once, from the main thread, unless SIGTERM is ignored."""
    global _INSTALLED, _PREVIOUS_HANDLER
    if _INSTALLED or threading.current_thread() is not threading.main_thread():
        return
    try:
        prev = signal.getsignal(signal.SIGTERM)
        if prev is signal.SIG_IGN:
            _INSTALLED = True
            return
        signal.signal(signal.SIGTERM, _on_sigterm)
    except (ValueError, OSError):  # not the main interpreter / no signals here
        return
    _PREVIOUS_HANDLER = None if prev in (signal.SIG_DFL, None) else prev
    _INSTALLED = True


def _register(path: str, is_dir: bool) -> None:
    _install_handler()
    with _LOCK:
        entry = _LIVE.setdefault(path, [is_dir, 0])
        entry[0] = entry[0] or is_dir
        entry[1] += 1


def _unregister(path: str) -> None:
    # registrations of one path nest (a caller that holds a temporary across a library call
    # that registers the same path for its own block): the path stays registered until the
    # outermost block ends, so that no SIGTERM between the two blocks finds it unregistered
    with _LOCK:
        entry = _LIVE.get(path)
        if entry is not None:
            entry[1] -= 1
            if entry[1] <= 0:
                del _LIVE[path]


@contextlib.contextmanager
def temporary(path, is_dir: bool = False) -> Iterator[str]:
    """Register ``path`` (a temporary file, or folder with ``is_dir``, that the caller made)
    for the block: a SIGTERM in the block removes it before the process ends. The caller
    still removes it on an exception and renames it on success; the registration ends with
    the block (with the outermost block where blocks of the same path nest)."""
    path = os.fspath(path)
    _register(path, is_dir)
    try:
        yield path
    finally:
        _unregister(path)


def write_exr(path, header: dict, channels: dict, target=None) -> None:
    """Write an OpenEXR file (``OpenEXR.File(header, channels).write(path)``), raising
    OSError naming ``target`` (default ``path``) where OpenEXR fails: errno ENOSPC for a full
    disk (OpenEXR raises RuntimeError "... No space left on device"), EIO otherwise."""
    import OpenEXR

    # OpenEXR compresses the file's blocks on its global thread pool when it has one (none
    # by default): the same bytes, and on two cores half the wall time of a 4096 x 2048 ZIP
    # map (docs/performance.md); the caller's setting is restored
    threads = OpenEXR.global_thread_count()
    if threads == 0:
        OpenEXR.set_global_thread_count(min(os.cpu_count() or 1, 8))
    try:
        with OpenEXR.File(header, channels) as f:
            f.write(os.fspath(path))
    except RuntimeError as exc:
        text = " ".join(str(exc).split())
        for code in (errno.ENOSPC, errno.EDQUOT, errno.EACCES, errno.EROFS):
            if os.strerror(code).lower() in text.lower():
                raise OSError(code, os.strerror(code), os.fspath(target or path)) from None
        raise OSError(errno.EIO, f"OpenEXR could not write the file ({text})",
                      os.fspath(target or path)) from None
    finally:
        if threads == 0:
            OpenEXR.set_global_thread_count(0)


def write_npy(path, array) -> None:
    """``np.save(path, array)`` through Python's file writes, in 1 MiB pieces: a full disk
    raises OSError ENOSPC naming the file (``np.save`` to a name writes with
    ``ndarray.tofile``, whose short write is an OSError without an errno or a file name)."""
    import numpy as np

    a = np.ascontiguousarray(array)
    with open(path, "wb") as f:
        np.lib.format.write_array_header_1_0(
            f, {"descr": np.lib.format.dtype_to_descr(a.dtype), "fortran_order": False,
                "shape": a.shape})
        data = memoryview(a.reshape(-1)).cast("B")
        for i in range(0, len(data), 1 << 20):
            f.write(data[i:i + (1 << 20)])


def _named(exc: OSError, tmp, path) -> OSError:
    """``exc`` naming the target ``path`` where it named the temporary ``tmp`` or nothing
    (a write error names what the user asked for, not a hidden temporary)."""
    if exc.errno is None or exc.filename not in (None, os.fspath(tmp)):
        return exc
    return OSError(exc.errno, exc.strerror or os.strerror(exc.errno), os.fspath(path))


def _parent(path: Path) -> Path:
    return path.parent if str(path.parent) else Path(".")


@contextlib.contextmanager
def atomic_file(path, suffix: str | None = None) -> Iterator[str]:
    """Yield the name of a temporary file beside ``path``; on a clean exit rename it to ``path``.

    The temporary keeps ``path``'s suffix (or ``suffix``) so that writers which choose a
    format from the file name (Pillow, matplotlib, numpy) choose the right one. On any
    exception, ``KeyboardInterrupt`` or SIGTERM the temporary is removed and ``path`` is left
    as it was.
    """
    path = Path(path)
    suf = path.suffix if suffix is None else suffix
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + suf, dir=_parent(path))
    os.close(fd)
    _register(tmp, False)
    try:
        yield tmp
        try:
            mode = stat.S_IMODE(os.stat(path).st_mode)   # replacing: keep the target's mode
        except FileNotFoundError:
            mode = 0o666 & ~current_umask()
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except OSError as exc:
        _remove(tmp, False)
        raise _named(exc, tmp, path) from exc
    except BaseException:
        _remove(tmp, False)
        raise
    finally:
        _unregister(tmp)


def atomic_write(path, write: Callable[[str], None], suffix: str | None = None) -> Path:
    """Call ``write(tmp)`` on a temporary file beside ``path`` and rename it to ``path``."""
    with atomic_file(path, suffix=suffix) as tmp:
        write(tmp)
    return Path(path)


def check_output_folder(path, name: str = "out") -> Path:
    """Check, before any work, that ``path`` can become an output folder.

    It must not be an existing file, and its parent folder must exist and be writable (or,
    when ``path`` exists as a folder, ``path`` itself must be writable). Raises ValueError
    naming the option ``name`` and the value.
    """
    p = Path(path)
    if str(path) == "":
        raise ValueError(f"{name} = '': give an output folder")
    if p.exists() and not p.is_dir():
        raise ValueError(f"{name} = {str(path)!r} is an existing file, not a folder")
    parent = _parent(p)
    if not parent.is_dir():
        raise ValueError(f"{name} = {str(path)!r}: folder {str(parent)!r} does not exist")
    writable = p if p.is_dir() else parent
    if not os.access(writable, os.W_OK | os.X_OK):
        raise ValueError(f"{name} = {str(path)!r}: folder {str(writable)!r} is not writable")
    return p


def check_output_file(path, suffixes=None, name: str = "out") -> Path:
    """Check, before any work, that ``path`` can be written as an output file: its suffix is
    one of ``suffixes`` (when given), it is not an existing folder, and its folder exists and
    is writable. Raises ValueError naming the option ``name`` and the value."""
    p = Path(path)
    if str(path) == "":
        raise ValueError(f"{name} = '': give an output file")
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise ValueError(f"{name} = {str(path)!r}: the file must end in {', '.join(suffixes)}")
    if p.is_dir():
        raise ValueError(f"{name} = {str(path)!r} is an existing folder, not a file")
    parent = _parent(p)
    if not parent.is_dir():
        raise ValueError(f"{name} = {str(path)!r}: folder {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"{name} = {str(path)!r}: folder {str(parent)!r} is not writable")
    return p


@contextlib.contextmanager
def atomic_files(paths, suffixes=None) -> Iterator[list[str]]:
    """Several files as one unit, all or none: yield a temporary file beside each of
    ``paths`` (keeping its suffix, or the one in ``suffixes``); on a clean exit rename every
    one into place. On any exception, ``KeyboardInterrupt`` or SIGTERM while they are written
    every temporary is removed and no target is touched; should a rename fail (after all
    were written) the targets already renamed are removed too, so that no file is left
    without the others."""
    paths = [Path(p) for p in paths]
    sufs = [p.suffix for p in paths] if suffixes is None else list(suffixes)
    tmps: list[str] = []
    done: list[Path] = []
    try:
        for p, suf in zip(paths, sufs):
            fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp" + suf,
                                       dir=_parent(p))
            os.close(fd)
            _register(tmp, False)
            tmps.append(tmp)
        yield list(tmps)
        for p, tmp in zip(paths, tmps):
            try:
                mode = stat.S_IMODE(os.stat(p).st_mode)
            except FileNotFoundError:
                mode = 0o666 & ~current_umask()
            os.chmod(tmp, mode)
        for p, tmp in zip(paths, tmps):
            os.replace(tmp, p)
            done.append(p)
    except BaseException:
        for tmp in tmps:
            _remove(tmp, False)
        if len(done) < len(paths):
            for p in done:
                _remove(str(p), False)
        raise
    finally:
        for tmp in tmps:
            _unregister(tmp)


@contextlib.contextmanager
def atomic_folder(path) -> Iterator[Path]:
    """Yield a temporary folder beside ``path``; on a clean exit its files become ``path``.

    If ``path`` does not exist the whole temporary folder is renamed to it (one atomic step);
    if it is an existing folder, each file is renamed into it (files of the same name are
    replaced, others kept). On any exception, ``KeyboardInterrupt`` or SIGTERM the temporary
    folder is removed and ``path`` is left as it was.
    """
    path = check_output_folder(path)
    tmp = tempfile.mkdtemp(prefix=f".{path.name or 'out'}.", suffix=".tmp", dir=_parent(path))
    _register(tmp, True)
    try:
        yield Path(tmp)
        if not path.exists():
            os.chmod(tmp, 0o777 & ~current_umask())
            os.rename(tmp, path)
        else:
            for f in sorted(os.listdir(tmp)):
                os.replace(os.path.join(tmp, f), path / f)
    except OSError as exc:   # name the file in the target folder, not in the temporary one
        name = os.fspath(exc.filename) if isinstance(exc.filename, (str, Path)) else None
        if exc.errno is not None and (name is None or name.startswith(tmp)):
            where = str(path) if name is None else str(path) + name[len(tmp):]
            raise OSError(exc.errno, exc.strerror or os.strerror(exc.errno), where) from exc
        raise
    finally:
        _remove(tmp, True)
        _unregister(tmp)
