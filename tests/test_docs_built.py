"""docs/models.md and docs/effects.md are assembled from docs/sections/ (docs/build_models.py,
`scripts/build-docs`): the committed files must be what the sections give, so that an edit
made to one side only is caught."""

from pathlib import Path

from _tools import load_script

ROOT = Path(__file__).resolve().parents[1]


def test_assembled_docs_match_their_sections():
    mod = load_script("docs/build_models.py", "build_models")
    for target, text in mod.assembled().items():
        assert target.read_text() == text, (
            f"{target.name} differs from docs/sections/: edit the sections, then run "
            "scripts/build-docs")
