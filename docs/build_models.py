"""Assemble docs/models.md from the sections in docs/sections/ in a fixed order."""

from pathlib import Path

HERE = Path(__file__).resolve().parent
ORDER = [
    "atmosphere", "spectra", "sun", "transport", "rendering",
    "cie", "perez", "preetham",
    "klassen_kaneda", "nishita1993", "nishita1996_dobashi1995", "oneil_dobashi2002",
    "montecarlo", "precomputed", "hillaire2020", "validation",
    "effects_mie", "comparison",
]
HEADER = """# skydome: the models

Every model and every piece of physics in skydome: the paper and equations it implements,
its parameters and valid range, what it does outside that range, every deviation from the
paper, and what it was checked against, with the numbers. This file is assembled from
`docs/sections/` by `scripts/build-docs`; edit the sections.

"""


def main() -> None:
    sections = {p.stem: p for p in (HERE / "sections").glob("*.md")}
    names = [n for n in ORDER if n in sections] + sorted(set(sections) - set(ORDER))
    toc = []
    body = []
    for n in names:
        text = sections[n].read_text().strip() + "\n"
        title = next((ln.lstrip("# ").strip() for ln in text.splitlines() if ln.startswith("#")), n)
        toc.append(f"- [{title}](sections/{n}.md)")
        body.append(text)
    out = HEADER + "## Contents\n\n" + "\n".join(toc) + "\n\n" + "\n\n".join(body)
    (HERE / "models.md").write_text(out)
    print(f"wrote {HERE / 'models.md'} ({len(names)} sections)")


if __name__ == "__main__":
    main()
