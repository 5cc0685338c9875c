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

Only the standard library is imported here.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import stat
import tempfile
import threading
from pathlib import Path
from typing import Callable, Iterator

__all__ = ["atomic_file", "atomic_write", "atomic_folder", "check_output_file", "check_output_folder",
           "current_umask"]

# live temporaries: path -> True for a folder, False for a file
_LIVE: dict[str, bool] = {}
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


def _on_sigterm(signum, frame):  # pragma: no cover - exercised in a child process by the tests
    for path, is_dir in list(_LIVE.items()):
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
        _LIVE[path] = is_dir


def _unregister(path: str) -> None:
    with _LOCK:
        _LIVE.pop(path, None)


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
    finally:
        _remove(tmp, True)
        _unregister(tmp)
