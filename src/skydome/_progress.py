"""Progress of long set-up work: a tiny protocol between the models and whoever shows it.

A model's constructor that does lengthy work (precomputed tables, dobashi1995's basis
table) reports its progress by calling :func:`report`::

    from skydome._progress import report

    for k in range(n_steps):
        ...                                       # one step of the work
        report("precomputing tables", k + 1, n_steps)

By default nothing happens (a no-op costing one context-variable read). A caller that wants
to show progress (the command line shows a rich progress bar) wraps the work in
:func:`reporting`::

    with reporting(lambda stage, done, total: print(stage, done, total)):
        sky = skydome.model("precomputed", sun=sun)

The callback receives ``(stage, done, total)``: a short human-readable name of the stage,
the number of units done and the total (``done <= total``; ``done == total`` when the
stage is complete). It must be cheap and must not raise. Reporters are per thread / per
asyncio task (a :class:`contextvars.ContextVar`), so concurrent work does not mix.
"""

from __future__ import annotations

import contextlib
import contextvars
from typing import Callable, Iterator, Protocol

__all__ = ["ProgressCallback", "report", "reporting", "no_progress"]


class ProgressCallback(Protocol):
    def __call__(self, stage: str, done: int, total: int) -> None: ...


def no_progress(stage: str, done: int, total: int) -> None:
    """The default reporter: does nothing."""


_CURRENT: contextvars.ContextVar[Callable[[str, int, int], None]] = contextvars.ContextVar(
    "skydome_progress", default=no_progress)


def report(stage: str, done: int, total: int) -> None:
    """Tell the current reporter that ``done`` of ``total`` units of ``stage`` are finished."""
    _CURRENT.get()(stage, int(done), int(total))


@contextlib.contextmanager
def reporting(callback: Callable[[str, int, int], None] | None) -> Iterator[None]:
    """Send :func:`report` calls made inside the ``with`` block to ``callback`` (None: none)."""
    if callback is not None and not callable(callback):
        raise TypeError(f"callback must be callable or None, got {callback!r}")
    token = _CURRENT.set(no_progress if callback is None else callback)
    try:
        yield
    finally:
        _CURRENT.reset(token)
