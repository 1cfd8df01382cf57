"""The velocity model of one pose of a translational rod-leg machine in plain Python floats
(issue 22 §1).

:class:`OnePoseJacobians` is what :meth:`Machine.jacobian` returns for one plain pose: a
:class:`~pkmkit.machines.velocity.LazyJacobians` (same fields, same shapes and types as the
batch path's single row) whose fields come from :class:`OnePoseVelocity` — the formulas of
:func:`pkmkit.machines.velocity.velocity_chunk` and :mod:`pkmkit.numerics.small` written out in
scalars for one pose (n = dims = 2 or 3), the same operations in the same order, so **the same
bits** as the batch path's row. Each field computes only the pieces it needs, once per record:

- ``A``, ``B``, ``J_inv``, ``det_B``: the rows ``p − c_i`` and the diagonal of B;
- ``J``, ``det_A``, ``mode``: those, the cofactors of A and one division (J = adj(A) B / det A),
  and whether the pose is a parallel singularity (J is NaN there);
- ``singular_values``, ``condition``: those and one closed-form singular-value computation of J;
- ``parallel_measure``: one of A with unit rows; ``serial_measure``: the row lengths;
  ``singularity``: both measures' tests.

Whether σ_min/σ_max of A with unit rows is below a threshold t is decided without computing it
where :func:`_surely_above` proves it is not (its lower bound |det A| / (2 ∏|a_i|)); only near a
parallel singularity is the measure itself computed. Whatever the batch path treats specially is
handed to it (a :class:`LazyJacobians` of one row, the same numbers): a zero row, overflow, a
determinant whose reciprocal overflows. The machine-constant parts (per-leg tuples of Python
floats) are built once per machine.

With the C extension (:func:`pkmkit.numerics.jit.native_kernels_now`) the same operations run
in C: :meth:`Machine.jacobian <pkmkit.machines.machine.Machine.jacobian>` of a plain pose is one
call ``rod_jacobian_one`` (``native/rod_one.c``: the pose read and checked, its inverse model
and stroke check, kept in a state; :func:`native_record`), and a field read is one call
``rod_field``: the first computes the rows, the determinants, J and the flags in that state,
the first of ``singular_values``, ``condition``, ``parallel_measure`` the singular values (the
same bits; nearly equal singular values by NumPy's own LAPACK ``svd`` loop called from C,
so the Orthoglide near its isotropic home stays in C); whatever the C kernel does not answer
(the cases above) the Python pieces do, from the state's pose and actuator coordinates.
:func:`jacobian_one` is the path without the extension (``rod_inverse`` and ``rod_velocity``
where only ``rod_velocity`` of an older build is present).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from pkmkit.machines.closed_form import MAX_ABS, RodClosedForm
from pkmkit.machines.lazy_records import read_only
from pkmkit.machines.results import Singularity
from pkmkit.machines.velocity import NEAR_PARALLEL, LazyJacobians, VelocityEvaluation
from pkmkit.model.rods import CRANK, SLIDE
from pkmkit.numerics import jit

_SERIAL = int(Singularity.SERIAL)
_PARALLEL = int(Singularity.PARALLEL)
_NAN = float("nan")
_sqrt, _cos, _sin = math.sqrt, math.cos, math.sin
# NumPy's arccos and hypot, not math's: the batch path's bits (they differ in the last place
# for about one argument in ten, resp. one in two hundred, on this machine)
_arccos, _hypot = np.arccos, np.hypot
_float64, _int64 = np.float64, np.int64


class _Unusual(Exception):
    """A case the batch path treats specially: hand the pose to it."""


class _AtTolerance(_Unusual):
    """A singularity measure within :data:`FLAG_BAND` of ``tol``: the general path's answer."""


#: What makes a one-pose field hand its pose to the batch path.
_HANDED_OVER = (_Unusual, ZeroDivisionError, OverflowError, ValueError)

#: A measure within this (relative) of ``tol``: its singularity flag is decided by its last
#: bits, which the batch path rounds otherwise (an ulp or a few; 8 of 250 flags at ``tol``
#: equal to the measure differed on the Delta), so the flags, J and what follows them are the
#: batch path's (``native/velocity.c`` PK_FLAG_BAND, ``pose_velocity.c`` the same for the
#: full-pose machines).
FLAG_BAND = 1e-9


def in_band(measure: float, tol: float) -> bool:
    """Whether ``measure`` lies within :data:`FLAG_BAND` (relative) of ``tol``."""
    return abs(measure - tol) <= FLAG_BAND * tol


def _legs(closed: RodClosedForm) -> tuple:
    """Per-leg constants as Python floats, computed once per machine: ``(kind, terms)`` with
    terms ``(centre0 (3), axis (3))`` for a slide, ``(tip0 (3), e1 (3), e2 (3), radius,
    platform (3))`` for a crank (``tip0`` the centre of the arm's circle, ``e1``, ``e2`` the arm
    directions, ``radius`` its length, ``platform`` the rod's platform joint: the terms of
    :meth:`RodClosedForm.centres`, in its order of operations), ``(centre0 (3), length)`` for a
    strut; a plane machine's vectors padded with 0."""
    cached = closed.__dict__.get("_one_velocity")
    if cached is None:
        m = closed.model
        dims = m.dims

        def padded(v: np.ndarray) -> list[float]:
            return [*np.asarray(v, dtype=float)[:dims].tolist(), 0.0, 0.0][:3]

        legs = []
        for i in range(m.n_legs):
            kind = int(m.leg_kind[i])
            if kind == SLIDE:
                terms = (*padded(closed.centre0[i]), *padded(closed.axis[i]))
            elif kind == CRANK:
                terms = (*padded(m.leg_pivot[i] + closed.crank_offset[i] * m.leg_axis[i]),
                         *padded(closed.crank_e1[i]), *padded(closed.crank_e2[i]),
                         float(closed.crank_radius[i]), *padded(m.leg_platform[i]))
            else:
                terms = (*padded(closed.centre0[i]), float(m.leg_length[i]))
            legs.append((kind, terms))
        cached = tuple(legs)
        object.__setattr__(closed, "_one_velocity", cached)
    return cached


def native_legs(closed: RodClosedForm) -> bytes:
    """:func:`_legs` as the C kernel ``rod_velocity`` takes them: ``n × 14`` float64 (the
    kind, then the terms, zero-padded), computed once per machine."""
    cached = closed.__dict__.get("_one_velocity_native")
    if cached is None:
        table = np.zeros((closed.model.n_legs, 14))
        for i, (kind, terms) in enumerate(_legs(closed)):
            table[i, 0] = kind
            table[i, 1:1 + len(terms)] = terms
        cached = table.tobytes()
        object.__setattr__(closed, "_one_velocity_native", cached)
    return cached


def rows(closed: RodClosedForm, x: Sequence[float], q: Sequence[float]
         ) -> tuple[list[float], list[float]]:
    """A row-major (``n × dims`` floats: rows ``p − c_i``) and the diagonal of B of one pose,
    as :meth:`RodClosedForm.jacobians_t` computes them (the same operations, the same bits)."""
    plane = len(x) == 2
    x0, x1 = x[0], x[1]
    x2 = 0.0 if plane else x[2]
    a: list[float] = []
    b: list[float] = []
    for (kind, terms), qi in zip(_legs(closed), q, strict=True):
        if kind == SLIDE:
            c0, c1, c2, u0, u1, u2 = terms
            a0, a1, a2 = x0 - (c0 + qi * u0), x1 - (c1 + qi * u1), x2 - (c2 + qi * u2)
            bi = 0.0  # the batch path adds a term per non-zero axis component
            if u0:
                bi += a0 * u0
            if u1:
                bi += a1 * u1
            if u2:
                bi += a2 * u2
        elif kind == CRANK:  # centres(): tip0 + r (cos e1 + sin e2) − b; rate r (cos e2 − sin e1)
            t0, t1, t2, e0, e1, e2, f0, f1, f2, radius, p0, p1, p2 = terms
            cos, sin = _cos(qi), _sin(qi)
            a0 = x0 - ((t0 + radius * (cos * e0 + sin * f0)) - p0)
            a1 = x1 - ((t1 + radius * (cos * e1 + sin * f1)) - p1)
            a2 = x2 - ((t2 + radius * (cos * e2 + sin * f2)) - p2)
            bi = (0.0 + a0 * (radius * (cos * f0 - sin * e0))
                  + a1 * (radius * (cos * f1 - sin * e1)) + a2 * (radius * (cos * f2 - sin * e2)))
        else:  # strut
            c0, c1, c2, length = terms
            a0, a1, a2 = x0 - c0, x1 - c1, x2 - c2
            bi = length + qi
        if plane:
            a += (a0, a1)
        else:
            a += (a0, a1, a2)
        b.append(bi)
    return a, b


def _singular_values3(m00: float, m01: float, m02: float, m10: float, m11: float, m12: float,
                      m20: float, m21: float, m22: float) -> list[float]:
    """:func:`pkmkit.numerics.small.singular_values` of one finite 3×3 matrix, in scalars."""
    g00 = m00 * m00 + m10 * m10 + m20 * m20
    g11 = m01 * m01 + m11 * m11 + m21 * m21
    g22 = m02 * m02 + m12 * m12 + m22 * m22
    g01 = m00 * m01 + m10 * m11 + m20 * m21
    g02 = m00 * m02 + m10 * m12 + m20 * m22
    g12 = m01 * m02 + m11 * m12 + m21 * m22
    mean = (g00 + g11 + g22) / 3.0
    d0, d1, d2 = g00 - mean, g11 - mean, g22 - mean
    spread = _sqrt((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * (g01 * g01 + g02 * g02 + g12 * g12))
                   / 6.0)
    scale = 1.0 / spread if spread > 0 else 0.0
    s00, s11, s22 = d0 * scale, d1 * scale, d2 * scale
    s01, s02, s12 = g01 * scale, g02 * scale, g12 * scale
    sym_det = (s00 * (s11 * s22 - s12 * s12) - s01 * (s01 * s22 - s12 * s02)
               + s02 * (s01 * s12 - s11 * s02))
    half_det = min(max(0.5 * sym_det, -1.0), 1.0)
    lam1 = mean + 2.0 * spread * _cos(_arccos(half_det) / 3.0)
    s1 = _sqrt(lam1) if lam1 > 0 else 0.0
    c00, c01, c02 = m11 * m22 - m12 * m21, m12 * m20 - m10 * m22, m10 * m21 - m11 * m20
    c10, c11, c12 = m21 * m02 - m22 * m01, m22 * m00 - m20 * m02, m20 * m01 - m21 * m00
    c20, c21, c22 = m01 * m12 - m02 * m11, m02 * m10 - m00 * m12, m00 * m11 - m01 * m10
    d = abs(m00 * c00 + m01 * c01 + m02 * c02)
    e2 = (c00 * c00 + c01 * c01 + c02 * c02 + c10 * c10 + c11 * c11 + c12 * c12
          + c20 * c20 + c21 * c21 + c22 * c22)
    pair = d / s1 if s1 > 0 else 0.0
    rest = (e2 - pair * pair) / lam1 if lam1 > 0 else 0.0
    if spread > 0 and (abs(half_det) > 1.0 - 1e-6 or rest - 2 * pair < 1e-6 * rest):
        # nearly equal singular values: LAPACK, as the batch path (the same bits)
        return np.linalg.svd(np.array([[m00, m01, m02], [m10, m11, m12], [m20, m21, m22]]),
                             compute_uv=False).tolist()
    s2 = 0.5 * (_sqrt(max(rest + 2 * pair, 0.0)) + _sqrt(max(rest - 2 * pair, 0.0)))
    s3 = pair / s2 if s2 > 0 else 0.0
    if s2 > s1:
        s2 = s1
    return [s1, s2, s3 if s3 < s2 else s2]


def singular_values(m: Sequence[float]) -> list[float]:
    """Singular values, decreasing, of one finite 2×2 or 3×3 matrix given row-major (4 or 9
    floats): the closed forms of :func:`pkmkit.numerics.small.singular_values` in scalars,
    the same bits; where those hand the matrix to LAPACK (nearly equal singular values),
    LAPACK too."""
    if len(m) == 4:
        a, b, c, d = m
        s1 = 0.5 * float(_hypot(a + d, c - b) + _hypot(a - d, b + c))
        return [s1, abs(a * d - b * c) / s1 if s1 > 0 else 0.0]
    return _singular_values3(*m)


def _surely_above(det_a: float, lengths: list[float], t: float) -> bool:
    """Whether σ_min/σ_max of A with unit rows is ≥ ``t`` (with margin), from its lower bound
    |det U| / 2 (rows of unit length: σ1²σ2 ≤ 2 in 3-D, σ1² ≤ 2 in the plane). The factor 2
    and the 1e-12 absorb the rounding of det A and of the singular values (relative 1e-10 at
    worst, where the closed forms are closest to their LAPACK switch)."""
    product = lengths[0] * lengths[1] * (lengths[2] if len(lengths) == 3 else 1.0)
    return abs(det_a) > (4.0 * t + 2e-12) * product


class OnePoseVelocity:
    """The velocity model of one pose, each piece computed when a field first needs it.

    Args:
        closed: the machine's closed forms. x: the pose (``dims`` floats, m). q: its actuator
            coordinates (``n`` floats). tol: threshold of the singularity measures.
    """

    # the pieces, computed when first needed (class-level None: a record sets only its inputs)
    _ab = _adj = _lengths = _parallel = _flags = _j = _sv = _batch = None
    #: a measure at the tolerance (in_band): the batch path's q too (its ik rounds otherwise)
    _general_q = False
    #: the C kernel's state (:meth:`native`): None not yet asked, False no extension
    _state: Any = None
    _native_field: Any = None

    def __init__(self, closed: RodClosedForm, x: list[float], q: list[float], tol: float):
        self.closed, self.x, self.q, self.tol = closed, x, q, tol

    def __getattr__(self, name: str) -> Any:
        """``x`` and ``q`` (lists of floats) of an evaluation made from a ``rod_jacobian_one``
        state (:func:`native_record`), read from it when the Python pieces first need them."""
        state = self.__dict__.get("_state")
        if name not in ("x", "q") or not state:
            raise AttributeError(name)
        value = self._native_field(state, 13 if name == "x" else 12).tolist()
        self.__dict__[name] = value
        return value

    def field(self, name: str):
        """The value of field ``name`` of the single-pose :class:`Jacobians`."""
        if self._batch is None:
            try:
                return _BUILD[name](self)
            except _AtTolerance:
                self._general_q = True
            except _HANDED_OVER:
                pass
        return self.from_batch(name)

    def answer(self, name: str, code: int | None):
        """Field ``name``: from the C state (``code`` its ``rod_field`` code, None where the C
        kernel has no such field), else the Python pieces, else the batch path's row."""
        value = None
        if code is not None and self._batch is None:
            state = self._state
            if state is None:
                state = self.native()
            if state:  # None from the kernel: the Python pieces below decide
                value = self._native_field(state, code)
        if value is None:
            value = self.field(name)
        return value

    def from_batch(self, name: str):
        """Field ``name`` of the batch path's velocity model of this pose."""
        if self._batch is None:
            x, q = np.array([self.x]), np.array([self.q])
            if self._general_q:  # the general path's: its q from the batch inverse model
                q = np.ascontiguousarray(self.closed.inverse(x, self.closed.model.leg_branch))
            self._batch = LazyJacobians(VelocityEvaluation(self.closed, x, q, self.tol), True)
        return getattr(self._batch, name)

    def native(self) -> Any:
        """The state of the C twin ``pkmkit.native.kernels.rod_velocity`` of this pose (every
        field it can answer, the batch row's bits), or False without the extension (not
        built, ``PKMKIT_NATIVE=0``, ``PKMKIT_COMPILED=0``): the Python pieces then answer."""
        native = jit.native_kernels_now()
        rod_velocity = getattr(native, "rod_velocity", None)
        if rod_velocity is None:
            state = False
        else:
            state = rod_velocity(native_legs(self.closed), self.x, self.q, self.tol,
                                 NEAR_PARALLEL)
            self._native_field = native.rod_field
        self._state = state
        return state

    # ------------------------------------------------------------------ pieces
    def ab(self) -> tuple[list[float], list[float]]:
        """A row-major and diag B (:func:`rows`); not finite: the batch path."""
        ab = self._ab
        if ab is None:
            a, b = rows(self.closed, self.x, self.q)
            if not -math.inf < sum(a) + sum(b) < math.inf:  # NaN, ±inf (or a sum overflowing)
                raise _Unusual
            ab = self._ab = (a, b)
        return ab

    def adj(self) -> tuple[list[float], float]:
        """The cofactors ``C`` of A (row-major) and det A, as :mod:`pkmkit.numerics.small`."""
        adj = self._adj
        if adj is None:
            a = self.ab()[0]
            if len(a) == 4:
                cof = [a[3], -a[2], -a[1], a[0]]
                det_a = a[0] * a[3] - a[1] * a[2]
            else:
                a00, a01, a02, a10, a11, a12, a20, a21, a22 = a
                cof = [a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20,
                       a21 * a02 - a22 * a01, a22 * a00 - a20 * a02, a20 * a01 - a21 * a00,
                       a01 * a12 - a02 * a11, a02 * a10 - a00 * a12, a00 * a11 - a01 * a10]
                det_a = a00 * cof[0] + a01 * cof[1] + a02 * cof[2]
            adj = self._adj = (cof, det_a)
        return adj

    def lengths(self) -> list[float]:
        """|a_i| (sums in the batch path's order)."""
        lengths = self._lengths
        if lengths is None:
            a = self.ab()[0]
            if len(a) == 4:
                a00, a01, a10, a11 = a
                lengths = [_sqrt(a00 * a00 + a01 * a01), _sqrt(a10 * a10 + a11 * a11)]
            else:
                a00, a01, a02, a10, a11, a12, a20, a21, a22 = a
                lengths = [_sqrt(a00 * a00 + a01 * a01 + a02 * a02),
                           _sqrt(a10 * a10 + a11 * a11 + a12 * a12),
                           _sqrt(a20 * a20 + a21 * a21 + a22 * a22)]
            if not (lengths[0] > 0 and lengths[1] > 0 and lengths[-1] > 0):
                raise _Unusual  # a zero row: NaN measures in the batch path
            self._lengths = lengths
        return lengths

    def parallel(self) -> float:
        """σ_min/σ_max of A with unit rows (one singular-value computation)."""
        parallel = self._parallel
        if parallel is None:
            a, lengths = self.ab()[0], self.lengths()
            n = len(lengths)
            unit = [a[k] / lengths[k // n] for k in range(n * n)]
            sv = singular_values(unit)
            parallel = self._parallel = sv[-1] / sv[0]
        return parallel

    def at_parallel(self) -> bool:
        """Whether the batch path flags a parallel singularity (measure < tol or det A = 0)."""
        det_a = self.adj()[1]
        if _surely_above(det_a, self.lengths(), self.tol):
            return False
        parallel = self.parallel()
        if det_a != 0.0 and in_band(parallel, self.tol):
            raise _AtTolerance
        return parallel < self.tol or det_a == 0.0

    def serial(self) -> float:
        b, lengths = self.ab()[1], self.lengths()
        return min([abs(bi) / li for bi, li in zip(b, lengths, strict=True)])

    def j(self) -> list[float] | None:
        """J = adj(A) B / det A row-major, or None at a parallel singularity."""
        j = self._j
        if j is None:
            if self.at_parallel():
                return None
            cof, det_a = self.adj()
            inv_det = 1.0 / det_a
            if not -math.inf < inv_det < math.inf:
                raise _Unusual
            b = self.ab()[1]
            if len(b) == 2:
                s0, s1 = b[0] * inv_det, b[1] * inv_det
                j = [cof[0] * s0, cof[2] * s1, cof[1] * s0, cof[3] * s1]
            else:
                s0, s1, s2 = b[0] * inv_det, b[1] * inv_det, b[2] * inv_det
                c00, c01, c02, c10, c11, c12, c20, c21, c22 = cof
                j = [c00 * s0, c10 * s1, c20 * s2, c01 * s0, c11 * s1, c21 * s2,
                     c02 * s0, c12 * s1, c22 * s2]
            for v in j:
                if not -math.inf < v < math.inf:
                    raise _Unusual
            self._j = j
        return j

    def sv(self) -> list[float] | None:
        """Singular values of J (from J⁻¹ near a parallel singularity, as the batch path), or
        None at a parallel singularity."""
        sv = self._sv
        if sv is None:
            j = self.j()
            if j is None:
                return None
            det_a = self.adj()[1]
            if not _surely_above(det_a, self.lengths(), NEAR_PARALLEL) and (
                    self.parallel() < NEAR_PARALLEL and self.parallel() < self.serial()):
                a, b = self.ab()
                n = len(b)
                inverse = singular_values([a[k] / b[k // n] for k in range(n * n)])
                sv = [1.0 / s for s in reversed(inverse)]
            else:
                sv = singular_values(j)
            self._sv = sv
        return sv

    def flags(self) -> int:
        flags = self._flags
        if flags is None:
            serial = self.serial()
            if in_band(serial, self.tol):
                raise _AtTolerance
            flags = _SERIAL if serial < self.tol else 0
            if self.at_parallel():
                flags |= _PARALLEL
            self._flags = flags
        return flags


def _square(values: list[float]) -> np.ndarray:
    n = 3 if len(values) == 9 else 2
    return np.array(values).reshape(n, n)


def _diagonal(b: list[float]) -> np.ndarray:
    out = np.zeros((len(b), len(b)))
    out.flat[:: len(b) + 1] = b
    return out


def _j(e: OnePoseVelocity) -> np.ndarray:
    j = e.j()
    n = len(e.q)
    return np.full((n, n), _NAN) if j is None else _square(j)


def _j_inv(e: OnePoseVelocity) -> np.ndarray:
    a, b = e.ab()
    n = len(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _square(a) / np.array(b)[:, None] if 0.0 in b else _square(
            [a[k] / b[k // n] for k in range(n * n)])


def _singular_values(e: OnePoseVelocity) -> np.ndarray:
    sv = e.sv()
    return np.full(len(e.q), _NAN) if sv is None else np.array(sv)


def _condition(e: OnePoseVelocity) -> np.float64:
    sv = e.sv()
    if sv is None:
        return _float64(_NAN)
    return _float64(math.inf if sv[-1] == 0.0 else sv[0] / sv[-1])


def _det_b(e: OnePoseVelocity) -> np.float64:
    b = e.ab()[1]
    det_b = b[0] * b[1]
    return _float64(det_b * b[2] if len(b) == 3 else det_b)


def _mode(e: OnePoseVelocity) -> np.int64:
    det_a = e.adj()[1]
    return _int64((det_a > 0) - (det_a < 0))


_BUILD: dict[str, Callable[[OnePoseVelocity], Any]] = {
    "A": lambda e: _square(e.ab()[0]),
    "B": lambda e: _diagonal(e.ab()[1]),
    "J": _j,
    "J_inv": _j_inv,
    "singular_values": _singular_values,
    "condition": _condition,
    "det_A": lambda e: _float64(e.adj()[1]),
    "det_B": _det_b,
    "parallel_measure": lambda e: _float64(e.parallel()),
    "serial_measure": lambda e: _float64(e.serial()),
    "singularity": lambda e: _int64(e.flags()),
    "tolerance": lambda e: e.tol,
    "q": lambda e: np.array(e.q),
    "mode": _mode,
}


#: The codes of the fields the C kernel answers (``rod_field``).
_NATIVE_CODES = {name: code for code, name in enumerate(
    ("A", "B", "J", "J_inv", "singular_values", "condition", "det_A", "det_B",
     "parallel_measure", "serial_measure", "singularity", "mode", "q"))}


def _one_field(name: str) -> property:
    code = _NATIVE_CODES.get(name)

    def get(self):
        cache = self._cache
        if name in cache:  # computed, or given (dataclasses.replace): read-only once read
            value = cache[name] = read_only(cache[name])
            return value
        state = self._state  # a rod_jacobian_one state (native_record): one C call
        if state is not None and code is not None:
            value = self._field(state, code)
            if value is not None:
                if type(value) is np.ndarray:  # a new array of the C call's: frozen, no view
                    value.setflags(write=False)
                cache[name] = value
                return value
        value = cache[name] = read_only(self._evaluation.answer(name, code))
        return value

    return property(get, doc=f"``{name}`` of the single pose (computed when first read)")


class OnePoseJacobians(LazyJacobians):
    """The :class:`~pkmkit.machines.velocity.LazyJacobians` of one pose (fields without the
    batch axis), each field computed from an :class:`OnePoseVelocity` when first read. Built
    with every field (``dataclasses.replace``) it is a plain record. Made by
    :func:`native_record`, it reads its fields from a C state (``_state``, ``_field``) and makes
    its evaluation only when the Python pieces must answer a field."""

    _state: Any = None  # a rod_jacobian_one state and rod_field (native_record), else None
    _field: Any = None

    def __getattr__(self, name: str) -> Any:
        """The evaluation of a record made by :func:`native_record`, made when first needed."""
        attributes = self.__dict__
        state = attributes.get("_state")
        if name != "_evaluation" or state is None:
            raise AttributeError(name)
        evaluation = object.__new__(OnePoseVelocity)
        values = evaluation.__dict__
        values["closed"], values["tol"] = attributes["_closed"], attributes["_tol"]
        values["_state"], values["_native_field"] = state, attributes["_field"]
        attributes["_evaluation"] = evaluation
        return evaluation

    def __repr__(self) -> str:
        ev = self._evaluation
        if ev is None:
            return f"LazyJacobians(condition={self.condition!r})"
        return (f"LazyJacobians(1 pose, {len(ev.q)} actuators, tolerance {ev.tol:g}; "
                "fields computed when read)")


for _name in _BUILD:  # each field a property reading the record's cache, else the evaluation
    setattr(OnePoseJacobians, _name, _one_field(_name))


def _record(evaluation: OnePoseVelocity) -> OnePoseJacobians:
    """An :class:`OnePoseJacobians` without the generic constructor's work."""
    record = object.__new__(OnePoseJacobians)
    state = record.__dict__
    state["_evaluation"], state["_single"], state["_cache"] = evaluation, True, {}
    return record


def native_record(closed: RodClosedForm, state: bytearray, tol: float,
                  field: Callable[[bytearray, int], Any]) -> OnePoseJacobians:
    """The record of one pose from a ``rod_jacobian_one`` state (``native/rod_one.c``: the pose
    and its inverse model, within the strokes), ``field`` the extension's ``rod_field``: each
    field read is one C call computing what the state lacks for it (the module docstring), the
    Python pieces answer what it does not."""
    record = object.__new__(OnePoseJacobians)
    attributes = record.__dict__  # its evaluation made when needed (OnePoseJacobians.__getattr__)
    attributes["_state"], attributes["_field"], attributes["_cache"] = state, field, {}
    attributes["_closed"], attributes["_tol"], attributes["_single"] = closed, tol, True
    return record


def jacobian_one(closed: RodClosedForm, x: Any, tol: float, branches: Sequence[float],
                 within_strokes: Callable[[list[float]], bool]) -> OnePoseJacobians | None:
    """The velocity model of one plain pose ``x`` (``dims`` finite floats: a list, a tuple or a
    1-D float array) whose inverse model (working ``branches``) lies within the strokes, or
    None: the machine's batch path then answers (and raises what it raises).

    With the C extension (:func:`pkmkit.numerics.jit.native_kernels`) the inverse model of a
    list or tuple of floats is its C twin ``rod_inverse`` (the same bits), and the fields are
    read from ``rod_velocity`` (:meth:`OnePoseVelocity.native`)."""
    if isinstance(x, np.ndarray):
        if x.ndim != 1 or x.dtype.kind != "f":
            return None
        x = x.tolist()  # floats
    elif not isinstance(x, list | tuple):
        return None
    native = jit.native_kernels_now()
    rod_inverse = None if native is None else getattr(native, "rod_inverse", None)
    if rod_inverse is not None:
        q = rod_inverse(closed.single_legs_packed(branches), x, MAX_ABS)
        if q is not None:  # x: exact floats, every leg closes
            if not within_strokes(q):
                return None
            return _record(OnePoseVelocity(closed, list(x), q, tol))
    q = closed.inverse_one(x, branches)  # checks the entries are plain finite numbers
    if q is None or not within_strokes(q):
        return None
    return _record(OnePoseVelocity(closed, [float(v) for v in x], q, tol))
