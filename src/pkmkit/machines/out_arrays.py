"""The ``out=`` argument of the protocol's batch ``ik`` and ``fk``: the caller's array, reused.

``m.ik(X, out=Q)`` writes the actuator values of the pose rows ``X (N, dims)`` into ``Q`` and
returns ``Q`` itself (``m.fk(Q, out=X)`` likewise the poses), as NumPy's ufuncs do: a caller
that solves batch after batch (a controller's look-ahead, the command line's chunks) stops
paying for fresh pages of memory on every call — on a 2-core machine Linux clearing a fresh
output costs a quarter of the six-axis inverse kernel's time per pose (docs/benchmarks.md,
"Six-axis kernels"). Every family takes it through the same keyword; the compiled inverse
kernels (the full-pose machines', the rod legs' closed form) write straight into it, the other
paths (engines, NumPy references, joint chains) fill it from the result of their own pass.

What ``out`` must be is checked here once per call, never silently copied or converted:
float64, C-contiguous, writeable, of shape ``(N, width)`` for a batch of ``N`` rows, and not
sharing memory with the input. A single pose (``x`` of shape ``(dims,)``) refuses it — its
result is one small new array from the one-pose paths. With ``full_output=True`` the
record's ``q`` (``pose`` for ``fk``) is ``out``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError


def checked_out(out: Any, given: Any, rows: np.ndarray, single: bool, width: int,
                what: str) -> np.ndarray:
    """``out`` if it can hold the ``(N, width)`` result of the batch ``rows`` (the call's
    input ``given``, as the caller passed it), else an :class:`InputError` naming ``out``,
    what was expected and what was given. ``what`` names the call (``"ik"``, ``"fk"``)."""
    if single:
        raise InputError(f"{what}(x, out=...): out is for a batch of rows (N, {width}); a "
                         f"single row's result is a new array of shape ({width},)")
    expected = (rows.shape[0], width)
    if not isinstance(out, np.ndarray):
        raise InputError(f"{what}: out must be a NumPy array float64 of shape {expected}, "
                         f"given {type(out).__name__}")
    if out.dtype != np.float64 or out.shape != expected:
        raise InputError(f"{what}: out must be float64 of shape {expected}, given "
                         f"{out.dtype} of shape {out.shape}")
    if not out.flags.c_contiguous:
        raise InputError(f"{what}: out must be C-contiguous (row-major, e.g. np.empty("
                         f"{expected})), given an array with strides {out.strides}")
    if not out.flags.writeable:
        raise InputError(f"{what}: out must be writeable, given a read-only array")
    for source in (given, rows):
        if isinstance(source, np.ndarray) and np.shares_memory(source, out):
            raise InputError(f"{what}: out shares memory with the input; give a separate "
                             "array (the input is read while out is written)")
    return out


def filled(out: np.ndarray | None, values: np.ndarray) -> np.ndarray:
    """``values`` written into ``out`` and ``out`` returned (``values`` itself without one;
    nothing copied when the kernel already wrote into ``out``)."""
    if out is None or values is out:
        return values
    np.copyto(out, values)
    return out


def into(out: np.ndarray | None, given: Any, result: Any, width: int, what: str = "ik",
         name: str = "q") -> Any:
    """The ``result`` of a call on ``given`` (an array, or a record whose field ``name`` is
    one) with that array written into the caller's ``out`` (checked as :func:`checked_out`
    checks it); ``result`` as it is without ``out``."""
    if out is None:
        return result
    rows = np.asarray(given)
    checked_out(out, given, rows, rows.ndim != 2, width, what)
    if isinstance(result, np.ndarray):
        return filled(out, result)
    if hasattr(result, "known_fields"):  # a lazy record (lazy_records): replace would compute
        result.known_fields()[name] = filled(out, getattr(result, name))  # every field
        return result
    return dataclasses.replace(result, **{name: filled(out, getattr(result, name))})
