"""``skydome validate``: models against measured skies.

``skydome validate measured`` compares the models with the Kider et al. 2014 scans
(``--day``: 2013-05-27, 2013-09-24 or all; :func:`skydome.validation.compare.compare_measured`)
and prints, or writes (``--out table.md``, atomically), each day's table and the table of
every capture; ``skydome validate closure`` the broadband
irradiance against the pyranometer (:mod:`skydome.validation.closure`).
"""

from __future__ import annotations

from typing import Optional

import typer

from skydome.cli._kit import _fail

validate_app = typer.Typer(add_completion=False, no_args_is_help=True, rich_markup_mode=None,
                           help="Validate the models against measured skies.")


def _captures(captures, days=None):
    """The capture labels of a comma-separated option (None: all), each a capture of one of
    ``days`` (default the first day)."""
    from skydome.validation.kider2014 import DEFAULT_DAY, capture_labels

    if captures is None:
        return None
    days = [DEFAULT_DAY] if days is None else days
    valid = list(dict.fromkeys(lab for d in days for lab in capture_labels(d)))
    labs = [c.strip() for c in captures.split(",") if c.strip()]
    wrong = [c for c in labs if c not in valid]
    if not labs or wrong:
        _fail(f"captures = {captures!r}: each must be one of {', '.join(valid)}")
    return labs


def _days(day):
    from skydome.validation.kider2014 import DAYS

    if day == "all":
        return list(DAYS)
    if day not in DAYS:
        _fail(f"day = {day!r}: must be one of {', '.join(DAYS)} or all")
    return [day]


@validate_app.command("measured")
def measured(
    models: str = typer.Option(",".join(("precomputed", "hillaire2020", "nishita1996",
                                         "single_scattering", "fitted", "preetham1999",
                                         "hosek_wilkie2012", "perez1993", "cie2003")),
                               help="Comma-separated models (also montecarlo, precomputed_accurate)."),
    captures: Optional[str] = typer.Option(
        None, help="Comma-separated capture labels HH:MM:SS (default all of the day)."),
    day: str = typer.Option("2013-05-27", help="2013-05-27, 2013-09-24 or all."),
    aerosol: str = typer.Option(
        "auto", help="aeronet (the Egbert retrieval; 2013-05-27 only), fitted (tau440 and alpha "
                     "fitted to each scan) or auto (aeronet where there is one, else fitted)."),
    phase: str = typer.Option("tabulated", help="Aerosol phase of the physically based models: tabulated "
                                                "(AERONET, measured), henyey_greenstein or cornette_shanks."),
    fast: bool = typer.Option(False, "--fast", help="Coarse model settings (quick look)."),
    out: Optional[str] = typer.Option(None, help="Write the Markdown table to this .md file."),
) -> None:
    """Compare models with the Kider et al. 2014 sky scans (Cornell): each day's table, then
    every capture."""
    from pathlib import Path

    from skydome.validation.compare import MODELS, measured_report

    names = [m.strip() for m in models.split(",") if m.strip()]
    valid = MODELS + ("precomputed_accurate",)
    bad = [m for m in names if m not in valid]
    if not names or bad:
        _fail(f"models = {models!r}: each must be one of {', '.join(valid)}")
    days = _days(day)
    labs = _captures(captures, days)
    if aerosol not in ("auto", "aeronet", "fitted"):
        _fail(f"aerosol = {aerosol!r}: must be auto, aeronet or fitted")
    if aerosol == "aeronet" and days != ["2013-05-27"]:
        _fail(f"aerosol = 'aeronet' with day = {day!r}: AERONET is shipped for 2013-05-27 only")
    if phase not in ("tabulated", "henyey_greenstein", "cornette_shanks"):
        _fail(f"phase = {phase!r}: must be tabulated, henyey_greenstein or cornette_shanks")
    if out is not None:
        p = Path(out)
        if p.suffix.lower() != ".md":
            _fail(f"out = {out!r}: must be a .md file")
        if not p.parent.is_dir():
            _fail(f"out = {out!r}: folder {str(p.parent)!r} does not exist")
    try:
        table, _ = measured_report(names, days, labs, fast=fast, phase=phase,
                                   aerosol=None if aerosol == "auto" else aerosol,
                                   progress=lambda d, m, c: typer.echo(f"{d} {m} {c}", err=True))
    except (ValueError, TypeError) as exc:
        _fail(str(exc.args[0] if exc.args else exc))
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
