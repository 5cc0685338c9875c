"""numba's cache keyed on a kernel file's imports as well as on its own text.

numba keys a cached kernel on its own source file alone (a SHA-256 of its content since
numba 0.68, its modification time and size before). A kernel compiles the ``@njit``
functions it calls from other files, and the module-level constants it reads from them,
into its own machine code; after such a file changes, the cached caller still runs the
old callee (or the old constant) until the caller's own file changes too. Seen in this
package: ``render_observer`` (``precomputed/_render.py``) kept the old ``slice_index`` of
``_multiple.py`` after the sky map's rows changed, and read the new map with the old
lookup (100-300 % off). The same holds for an upgrade whose caller file is unchanged but
whose callee file is not, with entries left in a user's cache folder.

Importing this module puts cache locators of skydome's own in front of numba's: the same
three folders numba would use (``NUMBA_CACHE_DIR``, the package's ``__pycache__``, the
user-wide cache folder), for source files of the registered packages (skydome) only. Their
source stamp is numba's own stamp of the file together with a SHA-256 over the content of
every file of the package that the file imports at module level, transitively: a kernel's
globals, callees included, can only come from there. A change to any of those files makes
numba compile the kernel again; a change elsewhere in the package does not. The stamp
names files by their path inside the package, so that the entries a wheel's build compiles
stay valid where pip installs them (``tests/test_kernel_build_cache.py``).

Kernel modules import ``njit`` (and ``prange``) from here, so that the locators are in place
before their first ``@njit(cache=True)``; ``tests/test_kernel_cache.py`` checks that every
kernel file does. Where ``NUMBA_CACHE_LOCATOR_CLASSES`` names locators, numba uses those
and this module changes nothing.
"""

from __future__ import annotations

import functools
import hashlib
import os
import re

from numba import njit, prange  # noqa: F401  (re-exported for the kernel modules)
from numba.core import caching as _caching

# packages whose files get the import-keyed stamp: name -> folder of its __init__.py
_PACKAGES: dict[str, str] = {"skydome": os.path.dirname(os.path.abspath(__file__))}

# module-level imports: a statement that starts a line (indented ones are inside functions
# or blocks and cannot give a kernel its globals); a parenthesised name list may span lines
_FROM = re.compile(r"^from[ \t]+([.\w]+)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)", re.M)
_IMPORT = re.compile(r"^import[ \t]+([^\n]+)", re.M)


def register_package(name: str, folder: str) -> None:
    """Give the source files of package *name* (its ``__init__.py`` in *folder*) the
    import-keyed stamp too."""
    _PACKAGES[name] = os.path.abspath(folder)
    _forget()


def _forget() -> None:
    """Drop what this process has read of the packages' files."""
    for cached in (_read, _imports, _closure, _digest):
        cached.cache_clear()


def _package_of(path: str) -> tuple[str, str] | None:
    """(package name, its folder) of a source file inside a registered package, else None."""
    path = os.path.abspath(path)
    for name, folder in _PACKAGES.items():
        if path.startswith(folder + os.sep):
            return name, folder
    return None


def _module_file(folder: str, parts: list[str]) -> str | None:
    """The file of module ``package.<parts>`` (a module or a package's __init__.py)."""
    base = os.path.join(folder, *parts)
    for candidate in (base + ".py", os.path.join(base, "__init__.py")):
        if os.path.isfile(candidate):
            return candidate
    return None


@functools.lru_cache(maxsize=None)
def _read(path: str) -> tuple[str, bytes]:
    """(text, SHA-256) of a source file, read once per process as the caches that use it
    (_imports, _digest) are; _forget drops it with them."""
    with open(path, "rb") as f:
        data = f.read()
    return data.decode("utf-8", errors="replace"), hashlib.sha256(data).digest()


def imported_files(path: str) -> list[str]:
    """The files of *path*'s package that *path* imports at module level (not transitively)."""
    return list(_imports(os.path.abspath(path)))


@functools.lru_cache(maxsize=None)
def _imports(path: str) -> tuple[str, ...]:
    found = _package_of(path)
    if found is None:
        return ()
    package, folder = found
    rel = os.path.relpath(os.path.abspath(path), folder).split(os.sep)
    here = rel[:-1]                 # the package a relative import of this file starts from
    text, _ = _read(path)
    out: list[str] = []

    def resolve(module: str) -> list[str] | None:
        """A module name's parts inside the package, or None outside it."""
        level = len(module) - len(module.lstrip("."))
        dotted = [p for p in module[level:].split(".") if p]
        if level:
            if level - 1 > len(here):
                return None
            return here[: len(here) - (level - 1)] + dotted
        if not dotted or dotted[0] != package:
            return None
        return dotted[1:]

    def add(parts: list[str] | None, names: list[str]) -> None:
        """The file of each name that is a submodule; the module's own file for the rest."""
        if parts is None:
            return
        rest = not names
        for name in names:
            sub = _module_file(folder, parts + [name]) if name != "*" else None
            if sub is not None:
                out.append(sub)
            else:
                rest = True
        own = _module_file(folder, parts) if rest else None
        if own is not None:
            out.append(own)

    for m in _FROM.finditer(text):
        listed = re.sub(r"#[^\n]*", "", m.group(2)).strip().strip("()")
        names = [item.split()[0] for item in listed.split(",") if item.split()]
        add(resolve(m.group(1)), names)
    for m in _IMPORT.finditer(text):
        for item in re.sub(r"#[^\n]*", "", m.group(1)).split(","):
            if item.split():
                add(resolve(item.split()[0]), [])
    return tuple(sorted(set(p for p in out if p != path)))


@functools.lru_cache(maxsize=None)
def _closure(path: str) -> tuple[str, ...]:
    """*path*'s package files imported at module level, transitively (without *path*)."""
    seen: set[str] = set()
    todo = [path]
    while todo:
        for f in _imports(todo.pop()):
            if f not in seen and f != path:
                seen.add(f)
                todo.append(f)
    return tuple(sorted(seen))


def imports_digest(path: str) -> bytes:
    """SHA-256 over (path inside the package, SHA-256 of the content) of every file that
    *path* imports at module level, transitively; the same digest wherever the package
    lies. Read once per file and process (every kernel of a file asks for it)."""
    return _digest(os.path.abspath(path))


@functools.lru_cache(maxsize=None)
def _digest(path: str) -> bytes:
    found = _package_of(path)
    if found is None:
        return b""
    folder = found[1]
    h = hashlib.sha256()
    for f in _closure(path):
        h.update(os.path.relpath(f, folder).replace(os.sep, "/").encode())
        h.update(_read(f)[1])
    return h.digest()


class _ImportsKeyed:
    """Mixin for numba's source-file locators: the stamp carries the imports' digest; only
    files of a registered package are taken."""

    def get_source_stamp(self):
        return (super().get_source_stamp(), imports_digest(self._py_file))

    @classmethod
    def from_function(cls, py_func, py_file):
        if _package_of(py_file) is None:
            return None
        return super().from_function(py_func, py_file)


def _locator(numba_name: str):
    base = (getattr(_caching, numba_name, None)
            or getattr(_caching, "_" + numba_name, None))      # numba < 0.68: private names
    if base is None:
        return None
    return type("Imports" + numba_name, (_ImportsKeyed, base), {"__module__": __name__})


def _install() -> None:
    impl = getattr(_caching, "CacheImpl", None) or getattr(_caching, "_CacheImpl", None)
    if impl is None or any(issubclass(c, _ImportsKeyed) for c in impl._locator_classes):
        return
    ours = [_locator(n) for n in ("UserProvidedCacheLocator", "InTreeCacheLocator",
                                  "UserWideCacheLocator")]
    if None in ours:
        return
    impl._locator_classes[:0] = ours


_install()
