"""Python warnings as one-line notes on standard error (the command line's face for them).

Inside a command, a warning raised anywhere (pkmkit's own, NumPy's, SciPy's) is shown once as
``note: <what> (<category>)`` instead of Python's two-line form with a source path and line.
"""

from __future__ import annotations

import sys
import warnings
from typing import Any


def one_line(message: Warning | str, category: type[Warning]) -> str:
    """The note for one warning: its text on one line, then its category."""
    text = " ".join(str(message).split())
    return f"note: {text} ({category.__name__})"


def install_warning_notes(stream: Any = None) -> None:
    """Show every warning of this process as one line on ``stream`` (standard error by
    default), each distinct one once."""
    seen: set[str] = set()

    def show(message, category, filename, lineno, file=None, line=None):
        note = one_line(message, category)
        if note in seen:
            return
        seen.add(note)
        target = file or stream or sys.stderr
        try:
            target.write(note + "\n")
        except (OSError, ValueError):
            pass

    warnings.showwarning = show
