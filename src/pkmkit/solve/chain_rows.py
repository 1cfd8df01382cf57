"""The batch entry points of the compiled closure of joint-chain machines
(:mod:`pkmkit.solve.chain_kernel`, whose module docstring states the problem and the
algorithm): :func:`solve` (the closure: the direct model) and :func:`solve_inverse` (the inverse
model of a complete machine), and :func:`model_arrays` (the kernel's view of a model); for the
velocity model of many configurations, :func:`closure_jacobian` (the closure's Jacobian) and
:func:`closure_rates` (``dU = −C_U⁺ C_q``, the rank and the singularity measure of C_U); for
the identification, :func:`linearise` (C_U, the defect columns C_δ, the tool frame's defect
twists) and :func:`absorb` (``dU = −C_U⁺ C_δ``).

They run the per-row Levenberg–Marquardt loop ``chain_kernel._solve_rows`` or, chosen by
:func:`pkmkit.numerics.jit.kernel`, its C twin in :mod:`pkmkit.native` (``chain_rows``: the same
statements, the same statuses, iterations and bits), which needs no Numba: this module imports
none, so a fresh process's closures with the extension built never pay Numba's import. The
same for ``chain_kernel._jacobian_rows``, ``_linearise_rows`` and
``chain_linalg._closure_rates_rows``, ``_absorb_rows`` (C twins ``chain_jacobian_rows``,
``chain_linearise_rows``, ``closure_rates``, ``absorb``: native/chain_velocity.c and
chain_linearise.c).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from pkmkit.model.chains import FIXED, PRISMATIC, REVOLUTE, JointChainModel
from pkmkit.numerics import jit

_TYPE_CODE = {FIXED: 0, REVOLUTE: 1, PRISMATIC: 2}
#: The Numba kernels' modules (:func:`pkmkit.numerics.jit.kernel` may run their C twins).
KERNEL = "pkmkit.solve.chain_kernel"
LINALG = "pkmkit.solve.chain_linalg"


def _rows_kernel() -> Callable[..., Any]:
    """``_solve_rows``: its C twin when built, else the Numba kernel."""
    return jit.kernel(KERNEL, "_solve_rows")


def velocity_native() -> bool:
    """Whether the C twins of the velocity kernels (:func:`closure_jacobian`,
    :func:`closure_rates`) run: the extension is built with them and not disabled."""
    return (jit.native_kernel(KERNEL, "_jacobian_rows") is not None
            and jit.native_kernel(LINALG, "_closure_rates_rows") is not None)


def linearise_native() -> bool:
    """Whether the C twins of the identification's kernels (:func:`linearise`,
    :func:`absorb`) run: the extension is built with them and not disabled."""
    return (jit.native_kernel(KERNEL, "_linearise_rows") is not None
            and jit.native_kernel(LINALG, "_absorb_rows") is not None)


def linearise(model: JointChainModel, values: np.ndarray, platform: np.ndarray,
              unknown_variables: np.ndarray) -> tuple[np.ndarray, ...]:
    """The closure linearised at solved configurations, compiled (``chain_kernel.
    _linearise_rows`` or its C twin): ``values (N, n_var)`` every joint variable, ``platform
    (N, 6)`` position and rotation vector. Returns ``C_U (N, 6L, 6 + n_u)`` (platform
    increments, then ``unknown_variables``), ``C_δ (N, 6L, d)`` (the model's defect columns,
    :func:`pkmkit.solve.chains.closure` with ``defects=True``), and the tool frame
    (:func:`pkmkit.solve.chains.tool_frame` with ``defects=True``): rotations ``(N, 3, 3)``,
    positions ``(N, 3)``, defect twists ``(N, 6, d)``."""
    from pkmkit.model.chains import cached_defect_twists

    frames, types, evar, elements, offsets, position = model_arrays(model, unknown_variables)
    local = np.ascontiguousarray(cached_defect_twists(model), dtype=float)
    owner = np.asarray(model.defect_index.element, dtype=np.int64)
    order = np.argsort(owner, kind="stable").astype(np.int64)
    counts = np.bincount(owner, minlength=len(model.elements))
    starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    head = np.array(model.head, dtype=np.int64)
    n, m, d = values.shape[0], 6 * len(model.legs), len(owner)
    cu = np.empty((n, m, 6 + len(unknown_variables)))
    cd = np.zeros((n, m, d))
    tool_r, tool_p, tool_tw = np.empty((n, 3, 3)), np.empty((n, 3)), np.zeros((n, 6, d))
    u = np.zeros((n, 6 + len(unknown_variables)))
    u[:, :6] = platform
    u[:, 6:] = values[:, np.asarray(unknown_variables, dtype=int)]
    jit.kernel(KERNEL, "_linearise_rows")(
        frames, types, evar, elements, offsets, position, local, order, starts, head,
        np.ascontiguousarray(values, dtype=float), u, float(model.characteristic_length), cu,
        cd, tool_r, tool_p, tool_tw)
    return cu, cd, tool_r, tool_p, tool_tw


def absorb(cu: np.ndarray, cd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``dU = −C_U⁺ C_δ (N, u, d)`` and the part no motion absorbs, ``C_δ + C_U dU (N, r, d)``,
    for closure Jacobians ``cu (N, r, u)`` of full column rank, by the normal equations
    (Cholesky of ``C_Uᵀ C_U``, compiled: ``chain_linalg._absorb_rows`` or its C twin);
    ``ok (N,)`` False for the rows whose ``C_U`` is (nearly) rank-deficient (pivot below
    ``chain_linalg.RANK_PIVOT``), whose outputs are NaN: the caller takes the pseudo-inverse
    there."""
    n, r, u = cu.shape
    du = np.empty((n, u, cd.shape[2]))
    rest = np.empty((n, r, cd.shape[2]))
    ok = np.empty(n, dtype=np.bool_)
    jit.kernel(LINALG, "_absorb_rows")(np.ascontiguousarray(cu, dtype=float),
                                       np.ascontiguousarray(cd, dtype=float), du, rest, ok)
    return du, rest, ok


def closure_jacobian(model: JointChainModel, values: np.ndarray, platform: np.ndarray,
                     variables: np.ndarray) -> np.ndarray:
    """``(N, 6L, 6 + len(variables))`` the closure's Jacobian at configurations ``values
    (N, n_var)`` (every joint variable) and ``platform (N, 6)`` (position, rotation vector):
    columns the platform increments, then ``variables`` — :func:`pkmkit.solve.chains.closure`'s
    ``platform`` and ``variables[:, variables]`` side by side, compiled
    (``chain_kernel._jacobian_rows`` or its C twin)."""
    variables = np.asarray(variables, dtype=int)
    frames, types, evar, elements, offsets, position = model_arrays(model, variables)
    values = np.ascontiguousarray(values, dtype=float)
    u = np.empty((len(values), 6 + len(variables)))
    u[:, :6] = platform
    u[:, 6:] = values[:, variables]
    out = np.empty((len(values), 6 * len(model.legs), u.shape[1]))
    jit.kernel(KERNEL, "_jacobian_rows")(frames, types, evar, elements, offsets, position,
                                          values, u, float(model.characteristic_length), out)
    return out


def closure_rates(cu: np.ndarray, cq: np.ndarray, rcond: float, tol: float, expected: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(dU (N, c, k), rank (N,), ratio (N,))`` of tall closure Jacobians ``cu (N, r, c)``
    (r ≥ c) and ``cq (N, r, k)``, compiled (``chain_linalg._closure_rates_rows`` or its C
    twin): ``dU = −C_U⁺ C_q`` (``np.linalg.pinv``'s cutoff ``rcond · σ_max``), the rank of
    C_U (singular values above that cutoff) and ``ratio = σ_expected / σ_max`` (``expected``:
    the rank at home).

    A row first gets a Householder QR ``C_U = Q R``: ``1 / (‖R‖_F ‖R⁻¹‖_F)`` is a lower bound
    of ``σ_min / σ_max``; where it clears ``max(tol, rcond)`` and ``expected = c`` the rank is
    ``c``, ``dU = −R⁻¹ Qᵀ C_q`` (the least-squares solution the pseudo-inverse gives, to
    rounding) and ``ratio`` is that bound (it clears ``tol``). Other rows — near a singular
    closure, or a machine rank-deficient at home — take the exact path: a one-sided Jacobi SVD
    (``C_U V = U Σ``, V accumulated; :mod:`pkmkit.numerics.svd_kernel`'s iteration) and
    ``C_U⁺ = V Σ⁻¹ Uᵀ``. Rows holding a non-finite entry give NaN (rank 0)."""
    n, _, c = cu.shape
    du = np.empty((n, c, cq.shape[2]))
    rank = np.zeros(n, dtype=np.int64)
    ratio = np.empty(n)
    jit.kernel(LINALG, "_closure_rates_rows")(
        np.ascontiguousarray(cu, dtype=float), np.ascontiguousarray(cq, dtype=float),
        float(rcond), float(tol), int(expected), du, rank, ratio)
    return du, rank, ratio


def model_arrays(model: JointChainModel, unknown_variables: np.ndarray) -> tuple:
    """The kernel's view of ``model``: ``(frames (E, 4, 4), types (E,), element variable (E,),
    leg elements (flattened), leg offsets (L + 1,), position of every variable in u (−1 for a
    known one))``; all but the positions computed once per (immutable) model."""
    cached = model.__dict__.get("_kernel_arrays")
    if cached is None:
        types = np.array([_TYPE_CODE[e.type] for e in model.elements], dtype=np.int64)
        evar = np.asarray(model.element_variable, dtype=np.int64)
        elements = np.array([e for leg in model.legs for e in leg], dtype=np.int64)
        offsets = np.cumsum([0] + [len(leg) for leg in model.legs]).astype(np.int64)
        cached = (np.ascontiguousarray(model.frames, dtype=float), types, evar, elements,
                  offsets)
        for arr in cached:  # kept on the model, which every copy of a machine shares
            arr.flags.writeable = False
        object.__setattr__(model, "_kernel_arrays", cached)
    position = np.full(model.n_variables, -1, dtype=np.int64)
    position[np.asarray(unknown_variables, dtype=int)] = 6 + np.arange(len(unknown_variables))
    return (*cached, position)


def solve(model: JointChainModel, known: np.ndarray, u0: np.ndarray,
          unknown_variables: np.ndarray, *, max_iter: int = 60, xtol: float = 1e-14,
          atol: float = 1e-14, gtol: float = 1e-12, stall: float = 0.01,
          residual_tol: float = 1e-9, damping: float = 1e-4) -> tuple[np.ndarray, ...]:
    """Closures of ``known (N, n_var)`` from ``u0 (N, 6 + n_u)``: ``(u (N, 6 + n_u), status
    (N,), residual (N,), iterations (N,))`` with the meanings of
    :class:`pkmkit.solve.least_squares.SolveResult` (options as there)."""
    frames, types, evar, elements, offsets, position = model_arrays(model, unknown_variables)
    known = np.ascontiguousarray(known, dtype=float)
    u = np.array(u0, dtype=float, order="C", copy=True)
    n_rows = u.shape[0]
    status = np.empty(n_rows, dtype=np.int64)
    residual = np.full(n_rows, np.nan)
    iterations = np.zeros(n_rows, dtype=np.int64)
    _rows_kernel()(frames, types, evar, elements, offsets, position, known, u,
                   float(model.characteristic_length), int(max_iter), float(xtol),
                   float(atol), float(gtol), float(stall), float(residual_tol),
                   float(damping), status, residual, iterations, _NO_HEAD, _NO_TARGETS,
                   _NO_TARGETS[:, 0], False)
    return u, status, residual, iterations


_NO_HEAD = np.zeros(0, dtype=np.int64)
_NO_TARGETS = np.zeros((1, 6))


def solve_inverse(model: JointChainModel, targets: np.ndarray, u0: np.ndarray,
                  tool_length: np.ndarray, *, max_iter: int = 60, xtol: float = 1e-14,
                  atol: float = 1e-14, gtol: float = 1e-12, stall: float = 0.01,
                  residual_tol: float = 1e-9, damping: float = 1e-4) -> tuple[np.ndarray, ...]:
    """The inverse model of a complete machine, compiled: the problem of
    :func:`pkmkit.solve.chains.solve_machine_inverse` (the legs' closure rows, then the tool
    rows ``(p_tool − p_target, L (a_tool − a_target))``; unknowns the platform pose and every
    joint variable) for ``targets (N, 6)`` (tool point m, unit axis), ``u0 (N, 6 + n_var)``
    and ``tool_length (N,)`` (m), with :func:`solve`'s algorithm. Returns ``(u, status,
    residual, iterations)`` as :func:`solve`."""
    every = np.arange(model.n_variables)
    frames, types, evar, elements, offsets, position = model_arrays(model, every)
    head = np.array(model.head, dtype=np.int64)
    u = np.array(u0, dtype=float, order="C", copy=True)
    n_rows = u.shape[0]
    status = np.empty(n_rows, dtype=np.int64)
    residual = np.full(n_rows, np.nan)
    iterations = np.zeros(n_rows, dtype=np.int64)
    _rows_kernel()(frames, types, evar, elements, offsets, position,
                   np.zeros((1, model.n_variables)), u, float(model.characteristic_length),
                   int(max_iter), float(xtol), float(atol), float(gtol), float(stall),
                   float(residual_tol), float(damping), status, residual, iterations, head,
                   np.ascontiguousarray(targets, dtype=float),
                   np.ascontiguousarray(tool_length, dtype=float).reshape(-1), True)
    return u, status, residual, iterations


def _keyword_defaults(function: Callable[..., Any]) -> dict[str, Any]:
    import inspect

    return {k: p.default for k, p in inspect.signature(function).parameters.items()
            if p.default is not inspect.Parameter.empty}


#: The engine options' defaults of :func:`solve` and :func:`solve_inverse` (read once, at
#: import: the one-pose paths pass them to their kernels as the batch path's calls do).
SOLVE_DEFAULTS = _keyword_defaults(solve)
SOLVE_INVERSE_DEFAULTS = _keyword_defaults(solve_inverse)

