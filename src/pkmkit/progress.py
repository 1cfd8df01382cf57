"""Progress of long batched work, shown only where a person watches.

Library code marks its long loops with :func:`tracked` (the chunked evaluations of
:mod:`pkmkit.parallel` do so for every grid, workspace and study). Nothing is shown unless a
caller opened a :func:`progress_display` scope: the command line does, for a terminal, so a
command that runs past :data:`DELAY` seconds gets a bar with the elapsed time and an estimate of
the time left on standard error; scripts, pipes and tests see nothing.

The environment variable ``PKMKIT_PROGRESS`` overrides the terminal test: ``1`` shows bars
(also into a pipe), ``0`` never does.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterable, Iterator
from contextvars import ContextVar
from typing import Any, TypeVar

T = TypeVar("T")

#: Seconds of work before a bar appears (shorter work shows nothing).
DELAY = 2.0

_display: ContextVar[dict[str, Any] | None] = ContextVar("pkmkit_progress", default=None)


def wanted(stream: Any = None) -> bool:
    """Whether bars should be shown on ``stream`` (standard error by default): the
    ``PKMKIT_PROGRESS`` override, else whether the stream is a terminal."""
    setting = os.environ.get("PKMKIT_PROGRESS", "").strip()
    if setting in {"0", "1"}:
        return setting == "1"
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


@contextlib.contextmanager
def progress_display(enabled: bool | None = None, *, delay: float = DELAY,
                     stream: Any = None) -> Iterator[None]:
    """Show the bars of :func:`tracked` loops run inside this block on ``stream`` (standard
    error by default) when ``enabled`` (default: :func:`wanted`), each only once its loop has
    run ``delay`` seconds."""
    stream = sys.stderr if stream is None else stream
    on = wanted(stream) if enabled is None else enabled
    token = _display.set({"delay": delay, "stream": stream} if on else None)
    try:
        yield
    finally:
        _display.reset(token)


def tracked(items: Iterable[T], *, total: int | None = None, label: str = "",
            unit: str = "chunk") -> Iterable[T]:
    """``items`` unchanged, counted by a progress bar when a :func:`progress_display` scope
    is open (else returned as is, at no cost)."""
    settings = _display.get()
    if settings is None:
        return items
    from tqdm import tqdm

    return tqdm(items, total=total, desc=label or None, unit=unit, leave=False,
                delay=settings["delay"], file=settings["stream"], dynamic_ncols=True,
                bar_format="{desc}: {percentage:3.0f}% |{bar}| {n_fmt}/{total_fmt} "
                           "[{elapsed} elapsed, {remaining} left]")
