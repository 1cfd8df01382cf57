"""The machine protocol's exact tool points under sampled defects (Monte Carlo tolerance
analysis, :func:`pkmkit.geometric_errors.tolerance.monte_carlo`, asks the machine):
``machine.sampled_tool_points(q, samples, tool_length=)`` gives ``(P, S, 3)`` tool points of
the machine with each defect sample ``(S, d)`` at actuator coordinates ``q (P, n)``, NaN where
it does not assemble.

- rod legs (:class:`RodDefectSamples`): the batched per-sample chord solver
  :mod:`pkmkit.solve.rod_samples` from the nominal poses (:func:`nominal_gains`,
  :func:`exact_rod_points`; ≥ 10⁶ pairs/s on the hexapod, docs/benchmarks.md);
- joint chains (:class:`ChainDefectSamples`): the machine rebuilt per sample (the one defect
  rule) and its direct model solved (slower); a sample that does not even close at home fails
  every pose.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, ParameterError


def nominal_gains(machine, q: np.ndarray):
    """Nominal platform poses at q and the pseudo-inverse of the closure Jacobian used by the
    chord iteration: ``(position (P, 3), rotation (P, 3, 3) or None, gain (P, k, m))``."""
    from pkmkit.model.defect_rule import defect_index
    from pkmkit.solve.rod_samples import carriages, sampled_geometry
    from pkmkit.spatial.rotation import rotvec_to_matrix

    index = defect_index(machine)
    geom = sampled_geometry(machine.model, index, np.zeros((1, len(index))))
    x = np.atleast_2d(machine.fk(q))
    if not np.isfinite(x).all():
        bad = int(np.flatnonzero(~np.isfinite(x).all(axis=1))[0])
        raise InputError(f"configuration {bad}: the nominal machine does not assemble at q = "
                         f"{q[bad].tolist()}")
    a, _ = carriages(geom, q)  # (P, 1, m, 3)
    a = a[:, 0]
    p_count = q.shape[0]
    position = np.zeros((p_count, 3))
    if machine.model.full_pose:  # the rod model's platform turns (a full-pose machine)
        position[:] = x[:, :3]
        rot = rotvec_to_matrix(x[:, 3:6])
        w = np.einsum("pab,mb->pma", rot, geom.platform[0])
        d = position[:, None, :] + w - a
        unit = d / np.linalg.norm(d, axis=2, keepdims=True)
        jac = np.concatenate([unit, np.cross(w, unit)], axis=2)  # (P, m, 6)
        return position, rot, np.linalg.pinv(jac)
    dims = machine.dims
    position[:, :dims] = x[:, :dims]
    d = position[:, None, :] + geom.platform[0][None] - a
    unit = d / np.linalg.norm(d, axis=2, keepdims=True)
    return position, None, np.linalg.pinv(unit[:, :, :dims])


def exact_rod_points(machine, q: np.ndarray, samples: np.ndarray, *, tol: float = 1e-12,
                     max_iter: int = 30) -> np.ndarray:
    """Exact tool points ``(P, S, 3)`` of a rod machine with each defect sample of ``samples``
    ``(S, d)`` at actuator coordinates ``q (P, n)`` (NaN where it does not assemble)."""
    from pkmkit.model.defect_rule import defect_index
    from pkmkit.solve.rod_samples import sampled_geometry, solve_sampled_direct

    qb = np.atleast_2d(np.asarray(q, dtype=float))
    position, rot, gain = nominal_gains(machine, qb)
    geom = sampled_geometry(machine.model, defect_index(machine), samples)
    dims = 3 if machine.model.full_pose else machine.dims
    out = solve_sampled_direct(geom, qb, position, rot, gain, dims=dims, tol=tol,
                               max_iter=max_iter)
    return out.position


class RodDefectSamples:
    """Rod legs: the batched per-sample solver."""

    def sampled_tool_points(self, q: np.ndarray, samples: np.ndarray, *,
                            tool_length: Any = None) -> np.ndarray:
        """``(P, S, 3)`` exact tool points (m) with each defect sample ``samples (S, d)`` at
        ``q (P, n)`` (module docstring; ``tool_length`` is a joint chain's and is ignored)."""
        return exact_rod_points(self, q, samples)


class ChainDefectSamples:
    """Joint chains: the machine rebuilt per sample."""

    def sampled_tool_points(self, q: np.ndarray, samples: np.ndarray, *,
                            tool_length: Any = None) -> np.ndarray:
        """``(P, S, 3)`` exact tool points (m) with each defect sample ``samples (S, d)`` at
        ``q (P, n)`` and the tool ``tool_length`` (m; default the machine's)."""
        qb = np.atleast_2d(np.asarray(q, dtype=float))
        out = np.full((qb.shape[0], samples.shape[0], 3), np.nan)
        for s, delta in enumerate(samples):
            try:
                moved = self.with_defects(delta)
            except ParameterError:
                continue  # does not even close at home: every pose of the sample fails
            out[:, s] = moved.fk(qb, tool_length=tool_length, full_output=True).pose[:, :3]
        return out
