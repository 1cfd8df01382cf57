"""When to use the compiled (Numba) kernels instead of the NumPy reference paths.

The hot paths (closed-form inverse model, velocity model of many poses) have two
implementations: a vectorised NumPy one — the reference, used for small batches and compared
with the compiled one in the tests — and a fused per-pose loop compiled by Numba, which keeps
every intermediate in registers (no temporaries, no BLAS, one pass over memory). The compiled
path is used only for batches of at least :data:`MIN_ROWS` rows, so that single-pose calls and
the command line never pay Numba's import (≈ 0.3 s) or its first compilation (cached on disk
afterwards).

Environment: ``PKMKIT_COMPILED=0`` forces the NumPy paths everywhere (``=1`` forces the
compiled ones for every batch size, which the tests use). Without Numba installed the NumPy
paths are used silently.
"""

from __future__ import annotations

import importlib.util
import os

#: Smallest batch for which the compiled kernels are used (below: NumPy).
MIN_ROWS = 4096

_available: bool | None = None


def mode() -> str:
    """``"auto"`` (default), ``"0"`` (never compiled) or ``"1"`` (always compiled)."""
    value = os.environ.get("PKMKIT_COMPILED", "auto").strip().lower()
    return value if value in ("0", "1") else "auto"


def numba_available() -> bool:
    """Whether Numba can be imported (checked once, without importing it)."""
    global _available
    if _available is None:
        _available = importlib.util.find_spec("numba") is not None
    return _available


def use_compiled_solver() -> bool:
    """Whether the compiled per-pose solvers run (every batch size, one pose included): an
    iterative solve costs hundreds of microseconds per call through the NumPy engine and a few
    through its compiled kernel, which repays Numba's import within the first calls. Only
    ``PKMKIT_COMPILED=0`` (or Numba missing) selects the NumPy engine."""
    return mode() != "0" and numba_available()


def use_compiled(rows: int) -> bool:
    """Whether a batch of ``rows`` rows should run the compiled kernels (the caller imports
    its kernel module lazily, e.g. :mod:`pkmkit.machines.kernels`)."""
    choice = mode()
    if choice == "0" or (choice == "auto" and rows < MIN_ROWS):
        return False
    return numba_available()
