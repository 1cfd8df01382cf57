"""Six rod equations of a 6-DOF platform in Study (dual-quaternion) coordinates.

A rigid displacement ``x ↦ R x + p`` is the point ``(e, g) ∈ P⁷`` with ``e`` the rotation
quaternion (any non-zero scale) and ``g = ½ p e`` (quaternion product, ``p`` a pure quaternion).
Such points satisfy the **Study quadric** ``e·g = 0``; conversely ``R x = e x ē / (e·e)`` and
``p = 2 g ē / (e·e)``. ``(e, g)`` and ``(λe, λg)`` are the same displacement, so each real pose
is one point of ``P⁷`` (no ± quaternion doubling).

Multiplying the squared rod equation ``|p + R b_j − a_j|² − ℓ_j² = 0`` by ``e·e`` gives a
quadric in ``(e, g)`` (a_j, b_j pure quaternions)::

    f_j = 4 g·g + 4 g·(e b_j − a_j e) − 2 (a_j e)·(e b_j) + d_j e·e,
    d_j = |a_j|² + |b_j|² − ℓ_j².

All six share the term ``4 g·g``. With the Study quadric and one linear *patch* ``v·x = 1``
(``x = (e, g)``, ``v`` a fixed random complex vector, which keeps paths bounded when the
translation diverges) they form a square system of 8 equations in 8 unknowns whose generic
number of finite solutions is 40 (Raghavan 1993; Wampler 1996; Husty 1996); the displacements
at infinity are ``e = 0``.

Gradients (``ā = −a`` for a pure quaternion)::

    ∂f_j/∂e = 4 (a_j g − g b_j) + 4 (a_j e) b_j + 2 d_j e,     ∂f_j/∂g = 8 g + 4 (e b_j − a_j e).

Parameter homotopy: the parameters ``(a, b, d)`` move on the straight line
``π(t) = π_target + t (π_start − π_target)``, t from 1 (start) to 0 (target). Arrays here keep
the batch (paths) axis *last*, quaternions on the first axis, scalar part first.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Number of unknowns (e, g) and of equations (six rods, Study quadric, patch).
N_VARS = 8


def mul_pure_left(v: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Quaternion product ``v q`` of pure quaternions ``v (3, ...)`` and ``q (4, ...)``."""
    w = -(v[0] * q[1] + v[1] * q[2] + v[2] * q[3])
    x = v[0] * q[0] + v[1] * q[3] - v[2] * q[2]
    y = v[1] * q[0] + v[2] * q[1] - v[0] * q[3]
    z = v[2] * q[0] + v[0] * q[2] - v[1] * q[1]
    return np.stack([w, x, y, z])


def mul_pure_right(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Quaternion product ``q v`` of ``q (4, ...)`` and pure quaternions ``v (3, ...)``."""
    w = -(q[1] * v[0] + q[2] * v[1] + q[3] * v[2])
    x = q[0] * v[0] + q[2] * v[2] - q[3] * v[1]
    y = q[0] * v[1] + q[3] * v[0] - q[1] * v[2]
    z = q[0] * v[2] + q[1] * v[1] - q[2] * v[0]
    return np.stack([w, x, y, z])


def pose_to_study(position: np.ndarray, quaternion: np.ndarray) -> np.ndarray:
    """Study coordinates ``(P, 8)`` of positions ``(P, 3)`` and quaternions ``(P, 4)``
    (scalar first, any scale; complex allowed)."""
    e = np.asarray(quaternion).T
    g = 0.5 * mul_pure_left(np.asarray(position).T, e)
    return np.concatenate([e, g]).T


def study_to_pose(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``(P, 3)`` and unit quaternions ``(P, 4)`` (scalar first) of real Study points
    ``x (P, 8)``; the Study condition is assumed."""
    e, g = x[:, :4].T, x[:, 4:].T
    ee = (e * e).sum(axis=0)
    conj_e = e * np.array([1.0, -1.0, -1.0, -1.0])[:, None]
    # p = 2 g ē / (e·e): vector part of a quaternion product
    g0, gv = g[0], g[1:]
    c0, cv = conj_e[0], conj_e[1:]
    pv = g0 * cv + c0 * gv + np.cross(gv.T, cv.T).T
    position = (2.0 * pv / ee).T
    quat = (e / np.sqrt(ee)).T
    return position, quat


@dataclass(frozen=True)
class RodParameters:
    """Parameters of the Study rod system for a batch of C configurations (batch axis last).

    Attributes:
        base: ``(3, 6, C)`` base joint centres a_j.
        platform: ``(3, 6, C)`` platform joint centres b_j.
        offset: ``(6, C)`` d_j = |a_j|² + |b_j|² − ℓ_j².
    """

    base: np.ndarray
    platform: np.ndarray
    offset: np.ndarray

    @classmethod
    def from_geometry(
        cls, base: np.ndarray, platform: np.ndarray, lengths: np.ndarray
    ) -> RodParameters:
        """From batch-first ``base (C, 6, 3)``, ``platform (C, 6, 3)``, ``lengths (C, 6)``."""
        a = np.ascontiguousarray(np.transpose(base, (2, 1, 0)))
        b = np.ascontiguousarray(np.transpose(platform, (2, 1, 0)))
        d = (a * a).sum(axis=0) + (b * b).sum(axis=0) - np.asarray(lengths).T ** 2
        return cls(a, b, d)

    def take(self, columns: np.ndarray) -> RodParameters:
        """The configurations ``columns`` (index array)."""
        return RodParameters(
            self.base[:, :, columns], self.platform[:, :, columns], self.offset[:, columns]
        )


def rod_quadrics(x: np.ndarray, par: RodParameters) -> np.ndarray:
    """The six rod polynomials ``f_j`` at Study points ``x (8, P)`` for parameters with ``P``
    columns; returns ``(6, P)``."""
    e, g = x[:4, None], x[4:, None]
    ae = mul_pure_left(par.base, e)
    eb = mul_pure_right(e, par.platform)
    return (
        4.0 * (g * g).sum(axis=0)
        + 4.0 * (g * (eb - ae)).sum(axis=0)
        - 2.0 * (ae * eb).sum(axis=0)
        + par.offset * (e * e).sum(axis=0)
    )


def _basis_images() -> tuple[np.ndarray, np.ndarray]:
    """Gather indices and scales of the 17 linear maps ``Z_m`` (see :class:`StudyHomotopy`).

    Each ``Z_m`` maps ``x = (e, g)`` to a signed, scaled permutation of its entries (or zero), so
    ``Z_m(x)[r] = scale[m, r] · x_ext[index[m, r]]`` with ``x_ext = (x, 0)``.
    """
    unit = np.eye(4)[1:]

    def left(u: np.ndarray, q: np.ndarray) -> np.ndarray:  # u q, u pure
        return mul_pure_left(u[1:, None], q[:, None])[:, 0]

    def right(q: np.ndarray, u: np.ndarray) -> np.ndarray:  # q u, u pure
        return mul_pure_right(q[:, None], u[1:, None])[:, 0]

    zero = np.zeros(4)
    maps = []
    for k in range(3):  # coefficient a_k: (2 i_k g, −2 i_k e)
        maps.append(lambda x, k=k: np.r_[2 * left(unit[k], x[4:]), -2 * left(unit[k], x[:4])])
    for k in range(3):  # coefficient b_k: (−2 g i_k, 2 e i_k)
        maps.append(lambda x, k=k: np.r_[-2 * right(x[4:], unit[k]), 2 * right(x[:4], unit[k])])
    for k in range(3):  # coefficient a_k b_l: (2 i_k e i_l, 0)
        for m in range(3):
            maps.append(lambda x, k=k, m=m: np.r_[2 * right(left(unit[k], x[:4]), unit[m]), zero])
    maps.append(lambda x: np.r_[x[:4], zero])  # coefficient d: (e, 0)
    maps.append(lambda x: np.r_[zero, 4 * x[4:]])  # coefficient 1: (0, 4 g)
    index = np.full((len(maps), N_VARS), N_VARS)
    scale = np.zeros((len(maps), N_VARS))
    for m, f in enumerate(maps):
        matrix = np.stack([f(col) for col in np.eye(N_VARS)], axis=1)
        for r in range(N_VARS):
            nz = np.flatnonzero(matrix[r])
            if nz.size:
                index[m, r], scale[m, r] = nz[0], matrix[r, nz[0]]
    return index, scale


_BASIS_INDEX, _BASIS_SCALE = _basis_images()
#: ``(17, 8)`` gather indices (8: zero) and scales of the maps ``Z_m`` (compiled tracker).
BASIS_INDEX, BASIS_SCALE = _BASIS_INDEX, _BASIS_SCALE
#: Number of coefficients per rod in the expansion ``Q_j x = Σ_m c_jm Z_m(x)``.
N_COEFFS = _BASIS_INDEX.shape[0]


def rod_coefficients(par: RodParameters) -> np.ndarray:
    """Coefficients ``c (C, 6, 17)``: a (3), b (3), a_k b_l (9), d, 1 for each rod."""
    a = np.transpose(par.base, (2, 1, 0))  # (C, 6, 3)
    b = np.transpose(par.platform, (2, 1, 0))
    ab = (a[:, :, :, None] * b[:, :, None, :]).reshape(*a.shape[:2], 9)
    d = par.offset.T[:, :, None]
    return np.concatenate([a, b, ab, d, np.ones_like(d)], axis=2)


@dataclass(frozen=True)
class StudyHomotopy:
    """Straight-line parameter homotopy between one start system and C target systems.

    ``H(x, t) = F(x; π_target + t (π_start − π_target))`` with the Study quadric and the patch
    ``patch · x = 1`` appended; t = 1 is the start system, t = 0 the target.

    Evaluation: each rod polynomial is ``f_j = xᵀ Q_j x`` with ``Q_j`` symmetric, so
    ``∂f_j/∂x = 2 Q_j x``, and ``Q_j x = Σ_m c_jm Z_m(x)`` where the 17 maps ``Z_m`` are signed
    permutations of ``x`` (``(2 i_k g, −2 i_k e)`` for a_k, ``(−2 g i_l, 2 e i_l)`` for b_l,
    ``(2 i_k e i_l, 0)`` for a_k b_l, ``(e, 0)`` for d_j, ``(0, 4g)`` for 1) and ``c_j(t)`` is a
    polynomial of degree 2 in t. One gather builds every ``Z_m``; one batched product gives every
    ``Q_j x``; ``f_j = Σ_m c_jm (x·Z_m)`` and ``∂f_j/∂t = Σ_m ċ_jm (x·Z_m)``.

    Attributes:
        coeffs: ``(3, C, 6, 17)`` complex coefficients of t⁰, t¹, t² of ``c_j(t)``.
        patch: ``(8,)`` complex patch vector.
    """

    coeffs: np.ndarray
    patch: np.ndarray

    @classmethod
    def between(
        cls, start: RodParameters, target: RodParameters, patch: np.ndarray
    ) -> StudyHomotopy:
        """Homotopy from ``start`` (one column, complex) to ``target`` (C columns)."""
        c_start, c_target = rod_coefficients(start), rod_coefficients(target)
        n_conf = c_target.shape[0]
        c_start = np.broadcast_to(c_start, c_target.shape)
        a0, b0 = c_target[:, :, 0:3], c_target[:, :, 3:6]
        da, db = c_start[:, :, 0:3] - a0, c_start[:, :, 3:6] - b0
        coeffs = np.zeros((3, n_conf, 6, N_COEFFS), dtype=complex)
        coeffs[0] = c_target
        coeffs[1] = c_start - c_target
        # a(t) b(t) is quadratic in t: a0 b0 + t (a0 db + da b0) + t² da db
        outer = lambda u, v: (u[:, :, :, None] * v[:, :, None, :]).reshape(n_conf, 6, 9)  # noqa: E731
        coeffs[1, :, :, 6:15] = outer(a0, db) + outer(da, b0)
        coeffs[2, :, :, 6:15] = outer(da, db)
        return cls(coeffs, np.asarray(patch, dtype=complex))

    def evaluate(
        self, x: np.ndarray, t: np.ndarray, cols: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``H (P, 8)``, ``∂H/∂x (P, 8, 8)`` and ``∂H/∂t (P, 8)``.

        Args:
            x: ``(P, 8)`` complex points, batch first.
            t: ``(P,)`` homotopy parameters.
            cols: ``(P,)`` configuration (column) of each point; None when there is one
                configuration.
        """
        n_pts = x.shape[0]
        x_ext = np.concatenate([x, np.zeros((n_pts, 1), dtype=x.dtype)], axis=1)
        z = x_ext[:, _BASIS_INDEX] * _BASIS_SCALE  # (P, 17, 8)
        s = np.einsum("pmk,pk->pm", z, x)  # (P, 17)
        if cols is None:
            c0, c1, c2 = self.coeffs[:, 0]  # (6, 17) each, broadcast over P
        else:
            c0, c1, c2 = self.coeffs[:, cols]  # (P, 6, 17) each
        tt = t[:, None, None]
        c = c0 + tt * (c1 + tt * c2)  # (P, 6, 17)
        dc = c1 + (2.0 * tt) * c2
        y = np.matmul(c, z)  # (P, 6, 8): Q_j x
        res = np.empty((n_pts, N_VARS), dtype=complex)
        jac = np.empty((n_pts, N_VARS, N_VARS), dtype=complex)
        d_t = np.zeros((n_pts, N_VARS), dtype=complex)
        res[:, :6] = np.einsum("pjm,pm->pj", c, s)
        d_t[:, :6] = np.einsum("pjm,pm->pj", dc, s)
        res[:, 6] = np.einsum("pk,pk->p", x[:, :4], x[:, 4:])
        res[:, 7] = (x * self.patch).sum(axis=1) - 1.0  # no BLAS: see DESIGN.md
        jac[:, :6] = 2.0 * y
        jac[:, 6, :4] = x[:, 4:]
        jac[:, 6, 4:] = x[:, :4]
        jac[:, 7] = self.patch
        return res, jac, d_t
