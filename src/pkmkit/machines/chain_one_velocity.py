"""The velocity model of one pose of a joint-chain machine in one C call (issue 22 §1): what
``m.jacobian(x)`` does once the inverse solution of ``x`` is known
(:func:`pkmkit.machines.chain_one.jacobian`).

The inverse solution ``u`` = (platform pose, every joint variable) is the configuration the
batch path reaches again by the direct model at its actuators (``m.jacobian(X)``:
``ik``, then ``fk(q)`` from the direct model's first-order start, then the velocity model
there: :meth:`~pkmkit.machines.chain_jacobians.ChainVelocity._velocity`), so the velocity
model is evaluated at ``u`` directly — one call of the C kernel
``pkmkit.native.kernels.chain_one_jacobian`` (``native/chain_one_velocity.c``; its buffer form
``chain_one_velocity``) on constants packed once per machine (:class:`VelocityPack`, cached on
the machine), given the C inverse's solution array as it comes: the closure's Jacobian
``[C_U | C_q]`` (platform and passive joints; legs' actuators), the closure rates
``dU = −C_U⁺ C_q`` by a QR of ``C_U`` that takes each leg's own joints first (each leg's block
involves only the platform, its joints and the joints it shares), the tool twist per actuator
``J (6, n)``, ``J_homogeneous`` (the batch path's scale: angular rows × the characteristic
length), its singular values (round-robin one-sided Jacobi, ``native/svd.c``), the condition
number and a
lower bound of σ_min/σ_max of ``C_U`` (``1 / (‖C_U‖_F ‖C_U⁺‖_F)``).

The record (:class:`OnePoseChainJacobians`, made by :func:`at_solution` on the C inverse's
answer or by :func:`record`) has the batch row's fields and meanings: ``q``, ``status`` and the
ranks given; ``J``, ``J_homogeneous`` and ``passive_rates`` views of the kernel's new output
array, made at their first read and kept in the record's ``__dict__`` (later reads are plain
attribute reads); the singular values and the condition number computed at the first read of
either (the kernel's singular stage, one more C call on the array's ``J_homogeneous``: ``J``
alone does not pay the SVD) — once that happened on a machine object, its later calls run the
stage inside their one C call (``_Singular``; the same bits; a mark in that object's own
``__dict__``, not on the pack its copies share), so a loop reading ``condition`` makes one C
call per pose. ``q`` is a read-only view of the actuators, made at its first read and kept.
``m.jacobian(x)`` itself (:func:`at_call`, :func:`at_pose`) takes the *record layout* of the
fused call (``chain_one_ik_jacobian(..., record=True)``: one read-only ``(R, n)`` array of
rows J, J_homogeneous, the singular values and the condition, the passive rates and q): each
field of its record one index of that array (:class:`OnePoseChainJacobians`); the records of
:func:`record` and :func:`at_solution` keep the flat array (:class:`FlatOnePoseChainJacobians`).
``closure_rank`` is ``n_u`` and ``status``
OK only where the bound clears :data:`~pkmkit.machines.chain_one.BOUND_MARGIN` × max(``tol``,
:data:`~pkmkit.machines.chain_velocity_record.RANK_RCOND`): the closure is then certainly
regular, of full rank, and not singular by the batch path's SVD; elsewhere (near a singular
closure) the batch path answers, and raises its typed errors.

Agreement with the batch row (tests/machines/test_chain_one_velocity.py): the same
configuration to the solvers' tolerances, the same closure rates to rounding × the closure's
condition number; measured over 1,000 workspace poses of the Tripteor X7 and the TriMule 600,
every field within 1.5e-13 of its largest entry (``bench/chain_jacobian_agreement.py``;
docs/benchmarks.md, "One pose per call"). The kernel declines (and the Numba path that solves
the direct model again, :func:`pkmkit.solve.chain_one_kernel.velocity_one`, answers, as it
does without the C extension or with ``PKMKIT_NATIVE=0``): an inverse solution outside the
legs' home assembly modes (the batch path's direct model, started near home, may reach the
home-mode closure: the same J, a passive rate of the other sign), and a residual (the
largest closure or tool row, m) beyond :data:`RESIDUAL_GUARD` — a converged but inconsistent
closure (a model with defects: residuals up to the solver's ``residual_tol``, 1e-9) need not
be the direct model's least-squares closure.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.machines.chain_velocity_record import RANK_RCOND, ChainJacobians
from pkmkit.machines.lazy_records import read_only
from pkmkit.numerics import jit

#: Largest residual of the inverse solution (its closure and tool rows: m, and rad × the
#: characteristic length) for which it is taken as the direct model's closure (module
#: docstring). A nominal machine's inverse converges to ~1e-16.
RESIDUAL_GUARD = 1e-12
_OK = np.int64(0)  # Status.OK, as the batch row's
#: Margin of the bound over the thresholds (:data:`pkmkit.machines.chain_one.BOUND_MARGIN`).
BOUND_MARGIN = 2.0


class VelocityPack:
    """A machine's constants of the C kernel (module docstring), built once: the model
    arrays, the closure Jacobian's column of each variable (platform 0–5, the passive joints
    in ``m.passive_variables`` order, then the legs' actuators), the head actuators' and the
    leg actuators' places in J, the leg owning each column alone (−1: the platform's and the
    joints shared by legs), and the output buffer's layout."""

    __slots__ = ("call", "condition_at", "expected", "fusable", "ik_jacobian", "jacobian",
                 "layout", "n", "n_p", "pack", "rank", "records", "rows", "size", "sv_start",
                 "sv_stop")

    def __init__(self, m: Any, native: Any, arguments: dict | None = None) -> None:
        arguments = pack_arguments(m) if arguments is None else arguments
        self.pack = native.chain_velocity_pack(*arguments.values())
        self.call = native.chain_one_velocity
        self.jacobian = getattr(native, "chain_one_jacobian", None)  # None: an older build
        self.ik_jacobian = getattr(native, "chain_one_ik_jacobian", None)  # likewise
        # the singular stage in the same call (its sixth argument; not in an older build):
        # asked on a machine object once one of its records' condition or singular values was
        # read (_Singular: the machine's own _FUSED entry, never this pack, which copies of
        # the machine share)
        doc = getattr(self.ik_jacobian, "__doc__", "") or ""
        self.fusable = "singular=False" in doc
        self.records = "record=False" in doc  # the record layout (rows; _fused)
        n = int(np.count_nonzero(m.model.actuated))
        k = min(6, n)
        self.n, self.n_p = n, len(m.passive_variables)
        self.rank = np.int64(6 + self.n_p)  # the closure's, where the bound certifies it
        self.expected = 6 + self.n_p  # at home, where the one-pose path applies (an int)
        self.size = 12 * n + k + 1 + self.n_p * n
        self.layout = {"J": (0, 6 * n, (6, n)), "J_homogeneous": (6 * n, 12 * n, (6, n)),
                       "singular_values": (12 * n, 12 * n + k, None),
                       "condition": (12 * n + k, None, None),
                       "passive_rates": (12 * n + k + 1, self.size, (self.n_p, n))}
        self.sv_start, self.sv_stop = 12 * n, 12 * n + k  # the singular values; condition
        # the record layout (chain_one_ik_jacobian(..., record=True)): a read-only (R, n) array
        # of rows J, J_homogeneous, the singular values and the condition (s rows), the
        # passive rates, q; each field one index of it (OnePoseChainJacobians)
        s = 1 if k < n else 2
        self.condition_at = divmod(12 * n + k, n)
        self.rows = {"J": slice(0, 6), "J_homogeneous": slice(6, 12),
                     "singular_values": (12, slice(0, k)),
                     "passive_rates": slice(12 + s, 12 + s + self.n_p), "q": 12 + s + self.n_p}

    def __reduce__(self) -> tuple:
        """Pickled (or deep-copied with its machine) as nothing: rebuilt at the next call (it
        holds a capsule)."""
        return _nothing, ()


def pack_arguments(m: Any) -> dict[str, Any]:
    """The arguments of ``chain_velocity_pack`` for machine ``m``, by name (in order)."""
    from pkmkit.solve.chain_rows import model_arrays

    model = m.model
    n_var = model.n_variables
    passive = np.asarray(m.passive_variables, dtype=np.int64)
    act = np.flatnonzero(model.actuated)
    n_u = 6 + len(passive)
    loop_act = [int(v) for v in act if model.loop_variables[v]]
    position = np.full(n_var, -1, dtype=np.int64)
    position[passive] = 6 + np.arange(len(passive))
    position[loop_act] = n_u + np.arange(len(loop_act))
    order = {int(v): k for k, v in enumerate(act)}
    head_position = np.full(n_var, -1, dtype=np.int64)
    for v in act:
        if not model.loop_variables[v]:
            head_position[v] = order[int(v)]
    frames, types, evar, elements, offsets, _ = model_arrays(model, passive)
    slides, turns = m.leg_joints_by_type()  # the legs' home modes
    home = m.home_values
    return {"frames": frames, "types": types, "evar": evar, "elements": elements,
            "offsets": offsets, "position": position,
            "head": np.array(model.head, dtype=np.int64), "head_position": head_position,
            "loop_columns": np.array([order[v] for v in loop_act], dtype=np.int64),
            "column_leg": _column_legs(types, evar, elements, offsets, position, n_u),
            "n_u": n_u, "length": float(model.characteristic_length),
            "tool": float(m.tool_length),
            "slides": 6 + np.array(slides, dtype=np.int64),
            "signs": np.sign(home[slides]).astype(float),
            "turns": 6 + np.array(turns, dtype=np.int64), "homes": home[turns].astype(float)}


def _nothing() -> None:
    """What a pickled :class:`VelocityPack` becomes."""
    return None


def _column_legs(types: np.ndarray, evar: np.ndarray, elements: np.ndarray,
                 offsets: np.ndarray, position: np.ndarray, n_u: int) -> np.ndarray:
    """``(n_u,)`` the leg whose joint alone each unknown column of the closure is (−1 for the
    platform's columns and a joint met in several legs)."""
    owner = np.full(n_u, -1, dtype=np.int64)
    seen = np.zeros(n_u, dtype=np.int64)
    for leg in range(len(offsets) - 1):
        cols = {int(position[evar[e]]) for e in elements[offsets[leg]:offsets[leg + 1]]
                if types[e] != 0 and 6 <= position[evar[e]] < n_u}
        for col in cols:
            seen[col] += 1
            owner[col] = leg
    owner[seen != 1] = -1
    return owner


def pack(m: Any) -> VelocityPack | None:
    """The machine's :class:`VelocityPack` (built at its first call), or None without the C
    extension (or one built from sources without the kernel)."""
    p = m.__dict__.get("_chain_one_velocity")
    if p is None:
        native = jit.native_kernels_now()
        if native is None or not hasattr(native, "chain_one_jacobian"):
            return None
        p = VelocityPack(m, native)
        object.__setattr__(m, "_chain_one_velocity", p)
    elif jit.native_kernels_now() is None:  # PKMKIT_NATIVE=0 set since
        return None
    return p


class _View:
    """A view field of :class:`OnePoseChainJacobians` (``J``, ``J_homogeneous``,
    ``passive_rates``) made at its first read from the record's buffer and kept in the
    record's ``__dict__`` (a non-data descriptor: later reads are plain attribute reads)."""

    __slots__ = ("name",)

    def __init__(self, name: str) -> None:
        self.name = name

    def __get__(self, record: Any, owner: type | None = None) -> Any:
        if record is None:
            return self
        fields = record.__dict__
        start, stop, shape = fields["_pack"].layout[self.name]
        value = fields[self.name] = read_only(fields["_out"][start:stop].reshape(shape))
        return value


class _Singular:
    """``singular_values`` or ``condition`` of :class:`OnePoseChainJacobians`: its first read
    keeps it in the record's ``__dict__`` (the other made at its own first read: one NumPy
    object each), running the kernel's singular stage first (one C call on the buffer's
    ``J_homogeneous``) unless the record's C call ran it (the condition not NaN). That first
    run marks the machine object the record came from (:data:`_FUSED` in its ``__dict__``,
    kept by the record as ``_owner``; never the pack, which every copy of a built machine
    shares): that object's later one-pose calls run the stage in their own C call (the same
    function on the same ``J_homogeneous``: the same bits), so a loop reading ``condition``
    pays no second call and one that never reads it no singular stage, and a read on one copy
    changes no other copy's calls."""

    __slots__ = ("condition",)

    def __init__(self, condition: bool) -> None:
        self.condition = condition

    def __get__(self, record: Any, owner: type | None = None) -> Any:
        if record is None:
            return self
        fields = record.__dict__
        p, out = fields["_pack"], fields["_out"]
        stop = p.sv_stop
        condition = out[stop]
        if condition != condition:  # NaN: not computed in the record's call
            p.call(p.pack, None, out)
            condition = out[stop]
            if p.fusable:  # this machine object's later calls: the stage in their C call
                fields["_owner"][_FUSED] = True
        if self.condition:
            fields["condition"] = condition
            return condition
        values = fields["singular_values"] = read_only(out[p.sv_start:stop])
        return values


class _Given:
    """``q`` of :class:`OnePoseChainJacobians`: the builders below keep the actuators given as
    ``_q``; the first read stores their read-only view (:func:`read_only`: the caller's own
    array stays writeable, this view of it does not) as ``q`` in the record's ``__dict__``,
    where every later read finds it (a non-data descriptor: a plain attribute read, no second
    wrapping; a record whose ``q`` is never read pays none). The dataclass ``__init__``
    (``dataclasses.replace``) stores ``q`` there directly (its ``__post_init__`` makes it
    read-only)."""

    __slots__ = ()

    def __get__(self, record: Any, owner: type | None = None) -> Any:
        if record is None:
            return self
        fields = record.__dict__
        value = fields["q"] = read_only(fields["_q"])
        return value


class _Row:
    """A field of :class:`OnePoseChainJacobians` (``J``, ``J_homogeneous``, ``passive_rates``,
    ``q``): one index of the record's read-only array (the pack's ``rows``), a view read-only
    as the array is, made at its first read and kept in the record's ``__dict__`` (a non-data
    descriptor: later reads are plain attribute reads)."""

    __slots__ = ("name",)

    def __init__(self, name: str) -> None:
        self.name = name

    def __get__(self, record: Any, owner: type | None = None) -> Any:
        if record is None:
            return self
        fields = record.__dict__
        value = fields[self.name] = fields["_out"][fields["_pack"].rows[self.name]]
        return value


class _RowSingular:
    """``singular_values`` or ``condition`` of :class:`OnePoseChainJacobians` (as
    :class:`_Singular`, on the record layout): where the record's C call did not run the
    singular stage (the condition NaN), the stage runs on a writeable copy of the record's
    array (the one the fields read so far are views of stays as it is: read-only, the same
    entries but the stage's), which becomes the record's array, read-only; and marks the
    record's machine object (:data:`_FUSED`)."""

    __slots__ = ("condition",)

    def __init__(self, condition: bool) -> None:
        self.condition = condition

    def __get__(self, record: Any, owner: type | None = None) -> Any:
        if record is None:
            return self
        fields = record.__dict__
        p, out = fields["_pack"], fields["_out"]
        condition = out[p.condition_at]
        if condition != condition:  # NaN: not computed in the record's call
            out = out.copy()
            p.call(p.pack, None, out.reshape(-1))
            out.setflags(write=False)
            fields["_out"], condition = out, out[p.condition_at]
            if p.fusable:  # this machine object's later calls: the stage in their C call
                fields["_owner"][_FUSED] = True
        if self.condition:
            fields["condition"] = condition
            return condition
        values = fields["singular_values"] = out[p.rows["singular_values"]]
        return values


class _FromPack:
    """``closure_rank`` or ``expected_rank`` of :class:`OnePoseChainJacobians`: the pack's
    (``rank``, ``expected``: the closure's rank at home where the bound certifies it), kept in
    the record's ``__dict__`` at the first read."""

    __slots__ = ("attribute", "name")

    def __init__(self, name: str, attribute: str) -> None:
        self.name, self.attribute = name, attribute

    def __get__(self, record: Any, owner: type | None = None) -> Any:
        if record is None:
            return self
        fields = record.__dict__
        value = fields[self.name] = getattr(fields["_pack"], self.attribute)
        return value


class OnePoseChainJacobians(ChainJacobians):
    """A joint-chain machine's velocity model of one pose (this module): ``J``,
    ``J_homogeneous``, ``passive_rates`` and ``q`` views of the one read-only array of the
    fused C call (the record layout: one index each, made when first read; ``J`` and, on a
    machine object whose records' ``condition`` was read, ``condition`` kept at once: the
    fields a loop reads), ``singular_values`` and ``condition`` computed then where the call
    did not (the singular stage); ``status`` OK and the ranks the pack's. Equality is identity
    (comparing would compute every field); pickled, it becomes the plain
    :class:`~pkmkit.machines.chain_velocity_record.ChainJacobians`."""

    J = _Row("J")
    J_homogeneous = _Row("J_homogeneous")
    singular_values = _RowSingular(False)
    condition = _RowSingular(True)
    passive_rates = _Row("passive_rates")
    q = _Row("q")
    closure_rank = _FromPack("closure_rank", "rank")
    expected_rank = _FromPack("expected_rank", "expected")
    status = _OK  # the one-pose path answers only where the closure is certainly regular

    def __eq__(self, other: object) -> bool:
        return self is other

    __hash__ = object.__hash__

    def __repr__(self) -> str:
        return f"ChainJacobians(1 pose, {len(self.q)} actuators; fields read from one C call)"

    def __reduce__(self) -> tuple:  # pickled as the plain record, every field computed
        return ChainJacobians, tuple(getattr(self, name)
                                     for name in ChainJacobians.__dataclass_fields__)


class FlatOnePoseChainJacobians(OnePoseChainJacobians):
    """:class:`OnePoseChainJacobians` on ``chain_one_jacobian``'s flat output array (the
    records of :func:`record`, :func:`at_solution` and of a build without the record layout):
    ``J``, ``J_homogeneous``, ``passive_rates`` read-only views of its slices, ``q`` the
    actuators given (a read-only view made at its first read)."""

    J = _View("J")
    J_homogeneous = _View("J_homogeneous")
    singular_values = _Singular(False)
    condition = _Singular(True)
    passive_rates = _View("passive_rates")
    q = _Given()


_NEW = object.__new__


def record(m: Any, q: Any, u: Any, residual: float, tol: float, margin: float,
           expected_rank: int) -> Any:
    """The velocity model of one pose at the inverse solution ``u`` (6 + n_var floats: a list
    or a float64 array; ``q`` its actuators, an array or a sequence, ``residual`` its largest
    residual): the record; None where the bound does not clear ``margin`` × ``tol`` (the batch
    path answers); False where this path does not apply (no C extension, a residual beyond
    :data:`RESIDUAL_GUARD`, ``u`` outside the legs' home assembly modes: the Numba path,
    which solves the direct model again as the batch path does, answers)."""
    p = pack(m) if residual <= RESIDUAL_GUARD else None
    if p is None:
        return False
    out = p.jacobian(p.pack, u, margin * tol, _FUSED in m.__dict__) if p.fusable \
        else p.jacobian(p.pack, u, margin * tol)  # the singular values when read (_Singular)
    if out is None or out is False:  # the bound does not clear; outside the legs' home modes
        return out
    one = _NEW(FlatOnePoseChainJacobians)
    fields = one.__dict__
    fields["_out"], fields["_pack"], fields["status"] = out, p, _OK
    fields["_q"] = q if type(q) is np.ndarray else np.array(q)
    fields["closure_rank"], fields["expected_rank"] = p.rank, expected_rank
    fields["_owner"] = m.__dict__
    return one


def at_solution(m: Any, solved: tuple, tol: float) -> Any:
    """:func:`record` of the C inverse's full answer ``solved`` = ``(q, u, iterations,
    residual)`` (``chain_one_ik(..., full=True)``) with the one-pose path's threshold
    :data:`BOUND_MARGIN` × max(``tol``, ``RANK_RCOND``) and the closure's rank at home: the
    record, None or False as :func:`record` answers, in fewer Python steps (the per-call path
    of ``m.jacobian(x)``)."""
    p = m.__dict__.get("_chain_one_velocity")
    if p is None or _native_now() is None:  # not packed yet, or PKMKIT_NATIVE=0 set since
        p = pack(m)
        if p is None:
            return False
    if solved[3] > RESIDUAL_GUARD:
        return False
    owner = m.__dict__
    threshold = BOUND_MARGIN * (tol if tol > RANK_RCOND else RANK_RCOND)
    out = p.jacobian(p.pack, solved[1], threshold, _FUSED in owner) if p.fusable \
        else p.jacobian(p.pack, solved[1], threshold)
    if out is None or out is False:
        return out
    one = _NEW(FlatOnePoseChainJacobians)
    fields = one.__dict__
    fields["_out"], fields["_pack"], fields["status"], fields["_q"] = out, p, _OK, solved[0]
    fields["closure_rank"], fields["expected_rank"] = p.rank, p.expected
    fields["_owner"] = owner
    return one


def at_pose(m: Any, c: Any, x: Any, tol: float) -> Any:
    """``m.jacobian(x)``'s C path for one plain pose ``x`` given the machine's one-pose pack
    ``c`` (:func:`pkmkit.machines.chain_one_native.packed`): the inverse and the velocity model
    in one C call (``chain_one_ik_jacobian``, native/chain_one.c: the closure's Jacobian of the
    inverse's last evaluation handed to the velocity kernel when that evaluation was at the
    kept solution — the same bits as evaluating it again); the record, None or False as
    :func:`at_solution` answers (False too where the C inverse declines). An older build
    without the fused call takes ``chain_one_ik`` then :func:`at_solution`."""
    p = m.__dict__.get("_chain_one_velocity")
    if p is None or _native_now() is None:  # not packed yet, or PKMKIT_NATIVE=0 set since
        p = pack(m)
        if p is None:
            return False
    if p.ik_jacobian is None:
        solved = c.ik(c.capsule, x, True, True)
        return False if solved is None else at_solution(m, solved, tol)
    return _fused(p, c, x, tol, m.__dict__)


def at_call(m: Any, x: Any, tol: Any) -> Any:
    """The first step of ``m.jacobian(x)`` (:meth:`~pkmkit.machines.chain_jacobians.
    ChainVelocity.jacobian`, before its batch wrapper): :func:`at_pose` once the machine's
    packs exist, in the fewest Python steps — the record; None where the bound does not clear
    (the batch path answers); False where the other one-pose paths answer
    (:func:`pkmkit.machines.chain_one.jacobian`: the packs not built yet, no C extension or
    ``PKMKIT_NATIVE=0``, a ``tol`` that is not a positive finite float, an ``x`` the C
    inverse declines, a solution outside the legs' home modes or beyond the residual
    guard)."""
    fields = m.__dict__
    p, c = fields.get("_chain_one_velocity"), fields.get(_PACKED)
    if p is None or not c or type(tol) is not float or not 0.0 < tol < _INF \
            or p.ik_jacobian is None or _native_now() is None:
        return False
    return _fused(p, c, x, tol, fields)


def _fused(p: VelocityPack, c: Any, x: Any, tol: float, owner: dict) -> Any:
    """The fused C call (``chain_one_ik_jacobian``) and the record (:func:`at_pose`) of the
    machine object whose ``__dict__`` is ``owner`` (its :data:`_FUSED` entry: the singular
    stage in the call)."""
    threshold = BOUND_MARGIN * (tol if tol > RANK_RCOND else RANK_RCOND)
    if p.records:  # the record layout: the array alone, or None / False
        fused = _FUSED in owner
        out = p.ik_jacobian(c.capsule, p.pack, x, threshold, RESIDUAL_GUARD, fused, True)
        if type(out) is not _ARRAY:
            return out
        one = _NEW(OnePoseChainJacobians)  # status and the ranks: the class's (_FromPack)
        fields = one.__dict__
        fields["_out"], fields["_pack"], fields["_owner"], fields["J"] = out, p, owner, out[:6]
        if fused:  # this machine object's records have their condition read: kept now
            fields["condition"] = out[p.condition_at]
        return one
    got = p.ik_jacobian(c.capsule, p.pack, x, threshold, RESIDUAL_GUARD, True) \
        if _FUSED in owner else p.ik_jacobian(c.capsule, p.pack, x, threshold, RESIDUAL_GUARD)
    if got is None:
        return False
    q, out = got
    if out is None or out is False:
        return out
    one = _NEW(FlatOnePoseChainJacobians)
    fields = one.__dict__
    fields["_out"], fields["_pack"], fields["status"], fields["_q"] = out, p, _OK, q
    fields["closure_rank"], fields["expected_rank"], fields["_owner"] = p.rank, p.expected, owner
    return one


_native_now = jit.native_kernels_now
_PACKED = "_chain_one_native"  # the key of chain_one_native.packed's pack on the machine
_INF = float("inf")
_ARRAY = np.ndarray
#: The key, in a machine object's ``__dict__``, that asks its one-pose calls for the singular
#: stage inside their C call (set by :class:`_Singular` on a fusable build; per machine object:
#: a copy of the machine has its own ``__dict__``).
_FUSED = "_chain_one_fused"
