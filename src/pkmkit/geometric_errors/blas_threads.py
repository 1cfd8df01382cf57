"""One BLAS thread for the error analyses.

Their linear algebra is many small or thin matrices (per-configuration closures, Jacobians of a
few hundred rows): a multi-threaded BLAS gains nothing there and collapses when another process
holds a core (a 720 × 30 SVD measured at 0.7 s instead of 0.4 ms on a loaded 2-core machine).
Public entry points of :mod:`pkmkit.geometric_errors` run under :func:`single_blas`.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import wraps
from typing import TypeVar

F = TypeVar("F", bound=Callable)

_CONTROLLER = None


def _controller():
    global _CONTROLLER
    if _CONTROLLER is None:
        from threadpoolctl import ThreadpoolController

        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


def one_blas_thread():
    """A context in which BLAS/LAPACK run on one thread (restored afterwards)."""
    return _controller().limit(limits=1, user_api="blas")


def single_blas(func: F) -> F:
    """Run ``func`` with the BLAS limited to one thread (:func:`one_blas_thread`)."""

    @wraps(func)
    def wrapper(*args, **kwargs):
        with one_blas_thread():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
