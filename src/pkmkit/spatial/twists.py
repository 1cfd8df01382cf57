"""Twists, small-displacement torsors and adjoints (batched).

**Convention, stated once for the whole package**: a twist or a small-displacement torsor is a
6-vector with the **linear part first**, ``ξ = (v, ω)`` — as in Pinocchio's ``Motion``, and
unlike scipy's ``RigidTransform.from_exp_coords`` (rotation first; this module converts).

- ``v`` (m or m/s) is the displacement/velocity of the point at the frame origin, ``ω`` (rad or
  rad/s) the rotation; the displacement of a point x is ``v + ω × x`` (small displacements).
- A *spatial* (world-frame) increment acts on the left, ``T ← exp(ξ̂) T``; a *body* increment on
  the right, ``T ← T exp(ξ̂)``. They are related by the adjoint: ``ξ_spatial = Ad_T ξ_body``.
- ``Ad_T = [[R, [p]× R], [0, R]]`` for ``T = (R, p)``.

>>> import numpy as np
>>> xi = np.array([0.1, 0.0, 0.0, 0.0, 0.0, np.pi / 2])
>>> T = se3_exp(xi)
>>> np.allclose(se3_log(T), xi)
True
"""

from __future__ import annotations

import numpy as np

from pkmkit.spatial.rotation import skew


def _rows(x: np.ndarray, width: int) -> tuple[np.ndarray, bool]:
    arr = np.asarray(x, dtype=float)
    single = arr.ndim == 1
    return arr.reshape(-1, width), single


def se3_exp(xi: np.ndarray) -> np.ndarray:
    """Homogeneous matrices ``(N, 4, 4)`` (or ``(4, 4)``) of twists ``(N, 6)`` = (v, ω)."""
    from scipy.spatial.transform import RigidTransform  # lazy: start-up time

    arr, single = _rows(xi, 6)
    out = RigidTransform.from_exp_coords(np.concatenate([arr[:, 3:], arr[:, :3]], axis=1))
    mat = out.as_matrix().reshape(-1, 4, 4)
    return mat[0] if single else mat


def se3_log(matrix: np.ndarray) -> np.ndarray:
    """Twists ``(N, 6)`` = (v, ω) (or ``(6,)``) of homogeneous matrices ``(N, 4, 4)``."""
    from scipy.spatial.transform import RigidTransform  # lazy: start-up time

    arr = np.asarray(matrix, dtype=float)
    single = arr.ndim == 2
    coords = RigidTransform.from_matrix(arr.reshape(-1, 4, 4)).as_exp_coords().reshape(-1, 6)
    out = np.concatenate([coords[:, 3:], coords[:, :3]], axis=1)
    return out[0] if single else out


def adjoint(rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    """Adjoint matrices ``(..., 6, 6)`` of transforms (R ``(..., 3, 3)``, p ``(..., 3)``) acting
    on linear-first twists: ``Ad = [[R, [p]× R], [0, R]]``."""
    rot = np.asarray(rotation, dtype=float)
    pos = np.asarray(position, dtype=float)
    shape = np.broadcast_shapes(rot.shape[:-2], pos.shape[:-1])
    out = np.zeros((*shape, 6, 6))
    out[..., :3, :3] = rot
    out[..., 3:, 3:] = rot
    out[..., :3, 3:] = skew(pos) @ rot
    return out


def adjoint_inverse(rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    """``Ad_T⁻¹ = Ad_{T⁻¹} = [[Rᵀ, −Rᵀ[p]×], [0, Rᵀ]]``, batched like :func:`adjoint`."""
    rot_t = np.swapaxes(np.asarray(rotation, dtype=float), -1, -2)
    pos = np.asarray(position, dtype=float)
    shape = np.broadcast_shapes(rot_t.shape[:-2], pos.shape[:-1])
    out = np.zeros((*shape, 6, 6))
    out[..., :3, :3] = rot_t
    out[..., 3:, 3:] = rot_t
    out[..., :3, 3:] = -rot_t @ skew(pos)
    return out


def point_displacement(torsor: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Displacement ``v + ω × x`` of points x under small-displacement torsors (v, ω) given at
    the origin. ``torsor (..., 6)``, ``points (..., 3)`` broadcast → ``(..., 3)``."""
    t = np.asarray(torsor, dtype=float)
    x = np.asarray(points, dtype=float)
    return t[..., :3] + np.cross(t[..., 3:], x)


def move_reduction_point(torsor: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """The same small-displacement torsor reduced at the point ``offset`` (from the current
    reduction point): ``(v + ω × offset, ω)``. Shapes broadcast, ``(..., 6)``."""
    t = np.asarray(torsor, dtype=float)
    out = np.array(np.broadcast_to(t, np.broadcast_shapes(t.shape, (*np.shape(offset)[:-1], 6))))
    out[..., :3] = point_displacement(t, offset)
    return out


def hat(xi: np.ndarray) -> np.ndarray:
    """``ξ̂ (..., 4, 4)`` of twists ``(..., 6)`` (v, ω)."""
    xi = np.asarray(xi, dtype=float)
    out = np.zeros((*xi.shape[:-1], 4, 4))
    out[..., :3, :3] = skew(xi[..., 3:])
    out[..., :3, 3] = xi[..., :3]
    return out
