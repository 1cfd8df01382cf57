"""The compiled direct model of full-pose rod machines, as the machine calls it.

:class:`DirectKernel` holds a machine's rods and home data in the flat layout of
:mod:`pkmkit.machines.full_pose_direct_kernel` (built once per machine) and runs its per-pose
Levenberg–Marquardt solve on a batch (:meth:`DirectKernel.solve`) or on one configuration
(:meth:`DirectKernel.solve_one`, a few microseconds from Python). Both are the same compiled
function, so a single configuration and the same row of a batch give the same bits. That
function is the C twin in :mod:`pkmkit.native` when the extension was built (no import cost:
every call runs it), else the Numba one, whose import (≈ 0.4 s of CPU) is paid by batches of
:data:`~pkmkit.numerics.jit.SOLVER_ROWS` rows or more and by the second single call of a
machine, not by a one-shot call (the command line), which takes the NumPy engine (≈ 2 ms). The
reference is the batched NumPy engine (:func:`pkmkit.solve.rod_closure.solve_direct` with
``dof="full"``), with the same options, stopping rules and status codes; it is still used when
Numba is missing, ``PKMKIT_COMPILED=0``, or an option only the engine knows is passed.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.model.rods import RodModel
from pkmkit.numerics import jit

#: The Numba kernels' module (:func:`pkmkit.numerics.jit.kernel` may run their C twins).
KERNELS = "pkmkit.machines.full_pose_direct_kernel"

#: The engine's defaults (:func:`pkmkit.solve.least_squares.solve_least_squares`), in the
#: order of the kernel's option vector.
DEFAULTS = {"max_iter": 60, "xtol": 1e-14, "atol": 1e-14, "gtol": 1e-12, "stall": 0.01,
            "residual_tol": 1e-9, "damping": 1e-4}


def usable(options: Mapping[str, Any], rows: int, *, native: bool = False) -> bool:
    """Whether the compiled solve serves a call on ``rows`` rows with these engine ``options``
    (only the options of :data:`DEFAULTS`, ``compute_rank`` off; and
    :func:`pkmkit.numerics.jit.use_compiled_solver`, with ``native`` for this module's
    :class:`DirectKernel`, which has a C twin)."""
    if options and (options.get("compute_rank", False)
                    or not set(options) <= {*DEFAULTS, "compute_rank"}):
        return False
    return jit.use_compiled_solver(rows, native=native)


@dataclass(frozen=True, eq=False)
class DirectKernel:
    """A machine's data for the compiled direct model.

    Attributes:
        geom: ``(m, 16)`` per rod: a0, b, axis, pivot, ℓ0, kind, actuator (kernel docstring).
        home: ``(6 + n + 6n,)`` home pose, home q, J(home) row-major.
        n_actuators: n.
    """

    geom: np.ndarray
    home: np.ndarray
    n_actuators: int

    @classmethod
    def of(cls, model: RodModel, home_pose: np.ndarray, home_q: np.ndarray,
           home_jacobian: np.ndarray) -> DirectKernel:
        """Flatten ``model``'s rods and the home data (pose ``(6,)``, q ``(n,)``, J ``(6, n)``)."""
        geom = np.zeros((model.n_rods, 16))
        geom[:, 0:3] = model.rod_base
        geom[:, 3:6] = model.rod_platform
        geom[:, 6:9] = model.rod_axis
        geom[:, 9:12] = model.rod_pivot
        geom[:, 12] = model.rod_length
        geom[:, 13] = model.rod_kind
        geom[:, 14] = model.rod_actuator
        home = np.concatenate([home_pose, home_q, np.asarray(home_jacobian).reshape(-1)])
        return cls(geom=geom, home=home, n_actuators=int(model.n_actuators))

    @staticmethod
    def options(options: Mapping[str, Any]) -> np.ndarray:
        """The kernel's option vector ``(7,)`` from engine options (defaults filled in)."""
        return np.array([float(options.get(k, v)) for k, v in DEFAULTS.items()])

    def solve(self, q: np.ndarray, x0: np.ndarray | None,
              options: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                   np.ndarray]:
        """Direct model of ``q (N, n)`` from ``x0 (N, 6)`` (None: the first-order guess).

        Returns:
            ``(pose (N, 6), status (N,) int, iterations (N,) int, residual (N,))`` as the
            engine's :class:`~pkmkit.solve.least_squares.SolveResult` (``u``, ``status``,
            ``iterations``, ``residual``; m).
        """
        solve_rows = jit.kernel(KERNELS, "solve_rows")
        q = np.ascontiguousarray(q, dtype=float)
        guess = (np.empty((q.shape[0], 6)) if x0 is None
                 else np.ascontiguousarray(x0, dtype=float))
        out = np.empty((q.shape[0], 9))
        opts = self.options(options)

        def work(start: int, stop: int) -> None:
            solve_rows(q[start:stop], guess[start:stop], x0 is not None, self.geom, self.home,
                       opts, out[start:stop])

        jit.run_chunks(work, q.shape[0], jit.SOLVER_PIECE_ROWS)
        return (out[:, :6].copy(), out[:, 6].astype(int), out[:, 7].astype(int),
                out[:, 8].copy())

    def solve_one(self, q: np.ndarray, function: Callable[..., Any] | None = None) -> np.ndarray:
        """One configuration ``q (n,)`` (float array) from the first-order guess, default
        options: ``(9,)`` pose, status, iterations, residual (as :meth:`solve`'s row);
        ``function``: the kernel's ``solve_one`` when the caller has chosen it already."""
        out = np.empty(9)
        solve_one = function or jit.kernel(KERNELS, "solve_one")
        solve_one(np.ascontiguousarray(q), _EMPTY6, False, self.geom, self.home,
                  DEFAULT_OPTIONS, out)
        return out


def direct_one(machine: Any, q: Any, strokes: str) -> np.ndarray | None:
    """The pose ``(6,)`` of one plain configuration of a full-pose ``machine`` by the compiled
    solve (the batch path's own function, so the same bits) where the C extension's
    ``PoseOne.fk`` (:func:`pkmkit.machines.full_pose_one.native_one`: the same solve, checks
    and stroke test in one C call) does not serve the machine, or None — not one plain finite
    row, no assembly reached, a stroke to flag or refuse, no compiled solve, or the machine's
    first single call while Numba is not imported: the caller then takes the batch path (the
    same numbers, typed errors and warnings)."""
    if isinstance(q, (list, tuple)):
        if not all(type(v) in (float, int) for v in q) or any(
                type(v) is int and abs(v) > 2**1023 for v in q):  # beyond a double: batch path
            return None
        q = np.array(q, dtype=float)
    elif not (isinstance(q, np.ndarray) and q.dtype == np.float64):
        return None
    if q.shape != (machine.n_actuators,):
        return None
    solve_one = jit.native_kernel(KERNELS, "solve_one")  # the C twin: no import to pay
    if solve_one is None:
        if not jit.compiled_from_second_call(machine, "direct"):
            # no Numba, PKMKIT_COMPILED=0, or this machine's first single call while Numba is
            # not imported: the batch path (the NumPy engine, ≈ 2 ms)
            return None
        solve_one = _numba_solve_one()
    out = machine.direct_kernel().solve_one(q, solve_one)
    if out[6] != 0.0 or not (strokes == "ignore" or machine.within_strokes(q.tolist())):
        return None  # not OK (Status.OK is 0), or a stroke to judge
    return out[:6]


_EMPTY6 = np.zeros(6)
#: The kernel's option vector of the defaults (one-pose calls; also
#: :func:`pkmkit.machines.full_pose_one.native_one`).
DEFAULT_OPTIONS = DirectKernel.options({})
_numba: Callable[..., Any] | None = None


def _numba_solve_one() -> Callable[..., Any]:
    """The Numba ``solve_one`` (its module imported once)."""
    global _numba
    if _numba is None:
        from pkmkit.machines.full_pose_direct_kernel import solve_one

        _numba = solve_one
    return _numba
