"""``skydome validate``: models against measured skies.

``skydome validate measured`` compares the models with the Kider et al. 2014 scans of
2013-05-27 (:func:`skydome.validation.compare.compare_measured`) and prints, or writes
(``--out table.md``, atomically), the day's table; ``skydome validate closure`` the broadband
irradiance against the pyranometer (:mod:`skydome.validation.closure`).
"""

from __future__ import annotations

from typing import Optional

import typer

from skydome.cli._kit import _fail

validate_app = typer.Typer(add_completion=False, no_args_is_help=True, rich_markup_mode=None,
                           help="Validate the models against measured skies.")


def _captures(captures):
    """The capture labels of a comma-separated option (None: all)."""
    from skydome.validation.kider2014 import capture_labels

    if captures is None:
        return None
    labs = [c.strip() for c in captures.split(",") if c.strip()]
    wrong = [c for c in labs if c not in capture_labels()]
    if not labs or wrong:
        _fail(f"captures = {captures!r}: each must be one of {', '.join(capture_labels())}")
    return labs


@validate_app.command("measured")
def measured(
    models: str = typer.Option(",".join(("precomputed", "hillaire2020", "nishita1996", "single_scattering",
                                         "preetham1999", "hosek_wilkie2012", "perez1993", "cie2003")),
                               help="Comma-separated models (also montecarlo, precomputed_accurate)."),
    captures: Optional[str] = typer.Option(None, help="Comma-separated capture labels HH:MM:SS (default all 15)."),
    phase: str = typer.Option("tabulated", help="Aerosol phase of the physically based models: tabulated "
                                                "(AERONET, measured), henyey_greenstein or cornette_shanks."),
    fast: bool = typer.Option(False, "--fast", help="Coarse model settings (quick look)."),
    out: Optional[str] = typer.Option(None, help="Write the Markdown table to this .md file."),
) -> None:
    """Compare models with the Kider et al. 2014 sky scans of 2013-05-27 (Cornell)."""
    from pathlib import Path

    from skydome.validation.compare import MODELS, compare_measured, day_table

    names = [m.strip() for m in models.split(",") if m.strip()]
    valid = MODELS + ("precomputed_accurate",)
    bad = [m for m in names if m not in valid]
    if not names or bad:
        _fail(f"models = {models!r}: each must be one of {', '.join(valid)}")
    labs = _captures(captures)
    if phase not in ("tabulated", "henyey_greenstein", "cornette_shanks"):
        _fail(f"phase = {phase!r}: must be tabulated, henyey_greenstein or cornette_shanks")
    if out is not None:
        p = Path(out)
        if p.suffix.lower() != ".md":
            _fail(f"out = {out!r}: must be a .md file")
        if not p.parent.is_dir():
            _fail(f"out = {out!r}: folder {str(p.parent)!r} does not exist")
    try:
        results = compare_measured(names, labs, fast=fast, phase=phase,
                                   progress=lambda m, c: typer.echo(f"{m} {c}", err=True))
    except (ValueError, TypeError) as exc:
        _fail(str(exc.args[0] if exc.args else exc))
    table = day_table(results)
    if out is None:
        typer.echo(table)
        return
    from skydome._io import atomic_write

    def write(tmp):
        Path(tmp).write_text(table, encoding="utf-8")
    atomic_write(out, write)
    typer.echo(f"wrote {out}")


@validate_app.command("closure")
def closure_cmd(
    model: str = typer.Option("precomputed", help="precomputed or hillaire2020."),
    captures: Optional[str] = typer.Option(None, help="Comma-separated capture labels HH:MM:SS (default all)."),
    water: float = typer.Option(1.42, help="Precipitable water [cm], 0-10 (default: US standard)."),
    fast: bool = typer.Option(False, "--fast", help="precomputed at coarse table sizes."),
) -> None:
    """Broadband (300-2800 nm) global horizontal irradiance against the Kider et al. 2014
    pyranometer, capture by capture (prints a Markdown table)."""
    from skydome.validation import closure
    from skydome.validation.kider2014 import load_captures

    if model not in closure.CLOSURE_MODELS:
        _fail(f"model = {model!r}: must be one of {', '.join(closure.CLOSURE_MODELS)}")
    if not 0.0 <= water <= 10.0:
        _fail(f"water = {water:g} is out of range [0, 10] cm")
    labs = _captures(captures)
    res = closure.closure(load_captures(labs), model, precipitable_water_cm=water, fast=fast)
    typer.echo(closure.closure_table(res))
