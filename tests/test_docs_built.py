"""docs/models.md and docs/effects.md are assembled from docs/sections/ (docs/build_models.py,
`scripts/build-docs`): the committed files must be what the sections give, so that an edit
made to one side only is caught."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_assembled_docs_match_their_sections():
    spec = importlib.util.spec_from_file_location("build_models", ROOT / "docs" / "build_models.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    for target, text in mod.assembled().items():
        assert target.read_text() == text, (
            f"{target.name} differs from docs/sections/: edit the sections, then run "
            "scripts/build-docs")
