"""Saving figures atomically: a figure file appears whole or not at all."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pkmkit.exceptions import InputError
from pkmkit.io.atomic import atomic_path


def save_figure(fig: Any, path: str | Path, **options: Any) -> None:
    """``fig.savefig(path, **options)`` through a temporary file that replaces ``path`` only
    when complete (the format follows ``path``'s extension).

    Raises:
        InputError: the destination cannot be written, or matplotlib cannot write that format.
    """
    try:
        with atomic_path(path) as temp:
            fig.savefig(temp, **options)
    except OSError as exc:
        raise InputError(f"cannot write figure {str(path)!r}: {exc.strerror or exc}") from None
    except ValueError as exc:  # unknown format
        raise InputError(f"cannot write figure {str(path)!r}: {exc}") from None
