"""The velocity-model record of joint-chain machines and its rank and singularity thresholds
(shared by the batch path, :mod:`pkmkit.machines.chain_jacobians`, and the one-pose path,
:mod:`pkmkit.machines.chain_one`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.machines.results import VelocityModel

#: Relative threshold on singular values for ranks.
RANK_RCOND = 1e-9
#: A closure is singular where σ_min/σ_max of its Jacobian (platform and passive joints) falls
#: below this: the engine converges only to ~sqrt(eps) of an exact singularity, where the ratio
#: is ~1e-8; 0.002° from the crank-slider's folded configuration it is 1e-6.
SINGULAR_TOL = 1e-6


@dataclass(frozen=True)
class ChainJacobians(VelocityModel):
    """Velocity model of a joint-chain machine at N configurations.

    Attributes:
        J: ``(N, 6, n)`` tool twist per unit actuator rate: rows 0–2 the tool point's velocity
            (m per m or per rad), rows 3–5 the tool frame's angular velocity.
        J_homogeneous: ``(N, 6, n)`` angular rows times the characteristic length.
        singular_values: ``(N, min(6, n))`` of ``J_homogeneous``; condition: ``(N,)``.
        passive_rates: ``(N, n_p, n)`` passive joint rates per actuator rate.
        closure_rank: ``(N,)`` rank of the closure Jacobian with respect to the platform and
            passive joints (lower than at home: a parallel singularity).
        expected_rank: that rank at home.
        q: ``(N, n)`` actuator coordinates used.
        status: ``(N,)`` OK, NO_ASSEMBLY (the legs do not close: NaN), SINGULAR (the closure
            Jacobian is singular, :data:`SINGULAR_TOL`: the velocity model does not exist
            there, NaN).
    """

    J: np.ndarray
    J_homogeneous: np.ndarray
    singular_values: np.ndarray
    condition: np.ndarray
    passive_rates: np.ndarray
    closure_rank: np.ndarray
    expected_rank: int
    q: np.ndarray
    status: np.ndarray | None = None
