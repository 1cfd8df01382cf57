"""The direct model's default start of a joint-chain machine: home moved to first order towards
each row's actuator values (moved here from :mod:`pkmkit.machines.joint_chain`).

Every row's start is computed by batch-last contractions
(:func:`pkmkit.numerics.rowwise.einsum`), not a matrix product over the rows, whose rounding
changes with the batch (a product of one row runs another BLAS kernel): a row's start, hence its
closure, does not depend on the rows beside it (issue 22 §6).
"""

from __future__ import annotations

import importlib
import sys
from typing import Any

import numpy as np

from pkmkit.machines.chain_velocity_record import RANK_RCOND
from pkmkit.numerics import jit
from pkmkit.numerics.rowwise import einsum
from pkmkit.solve.chains import (
    closure,
    closure_residuals,
    compose_rotvecs,
    rotvec_matrices,
    tool_frame,
    tool_rows,
)
from pkmkit.spatial.rotation import rotvec_to_matrix


def home_rates(m: Any) -> tuple[np.ndarray, np.ndarray]:
    """At home of the machine ``m``, per unit actuator change: ``(6 + n_p, n)`` first-order
    change of the platform (δp, δω) and passive joints, and ``(6L, n)`` change of the closure
    residual with the platform and passive joints held (zero columns for the head); cached on
    ``m``."""
    cached = m.__dict__.get("_home_rates_cache")
    if cached is not None:
        return cached
    model = m.model
    values = m.home_values[:, None]
    rot = rotvec_to_matrix(m.home_platform[3:]).transpose(1, 2, 0)
    c = closure(model, rot, m.home_platform[:3, None], values)
    cu = np.concatenate([c.platform, c.variables[:, m.passive_variables]], axis=1)[:, :, 0]
    cq = c.variables[:, m.actuated_columns, 0]
    rates = (-np.linalg.pinv(cu, rcond=RANK_RCOND) @ cq, cq)
    object.__setattr__(m, "_home_rates_cache", rates)
    return rates


def default_start(m: Any, qb: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Starts ``(N, 6 + n_p)`` of the direct model of ``m`` at actuator values ``qb (N, n)``
    (every joint's values ``values (N, n_var)``): home moved to first order towards each q (a
    Gauss–Newton iteration fewer near home), or home itself where the legs close worse from
    that prediction than from home (far from home; the home residual to first order)."""
    n = qb.shape[0]
    home = np.concatenate([m.home_platform, m.home_values[m.passive_variables]])
    u_home = np.tile(home, (n, 1))
    rates, residual_rates = home_rates(m)
    delta = np.ascontiguousarray((qb - m.home_q).T)  # (n, N): batch last
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        du = einsum("pn,nk->pk", rates, delta).T
        u_pred = u_home + du
        u_pred[:, 3:6] = compose_rotvecs(du[:, 3:6].T, u_home[:, 3:6].T).T
        full = values.T.copy()
        full[m.passive_variables] = u_pred[:, 6:].T
        res = closure_residuals(m.model, rotvec_matrices(u_pred[:, 3:6].T), u_pred[:, :3].T,
                                full)
        from_home = einsum("pn,nk->pk", residual_rates, delta)
    worse = ~(einsum("mk,mk->k", res, res) <= einsum("mk,mk->k", from_home, from_home))
    u_pred[worse] = u_home[worse]
    closed = closed_direct_starts(m, qb)
    if closed is not None:
        exact = np.isfinite(closed).all(axis=1)
        u_pred[exact] = closed[exact]
    return u_pred


def closed_direct_starts(m: Any, qb: np.ndarray) -> np.ndarray | None:
    """``(N, 6 + n_p)`` the kind's closed-form starts of the direct model
    (``MachineKind.direct_start``; the TriMule's
    :func:`~pkmkit.machines.trimule_forms.direct_unknowns`: platform and passive joints) at
    actuator values ``qb (N, n)``; NaN rows where it declines; None where the kind has none
    or the model is not the kind's own (its variables in another order). :func:`default_start`
    takes it wherever it answers; ``native/chain_one.c`` (``closed_direct``) starts the
    one-pose call alike (issue 22 §1, session 33 wave 2)."""
    start = getattr(m.kind, "direct_start", None)
    if start is None:
        return None
    ok = m.__dict__.get("_closed_direct_ok")
    if ok is None:
        ok = tuple(m.model.variables) == getattr(start, "variables", None)
        object.__setattr__(m, "_closed_direct_ok", ok)
    if not ok:
        return None
    twin = compiled_start(m, start)
    if twin is None:
        u = start(m.params, qb)  # qb's columns: the kind's actuators in its order
    else:
        u = np.empty((len(qb), 6 + len(start.variables)))
        twin[0].direct_rows(twin[1], np.ascontiguousarray(qb, dtype=float), u)
    return u[:, np.concatenate([np.arange(6), 6 + np.asarray(m.passive_variables)])]


def compiled_start(m: Any, start: Any) -> tuple[Any, np.ndarray] | None:
    """``(kernels, constants)`` of the compiled twin of the kind's closed-form start ``start``
    (``MachineKind.inverse_start`` / ``direct_start``) of the machine ``m``, or None (its NumPy
    function): ``kernels.inverse_rows(constants, targets, tools, branches, out)`` /
    ``kernels.direct_rows(constants, q, out)`` (branch 0: the one nearest home; NaN rows where
    it declines). A start declares its twins by attributes: its C constants as
    ``start.native(params)`` (the family's code first), its Numba module's name as
    ``start.compiled`` (the constants after the code).

    With the C extension, its batch entries (``native/chain_closed_rows.c``: the one-pose C
    call's starts over rows) in every process — no Numba import, the same bits whether Numba
    is imported or not; without it, the Numba twin once Numba is imported (or
    ``PKMKIT_COMPILED=1``; never with ``=0``), whose bits are the C's (the same libm calls, no
    contraction; ``tests/machines/test_closed_starts.py``). The batch rows here and the
    one-pose paths (:mod:`pkmkit.machines.chain_one`) start from the same compiled function —
    their answers agree bit for bit — whatever the batch's size. The NumPy function (the
    reference, to rounding: its AVX-512 transcendentals are not libm's) runs where neither
    does; before, a one-row call of it cost ≈ 250–650 µs, a one-pose ``full_output`` call's
    most (issue 22 §1, session 35)."""
    name = getattr(start, "compiled", None)
    if name is None or jit.mode() == "0":
        return None
    native = jit.native_kernels()
    if native is not None and hasattr(native, "chain_closed_rows") and hasattr(start, "native"):
        key, kernels = "C " + name, _NativeStarts(native)
    elif jit.use_compiled_solver(1):
        key, module = name, sys.modules.get(name)
        kernels = importlib.import_module(name) if module is None else module
    else:
        return None
    cache = m.__dict__.get("_compiled_starts")  # the constants by twin (picklable)
    if cache is None:
        cache = {}
        object.__setattr__(m, "_compiled_starts", cache)
    k = cache.get(key)
    if k is None:
        k = np.ascontiguousarray(start.native(m.params), dtype=float)
        k = cache[key] = k if key.startswith("C ") else np.ascontiguousarray(k[1:])
    return kernels, k


class _NativeStarts:
    """The C extension's batch entries of the closed-form starts under the Numba twins'
    names (:func:`compiled_start`)."""

    __slots__ = ("direct_rows", "inverse_rows")

    def __init__(self, native: Any) -> None:
        self.inverse_rows = native.chain_closed_rows
        self.direct_rows = native.chain_closed_direct_rows


#: Singular values of the inverse model's Jacobian at home below this fraction of the largest
#: are left out of the first-order start's rates (the wrist singularity at home: its rates
#: would be ~1/0.004 of the others' and throw the start far off).
INVERSE_RATE_CUTOFF = 0.02


def inverse_rates(m: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The inverse model's first-order start at home of the machine ``m``, cached on ``m``:
    ``(u_home (6 + n_var,), base (6,), rates (6 + n_var, 6))`` — home's unknowns (platform
    position, rotation vector, every joint variable), the flange point (the tool frame's
    origin, m) and tool axis at home, and the change of the unknowns per unit change of the
    flange point and axis (the rotation-vector rows for a rotation composed on the left, as
    the engine's retraction). Rates in the flange point, not the tool point, so that one set
    serves every tool length: a target ``(p, a)`` with tool length ``ℓ`` is the flange point
    ``p − ℓ a`` with axis ``a``. The least-squares rates of the residual of
    :func:`pkmkit.solve.chains.solve_machine_inverse` (tool length 0) linearised at home,
    its singular values below :data:`INVERSE_RATE_CUTOFF` × the largest left out."""
    cached = m.__dict__.get("_inverse_rates_cache")
    if cached is not None:
        return cached
    model = m.model
    length = float(model.characteristic_length)
    platform = m.home_platform
    values = m.home_values[:, None]
    rot = rotvec_to_matrix(platform[3:]).transpose(1, 2, 0)
    position = platform[:3, None]
    c = closure(model, rot, position, values)
    frame = tool_frame(model, rot, position, values, twists=True)
    flange, axis = frame.p[:, 0], frame.R[:, 2, 0]
    rigid = np.zeros((6, 6, 1))  # the platform increments as a spatial twist of the tool frame
    rigid[:3, :3, 0] = rigid[3:, 3:, 0] = np.eye(3)
    rigid[:3, 3:, 0] = _skew(platform[:3])
    tool = np.concatenate([tool_rows(rigid, frame.p, frame.R[:, 2], length),
                           tool_rows(frame.variable_twists, frame.p, frame.R[:, 2], length)],
                          axis=1)[:, :, 0]
    jac = np.concatenate([np.concatenate([c.platform, c.variables], axis=1)[:, :, 0], tool])
    rhs = np.zeros((len(jac), 6))
    rhs[-6:-3, :3] = np.eye(3)
    rhs[-3:, 3:] = length * np.eye(3)
    left, sv, right = np.linalg.svd(jac, full_matrices=False)
    keep = sv > INVERSE_RATE_CUTOFF * sv[0]
    rates = (right[keep].T / sv[keep]) @ (left[:, keep].T @ rhs)
    rates[3:6] = _left_jacobian_inverse(platform[3:]) @ rates[3:6]
    cached = (np.concatenate([platform, m.home_values]), np.concatenate([flange, axis]),
              np.ascontiguousarray(rates))
    object.__setattr__(m, "_inverse_rates_cache", cached)
    return cached


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _left_jacobian_inverse(phi: np.ndarray) -> np.ndarray:
    """``(3, 3)``: the change of the rotation vector ``log(exp(δ) exp(φ))`` per unit ``δ`` at
    ``δ = 0`` (the inverse of SO(3)'s left Jacobian at ``phi``; ``|φ|`` up to π)."""
    theta = float(np.linalg.norm(phi))
    k = _skew(phi)
    if theta < 1e-4:
        factor = 1.0 / 12.0
    else:
        factor = 1.0 / theta ** 2 - 1.0 / (2.0 * theta * np.tan(theta / 2.0))
    return np.eye(3) - 0.5 * k + factor * (k @ k)


def inverse_starts(m: Any, targets: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """``(N, 6 + n_var)`` first-order starts of the inverse model of ``m`` (:func:`inverse_rates`)
    for ``targets (N, 6)`` (tool point m, unit axis) and tool lengths ``lengths (N,)`` (m):
    ``u_home + Σ_j rates[:, j] d_j`` with ``d = (p − ℓ a − flange_home, a − axis_home)``,
    summed in ``j``'s order term by term — each row's bits its own, whatever the batch, and
    those of :func:`pkmkit.solve.chain_one_kernel.inverse_start` (the one-pose path) — except
    the rows where the kind's closed-form start answers (:func:`closed_starts`), which take
    it."""
    u_home, base, rates = inverse_rates(m)
    targets = np.asarray(targets, dtype=float)
    with np.errstate(invalid="ignore", over="ignore"):
        d = np.empty((len(targets), 6))
        d[:, :3] = targets[:, :3] - lengths[:, None] * targets[:, 3:]
        d[:, :3] -= base[:3]
        d[:, 3:] = targets[:, 3:] - base[3:]
        acc = d[:, 0, None] * rates[:, 0]
        for j in range(1, 6):
            acc = acc + d[:, j, None] * rates[:, j]
        out = u_home + acc
    closed = closed_starts(m, targets, lengths)
    if closed is not None:
        exact = np.isfinite(closed).all(axis=1)
        out[exact] = closed[exact]
    return out


def closed_starts(m: Any, targets: np.ndarray, lengths: np.ndarray,
                  branch: np.ndarray | None = None) -> np.ndarray | None:
    """``(N, 6 + n_var)`` the kind's closed-form starts of the inverse model
    (``MachineKind.inverse_start``; the TriMule's
    :func:`~pkmkit.machines.trimule_forms.start_unknowns`) for ``targets (N, 6)`` (unit axes)
    and tool lengths ``(N,)``, on the head's ``branch (N,)`` (±1) or the branch nearest home
    (None); NaN rows where it declines; None where the kind has none (the first-order start).

    With one, :func:`inverse_starts` takes it wherever it answers — on the TriMule the
    solution itself to ~1e-15 on the poses away from the wrist singularity (the first solve
    then stops at its first test: 0 iterations, where the first-order start took 8.3 on
    average) — and the head's branch rule starts the mirror from it
    (:meth:`~pkmkit.machines.warm_starts.ChainWarmStart._nearest_branch`): the batch path, the
    Numba one-pose path (:mod:`pkmkit.machines.chain_one`) and the C call (``native/
    chain_one.c``, the same arithmetic) start alike, so their answers agree as before (issue
    22 §1, session 33)."""
    start = getattr(m.kind, "inverse_start", None)
    if start is None:
        return None
    ok = m.__dict__.get("_closed_start_ok")
    if ok is None:  # the kind's own variables in its order: a model the kind built
        ok = tuple(m.model.variables) == getattr(start, "variables", None)
        object.__setattr__(m, "_closed_start_ok", ok)
    if not ok:
        return None
    twin = compiled_start(m, start)
    if twin is None:
        return start(m.params, targets, lengths, branch)
    targets = np.ascontiguousarray(targets, dtype=float)
    n = len(targets)
    out = np.empty((n, 6 + len(start.variables)))
    branches = np.zeros(n) if branch is None else np.ascontiguousarray(branch, dtype=float)
    twin[0].inverse_rows(twin[1], targets, np.ascontiguousarray(
        np.broadcast_to(np.asarray(lengths, dtype=float), (n,))), branches, out)
    return out
