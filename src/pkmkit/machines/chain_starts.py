"""The direct model's default start of a joint-chain machine: home moved to first order towards
each row's actuator values (moved here from :mod:`pkmkit.machines.joint_chain`).

Every row's start is computed by batch-last contractions
(:func:`pkmkit.numerics.rowwise.einsum`), not a matrix product over the rows, whose rounding
changes with the batch (a product of one row runs another BLAS kernel): a row's start, hence its
closure, does not depend on the rows beside it (issue 22 §6).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.machines.chain_velocity_record import RANK_RCOND
from pkmkit.numerics.rowwise import einsum
from pkmkit.solve.chains import closure, closure_residuals, compose_rotvecs, rotvec_matrices
from pkmkit.spatial.rotation import rotvec_to_matrix


def home_rates(m: Any) -> tuple[np.ndarray, np.ndarray]:
    """At home of the machine ``m``, per unit actuator change: ``(6 + n_p, n)`` first-order
    change of the platform (δp, δω) and passive joints, and ``(6L, n)`` change of the closure
    residual with the platform and passive joints held (zero columns for the head); cached on
    ``m``."""
    cached = m.__dict__.get("_home_rates_cache")
    if cached is not None:
        return cached
    model = m.model
    values = m._home["values"][:, None]
    rot = rotvec_to_matrix(m._home["platform"][3:]).transpose(1, 2, 0)
    c = closure(model, rot, m._home["platform"][:3, None], values)
    cu = np.concatenate([c.platform, c.variables[:, m._passive]], axis=1)[:, :, 0]
    cq = c.variables[:, m._actuated, 0]
    rates = (-np.linalg.pinv(cu, rcond=RANK_RCOND) @ cq, cq)
    object.__setattr__(m, "_home_rates_cache", rates)
    return rates


def default_start(m: Any, qb: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Starts ``(N, 6 + n_p)`` of the direct model of ``m`` at actuator values ``qb (N, n)``
    (every joint's values ``values (N, n_var)``): home moved to first order towards each q (a
    Gauss–Newton iteration fewer near home), or home itself where the legs close worse from
    that prediction than from home (far from home; the home residual to first order)."""
    n = qb.shape[0]
    home = np.concatenate([m._home["platform"], m._home["values"][m._passive]])
    u_home = np.tile(home, (n, 1))
    rates, residual_rates = home_rates(m)
    delta = np.ascontiguousarray((qb - m.home_q).T)  # (n, N): batch last
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        du = einsum("pn,nk->pk", rates, delta).T
        u_pred = u_home + du
        u_pred[:, 3:6] = compose_rotvecs(du[:, 3:6].T, u_home[:, 3:6].T).T
        full = values.T.copy()
        full[m._passive] = u_pred[:, 6:].T
        res = closure_residuals(m.model, rotvec_matrices(u_pred[:, 3:6].T), u_pred[:, :3].T,
                                full)
        from_home = einsum("pn,nk->pk", residual_rates, delta)
    worse = ~(einsum("mk,mk->k", res, res) <= einsum("mk,mk->k", from_home, from_home))
    u_pred[worse] = u_home[worse]
    return u_pred
