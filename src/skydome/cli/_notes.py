"""The library's notes on stderr as one line each: ``note: ...``.

Some library functions tell of something kept or left out (hours beyond the clear-sky
limit, lit hours outside a model's sun range) by a warning of a class of their own
(:class:`skydome.daylighting.skymatrix.ClearSkyNote`, ``SunRangeNote``). A command shows
these as one line each instead of Python's two-line warning format; other warnings keep
theirs. This module imports nothing of typer (the sky-matrix fast path uses it).
"""

from __future__ import annotations

import contextlib
import sys
import warnings
from typing import Callable, Iterator


def _print_note(text: str) -> None:
    print(text, file=sys.stderr)


@contextlib.contextmanager
def notes_as_lines(*categories: type[Warning],
                   emit: Callable[[str], None] = _print_note) -> Iterator[None]:
    """Inside the ``with`` block, each warning of ``categories`` goes to ``emit`` as the
    line ``note: MESSAGE`` (its whitespace folded into single spaces), every time it is
    raised; other warnings are shown as before."""
    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, categories):
            emit("note: " + " ".join(str(message).split()))
        else:
            shown(message, category, filename, lineno, file, line)

    with warnings.catch_warnings():
        for category in categories:
            warnings.simplefilter("always", category)
        warnings.showwarning = show
        yield
