"""Batched rotations.

Orientations are rotation vectors φ (axis × angle, radians) at the interfaces and rotation
matrices inside computations. Conversions go through :class:`scipy.spatial.transform.Rotation`,
which handles the small-angle and near-π cases carefully.

Perturbations are *left* (world-frame) increments: ``R ← exp([δ]×) R``.
"""

from __future__ import annotations

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrices ``[v]×`` with ``[v]× w = v × w``.

    Args:
        v: ``(..., 3)``.

    Returns:
        ``(..., 3, 3)``.
    """
    v = np.asarray(v, dtype=float)
    out = np.zeros((*v.shape, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def rotvec_to_matrix(phi: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(N, 3, 3)`` of rotation vectors ``(N, 3)`` (radians)."""
    from scipy.spatial.transform import Rotation  # lazy: SciPy's spatial costs 0.2 s to import

    return Rotation.from_rotvec(np.asarray(phi, dtype=float).reshape(-1, 3)).as_matrix()


def compose_rotvec(delta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Rotation vector of ``exp(δ) · exp(φ)`` (left increment δ applied to φ), rows ``(N, 3)``."""
    from scipy.spatial.transform import Rotation

    d = Rotation.from_rotvec(np.asarray(delta, dtype=float).reshape(-1, 3))
    p = Rotation.from_rotvec(np.asarray(phi, dtype=float).reshape(-1, 3))
    return (d * p).as_rotvec()
