"""Diagnoses of joint-chain configurations: which leg misses the platform and by how much, which
joint is beyond its stroke, whether the closure is singular — batched, with one message per row.

These turn the engine's per-row outcome into what a machine user needs to read: "leg 2 misses
the platform by 12.4 mm and 0.31°", "Q1 = 1200 mm is beyond its stroke [975, 995] mm by 205 mm"
(lengths in mm, the unit of the misses, in every sentence).
"""

from __future__ import annotations

import numpy as np

from pkmkit.machines.strokes import signed_excess
from pkmkit.model.chains import REVOLUTE, JointChainModel
from pkmkit.solve.chains import closure
from pkmkit.spatial.rotation import rotvec_to_matrix


def _closure_at(model: JointChainModel, values: np.ndarray, platform: np.ndarray):
    rot = rotvec_to_matrix(np.nan_to_num(platform[:, 3:6])).transpose(1, 2, 0)
    return closure(model, rot, np.nan_to_num(platform[:, :3]).T, np.nan_to_num(values).T)


def leg_misses(model: JointChainModel, values: np.ndarray, platform: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """How far each leg's end frame is from the platform frame.

    Args:
        values: ``(N, n_var)`` joint values (rad or m).
        platform: ``(N, 6)`` platform position (m) and rotation vector (rad).

    Returns:
        ``translation (N, n_legs)`` (m) and ``rotation (N, n_legs)`` (rad; the angle of
        ``R_leg R_Xᵀ``, from its skew part, exact below 90°).
    """
    res = _closure_at(model, values, platform).residual  # (6 L, N)
    blocks = res.reshape(len(model.legs), 6, -1)
    translation = np.linalg.norm(blocks[:, :3], axis=1).T
    sine = np.linalg.norm(blocks[:, 3:], axis=1).T / model.characteristic_length
    return translation, np.arcsin(np.clip(sine, 0.0, 1.0))


def miss_message(model: JointChainModel, translation: np.ndarray, rotation: np.ndarray
                 ) -> tuple[int, str]:
    """The leg that misses the (least-squares) platform pose most, by translation + L ×
    rotation, and a sentence saying by how much — and by how much the other legs miss it —
    for one row ``translation (n_legs,)``, ``rotation (n_legs,)``."""
    score = translation + model.characteristic_length * rotation
    if not np.isfinite(score).any():
        return 0, "the closure could not be evaluated"
    order = np.argsort(-np.nan_to_num(score, nan=-1.0))
    leg = int(order[0])

    def miss(i: int) -> str:
        mm, deg = translation[i] * 1e3, np.degrees(rotation[i])
        return f"{mm if mm > 1e-9 else 0:.4g} mm and {deg if deg > 1e-9 else 0:.4g}°"

    text = f"{model.leg_names[leg]} misses the platform by {miss(leg)}"
    others = [f"{model.leg_names[i]} by {miss(i)}" for i in order[1:]
              if score[i] > 1e-9 * model.characteristic_length]
    if others:
        text += f" ({', '.join(others)})"
    return leg, text


def _unit(model: JointChainModel, variable: int) -> tuple[float, str]:
    """Display scale and unit of a joint: degrees, or mm as the legs' misses (one unit for the
    lengths of a message)."""
    e = int(np.flatnonzero(model.element_variable == variable)[0])
    if model.elements[e].type == REVOLUTE:
        return 180.0 / np.pi, "°"
    return 1e3, " mm"


def stroke_violations(model: JointChainModel, values: np.ndarray, variables: np.ndarray,
                      rows: np.ndarray | None = None, *,
                      messages: bool = True) -> tuple[np.ndarray, list[str]]:
    """Rows whose joint values lie outside their strokes, with a message naming the first
    offending joint of each.

    Args:
        values: ``(N, n_var)`` joint values.
        variables: indices of the variables to check.
        rows: ``(N,)`` bool, the rows to check (default all).
        messages: write the messages (False: every message ``""``, for callers that only
            need ``bad``).

    Returns:
        ``bad (N,)`` bool and ``messages`` (N strings, ``""`` for rows within strokes).
    """
    n = values.shape[0]
    rows = np.ones(n, dtype=bool) if rows is None else rows
    variables = np.asarray(variables, dtype=int)
    sub = values[:, variables]
    lo, hi = model.q_min[variables], model.q_max[variables]
    outside = (signed_excess(sub, lo, hi) != 0) & rows[:, None]
    bad = outside.any(axis=1)
    texts = [""] * n
    rows_bad = np.flatnonzero(bad)
    if not (rows_bad.size and messages):
        return bad, texts
    # the first offending joint of each bad row, its value and excess, in one pass
    first = np.argmax(outside[rows_bad], axis=1)
    found = sub[rows_bad, first]
    excess = signed_excess(sub[rows_bad], lo, hi)[np.arange(rows_bad.size), first]
    units = {int(v): _unit(model, int(v)) for v in np.unique(variables[first])}
    for i, k, value, over in zip(rows_bad.tolist(), first.tolist(), found.tolist(),
                                 excess.tolist(), strict=True):
        variable = int(variables[k])
        texts[i] = _stroke_text(model, variable, value, over, units[variable])
    return bad, texts


def stroke_message(model: JointChainModel, variable: int, value: float) -> str:
    """``"Q1 = 1200 mm is beyond its stroke [975, 995] mm by 205 mm"`` (degrees for
    revolutes)."""
    over = float(signed_excess(np.array([[value]]), model.q_min[variable:variable + 1],
                               model.q_max[variable:variable + 1])[0, 0])
    return _stroke_text(model, variable, value, over, _unit(model, variable))


def _stroke_text(model: JointChainModel, variable: int, value: float, over: float,
                 unit_of: tuple[float, str]) -> str:
    """:func:`stroke_message` from the joint's excess ``over`` and display unit."""
    scale, unit = unit_of
    lo, hi = model.q_min[variable] * scale, model.q_max[variable] * scale
    side = "below" if value < model.q_min[variable] else "beyond"
    return (f"{model.variables[variable]} = {value * scale:.6g}{unit} is {side} its stroke "
            f"[{lo:.6g}, {hi:.6g}]{unit} by {abs(over) * scale:.6g}{unit}")


def closure_conditioning(model: JointChainModel, values: np.ndarray, platform: np.ndarray,
                         unknown: np.ndarray, rank: int) -> np.ndarray:
    """``(N,)`` σ_rank / σ_max of the closure Jacobian with respect to the platform pose and the
    variables ``unknown``, ``rank`` being its rank at a regular configuration (home): it
    vanishes at a parallel singularity (the actuators no longer fix the passive joints)."""
    c = _closure_at(model, values, platform)
    cu = np.concatenate([c.platform, c.variables[:, unknown]], axis=1).transpose(2, 0, 1)
    sv = np.linalg.svd(cu, compute_uv=False)
    return sv[:, rank - 1] / sv[:, 0]
