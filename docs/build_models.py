"""Assemble docs/models.md (models and physics) and docs/effects.md (effects_* sections)
from the sections in docs/sections/ in a fixed order."""

from pathlib import Path

HERE = Path(__file__).resolve().parent
ORDER = [
    "atmosphere", "spectra", "sun", "transport", "rendering", "illuminance",
    "cie", "perez", "preetham", "hosek_wilkie",
    "klassen_kaneda", "nishita1993", "nishita1996_dobashi1995", "oneil_dobashi2002",
    "montecarlo", "precomputed", "hillaire2020", "fitted", "validation",
    "comparison",
]
EFFECTS_ORDER = ["effects_timelapse", "effects_twilight", "effects_airlight", "effects_mie",
                 "effects_polarisation"]
EFFECTS_HEADER = """# skydome: atmospheric effects (survey section 5)

Each effect with the physics that causes it, how to run it (CLI and API), its parameters,
a rendered figure, and the numeric signature the tests assert. Assembled from
`docs/sections/effects_*.md` by `scripts/build-docs`.

"""
HEADER = """# skydome: the models

Every model and every piece of physics in skydome: the paper and equations it implements,
its parameters and valid range, what it does outside that range, every deviation from the
paper, and what it was checked against, with the numbers. This file is assembled from
`docs/sections/` by `scripts/build-docs`; edit the sections.

"""


def assembled() -> dict:
    """{target path: its text assembled from docs/sections/}."""
    allsec = {p.stem: p for p in (HERE / "sections").glob("*.md")}
    effects = {k: v for k, v in allsec.items() if k.startswith("effects_")}
    models = {k: v for k, v in allsec.items() if k not in effects}
    return {HERE / "models.md": build(models, ORDER, HEADER),
            HERE / "effects.md": build(effects, EFFECTS_ORDER, EFFECTS_HEADER)}


def main() -> None:
    for target, text in assembled().items():
        target.write_text(text)
        print(f"wrote {target}")


def build(sections, order, header) -> str:
    names = [n for n in order if n in sections] + sorted(set(sections) - set(order))
    toc = []
    body = []
    for n in names:
        # figure links are relative to docs/sections/; the assembled file lives in docs/
        text = sections[n].read_text().strip().replace("](../figures/", "](figures/") + "\n"
        title = next((ln.lstrip("# ").strip() for ln in text.splitlines() if ln.startswith("#")), n)
        toc.append(f"- [{title}](sections/{n}.md)")
        body.append(text)
    return header + "## Contents\n\n" + "\n".join(toc) + "\n\n" + "\n\n".join(body)


if __name__ == "__main__":
    main()
