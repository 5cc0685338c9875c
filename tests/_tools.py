"""Load a script of the repository (tools/, docs/) as a module, for the tests of its
functions and argument checks; write a data-set chunk in the layout that
skydome.distributed documents, for the tests of the tools that read one."""

import hashlib
import importlib.util
import io
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def load_script(relative: str, name: str | None = None):
    """The module of the script ``relative`` to the repository's root (e.g.
    "tools/fit_fitted.py"), executed under ``name`` (default: its stem + "_tool")."""
    path = ROOT / relative
    spec = importlib.util.spec_from_file_location(name or f"{path.stem}_tool", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def write_chunk(folder, key: str, arr) -> None:
    """Write ``arr`` as the chunk ``key`` of the data-set folder ``folder``: ``KEY.npy`` (the
    array as numpy saves it) and ``KEY.npy.sha256`` (its SHA-256 in hex), the layout that
    skydome.distributed's run_chunks writes and its assemble_chunks verifies."""
    buf = io.BytesIO()
    np.save(buf, np.ascontiguousarray(arr))
    (Path(folder) / f"{key}.npy").write_bytes(buf.getvalue())
    (Path(folder) / f"{key}.npy.sha256").write_text(hashlib.sha256(buf.getvalue()).hexdigest())
