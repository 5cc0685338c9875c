"""Radiance matrix files (the format of rmtxop, dctimestep, gendaymtx) and .npy.

A Radiance matrix file is an information header, a blank line, then the data [RMTX]::

    #?RADIANCE
    <command line or comment lines>
    NROWS=146
    NCOLS=8760
    NCOMP=3
    FORMAT=ascii          (or float / double; binary files also carry BigEndian=0|1)

    <data>

The data is row-major: for each row, each column, NCOMP components. A sky matrix has one row
per sky patch and one column per time step (gendaymtx's layout); skydome holds it in memory as
(n_hours, n_patches, n_components) and transposes on writing.

References
----------
.. [RMTX] G. Ward, "rmtxop", "dctimestep" and "gendaymtx" manual pages, Radiance 5.4
   (matrix file header: NROWS, NCOLS, NCOMP, FORMAT).
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from skydome._io import _named, temporary

__all__ = ["write_matrix", "read_matrix", "matrix_file", "atomic_write_bytes",
           "atomic_write_stream", "FORMATS"]

FORMATS = ("ascii", "float", "double")


def atomic_write_bytes(path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file beside it and a rename."""
    atomic_write_stream(path, [data])


def _umask() -> int:
    m = os.umask(0)
    os.umask(m)
    return m


#: A binary file's data starts at a multiple of this many bytes (the item size of a double).
DATA_ALIGN = 8


def _header(nrows: int, ncols: int, ncomp: int, fmt: str, info: list[str]) -> bytes:
    """The header, ending with its blank line. For a binary format the NCOMP line is padded
    with trailing spaces so that the data starts at a multiple of :data:`DATA_ALIGN` bytes
    (Radiance and ``int()`` read the value and ignore them): a memory map of the body is then
    aligned, which numpy needs to write into it in place; into a misaligned float32 map (a
    238-byte header) every ufunc and matrix product went through a copy, and the annual MF:4
    matrix + file cost 0.29-0.30 s of CPU against 0.25 s aligned (best of 6, interleaved)."""
    lines = ["#?RADIANCE"] + [s.replace("\n", " ") for s in info]
    lines += [f"NROWS={nrows}", f"NCOLS={ncols}", f"NCOMP={ncomp}"]
    if fmt != "ascii":
        lines.append(f"BigEndian={int(sys.byteorder == 'big')}")
    lines.append(f"FORMAT={fmt}")
    size = len(("\n".join(lines) + "\n\n").encode())
    if fmt != "ascii" and size % DATA_ALIGN:
        lines[-3] += " " * (DATA_ALIGN - size % DATA_ALIGN)  # NCOMP=, BigEndian=, FORMAT=
    return ("\n".join(lines) + "\n\n").encode()


def write_matrix(path, matrix, fmt: str = "float", info=(), overwrite: bool = False,
                 transpose: bool = False) -> None:
    """Write a Radiance matrix file atomically, streaming it in blocks of rows.

    Parameters
    ----------
    path : str or Path
        Target file; a ``.npy`` suffix writes NumPy's format instead (the array as given).
    matrix : array_like
        (nrows, ncols, ncomp) or (nrows, ncols) (one component) in file order (rows first);
        with ``transpose`` (ncols, nrows, ncomp), e.g. a sky matrix held as (hours, patches,
        components), written without a transposed copy in memory.
    fmt : {"ascii", "float", "double"}
        Data format (ascii with 7 significant digits; float/double in native byte order).
    info : sequence of str
        Header lines (e.g. the command line that made the matrix).
    overwrite : bool
        Refuse an existing ``path`` unless True.
    """
    from skydome._validate import check_choice

    check_choice("fmt", fmt, FORMATS)
    m = np.asarray(matrix)
    if m.ndim == 2:
        m = m[:, :, None]
    if m.ndim != 3:
        raise ValueError(f"matrix has shape {m.shape}; expected (nrows, ncols[, ncomp])")
    path = Path(path)
    if path.exists() and not overwrite:
        raise ValueError(f"out = {str(path)!r} exists (pass overwrite to replace it)")
    if not path.parent.is_dir():
        raise ValueError(f"out = {str(path)!r}: folder {str(path.parent)!r} does not exist")
    if transpose:
        m = np.swapaxes(m, 0, 1)  # a view
    nrows, ncols, ncomp = m.shape
    block = max(1, (1 << 22) // max(1, ncols * ncomp))  # about 4 M values per block
    for r0 in range(0, nrows, block):
        if not np.all(np.isfinite(m[r0:r0 + block])):
            raise ValueError("matrix holds nan or inf values")
    if path.suffix.lower() == ".npy":
        import io

        buf = io.BytesIO()
        np.save(buf, np.asarray(matrix, dtype=np.float64))
        atomic_write_bytes(path, buf.getvalue())
        return
    head = _header(nrows, ncols, ncomp, fmt, list(info))
    dtype = {"float": np.float32, "double": np.float64}.get(fmt)

    def blocks():
        yield head
        for r0 in range(0, nrows, block):
            part = m[r0:r0 + block]
            if fmt == "ascii":
                yield _ascii_body(np.asarray(part, dtype=np.float64))
            else:
                yield np.ascontiguousarray(part, dtype=dtype).data

    atomic_write_stream(path, blocks())


@contextlib.contextmanager
def matrix_file(path, nrows: int, ncols: int, ncomp: int, fmt: str = "float", info=(),
                overwrite: bool = False, check_finite: bool = True):
    """A binary Radiance matrix file filled in place: yields its data as a zero-filled
    (nrows, ncols, ncomp) memory map, to be filled (e.g. ``perez_sky_matrix(..., out=...)``).

    The file is a temporary one beside ``path`` (header, then a body of zeros written
    sequentially), renamed to ``path`` when the block ends without an exception and the data
    is finite; otherwise (also on SIGTERM) it is removed, nothing is left. Writing through
    the map costs no copy and no second pass. ``check_finite=False`` skips the final reading
    of the whole map for nan or inf (0.012-0.024 s for an annual MF:4 float matrix, 242 MB,
    on a 2-core EPYC): for a filler that has checked every value it wrote and raises
    otherwise.

    The body is written as zeros first, in 1 MiB blocks, rather than left sparse: a sky
    matrix kernel fills the map in runs of hours scattered over every patch row, and on a
    sparse file each first touch of a page is a page fault that allocates it out of order
    (annual MF:4 float matrix, 242 MB, 2-core EPYC, ext4: 0.32-0.39 s of system time and
    0.2-0.3 s more user time in the kernel). Writing the zeros costs 0.06-0.11 s, after which
    the kernel's faults find their pages in the page cache (0.01 s); a sequential ``dd`` of
    the same 242 MB costs 0.05-0.06 s.
    """
    from skydome._validate import check_choice

    check_choice("fmt", fmt, ("float", "double"))
    path = Path(path)
    if path.exists() and not overwrite:
        raise ValueError(f"out = {str(path)!r} exists (pass overwrite to replace it)")
    if not path.parent.is_dir():
        raise ValueError(f"out = {str(path)!r}: folder {str(path.parent)!r} does not exist")
    head = _header(nrows, ncols, ncomp, fmt, list(info))
    dtype = np.dtype(np.float32 if fmt == "float" else np.float64)
    size = nrows * ncols * ncomp * dtype.itemsize
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    mm = None
    try:
        with temporary(tmp):     # a SIGTERM meanwhile removes the temporary
            with os.fdopen(fd, "wb", buffering=0) as f:
                f.write(head)
                zeros = bytes(min(size, 1 << 20))
                for a in range(0, size, len(zeros) or 1):  # the body's pages, in file order
                    f.write(zeros[:min(len(zeros), size - a)])
            mm = np.memmap(tmp, dtype=dtype, mode="r+", offset=len(head),
                           shape=(nrows, ncols, ncomp))
            yield mm.view(np.ndarray)
            block = max(1, (1 << 22) // max(1, ncols * ncomp))
            for r0 in range(0, nrows if check_finite else 0, block):
                if not np.all(np.isfinite(mm[r0:r0 + block])):
                    raise ValueError("matrix holds nan or inf values")
            del mm  # no msync: the page cache is coherent, as for a written file
            mm = None
            os.chmod(tmp, 0o666 & ~_umask())
            os.replace(tmp, path)
    except OSError as exc:
        del mm
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise _named(exc, tmp, path) from exc
    except BaseException:
        del mm
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


#: Bytes per ``write`` call of a streamed file. Linux 6.x fills the page cache of a larger
#: write with large (2 MiB) folios; on the 2-core EPYC virtual machine of docs/performance.md
#: their first touch is slow: writing a 242 MB file in 2-8 MiB calls cost 0.3-0.8 s of system
#: time, in 64 KiB-1 MiB calls 0.05-0.07 s (every time, same run).
WRITE_SLICE = 1 << 20


def atomic_write_stream(path, chunks) -> None:
    """Write the byte chunks of an iterable to ``path`` through a temporary file and a
    rename (each chunk in ``write`` calls of at most :data:`WRITE_SLICE` bytes, no copy);
    nothing is left behind if it fails (an exception, Ctrl-C, or SIGTERM: the temporary is
    registered with :func:`skydome._io.temporary`). A failed write raises OSError naming
    ``path`` (ENOSPC on a full disk)."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    try:
        with temporary(tmp):     # a SIGTERM meanwhile removes the temporary
            with os.fdopen(fd, "wb") as f:
                for c in chunks:
                    c = memoryview(c).cast("B")
                    for a in range(0, len(c), WRITE_SLICE):
                        f.write(c[a:a + WRITE_SLICE])
            os.chmod(tmp, 0o666 & ~_umask())
            os.replace(tmp, path)
    except OSError as exc:       # a full disk: ENOSPC naming the file asked for
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise _named(exc, tmp, path) from exc
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _ascii_body(m: np.ndarray) -> bytes:
    """One line per (row, column) with NCOMP values; a blank line after each row."""
    nrows, ncols, ncomp = m.shape
    out = []
    flat = m.reshape(nrows, ncols * ncomp)
    fmt_row = " ".join(["%.7g"] * ncomp)
    for r in range(nrows):
        vals = flat[r].reshape(ncols, ncomp)
        out.append("\n".join(fmt_row % tuple(v) for v in vals))
        out.append("\n\n")
    return "".join(out).encode()


def read_matrix(path) -> tuple[np.ndarray, dict]:
    """Read a Radiance matrix file (or a .npy file).

    Returns
    -------
    matrix : numpy.ndarray
        (nrows, ncols, ncomp) float64.
    header : dict
        The header's variables (NROWS, NCOLS, NCOMP, FORMAT, BigEndian, ...) as strings,
        plus ``"lines"``: every header line.
    """
    path = Path(path)
    if path.suffix.lower() == ".npy":
        return np.load(path), {}
    raw = path.read_bytes()
    end = raw.find(b"\n\n")
    if not raw.startswith(b"#?RADIANCE") or end < 0:
        raise ValueError(f"{str(path)!r} is not a Radiance matrix file (no #?RADIANCE header)")
    lines = raw[:end].decode(errors="replace").splitlines()
    header: dict = {"lines": lines}
    for ln in lines[1:]:
        if "=" in ln:
            k, _, v = ln.partition("=")
            header[k.strip()] = v.strip()
    try:
        nrows, ncols = int(header["NROWS"]), int(header["NCOLS"])
        ncomp = int(header.get("NCOMP", "1"))
    except (KeyError, ValueError):
        raise ValueError(f"{str(path)!r}: header lacks NROWS/NCOLS") from None
    fmt = header.get("FORMAT", "ascii")
    body = raw[end + 2:]
    if fmt == "ascii":
        data = np.array(body.split(), dtype=np.float64)
    elif fmt in ("float", "double"):
        big = header.get("BigEndian", str(int(sys.byteorder == "big"))) == "1"
        dt = np.dtype(np.float32 if fmt == "float" else np.float64).newbyteorder(
            ">" if big else "<")
        data = np.frombuffer(body, dtype=dt).astype(np.float64)
    else:
        raise ValueError(f"{str(path)!r}: FORMAT={fmt} is not supported (ascii, float, double)")
    if data.size != nrows * ncols * ncomp:
        raise ValueError(f"{str(path)!r}: {data.size} values for {nrows} x {ncols} x {ncomp}")
    return data.reshape(nrows, ncols, ncomp), header
