"""Published tables shipped with skydome (CSV with '#' header lines naming the source).

``load_table(name)`` reads ``<name>.csv`` from this folder once and caches it.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

DATA_DIR = Path(__file__).resolve().parent


@lru_cache(maxsize=None)
def load_table(name: str) -> tuple[tuple[str, ...], np.ndarray]:
    """Return (column names, float array of shape (rows, columns)) of ``<name>.csv``.

    Lines starting with '#' are comments (source, units, grid); the first other line is
    the header with the column names. The array is read-only.
    """
    path = DATA_DIR / f"{name}.csv"
    if not path.exists():
        raise FileNotFoundError(f"no data table named {name!r} in {DATA_DIR.name}/")
    with path.open(encoding="utf-8") as f:
        lines = [ln for ln in f if ln.strip() and not ln.lstrip().startswith("#")]
    columns = tuple(c.strip() for c in lines[0].split(","))
    values = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]], dtype=np.float64)
    values.setflags(write=False)
    return columns, values


def table_source(name: str) -> str:
    """The '#' comment lines of ``<name>.csv`` (its provenance), joined."""
    path = DATA_DIR / f"{name}.csv"
    with path.open(encoding="utf-8") as f:
        return "".join(ln.lstrip()[1:].strip() + "\n" for ln in f if ln.lstrip().startswith("#"))
