"""The velocity model of one pose of a translational rod-leg machine in plain Python floats
(issue 22 §1).

:class:`OnePoseJacobians` is what :meth:`Machine.jacobian` returns for one plain pose: a
:class:`~pkmkit.machines.velocity.LazyJacobians` (same fields, same shapes and types as the
batch path's single row) whose fields come from :class:`OnePoseVelocity` — the formulas of
:func:`pkmkit.machines.velocity.velocity_chunk` and :mod:`pkmkit.numerics.small` written out in
scalars for one pose (n = dims = 2 or 3), computed when a field is first read. Whatever the
batch path treats specially is handed to it (a :class:`LazyJacobians` of one row, the same
numbers): a configuration near a parallel singularity where the batch path takes the singular
values from J⁻¹ (:data:`~pkmkit.machines.velocity.NEAR_PARALLEL`), nearly equal singular
values (LAPACK there), a zero rod, overflow.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from pkmkit.machines.closed_form import RodClosedForm
from pkmkit.machines.results import Singularity
from pkmkit.machines.velocity import NEAR_PARALLEL, LazyJacobians, VelocityEvaluation
from pkmkit.model.rods import CRANK, SLIDE
from pkmkit.numerics import jit

_SERIAL = int(Singularity.SERIAL)
_PARALLEL = int(Singularity.PARALLEL)
_NAN = float("nan")


class _Unusual(Exception):
    """A case the batch path treats specially: hand the pose to it."""


def _legs(closed: RodClosedForm) -> tuple:
    """Per-leg constants as Python floats, computed once per machine:
    ``(kind, centre0, axis, length, tip0, e1, e2, radius, platform)`` with ``tip0`` the
    centre of a crank arm's circle, ``e1``, ``e2`` the arm directions, ``radius`` its length and
    ``platform`` the rod's platform joint (the terms of :meth:`RodClosedForm.centres`, in its
    order of operations)."""
    cached = closed.__dict__.get("_one_velocity")
    if cached is None:
        m = closed.model
        dims = m.dims
        legs = []
        for i in range(m.n_legs):
            tip0 = (m.leg_pivot[i] + closed.crank_offset[i] * m.leg_axis[i])[:dims]
            legs.append((int(m.leg_kind[i]), tuple(closed.centre0[i].tolist()),
                         tuple(closed.axis[i].tolist()), float(m.leg_length[i]),
                         tuple(tip0.tolist()),
                         tuple(closed.crank_e1[i, :dims].tolist()),
                         tuple(closed.crank_e2[i, :dims].tolist()),
                         float(closed.crank_radius[i]),
                         tuple(m.leg_platform[i, :dims].tolist())))
        cached = tuple(legs)
        object.__setattr__(closed, "_one_velocity", cached)
    return cached


def _compiled_now(closed: RodClosedForm) -> bool:
    """Whether the compiled one-pose kernel runs: a spatial machine of three legs, in a
    process that has already imported Numba (a one-shot call does not pay its import), unless
    ``PKMKIT_COMPILED=0``."""
    return ("numba" in sys.modules and closed.model.dims == 3 and closed.model.n_legs == 3
            and jit.mode() != "0")


def _kernel_legs(closed: RodClosedForm) -> np.ndarray:
    """The legs ``(3, 21)`` of :mod:`pkmkit.machines.velocity_one_kernel`, built once."""
    cached = closed.__dict__.get("_one_velocity_kernel")
    if cached is None:
        kinds = {SLIDE: 0.0, CRANK: 2.0}
        cached = np.array([[kinds.get(kind, 1.0), *centre0, *axis, length, *tip0, *e1, *e2,
                            radius, *platform]
                           for kind, centre0, axis, length, tip0, e1, e2, radius, platform
                           in _legs(closed)])
        object.__setattr__(closed, "_one_velocity_kernel", cached)
    return cached


def rows(closed: RodClosedForm, x: Sequence[float], q: Sequence[float]
         ) -> tuple[list[list[float]], list[float]]:
    """A (rows ``p − c_i``) and the diagonal of B of one pose, as
    :meth:`RodClosedForm.jacobians_t` computes them."""
    a, b = [], []
    for (kind, centre0, axis, length, tip0, e1, e2, radius, platform), qi in zip(
            _legs(closed), q, strict=True):
        if kind == SLIDE:
            row = [xk - (ck + qi * uk) for xk, ck, uk in zip(x, centre0, axis, strict=True)]
            bi = 0.0
            for ak, uk in zip(row, axis, strict=True):
                if uk:
                    bi += ak * uk
        elif kind == CRANK:
            cos, sin = math.cos(qi), math.sin(qi)
            # centres(): pivot + h w + r (cos q e1 + sin q e2) − b; rates r (cos q e2 − sin q e1)
            row = [xk - ((tk + radius * (cos * f1 + sin * f2)) - bk)
                   for xk, tk, f1, f2, bk in zip(x, tip0, e1, e2, platform, strict=True)]
            bi = 0.0
            for ak, f1, f2 in zip(row, e1, e2, strict=True):
                bi += ak * (radius * (cos * f2 - sin * f1))
        else:  # strut
            row = [xk - ck for xk, ck in zip(x, centre0, strict=True)]
            bi = length + qi
        a.append(row)
        b.append(bi)
    return a, b


def _cofactors(m: list[list[float]]) -> list[list[float]]:
    if len(m) == 2:
        return [[m[1][1], -m[1][0]], [-m[0][1], m[0][0]]]
    out = [[0.0] * 3 for _ in range(3)]
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            out[i][j] = m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
    return out


def _det(m: list[list[float]], c: list[list[float]]) -> float:
    if len(m) == 2:
        return m[0][0] * m[1][1] - m[0][1] * m[1][0]
    return m[0][0] * c[0][0] + m[0][1] * c[0][1] + m[0][2] * c[0][2]


def singular_values(m: list[list[float]]) -> list[float]:
    """Singular values, decreasing, of one finite 2×2 or 3×3 matrix: the closed forms of
    :func:`pkmkit.numerics.small.singular_values` in scalars; where those hand the matrix to
    LAPACK (nearly equal singular values), LAPACK too."""
    if len(m) == 2:
        (a, b), (c, d) = m
        s1 = 0.5 * (math.hypot(a + d, c - b) + math.hypot(a - d, b + c))
        return [s1, abs(a * d - b * c) / s1 if s1 > 0 else 0.0]
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = m
    g00 = m00 * m00 + m10 * m10 + m20 * m20
    g11 = m01 * m01 + m11 * m11 + m21 * m21
    g22 = m02 * m02 + m12 * m12 + m22 * m22
    g01 = m00 * m01 + m10 * m11 + m20 * m21
    g02 = m00 * m02 + m10 * m12 + m20 * m22
    g12 = m01 * m02 + m11 * m12 + m21 * m22
    mean = (g00 + g11 + g22) / 3.0
    spread = math.sqrt(((g00 - mean) ** 2 + (g11 - mean) ** 2 + (g22 - mean) ** 2
                        + 2.0 * (g01 * g01 + g02 * g02 + g12 * g12)) / 6.0)
    scale = 1.0 / spread if spread > 0 else 0.0
    s00, s11, s22 = (g00 - mean) * scale, (g11 - mean) * scale, (g22 - mean) * scale
    s01, s02, s12 = g01 * scale, g02 * scale, g12 * scale
    sym_det = (s00 * (s11 * s22 - s12 * s12) - s01 * (s01 * s22 - s12 * s02)
               + s02 * (s01 * s12 - s11 * s02))
    half_det = min(max(0.5 * sym_det, -1.0), 1.0)
    lam1 = mean + 2.0 * spread * math.cos(math.acos(half_det) / 3.0)
    s1 = math.sqrt(lam1) if lam1 > 0 else 0.0
    c00, c01, c02 = m11 * m22 - m12 * m21, m12 * m20 - m10 * m22, m10 * m21 - m11 * m20
    c10, c11, c12 = m21 * m02 - m22 * m01, m22 * m00 - m20 * m02, m20 * m01 - m21 * m00
    c20, c21, c22 = m01 * m12 - m02 * m11, m02 * m10 - m00 * m12, m00 * m11 - m01 * m10
    d = abs(m00 * c00 + m01 * c01 + m02 * c02)
    e2 = (c00 * c00 + c01 * c01 + c02 * c02 + c10 * c10 + c11 * c11 + c12 * c12
          + c20 * c20 + c21 * c21 + c22 * c22)
    pair = d / s1 if s1 > 0 else 0.0
    rest = (e2 - pair * pair) / lam1 if lam1 > 0 else 0.0
    if spread > 0 and (abs(half_det) > 1.0 - 1e-6 or rest - 2 * pair < 1e-6 * rest):
        return np.linalg.svd(np.array(m), compute_uv=False).tolist()
    s2 = 0.5 * (math.sqrt(max(rest + 2 * pair, 0.0)) + math.sqrt(max(rest - 2 * pair, 0.0)))
    s3 = pair / s2 if s2 > 0 else 0.0
    if s2 > s1:
        s2 = s1
    return [s1, s2, s3 if s3 < s2 else s2]


class OnePoseVelocity:
    """The velocity model of one pose, evaluated when a field is first read.

    Args:
        closed: the machine's closed forms. x: the pose (``dims`` floats, m). q: its actuator
            coordinates (``n`` floats). tol: threshold of the singularity measures.
    """

    __slots__ = ("_fields", "closed", "q", "tol", "x")

    def __init__(self, closed: RodClosedForm, x: list[float], q: list[float], tol: float):
        self.closed, self.x, self.q, self.tol = closed, x, q, tol
        self._fields: dict | None = None

    def field(self, name: str):
        """The value of field ``name`` of the single-pose :class:`Jacobians`."""
        fields = self._fields
        if fields is None:
            fields = self._compiled() if _compiled_now(self.closed) else None
            if fields is None:
                try:
                    fields = self._compute()
                except (_Unusual, ZeroDivisionError, OverflowError, ValueError):
                    fields = {"batch": self.batch()}
            self._fields = fields
        batch = fields.get("batch")
        if batch is not None:
            return getattr(batch, name)
        return _BUILD[name](fields)

    def batch(self) -> LazyJacobians:
        """The batch path's velocity model of this pose (one row, single)."""
        x = np.array([self.x])
        q = np.array([self.q])
        return LazyJacobians(VelocityEvaluation(self.closed, x, q, self.tol), True)

    def _compiled(self) -> dict | None:
        """The fields by :func:`pkmkit.machines.velocity_one_kernel.velocity_one3`, or None
        where it leaves the pose to :meth:`_compute`."""
        from pkmkit.machines import velocity_one_kernel

        out = np.empty(30)
        if velocity_one_kernel.velocity_one3(np.array(self.x), np.array(self.q),
                                             _kernel_legs(self.closed), self.tol, out):
            return None
        condition, det_a, det_b, parallel, serial, flags = out[24:30].tolist()
        return {"a": out[0:9].reshape(3, 3), "b": out[9:12], "j": out[12:21].reshape(3, 3),
                "sv": out[21:24], "condition": condition, "det_A": det_a, "det_B": det_b,
                "parallel": parallel, "serial": serial, "flags": int(flags), "q": self.q,
                "tol": self.tol}

    def _compute(self) -> dict:
        a, b = rows(self.closed, self.x, self.q)
        n = len(b)
        if n == 3:
            return self._compute3(a, b)
        for v in (*b, *a[0], *a[1], *a[-1]):
            if not -math.inf < v < math.inf:
                raise _Unusual
        cof = _cofactors(a)
        det_a = _det(a, cof)
        lengths = [math.sqrt(r[0] * r[0] + r[1] * r[1] + (r[2] * r[2] if n == 3 else 0.0))
                   for r in a]
        sv_unit = singular_values([[v / length for v in r] for r, length in
                                   zip(a, lengths, strict=True)])
        parallel = sv_unit[-1] / sv_unit[0]
        serial = min([abs(bi) / length for bi, length in zip(b, lengths, strict=True)])
        inv_det = 1.0 / det_a if det_a != 0.0 else math.inf
        if -math.inf < inv_det < math.inf:
            j = [[cof[c][r] * (b[c] * inv_det) for c in range(n)] for r in range(n)]
            for v in (*j[0], *j[1], *j[-1]):
                if not -math.inf < v < math.inf:
                    raise _Unusual
            if parallel < NEAR_PARALLEL and parallel < serial:
                raise _Unusual  # the batch path takes these singular values from J⁻¹
            sv = singular_values(j)
        else:
            j = [[_NAN] * n for _ in range(n)]
            sv = [_NAN] * n
        flags = _SERIAL if serial < self.tol else 0
        if parallel < self.tol or det_a == 0.0:
            flags |= _PARALLEL
            j = [[_NAN] * n for _ in range(n)]
            sv = [_NAN] * n
            condition = _NAN
        else:
            condition = math.inf if sv[-1] == 0.0 else sv[0] / sv[-1]
        det_b = b[0]
        for bi in b[1:]:
            det_b *= bi
        return {"a": a, "b": b, "j": j, "sv": sv, "condition": condition, "det_A": det_a,
                "det_B": det_b, "parallel": parallel, "serial": serial, "flags": flags,
                "q": self.q, "tol": self.tol}


    def _compute3(self, a: list[list[float]], b: list[float]) -> dict:
        """:meth:`_compute` written out for 3 × 3 matrices (the same operations)."""
        (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a
        b0, b1, b2 = b
        for v in (a00, a01, a02, a10, a11, a12, a20, a21, a22, b0, b1, b2):
            if not -math.inf < v < math.inf:
                raise _Unusual
        c00, c01, c02 = a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20
        c10, c11, c12 = a21 * a02 - a22 * a01, a22 * a00 - a20 * a02, a20 * a01 - a21 * a00
        c20, c21, c22 = a01 * a12 - a02 * a11, a02 * a10 - a00 * a12, a00 * a11 - a01 * a10
        det_a = a00 * c00 + a01 * c01 + a02 * c02
        l0 = math.sqrt(a00 * a00 + a01 * a01 + a02 * a02)
        l1 = math.sqrt(a10 * a10 + a11 * a11 + a12 * a12)
        l2 = math.sqrt(a20 * a20 + a21 * a21 + a22 * a22)
        sv_unit = singular_values([[a00 / l0, a01 / l0, a02 / l0], [a10 / l1, a11 / l1, a12 / l1],
                                   [a20 / l2, a21 / l2, a22 / l2]])
        parallel = sv_unit[-1] / sv_unit[0]
        serial = min(abs(b0) / l0, abs(b1) / l1, abs(b2) / l2)
        tol = self.tol
        flags = _SERIAL if serial < tol else 0
        inv_det = 1.0 / det_a if det_a != 0.0 else math.inf
        if parallel < tol or det_a == 0.0:
            flags |= _PARALLEL
            j = _NAN3
            sv = [_NAN] * 3
            condition = _NAN
        elif -math.inf < inv_det < math.inf:
            s0, s1, s2 = b0 * inv_det, b1 * inv_det, b2 * inv_det
            j = [[c00 * s0, c10 * s1, c20 * s2], [c01 * s0, c11 * s1, c21 * s2],
                 [c02 * s0, c12 * s1, c22 * s2]]
            for row in j:
                for v in row:
                    if not -math.inf < v < math.inf:
                        raise _Unusual
            if parallel < NEAR_PARALLEL and parallel < serial:
                raise _Unusual  # the batch path takes these singular values from J⁻¹
            sv = singular_values(j)
            condition = math.inf if sv[-1] == 0.0 else sv[0] / sv[-1]
        else:
            raise _Unusual
        return {"a": a, "b": b, "j": j, "sv": sv, "condition": condition, "det_A": det_a,
                "det_B": b0 * b1 * b2, "parallel": parallel, "serial": serial,
                "flags": flags, "q": self.q, "tol": tol}


_NAN3 = [[_NAN] * 3 for _ in range(3)]


def _diagonal(b: list[float]) -> np.ndarray:
    out = np.zeros((len(b), len(b)))
    out.flat[:: len(b) + 1] = b
    return out


def _j_inv(f: dict) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.array(f["a"]) / np.array(f["b"])[:, None]


_BUILD = {
    "A": lambda f: np.array(f["a"]),
    "B": lambda f: _diagonal(f["b"]),
    "J": lambda f: np.array(f["j"]),
    "J_inv": _j_inv,
    "singular_values": lambda f: np.array(f["sv"]),
    "condition": lambda f: np.float64(f["condition"]),
    "det_A": lambda f: np.float64(f["det_A"]),
    "det_B": lambda f: np.float64(f["det_B"]),
    "parallel_measure": lambda f: np.float64(f["parallel"]),
    "serial_measure": lambda f: np.float64(f["serial"]),
    "singularity": lambda f: np.int64(f["flags"]),
    "tolerance": lambda f: f["tol"],
    "q": lambda f: np.array(f["q"]),
    "mode": lambda f: np.int64((f["det_A"] > 0) - (f["det_A"] < 0)),
}


class OnePoseJacobians(LazyJacobians):
    """The :class:`~pkmkit.machines.velocity.LazyJacobians` of one pose (fields without the
    batch axis), its fields built from a :class:`OnePoseVelocity` when first read."""

    def _get(self, name: str, compute):
        cache = self._cache
        if name not in cache:
            evaluation = self._evaluation
            if evaluation is None:  # built by dataclasses.replace: every field given
                return super()._get(name, compute)
            cache[name] = evaluation.field(name)
        return cache[name]

    def __repr__(self) -> str:
        ev = self._evaluation
        if ev is None:
            return f"LazyJacobians(condition={self.condition!r})"
        return (f"LazyJacobians(1 pose, {len(ev.q)} actuators, tolerance {ev.tol:g}; "
                "fields computed when read)")


def jacobian_one(closed: RodClosedForm, x: Any, tol: float, branches: Sequence[float],
                 within_strokes: Callable[[list[float]], bool]) -> OnePoseJacobians | None:
    """The velocity model of one plain pose ``x`` (``dims`` finite floats: a list, a tuple or a
    1-D float array) whose inverse model (working ``branches``) lies within the strokes, or
    None: the machine's batch path then answers (and raises what it raises)."""
    if isinstance(x, np.ndarray):
        if x.ndim != 1 or x.dtype.kind != "f":
            return None
        x = x.tolist()
    elif not isinstance(x, list | tuple):
        return None
    q = closed.inverse_one(x, branches)
    if q is None or not within_strokes(q):
        return None
    return OnePoseJacobians(OnePoseVelocity(closed, [float(v) for v in x], q, tol), True)
