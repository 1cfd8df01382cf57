"""Moving the reference point of stiffness and compliance matrices (batched).

Twists are ``(δp, δθ)`` — the small displacement of the reference point, then the small rotation,
both in the base frame; wrenches are ``(F, M)`` with M the moment about the reference point. For
a rigid body, the displacement of point b is ``δp_b = δp_a + δθ × (b − a)``, i.e. ``t_b = S t_a``
with ``S = [[I, −[r]×], [0, I]]``, ``r = b − a``; a wrench moves the other way, ``w_a = Sᵀ w_b``.
Hence ``C_b = S C_a Sᵀ`` and ``K_b = S⁻ᵀ K_a S⁻¹`` (``S⁻¹`` is S with −r).
"""

from __future__ import annotations

import numpy as np

from pkmkit.spatial.rotation import skew


def shift_matrix(offset: np.ndarray) -> np.ndarray:
    """``S (N, 6, 6)`` taking the twist at point a to the twist at ``b = a + offset`` for
    ``offset (N, 3)`` (m)."""
    offset = np.atleast_2d(np.asarray(offset, dtype=float))
    out = np.zeros((offset.shape[0], 6, 6))
    out[:, np.arange(6), np.arange(6)] = 1.0
    out[:, :3, 3:] = -skew(offset)
    return out


def move_compliance(compliance: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """Compliance ``(N, 6, 6)`` at ``a + offset`` from the compliance at a."""
    s = shift_matrix(offset)
    return np.einsum("nij,njk,nlk->nil", s, compliance, s)


def move_stiffness(stiffness: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """Stiffness ``(N, 6, 6)`` at ``a + offset`` from the stiffness at a: ``S⁻ᵀ K S⁻¹``."""
    s_inv = shift_matrix(-np.atleast_2d(np.asarray(offset, dtype=float)))
    return np.einsum("nji,njk,nkl->nil", s_inv, stiffness, s_inv)
