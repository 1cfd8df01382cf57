"""Validation of batched array arguments.

Every public kinematic function accepts one row ``(n,)`` or a batch ``(N, n)``. ``as_batch``
turns either into a C-contiguous float64 ``(N, n)`` array and remembers which it was, so the
result can be given back with the caller's shape by ``restore_shape``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import InputError


def as_batch(value: Any, width: int, name: str) -> tuple[np.ndarray, bool]:
    """Return ``(array (N, width) float64, single)`` from a row or a batch of rows.

    Args:
        value: array-like of shape ``(width,)`` or ``(N, width)``.
        width: expected length of each row.
        name: argument name used in error messages (e.g. ``"pose"``).

    Raises:
        InputError: wrong number of dimensions, wrong row length, an empty batch, or values that
            are not real numbers. Non-finite values are *not* rejected here: single calls reject
            them with :func:`require_finite`, batched calls flag the rows.
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:  # OverflowError: an int beyond a double
        raise InputError(f"{name} must be an array of real numbers: {exc}") from None
    if arr.ndim == 1:
        if arr.shape[0] != width:
            raise InputError(f"{name} must have {width} components, got {arr.shape[0]}")
        return np.ascontiguousarray(arr.reshape(1, width)), True
    if arr.ndim == 2:
        if arr.shape[1] != width:
            raise InputError(
                f"{name} must have shape ({width},) or (N, {width}); got {arr.shape}"
            )
        if arr.shape[0] == 0:
            raise InputError(f"{name} is an empty batch (shape {arr.shape})")
        return np.ascontiguousarray(arr), False
    raise InputError(f"{name} must have shape ({width},) or (N, {width}); got {arr.shape}")


def finite_rows(arr: np.ndarray) -> np.ndarray:
    """Mask ``(N,)`` of the rows of ``arr (N, ...)`` whose entries are all finite."""
    return np.isfinite(arr).reshape(arr.shape[0], int(np.prod(arr.shape[1:]))).all(axis=1)


def require_finite(arr: np.ndarray, name: str) -> None:
    """Raise :class:`InputError` naming the first non-finite entry of a single row ``(1, n)``."""
    bad = ~np.isfinite(arr)
    if bad.any():
        row, col = map(int, np.argwhere(bad)[0])
        raise InputError(f"{name} component {col} is not finite ({arr[row, col]})")


def restore_shape(arr: np.ndarray, single: bool) -> np.ndarray:
    """Drop the leading batch axis of ``arr`` when the caller passed a single row."""
    return arr[0] if single else arr


def real(value: Any, name: str, *, positive: bool = False, nonnegative: bool = False,
         limit: float | None = None) -> float:
    """A finite real scalar argument as float, or an :class:`InputError` naming ``name``.

    Args:
        value: a Python or NumPy real number (not a bool, string, sequence or None).
        positive, nonnegative: require > 0 / ≥ 0.
        limit: reject magnitudes beyond it (a unit mistake rather than a value; it also keeps
            squares and cubes of the value from overflowing).
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.integer
                                                            | np.floating):
        raise InputError(f"{name} must be a real number, got {value!r}")
    number = float(value)
    if not np.isfinite(number):
        raise InputError(f"{name} must be finite, got {number}")
    if positive and not number > 0:
        raise InputError(f"{name} must be > 0, got {number:g}")
    if nonnegative and not number >= 0:
        raise InputError(f"{name} must be >= 0, got {number:g}")
    if limit is not None and abs(number) > limit:
        raise InputError(f"{name} = {number:g} is beyond {limit:g}; check the units")
    return number


def real_pair(value: Any, name: str) -> tuple[float, float]:
    """Two finite real numbers ``(a, b)`` (e.g. bounds), or an :class:`InputError`."""
    try:
        a, b = value
    except (TypeError, ValueError):
        raise InputError(f"{name} must be two numbers (low, high), got {value!r}") from None
    return real(a, f"{name}[0]"), real(b, f"{name}[1]")
