"""The compiled position inverse of a full-pose machine commanded by its position alone, as the
machine calls it: :func:`solve` runs the per-row solve of
:mod:`pkmkit.machines.full_pose_position_kernel` (its ``solve_rows``) — or, chosen by
:func:`pkmkit.numerics.jit.kernel`, its C twin in :mod:`pkmkit.native` (``position_rows``,
the same statements: the same statuses, iterations and bits), which needs no Numba — in chunks
over the threads of :func:`pkmkit.numerics.jit.run_chunks`. This module imports no Numba."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from pkmkit.numerics import jit

#: The Numba kernel's module (:func:`pkmkit.numerics.jit.kernel` may run its C twin).
KERNEL = "pkmkit.machines.full_pose_position_kernel"


def solve(geom: np.ndarray, positions: np.ndarray, u0: np.ndarray | None, opts: np.ndarray,
          *, skip: np.ndarray | None = None, home: np.ndarray | None = None,
          jt_inv: np.ndarray | None = None, function: Callable[..., Any] | None = None,
          paired: bool = False) -> tuple[np.ndarray, ...]:
    """The position inverse of ``positions (N, 3)`` (m) from ``u0 (N, 6)`` (q, rotation
    vector; rows with a non-finite start are INVALID_INPUT) or, with ``u0`` None, from the
    kernel's first-order start (``home``: the direct kernel's home vector ``(27,)``, ``jt_inv
    (3, 3)``; rows of ``skip (N,)`` left INVALID_INPUT); ``geom (m, 16)`` and ``opts (9,)`` as
    the kernel's; ``function``: the ``solve_rows`` to run (default :func:`jit.kernel`'s
    choice). Returns ``(u (N, 6), status (N,), iterations (N,), residual (N,))`` as
    :func:`pkmkit.solve.rod_closure.solve_position_inverse`'s result; with ``paired``, a fifth
    ``(N,)`` bool: the rows the kernel's paired Newton solve answered (``opts (10,)``, its
    ``opts[9]`` = 1 and the branches in ``geom[:, 15]``)."""
    solve_rows = function or jit.kernel(KERNEL, "solve_rows")
    positions = np.ascontiguousarray(positions, dtype=float)
    size = positions.shape[0]
    has_guess = u0 is not None
    u0 = np.ascontiguousarray(u0, dtype=float) if has_guess else np.empty((size, 6))
    skip = (np.zeros(size, dtype=np.bool_) if skip is None
            else np.ascontiguousarray(skip, dtype=np.bool_))
    home = np.zeros(6 + 3 + 18) if home is None else np.ascontiguousarray(home, dtype=float)
    jt_inv = np.eye(3) if jt_inv is None else np.ascontiguousarray(jt_inv, dtype=float)
    opts = np.ascontiguousarray(opts, dtype=float)
    out = np.empty((size, 10 if paired else 9))

    def work(start: int, stop: int) -> None:
        solve_rows(positions[start:stop], u0[start:stop], has_guess, skip[start:stop], geom,
                   home, jt_inv, opts, out[start:stop])

    jit.run_chunks(work, size, jit.SOLVER_PIECE_ROWS)
    result = (out[:, :6].copy(), out[:, 6].astype(int), out[:, 7].astype(int), out[:, 8].copy())
    return (*result, out[:, 9] == 1.0) if paired else result
