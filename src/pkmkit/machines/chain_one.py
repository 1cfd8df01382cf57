"""One pose per call on a joint-chain machine (issue 22 §1): ``m.ik(x)``, ``m.fk(q)`` and
``m.jacobian(x)`` of one plain pose or configuration through one compiled call each
(:mod:`pkmkit.solve.chain_one_kernel`), without the batch machinery.

With the C extension, plain ``m.ik(x)`` (no ``start``, no ``full_output``) and ``m.fk(q)`` are
one C call each instead (:mod:`pkmkit.machines.chain_one_native`: the same rules in C, the
solve by block elimination, the batch row to rounding — not to the bit); the rest of this
module is then ``ik``'s ``start``/``full_output`` path, the Jacobian, and the path of every
call where the extension is absent or ``PKMKIT_NATIVE=0`` was set before the machine's first
single call.

Per machine, once (:class:`ChainOneConstants`, cached on the machine): the kernel's arrays,
the inverse's and the direct model's first-order starts, the strokes, the legs' home modes, the
head's wrist pair. Per call: a type and range check of the plain numbers, one compiled solve on
preallocated arrays, the stroke test in Python floats, the result assembled directly. Anything
unusual returns None and the machine takes the batch path, which gives the same numbers and
raises the typed errors: not 6 (or ``n``) plain finite numbers within ±``MAX_COORDINATE``, a
zero tool axis, no convergence (a row that fails from the first-order start, or leaves the
legs' home assembly modes from there, is first solved again from home, as on the batch path),
a joint beyond its stroke (unless ``strokes="ignore"`` and the batch path would keep the
solution), an inverse solution whose head could be on its other branch (the batch path's
:meth:`~pkmkit.machines.warm_starts.ChainWarmStart._nearest_branch` rule solves the mirror), a
closure the bound of :mod:`~pkmkit.solve.chain_one_kernel` cannot certify regular, a machine
whose closure Jacobian at home is rank deficient, and every option the fast paths do not take
(``q0``, ``start``, ``tool_length``, ``full_output``, engine options).

Agreement with the batch row of the same input: ``ik`` bit for bit (the same kernel from the
same start, :func:`~pkmkit.machines.chain_starts.inverse_starts` — the kind's closed form where
it answers, by its compiled twin as the batch rows once Numba is imported; the head's turn
wrapped as ``np.angle`` does); ``fk`` and ``jacobian`` to rounding (the direct model's start:
the kind's closed form by its twin, else first order formed in the kernel; the batch closure
may be C's; the rates by Cholesky with one refinement step,
not LAPACK's pseudo-inverse). No result depends on an earlier call: only constants are cached.

A one-shot call in a fresh process does not import Numba
(:func:`pkmkit.numerics.jit.compiled_from_second_call`): until Numba is imported, a machine's
first single call takes the batch path and the next imports it. Only a plain single pose (or
configuration) counts: a batch, even of one row, never builds the constants nor imports Numba
(a workspace study's batches run the closure's C twin).
"""

from __future__ import annotations

import math
import operator
import os
import sys
import threading
from typing import Any

import numpy as np

from pkmkit.machines import chain_one_velocity
from pkmkit.machines.chain_one_native import packed
from pkmkit.machines.chain_results import ChainInverseResult
from pkmkit.machines.chain_starts import (
    closed_direct_starts,
    closed_starts,
    compiled_start,
    home_rates,
    inverse_rates,
)
from pkmkit.machines.chain_velocity_record import RANK_RCOND, SINGULAR_TOL, ChainJacobians
from pkmkit.machines.common import MAX_COORDINATE
from pkmkit.machines.head_branches import FLIP_MARGIN
from pkmkit.machines.lazy_records import built_once, lazy_record_class
from pkmkit.machines.strokes import STROKE_TOL, row_excess, stroke_ends
from pkmkit.numerics import jit

_KERNELS = "pkmkit.solve.chain_one_kernel"
_FAR = math.pi / 2 - FLIP_MARGIN
_TWO_PI = 2.0 * math.pi
_ATAN2 = np.arctan2
#: Margin of the singularity bound over the thresholds (the batch path's SVD rounds).
BOUND_MARGIN = chain_one_velocity.BOUND_MARGIN


def usable(machine: Any, tag: str = "chain_ik") -> bool:
    """Whether a single call (``tag``: ``chain_ik``, ``chain_fk``, ``chain_jacobian``) of
    ``machine`` runs compiled now (module docstring; each method's first call counts, as the
    full-pose paths' direct and velocity calls: ``m.ik(m.home_pose)`` is a first ``fk`` then
    a first ``ik``)."""
    if "numba" in sys.modules and "PKMKIT_COMPILED" not in os.environ:
        return jit.numba_available()
    return jit.compiled_from_second_call(machine, tag)


def _options(defaults: dict[str, Any], **override: float) -> np.ndarray:
    """The engine options of the batch path's kernel call (``defaults``: the keyword defaults
    of :func:`pkmkit.solve.chain_rows.solve` or ``solve_inverse``, read at their import), as
    the one-row kernels take them."""
    defaults = {**defaults, **override}
    return np.array([defaults[k] for k in ("max_iter", "xtol", "atol", "gtol", "stall",
                                           "residual_tol", "damping")], dtype=float)


class _Kernel:
    """A compiled kernel called with the same argument types every time: after the first call
    through Numba's dispatcher (which compiles or loads it), its compiled entry point for
    those types is called directly (no type dispatch: ≈ 2 µs less per call); a C twin, or a
    kernel whose entry point is not found, is called as it is."""

    __slots__ = ("call", "function")

    def __init__(self, function: Any) -> None:
        self.function = function
        self.call = None

    def first(self, *args: Any) -> None:
        """Call through the dispatcher and find the entry point for ``args``' types."""
        self.function(*args)
        overloads = getattr(self.function, "overloads", None)
        entry = None
        if overloads:
            from numba import typeof

            found = overloads.get(tuple(typeof(a) for a in args))
            entry = getattr(found, "entry_point", None)
        self.call = entry if entry is not None else self.function


class ChainOneConstants:
    """What a machine's one-pose calls need, built once (module docstring)."""

    def __init__(self, m: Any) -> None:
        from pkmkit.solve import chain_kernel, chain_rows
        from pkmkit.solve.chains import CLOSURE_DAMPING

        model = m.model
        n_var = model.n_variables
        passive = np.asarray(m.passive_variables, dtype=int)
        act = np.flatnonzero(model.actuated)
        frames, types, evar, elements, offsets, position = chain_kernel.model_arrays(
            model, passive)
        every = chain_kernel.model_arrays(model, np.arange(n_var))[-1]
        head = np.array(model.head, dtype=np.int64)
        home = m.home_values
        self.n, self.n_u = len(act), 6 + len(passive)
        self.regular = m.expected_rank() == self.n_u  # else the bound cannot certify
        self.expected_rank = m.expected_rank()
        self.length = float(model.characteristic_length)
        self.tool = float(m.tool_length)
        self.act = act
        self.n_var = n_var
        # inverse model: u = (platform, every variable) from the first-order start
        self.tool_row = np.full(1, self.tool)
        self.inverse_args = (frames, types, evar, elements, offsets, every, head,
                             np.zeros((1, n_var)), self.length,
                             _options(chain_rows.SOLVE_INVERSE_DEFAULTS))
        # the first-order start's home, flange point and axis at home, rates (own copies)
        # and the legs' home modes (_mode_constants)
        self._mode_constants(m)
        self.u_home = inverse_rates(m)[0].copy()
        self.first_args = (*self.inverse_args, *(a.copy() for a in inverse_rates(m)),
                           *self.modes)
        # direct model: u = (platform, passive) from the first-order start
        rates, residual_rates = home_rates(m)
        self.direct_args = (frames, types, evar, elements, offsets, position, head,
                            np.concatenate([m.home_platform, home[passive]]),
                            np.ascontiguousarray(rates, dtype=float),
                            np.ascontiguousarray(residual_rates, dtype=float),
                            self.length, self.tool,
                            _options(chain_rows.SOLVE_DEFAULTS, damping=CLOSURE_DAMPING), home,
                            act.astype(np.int64))
        self.local = threading.local()  # each thread's work arrays (_work)
        self._velocity_constants(m, passive)
        self._joint_constants(m)
        self.passive = np.asarray(m.passive_variables, dtype=int)
        self.q_min, self.q_max = model.q_min[act], model.q_max[act]
        self.inverse_kernel = _Kernel(jit.kernel(_KERNELS, "inverse_one"))
        self.first_kernel = _Kernel(jit.kernel(_KERNELS, "inverse_first_one"))
        self.from_kernel = _Kernel(jit.kernel(_KERNELS, "inverse_from_one"))
        self.direct_kernel = _Kernel(jit.kernel(_KERNELS, "direct_one"))
        self.velocity_kernel = _Kernel(jit.kernel(_KERNELS, "velocity_one"))
        self.svd_kernel = _Kernel(jit.kernel("pkmkit.numerics.svd_kernel", "singular_values"))

    def _mode_constants(self, m: Any) -> None:
        """The legs' home assembly modes
        (:meth:`~pkmkit.machines.warm_starts.ChainWarmStart.mode_signature`) as places in u
        ``(6 + n_var)``: each slide's with its home sign, each revolute leg joint's with its
        home value."""
        slides, turns = m.leg_joints_by_type()
        home = m.home_values
        self.mode_slides = tuple((6 + int(v), float(np.sign(home[v]))) for v in slides)
        self.mode_turns = tuple((6 + int(v), float(home[v])) for v in turns)
        self.modes = (np.array([i for i, _ in self.mode_slides], dtype=np.int64),
                      np.array([s for _, s in self.mode_slides], dtype=float),
                      np.array([i for i, _ in self.mode_turns], dtype=np.int64),
                      np.array([h for _, h in self.mode_turns], dtype=float))

    def in_home_modes(self, u: list[float]) -> bool:
        """The closure ``u`` (6 + n_var) in the legs' home assembly modes (the test of
        :meth:`~pkmkit.machines.warm_starts.ChainWarmStart.in_home_modes`; its cosine here by
        ``math.cos``, whose sign agrees with NumPy's but for a joint a quarter turn from home
        to the last place)."""
        return all(u[i] * sign > 0 for i, sign in self.mode_slides) and all(
            math.cos(u[i] - home) > 0 for i, home in self.mode_turns)

    def _velocity_constants(self, m: Any, passive: np.ndarray) -> None:
        """The velocity kernel's column maps: the closure's (platform, passive, leg
        actuators), the head actuators' places in J, the leg actuators'; J's homogenising
        scale; the singularity bound's threshold of ``fk``'s default check."""
        model, act = m.model, self.act
        n_var = model.n_variables
        loop_act = [int(v) for v in act if model.loop_variables[v]]
        vel = np.full(n_var, -1, dtype=np.int64)
        vel[passive] = 6 + np.arange(len(passive))
        vel[loop_act] = self.n_u + np.arange(len(loop_act))
        head_position = np.full(n_var, -1, dtype=np.int64)
        order = {int(v): k for k, v in enumerate(act)}
        for v in act:
            if not model.loop_variables[v]:
                head_position[v] = order[int(v)]
        self.velocity_extra = (vel, head_position,
                               np.array([order[v] for v in loop_act], dtype=np.int64))
        self.scale = np.array([1, 1, 1, self.length, self.length, self.length], dtype=float)
        self.singular_bound = BOUND_MARGIN * SINGULAR_TOL

    def _joint_constants(self, m: Any) -> None:
        """The strokes (every variable: its bounds widened by ``STROKE_TOL``, unbounded for the
        head's passive joints), the actuators' places, the revolute actuators' home values and
        the wrist pair of the head's branch rule."""
        model, act = m.model, self.act
        home = m.home_values
        joints = model.loop_variables | model.actuated
        self.strokes = stroke_ends(model.q_min[act], model.q_max[act])  # row_excess()
        self.lower = np.where(joints, model.q_min - STROKE_TOL, -np.inf).tolist()
        self.upper = np.where(joints, model.q_max + STROKE_TOL, np.inf).tolist()
        # the actuators' values from every variable's, as a tuple (one actuator too)
        self.actuators = (operator.itemgetter(*act.tolist()) if len(act) > 1 else
                          lambda values, i=int(act[0]): (values[i],))
        self.turns = tuple((int(v), float(home[v])) for v in act
                           if m.element_of(int(v)).type == "R")
        pair = m.wrist_pair()
        self.wrist = None
        if pair is not None:  # (turn, its home, tilt, its home, the turn reaches π/2)
            t = pair[0]
            reach = max(abs(model.q_min[t] - home[t]), abs(model.q_max[t] - home[t]))
            self.wrist = (t, float(home[t]), pair[1], float(home[pair[1]]),
                          bool(reach >= np.pi / 2))
        # the kind's closed-form starts (chain_starts): their compiled twins where they have
        # them (compiled_start: the batch rows' functions, on one row)
        self.closed = self.closed_direct = None
        twin = compiled_start(m, m.kind.direct_start) if closed_direct_starts(
            m, np.zeros((0, len(act)))) is not None else None
        if twin is not None:
            self.closed_direct = (_Kernel(twin[0].direct_rows), twin[1], np.concatenate(
                [np.arange(6), 6 + np.asarray(m.passive_variables, dtype=int)]))
        if closed_starts(m, np.zeros((0, 6)), np.zeros(0)) is not None:
            twin = compiled_start(m, m.kind.inverse_start)
            self.closed = ((m.kind.inverse_start, dict(m.params)) if twin is None else
                           (_Kernel(twin[0].inverse_rows), twin[1]))

    def __reduce__(self) -> tuple:
        """Pickled (or deep-copied with its machine) as nothing: rebuilt at the next call (it
        holds compiled functions and per-thread arrays)."""
        return _nothing, ()

    def within(self, values: list[float]) -> bool:
        """Every joint of ``values`` (every variable, model order) within its stroke (the
        comparisons of :func:`~pkmkit.machines.strokes.signed_excess`, in C)."""
        return all(map(operator.le, self.lower, values)) and all(
            map(operator.le, values, self.upper))


def _nothing() -> None:
    """What a pickled :class:`ChainOneConstants` becomes."""
    return None


class _Work:
    """One thread's work arrays for the kernels of a machine (the kernels release the GIL:
    threads calling one machine must not share them)."""

    __slots__ = ("branch", "closed", "delta", "info", "pose", "q", "target", "u_dir", "u_inv",
                 "values")

    def __init__(self, c: ChainOneConstants) -> None:
        self.u_inv, self.target = np.zeros((1, 6 + c.n_var)), np.zeros((1, 6))
        self.closed, self.branch = np.zeros((1, 6 + c.n_var)), np.zeros(1)
        self.values, self.delta, self.q = np.zeros((1, c.n_var)), np.zeros(c.n), np.zeros(c.n)
        self.u_dir, self.pose, self.info = np.zeros((1, c.n_u)), np.zeros(6), np.zeros(4)


def _work(c: ChainOneConstants) -> _Work:
    """This thread's work arrays of ``c``."""
    try:
        return c.local.work
    except AttributeError:
        c.local.work = _Work(c)
        return c.local.work


def constants(m: Any, tag: str = "chain_ik") -> ChainOneConstants | None:
    """The machine's one-pose constants (built at the first compiled single call), or None
    where its single call of kind ``tag`` (:func:`usable`) takes the batch path."""
    c = m.__dict__.get("_chain_one_constants")
    if c is None or not ("numba" in sys.modules and "PKMKIT_COMPILED" not in os.environ):
        if not usable(m, tag):
            return None
        if c is None:
            c = ChainOneConstants(m)
            object.__setattr__(m, "_chain_one_constants", c)
    return c if c.regular else None


def _plain(x: Any, width: int) -> list[float] | None:
    """``width`` finite floats within ±MAX_COORDINATE from a list, tuple or 1-D float array."""
    if isinstance(x, np.ndarray):
        if x.shape != (width,) or x.dtype.kind != "f":
            return None
        x = x.tolist()
    elif type(x) in (list, tuple) and len(x) == width:
        if not all(type(v) is float or (type(v) is int and abs(v) <= MAX_COORDINATE)
                   for v in x):  # an int beyond a double: the batch path's typed error
            return None
        x = [float(v) for v in x]
    else:
        return None
    total = sum(x)  # NaN if any is
    if not (max(map(abs, x)) <= MAX_COORDINATE and total == total):
        return None
    return x


def inverse(m: Any, x: Any, strokes: str, start: Any = None) -> np.ndarray | None:
    """``m.ik(x)`` of one plain pose ``x`` (6 numbers) from the default start, or from
    ``start`` (6 + n_var plain numbers: a previous solution, as the batch path's ``start``):
    ``q (n,)``, or None (module docstring)."""
    found = _inverse_within(m, x, strokes, start)
    return None if found is None else np.array(found[0].actuators(found[1]))


def inverse_record(m: Any, x: Any, strokes: str, start: Any = None) -> Any:
    """``m.ik(x, full_output=True)`` of one plain pose (from ``start`` if given): the batch
    path's single-row :class:`~pkmkit.machines.chain_results.ChainInverseResult`, its fields
    but ``direct`` and ``pose`` given at once (``solution`` the ``start`` of a next call: a
    controller's loop), those two computed when read (the direct model at ``q`` from the
    inverse's closure, as the batch path computes them at once); or None (module
    docstring)."""
    found = _inverse_within(m, x, strokes, start)
    if found is None:
        return None
    c, values, u, iterations, residual = found  # within the strokes but with "ignore":
    # no actuator's excess (signed_excess's +0.0) there
    q = np.array(c.actuators(values))
    solution = np.array(u)
    closure = np.concatenate([solution[:6], solution[6:][c.passive]])
    record = _inverse_record_class()(None, q=q, status=np.int64(0), branches=None, shortfall=None,
                             method="numeric", mode=np.int64(0),
                             iterations=np.int64(iterations), residual=np.float64(residual),
                             out_of_stroke=None if strokes == "ignore" else np.False_,
                             stroke_excess=(row_excess(q.tolist(), c.strokes) if strokes == "ignore"
                                            else np.zeros(c.n)),
                             solution=solution, closure=closure)
    object.__setattr__(record, "_evaluation", _InverseFields(m, q, closure, strokes,
                                                             record.known_fields()))
    return record


@built_once
def _inverse_record_class() -> type:
    """The one-pose inverse record class, built on first use (its ``__reduce__`` set before
    any thread sees it)."""
    cls = lazy_record_class(
        ChainInverseResult, "OnePose",
        lambda r: f"1 pose, {len(r.q)} actuators; the direct model at q computed when read",
        "A joint chain's inverse record of one pose (:mod:`pkmkit.machines.chain_one`); "
        "direct and pose computed when first read.")
    from pkmkit.machines.chain_inverse_record import _plain_record

    # pickled as the plain record, every field computed (its fields are keyword-only)
    cls.__reduce__ = lambda self: (_plain_record, (
        {name: getattr(self, name) for name in ChainInverseResult.__dataclass_fields__},))
    return cls


class _InverseFields:
    """The fields of a one-pose inverse record computed when read: ``direct`` (the batch
    path's single-row ``direct_at``) and ``pose`` (its tool pose)."""

    __slots__ = ("cache", "closure", "m", "q", "strokes")

    def __init__(self, m: Any, q: np.ndarray, closure: np.ndarray, strokes: str,
                 cache: dict) -> None:
        self.m, self.q, self.closure, self.strokes, self.cache = m, q, closure, strokes, cache

    def field(self, name: str) -> Any:
        from pkmkit.machines.chain_inverse_record import direct_at

        if name == "direct":
            return direct_at(self.m, self.q[None], self.closure[None],
                             np.array([float(self.m.tool_length)]), self.strokes, True)
        if name == "pose":
            if "direct" not in self.cache:
                self.cache["direct"] = self.field("direct")
            return np.atleast_2d(self.cache["direct"].pose)[0]
        raise AttributeError(name)  # pragma: no cover - every other field is given


def _inverse_within(m: Any, x: Any, strokes: str, start: Any) -> tuple | None:
    """``(constants, every joint's value, the solution u, iterations, residual)`` of one plain
    pose within the strokes (or any with ``strokes="ignore"``), or None."""
    xs = _plain(x, 6)  # before constants(): a batch call is no single call (no Numba import)
    c = None if xs is None else constants(m)
    if c is None:
        return None
    if start is not None:
        start = _plain(start, 6 + c.n_var)
        if start is None:
            return None
    found = _inverse_values(c, xs, start)
    if found is None:
        return None
    if strokes != "ignore" and not c.within(found[0]):
        return None  # the batch path warns or refuses
    return (c, *found)


def _inverse_values(c: ChainOneConstants, xs: list[float], start: list[float] | None = None
                    ) -> tuple | None:
    """``(every joint variable, u, iterations, residual)`` of the inverse solution of pose
    ``xs`` from the batch path's default start — the kind's closed form where it answers
    (:func:`_closed_start`), else the first-order start — (or ``start``), revolute actuators
    on the turn nearest
    home, on the head's branch of the batch path's rule; None where the batch path must
    decide."""
    a, b, d = xs[3], xs[4], xs[5]
    norm = math.sqrt(a * a + b * b + d * d)
    if not norm > 0:
        return None
    w = _work(c)
    w.target[0] = (xs[0], xs[1], xs[2], a / norm, b / norm, d / norm)
    warm = start is not None  # a caller's start
    if start is None and c.closed is not None:  # the kind's closed form, as the batch path
        closed = _closed_start(c, w.target, None)
        if closed is not None:
            start = closed
    if start is None:  # from the first-order start, as the batch path's default
        kernel = c.first_kernel
    else:
        w.u_inv[0] = start
        kernel = c.from_kernel
    (kernel.call or kernel.first)(*c.first_args, w.u_inv, w.target, c.tool_row, w.info)
    first = w.info[0] == 0 and w.info[3] == 1.0  # converged, in the legs' home modes
    if first:
        u = w.u_inv[0].tolist()
    else:  # solved again (warm_starts._solve_from_closed): a caller's start failed, from the
        # closed-form start if it answers and converges within the legs' home modes; from home
        closed = _closed_start(c, w.target, None) if warm and c.closed is not None else None
        u = None if closed is None else _solve_inverse(c, w, closed)
        if u is None or not c.in_home_modes(u):
            u = _solve_inverse(c, w, c.u_home)
        if u is None:
            return None
    found = (_wrapped(c, u[6:]), u, int(w.info[2]), float(w.info[1]))
    if c.wrist is not None:
        return _nearest_branch(c, found, first)
    return found


def _closed_start(c: ChainOneConstants, target: np.ndarray, branch: float | None
                  ) -> np.ndarray | None:
    """The kind's closed-form start (:func:`~pkmkit.machines.chain_starts.closed_starts`, the
    same function on one row) of ``target (1, 6)`` on ``branch`` (±1, or None: nearest home),
    or None where it declines."""
    function, params = c.closed
    if type(function) is _Kernel:  # the compiled twin (0: the branch nearest home)
        w = _work(c)
        w.branch[0] = 0.0 if branch is None else branch
        if function.call is None:
            function.first(params, target, c.tool_row, w.branch, w.closed)
        function.call(params, target, c.tool_row, w.branch, w.closed)
        u = w.closed[0]
        return u if u[0] == u[0] else None  # a declined row: NaN throughout
    u = function(params, target, c.tool_row, None if branch is None else np.full(1, branch))[0]
    return u if np.isfinite(u).all() else None


def _closed_direct(c: ChainOneConstants, w: _Work) -> bool:
    """Whether the kind's direct start at ``w.q`` answered (its twin: the batch rows' start,
    :func:`~pkmkit.machines.chain_starts.closed_direct_starts`), into ``w.u_dir``."""
    kernel, k, columns = c.closed_direct
    q = w.q[None]
    if kernel.call is None:
        kernel.first(k, q, w.closed)
    kernel.call(k, q, w.closed)
    if not w.closed[0, 0] == w.closed[0, 0]:  # declined: NaN throughout
        return False
    w.u_dir[0] = w.closed[0, columns]
    return True


def _solve_inverse(c: ChainOneConstants, w: _Work, start: Any) -> list[float] | None:
    """The kernel's inverse of ``w.target`` from ``start`` (6 + n_var): the solution, or None
    where it did not converge (the batch path reports it)."""
    w.u_inv[0] = start
    kernel = c.inverse_kernel
    (kernel.call or kernel.first)(*c.inverse_args, w.u_inv, w.target, c.tool_row, w.info)
    return w.u_inv[0].tolist() if w.info[0] == 0 else None


def _wrapped(c: ChainOneConstants, values: list[float]) -> list[float]:
    """``values`` with the revolute actuators on the turn nearest home: ``home +
    np.angle(np.exp(1j (v − home)))`` — NumPy's arctan2 (math's differs in the last place)."""
    values = list(values)
    if c.turns:
        d = [values[v] - home for v, home in c.turns]
        for (v, home), a in zip(c.turns, _ATAN2(tuple(map(math.sin, d)),
                                                tuple(map(math.cos, d))).tolist(), strict=True):
            values[v] = home + a
    return values


def _turn_offset(angle: float) -> float:
    """``angle`` wrapped to (−π, π] (:func:`~pkmkit.machines.head_branches.wrapped`; Python's
    ``%`` is NumPy's ``mod`` for floats)."""
    return math.pi - (math.pi - angle) % _TWO_PI


def _nearest_branch(c: ChainOneConstants, found: tuple, first: bool) -> tuple | None:
    """The rule of :meth:`~pkmkit.machines.warm_starts.ChainWarmStart._nearest_branch` for one
    row (:func:`~pkmkit.machines.head_branches.nearest_head_branch` with home as the
    reference, the strokes judged around home): the mirror solved where the solution's turn is
    far from home's (or, when the turn's stroke reaches a quarter turn, beyond a stroke) and
    kept where it is nearer or alone within the strokes. ``found`` and the result: ``(values
    (wrapped), u, iterations, residual)`` of the branch kept (the iterations of both solves,
    as the batch path counts them), or None (the mirror did not converge, or is kept outside
    the legs' home modes after the first start (``first``): the batch path)."""
    values, u, iterations, _ = found
    turn, home_turn, tilt, tilt_centre, wide = c.wrist
    far = abs(_turn_offset(u[6 + turn] - home_turn)) > _FAR
    kept_inside = c.within(values)
    if not (far or (wide and not kept_inside)):
        return found
    start = list(u)
    start[6 + turn] += math.pi
    start[6 + tilt] = 2.0 * tilt_centre - start[6 + tilt]
    w = _work(c)
    if c.closed is not None:  # the other branch's closed form, as the batch path
        closed = _closed_start(c, w.target, 1.0 if math.sin(u[6 + tilt] - tilt_centre) < 0
                               else -1.0)
        if closed is not None:
            start = closed
    other = _solve_inverse(c, w, start)
    if other is None:
        return None  # not converged: the batch path (which keeps the first solution)
    other_values = _wrapped(c, other[6:])
    closer = abs(_turn_offset(other[6 + turn] - home_turn)) < abs(
        _turn_offset(u[6 + turn] - home_turn))
    flipped_inside = c.within(other_values)
    iterations += int(w.info[2])
    if (flipped_inside and not kept_inside) or (flipped_inside == kept_inside and closer):
        # the batch path solves a mirror outside the legs' home modes again from home (a row
        # from the first start)
        if first and not c.in_home_modes(other):
            return None
        return other_values, other, iterations, float(w.info[1])
    return values, u, iterations, found[3]


def direct(m: Any, q: Any, strokes: str, check_singular: bool | None) -> np.ndarray | None:
    """``m.fk(q)`` of one plain configuration ``q`` (``n`` numbers): the tool point and axis
    ``(6,)``, or None (module docstring)."""
    if isinstance(q, np.ndarray) and q.ndim != 1:
        return None  # a batch: no single call (constants() would count it, import Numba)
    c = constants(m, "chain_fk")
    qs = None if c is None else _plain(q, c.n)
    if qs is None:
        return None
    w = _work(c)
    w.q[:] = qs
    check = check_singular is None or bool(check_singular)
    info = w.info
    given = c.closed_direct is not None and _closed_direct(c, w)
    kernel = c.direct_kernel
    (kernel.call or kernel.first)(*c.direct_args, w.values, w.delta, w.q, check, w.u_dir,
                                  w.pose, info, given)
    if info[0] != 0 or (check and not info[3] >= c.singular_bound):
        return None
    if strokes != "ignore" and not c.within(w.values[0].tolist()):
        return None
    return w.pose.copy()


# ---------------------------------------------------------------- velocity model
@built_once
def _record_class() -> type:
    """The one-pose velocity record class, built on first use."""
    return lazy_record_class(
        ChainJacobians, "OnePose",
        lambda r: f"1 pose, {len(r.q)} actuators; singular values computed when read",
        "A joint-chain machine's velocity model of one pose (:mod:`pkmkit.machines.chain_one`)"
        "; J_homogeneous, singular_values and condition computed when first read.")




class _Velocity:
    """The fields of a one-pose record not given at construction (computed when read): the
    singular values of ``J_homogeneous`` by the compiled one-sided Jacobi kernel of
    :mod:`pkmkit.numerics.svd_kernel` (what the batch path runs on large stacks; on one row it
    calls LAPACK: the same values to ~1e-15 of σ_max)."""

    __slots__ = ("J", "c", "sv")

    def __init__(self, jac: np.ndarray, c: ChainOneConstants) -> None:
        self.J, self.c, self.sv = jac, c, None

    def field(self, name: str) -> Any:
        if name == "J_homogeneous":
            return self.J * self.c.scale[:, None]
        if self.sv is None:
            self.sv = np.empty((1, min(self.J.shape)))
            kernel = self.c.svd_kernel
            (kernel.call or kernel.first)((self.J * self.c.scale[:, None])[None], self.sv)
        if name == "singular_values":
            return self.sv[0].copy()
        if name == "condition":
            return self.sv[:, 0][0] / self.sv[:, -1][0]
        raise AttributeError(name)


def jacobian(m: Any, x: Any, tol: float) -> Any:
    """``m.jacobian(x)`` of one plain pose ``x``: a record with the batch row's fields
    (``J``, ``passive_rates``, ``status``, ranks at once; ``J_homogeneous``,
    ``singular_values``, ``condition`` when read), or None (module docstring). With the C
    extension the inverse solution and the velocity model at it are one C call
    (:func:`pkmkit.machines.chain_one_velocity.at_pose`); where that does not apply, the
    compiled ``velocity_one`` below (the direct model solved again)."""
    if type(tol) is not float or not tol > 0 or tol == math.inf:
        return None
    if (p := packed(m)) is not None:
        # the inverse solution and the velocity model at it by one C call (chain_one_native.py;
        # the stroke test left to the batch path, as _inverse_values)
        fast = chain_one_velocity.at_pose(m, p, x, tol)
        if fast is not False:
            return fast
    xs = _plain(x, 6)  # before constants(), as in _inverse_within
    c = None if xs is None else constants(m, "chain_jacobian")
    found = None if c is None else _inverse_values(c, xs)
    if found is None:
        return None
    values = found[0]
    qs = c.actuators(values)
    fast = chain_one_velocity.record(m, qs, found[1], found[3], max(tol, RANK_RCOND),
                                     BOUND_MARGIN, c.expected_rank)  # at u, in C
    if fast is not False:
        return fast
    w = _work(c)
    w.q[:] = qs
    jac = np.empty((6, c.n))
    rates = np.empty((c.n_u - 6, c.n))
    info = w.info
    kernel = c.velocity_kernel
    (kernel.call or kernel.first)(*c.direct_args, *c.velocity_extra, w.values, w.delta, w.q,
                                  w.u_dir, jac, rates, info)
    if info[0] != 0 or not info[3] >= BOUND_MARGIN * max(tol, RANK_RCOND):
        return None
    return _record_class()(_Velocity(jac, c), J=jac, passive_rates=rates,
                   closure_rank=np.int64(c.n_u), expected_rank=c.expected_rank,
                   q=w.q.copy(), status=np.int64(0))


# ---------------------------------------------------------------- the machine's entry points
_MODES = ("flag", "refuse", "ignore")


class ChainOnePose:
    """Mixin of :class:`~pkmkit.machines.joint_chain.JointChainMachine` (through
    :class:`~pkmkit.machines.chain_jacobians.ChainVelocity`): the first lines of its ``ik``
    and ``fk`` ask these for the one-pose answer — ``(result,)`` for one plain row without
    options (but ``strokes``, ``check_singular``, ``tol``), ``()`` where the batch path
    answers (module docstring); its ``jacobian`` asks
    :func:`~pkmkit.machines.chain_one_velocity.at_call`, then :func:`jacobian`."""

    def _ik_one(self, x: Any, q0: Any, tool_length: Any, full_output: bool, strokes: str,
                start: Any, engine_options: dict) -> tuple:
        if q0 is None and tool_length is None and not engine_options and strokes in _MODES:
            if not full_output and start is None and (c := packed(self)) is not None:
                q = c.ik(c.capsule, x, strokes == "ignore", False)  # chain_one_native.py
                return () if q is None else (q,)
            fast = (inverse_record if full_output else inverse)(self, x, strokes, start)
            if fast is not None:
                return (fast,)
        return ()

    def _fk_one(self, q: Any, strokes: str, check_singular: bool | None, x0: Any, start: Any,
                tool_length: Any, full_output: bool, max_misfit: Any,
                engine_options: dict) -> tuple:
        if x0 is None and start is None and tool_length is None and max_misfit is None \
                and not full_output and not engine_options and strokes in _MODES:
            if (c := packed(self)) is not None:  # chain_one_native.py
                fast = c.fk(c.capsule, q, strokes == "ignore",
                            check_singular is None or bool(check_singular))
                return () if fast is None else (fast,)
            fast = direct(self, q, strokes, check_singular)
            if fast is not None:
                return (fast,)
        return ()
