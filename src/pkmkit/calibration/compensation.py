"""Compensation of a nominal controller by an identified machine: corrected targets along tool
paths (a corrected G-code program) and on grids (a correction table), and the error left after
compensation.

The identified machine reaches X when commanded ``q = IGM_identified(X)``; the nominal controller
commands ``IGM_nominal(X')``, so the corrected target is ``X' = FGM_nominal(IGM_identified(X))``
(:func:`pkmkit.calibration.controller.corrected_targets`). Programs are corrected block by
block in :mod:`pkmkit.calibration.corrected_program`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.calibration.controller import as_targets, corrected_targets, executed
from pkmkit.exceptions import InputError

#: Targets per batch (progress bars advance per batch).
CHUNK = 2000


def chunked(func, x: np.ndarray, progress: bool, label: str) -> np.ndarray:
    """``func`` applied to ``x (N, k)`` in chunks of :data:`CHUNK` rows (a progress bar named
    ``label`` when ``progress`` and more than one chunk), the results concatenated."""
    from tqdm import tqdm

    parts = []
    starts = range(0, len(x), CHUNK)
    for start in tqdm(starts, desc=label, unit="batch", disable=not progress or len(x) <= CHUNK,
                      leave=False):
        parts.append(func(x[start:start + CHUNK]))
    return np.concatenate(parts) if parts else np.zeros((0, x.shape[1]))


def correct_targets(nominal, identified, targets: Any, *, tool_length: float | None = None,
                    progress: bool = False) -> np.ndarray:
    """Corrected targets ``(N, w)`` for ``targets`` (module docstring), in batches.

    Raises:
        InputError: targets the identified machine cannot reach (their rows named).
    """
    x = as_targets(identified, targets)
    out = chunked(lambda part: corrected_targets(nominal, identified, part, tool_length), x,
                   progress, "compensating")
    bad = np.flatnonzero(~np.isfinite(out).all(axis=1))
    if bad.size:
        rows = ", ".join(str(i + 1) for i in bad[:10])
        raise InputError(f"{bad.size} target(s) out of reach of the calibrated machine (rows "
                         f"{rows}{' …' if bad.size > 10 else ''})")
    return out


@dataclass(frozen=True)
class TargetFlags:
    """Per-row verdicts of corrected targets.

    Attributes:
        status: ``(N,)`` ``"ok"``, ``"out-of-reach"`` (the calibrated machine cannot reach the
            target), ``"correction"`` (larger than the bound) or ``"out-of-stroke"`` (the
            commanded actuators leave their strokes).
        correction: ``(N,)`` size of the position correction, m (NaN out of reach).
        actuator: ``(N,)`` the actuator furthest out of stroke (empty when none).
        excess: ``(N,)`` by how much, m or rad (0 when none).
        angular: ``(N,)`` that actuator is revolute (its excess in rad).
    """

    status: np.ndarray
    correction: np.ndarray
    actuator: np.ndarray
    excess: np.ndarray
    angular: np.ndarray

    @property
    def flagged(self) -> np.ndarray:
        """``(N,)`` rows not ``ok``."""
        return self.status != "ok"

    def describe(self, k: int, bound: float, scale: float = 1.0, unit: str = "m") -> str:
        """Row ``k``'s verdict in words (lengths in ``unit``, ``scale`` m per unit)."""
        status = self.status[k]
        if status == "correction":
            return (f"correction {self.correction[k] / scale:.4g} {unit} > "
                    f"{bound / scale:g} {unit}")
        if status == "out-of-stroke":
            by = (f"{np.degrees(self.excess[k]):.4g} deg" if self.angular[k]
                  else f"{self.excess[k] / scale:.4g} {unit}")
            return f"out-of-stroke {self.actuator[k]} by {by}"
        return str(status)


def correct_table(nominal, identified, targets: Any, *, max_correction: float,
                  tool_length: float | None = None, progress: bool = False
                  ) -> tuple[np.ndarray, TargetFlags]:
    """Corrected targets ``(N, w)`` and their per-row verdicts: rows out of reach of the
    calibrated machine, needing a correction above ``max_correction`` (m) or commanding an
    actuator beyond its stroke are flagged (their corrected values NaN), the others kept.
    """
    from pkmkit.calibration.controller import commanded_q, reached
    from pkmkit.motion.limits import stroke_excess

    x = as_targets(identified, targets)
    n = identified.n_actuators

    def command(part: np.ndarray) -> np.ndarray:
        q = commanded_q(identified, part, tool_length)
        return np.concatenate([reached(nominal, q, tool_length), q], axis=1)

    both = chunked(command, x, progress, "compensating")
    fixed, q = both[:, :x.shape[1]], both[:, x.shape[1]:x.shape[1] + n]
    size = np.linalg.norm(fixed[:, :3] - x[:, :3], axis=1)
    outside = np.nan_to_num(stroke_excess(identified, q))
    worst = outside.argmax(axis=1)
    excess = outside[np.arange(len(x)), worst]
    status = np.full(len(x), "ok", dtype=object)
    status[excess > 0] = "out-of-stroke"
    status[size > max_correction] = "correction"
    status[~np.isfinite(size) | ~np.isfinite(fixed).all(axis=1)] = "out-of-reach"
    names = np.array(identified.actuator_names, dtype=object)
    actuator = np.where(excess > 0, names[worst], "")
    fixed[status != "ok"] = np.nan
    angular = np.asarray(identified.angular_actuators, dtype=bool)[worst]
    return fixed, TargetFlags(status=status.astype(str), correction=size, actuator=actuator,
                              excess=excess, angular=angular & (excess > 0))


def home_offset(nominal, identified, tool_length: float | None = None) -> float:
    """Distance (m) between the tool points of ``identified`` and ``nominal`` at the nominal
    machine's home actuator coordinates (inf where either does not assemble): a calibration
    moves it by its defects, a machine of other dimensions by far more."""
    from pkmkit.calibration.controller import reached

    q = np.atleast_2d(np.asarray(nominal.home_q, dtype=float))
    a, b = reached(nominal, q, tool_length)[0, :3], reached(identified, q, tool_length)[0, :3]
    d = float(np.linalg.norm(a - b))
    return d if np.isfinite(d) else float("inf")


def grid_targets(lower: Any, upper: Any, counts: Any) -> np.ndarray:
    """Points of a regular grid ``(nx·ny·nz, 3)`` between ``lower`` and ``upper`` (m)."""
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    n = np.asarray(counts, dtype=int)
    if lo.shape != (3,) or hi.shape != (3,) or n.shape != (3,) or (n < 1).any():
        raise InputError("a grid needs 3 lower and 3 upper coordinates and 3 counts ≥ 1")
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise InputError("grid bounds must be finite")
    axes = [np.linspace(lo[k], hi[k], n[k]) if n[k] > 1 else np.array([(lo[k] + hi[k]) / 2])
            for k in range(3)]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([m.ravel() for m in mesh])


@dataclass(frozen=True)
class CompensationCheck:
    """Errors of a true machine at targets, commanded by the nominal controller without and
    with compensation: ``before (N,)``, ``after (N,)`` (m); ``after_rigid (N,)``: the errors
    with compensation once the best rigid motion between reached and wanted points is removed
    (what a frame identified with the machine leaves: a set-up offset of the workpiece, not an
    error of its shape)."""

    before: np.ndarray
    after: np.ndarray
    after_rigid: np.ndarray

    def to_dict(self, scale: float = 1.0) -> dict[str, float]:
        b, a, r = self.before / scale, self.after / scale, self.after_rigid / scale
        return {"mean_before": float(b.mean()), "rms_before": float(np.sqrt((b**2).mean())),
                "max_before": float(b.max()), "mean_after": float(a.mean()),
                "rms_after": float(np.sqrt((a**2).mean())), "max_after": float(a.max()),
                "mean_after_rigid": float(r.mean()), "max_after_rigid": float(r.max())}


def rigid_residuals(reached: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """``(N,)`` distances between ``wanted`` points and the ``reached`` ones after the best
    rigid motion of the latter (Kabsch; translation only for fewer than 3 points)."""
    from pkmkit.calibration.registration import register_points

    if len(reached) < 3:
        return np.linalg.norm(reached - reached.mean(axis=0) - wanted + wanted.mean(axis=0),
                              axis=1)
    try:
        reg = register_points(reached, wanted)
    except InputError:  # collinear points: translation only
        return np.linalg.norm(reached - reached.mean(axis=0) - wanted + wanted.mean(axis=0),
                              axis=1)
    return np.linalg.norm(reg.point_residuals, axis=1)


def check_compensation(true_machine, nominal, identified, targets: Any, *,
                       tool_length: float | None = None) -> CompensationCheck:
    """Where the true machine puts its tool for ``targets``: commanded by the nominal controller
    as is, and with the corrected targets (the residual error after compensation)."""
    x = as_targets(identified, targets)
    before = executed(true_machine, nominal, x, tool_length)
    corrected = corrected_targets(nominal, identified, x, tool_length)
    after = executed(true_machine, nominal, corrected, tool_length)
    ok = np.isfinite(before).all(axis=1) & np.isfinite(after).all(axis=1)
    if not ok.all():
        raise InputError(f"{(~ok).sum()} validation target(s) out of reach")
    return CompensationCheck(before=np.linalg.norm(before[:, :3] - x[:, :3], axis=1),
                             after=np.linalg.norm(after[:, :3] - x[:, :3], axis=1),
                             after_rigid=rigid_residuals(after[:, :3], x[:, :3]))
