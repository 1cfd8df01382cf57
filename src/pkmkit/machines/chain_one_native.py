"""One pose per call on a joint-chain machine through the C extension (issue 22 §1): ``m.ik(x)``
and ``m.fk(q)`` of one plain pose or configuration as one C call each
(``pkmkit.native.kernels.chain_one_ik`` / ``chain_one_fk``, native/chain_one.c).

Per machine, once: its constants — the closure's arrays (:func:`pkmkit.solve.chain_rows.
model_arrays`) for the inverse model (every joint variable unknown) and the direct model (the
passive ones), the engine options of the batch path, the inverse's first-order start
(:func:`~pkmkit.machines.chain_starts.inverse_rates`) and the direct model's
(:func:`~pkmkit.machines.chain_starts.home_rates`), the legs' home assembly modes, the revolute
actuators' homes, the strokes (widened by ``STROKE_TOL``), the head's wrist pair, the
singularity bound's threshold — copied into a capsule (``chain_one_pack``) cached on the
machine (pickled as nothing: rebuilt at the next call). Per call, in C: the plain-number check
(6, or ``n``, finite numbers within ±``MAX_COORDINATE`` from a list, tuple or 1-D float array),
the solve, the rules of :mod:`pkmkit.machines.chain_one` (the retry from home, the legs' home
modes, the turn wrapping, the head's branch rule, the stroke test; for ``fk`` the start, the
regularity bound and the tool point and axis), and the new NumPy array. Anything unusual
returns None and the machine takes the batch path (the same answers, the typed errors).

The solve is the batch path's Levenberg–Marquardt loop (the same stopping rules, statuses and
iteration counts) with each iteration's normal equations solved by block elimination onto the
platform's 6 unknowns (native/chain_one.c; the closure written by blocks,
native/chain_one_closure.c, chain.c's operations and bits): answers agree with the batch
rows to rounding (≤ 1e-12 m / rad measured on 1,000 workspace poses per machine,
tests/machines/test_chain_one_native.py), not to the bit. ``full_output``, ``start`` and
the Jacobian keep the Numba one-pose path of :mod:`pkmkit.machines.chain_one` (bit for bit
the batch record).

No Numba: a fresh process's first single call runs here (the extension costs no import).
``PKMKIT_NATIVE=0`` (or an extension built without ``chain_one.c``) leaves the Numba path.
"""

from __future__ import annotations

import contextlib
from typing import Any

import numpy as np

from pkmkit.machines.chain_starts import closed_starts, home_rates, inverse_rates
from pkmkit.machines.chain_velocity_record import SINGULAR_TOL
from pkmkit.machines.common import MAX_COORDINATE
from pkmkit.machines.head_branches import FLIP_MARGIN
from pkmkit.machines.strokes import STROKE_TOL
from pkmkit.numerics import jit

#: Margin of the singularity bound over the threshold (as :mod:`pkmkit.machines.chain_one`).
BOUND_MARGIN = 2.0
_KEY = "_chain_one_native"


class Packed:
    """A machine's packed constants (module docstring); ``ik``, ``fk`` the C entry points."""

    __slots__ = ("capsule", "fk", "ik")

    def __init__(self, capsule: Any, native: Any) -> None:
        self.capsule, self.ik, self.fk = capsule, native.chain_one_ik, native.chain_one_fk

    def __reduce__(self) -> tuple:
        """Pickled (or deep-copied with its machine) as nothing: packed again when needed."""
        return _nothing, ()


def _nothing() -> None:
    return None


def _options(defaults: dict[str, Any], **override: float) -> np.ndarray:
    defaults = {**defaults, **override}
    return np.array([defaults[k] for k in ("max_iter", "xtol", "atol", "gtol", "stall",
                                           "residual_tol", "damping")], dtype=float)


def pack_arguments(m: Any, structured: bool = True) -> tuple:
    """The arguments of ``chain_one_pack`` for machine ``m`` (module docstring)."""
    from pkmkit.solve import chain_rows
    from pkmkit.solve.chains import CLOSURE_DAMPING

    model = m.model
    n_var = model.n_variables
    passive = np.asarray(m.passive_variables, dtype=int)
    act = np.flatnonzero(model.actuated)
    frames, types, evar, elements, offsets, dir_position = chain_rows.model_arrays(model,
                                                                                   passive)
    inv_position = chain_rows.model_arrays(model, np.arange(n_var))[-1]
    home = m.home_values
    u_home, base, rates = inverse_rates(m)
    slides, turns = m.leg_joints_by_type()
    act_turns = [int(v) for v in act if m.element_of(int(v)).type == "R"]
    joints = model.loop_variables | model.actuated
    wrist = np.zeros(0)
    pair = m.wrist_pair()
    if pair is not None:
        t = pair[0]
        reach = max(abs(model.q_min[t] - home[t]), abs(model.q_max[t] - home[t]))
        wrist = np.array([t, home[t], pair[1], home[pair[1]], float(reach >= np.pi / 2)])
    d_rates, residual_rates = home_rates(m)
    i64 = np.int64
    return (
        frames, types, evar, elements, offsets, np.array(model.head, dtype=i64), inv_position,
        dir_position, float(model.characteristic_length),
        _options(chain_rows.SOLVE_INVERSE_DEFAULTS),
        _options(chain_rows.SOLVE_DEFAULTS, damping=CLOSURE_DAMPING),
        np.ascontiguousarray(u_home, dtype=float), np.ascontiguousarray(base, dtype=float),
        np.ascontiguousarray(rates, dtype=float), float(m.tool_length),
        (6 + np.asarray(slides)).astype(i64), np.sign(home[slides]).astype(float),
        (6 + np.asarray(turns)).astype(i64), home[turns].astype(float),
        np.array(act_turns, dtype=i64), home[act_turns].astype(float),
        np.where(joints, model.q_min - STROKE_TOL, -np.inf),
        np.where(joints, model.q_max + STROKE_TOL, np.inf), act.astype(i64), wrist,
        float(np.pi / 2 - FLIP_MARGIN),
        np.concatenate([m.home_platform, home[passive]]),
        np.ascontiguousarray(d_rates, dtype=float),
        np.ascontiguousarray(residual_rates, dtype=float), np.ascontiguousarray(home),
        BOUND_MARGIN * SINGULAR_TOL, float(MAX_COORDINATE), bool(structured),
        _closed_constants(m))


def _closed_constants(m: Any) -> np.ndarray | None:
    """The kind's closed-form start's constants for C (its ``native(params)``: the family's
    code, then its constants; chain_one.c ``closed_start``), or None: the kind has no
    closed-form start in C (:func:`~pkmkit.machines.chain_starts.closed_starts`)."""
    native = getattr(getattr(m.kind, "inverse_start", None), "native", None)
    if native is None or closed_starts(m, np.zeros((0, 6)), np.zeros(0)) is None:
        return None
    return np.asarray(native(m.params), dtype=float)


def packed(m: Any) -> Packed | None:
    """The machine's packed constants (built at its first single call), or None where the
    extension is absent or disabled, or the closure's Jacobian at home is rank deficient (the
    bound cannot certify a closure regular: the batch path)."""
    p = m.__dict__.get(_KEY)
    if p is None:
        native = jit.native_kernels()
        if native is None or not hasattr(native, "chain_one_pack"):
            return None
        p = False  # rank deficient at home, or beyond the C limits (more than 64 actuators)
        if m.expected_rank() == 6 + len(m.passive_variables):
            with contextlib.suppress(ValueError):
                p = Packed(native.chain_one_pack(*pack_arguments(m)), native)
        object.__setattr__(m, _KEY, p)
    return p or None
