"""Load a script of the repository (tools/, docs/) as a module, for the tests of its
functions and argument checks."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def load_script(relative: str, name: str | None = None):
    """The module of the script ``relative`` to the repository's root (e.g.
    "tools/fit_fitted.py"), executed under ``name`` (default: its stem + "_tool")."""
    path = ROOT / relative
    spec = importlib.util.spec_from_file_location(name or f"{path.stem}_tool", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod
