"""Which of the TriMule 600's head mirrors cannot come within the strokes (issue 22 §3, fifth
pass), so that the head-branch rule (:mod:`pkmkit.machines.head_branches`) need not solve them.

A sound bound from the geometry alone (:mod:`pkmkit.machines.trimule_forms`). Each slide's
length is the distance between a base point and a platform point — ``|Q_i| = |A_i B_i|`` for the
actuated legs 1–3 and ``L4 = |A4 P|`` for the measured leg — and the tool point T is fixed on the
platform by the head: in the platform frame ``T − B = h(Q4, Q5) − b`` with
``h = ((c2 + Lo sin Q5) cos Q4, (c2 + Lo sin Q5) sin Q4, c1 + Lo cos Q5)`` (eq. 3.36,
``Lo = spindle + tool length``) and ``b`` the platform point. A rotation keeps lengths, so for
*every* configuration that puts the tool point at T — either branch of the head, any assembly of
the legs — whose tilt Q5 lies in its stroke::

    | |T − A_i| − |Q_i| |  ≤  |T − B_i|  ≤  R_i = sqrt((|c2| + Lo·S + |b_xy|)² + (|c1 − b_z| + Lo)²)

(triangle inequality; ``S`` the largest |sin Q5| over Q5's stroke, Q4 free). So where
``|T − A_i| − R_i`` exceeds the slide's upper stroke end, or ``|T − A_i| + R_i`` falls short of
its lower end, every such configuration has that slide beyond its stroke, and one whose Q5 is
not in its stroke is beyond that stroke: no configuration at T is within every stroke. The
rule solves a row's mirror (Q4 + π) when the row is beyond a stroke only to see whether the
mirror alone is within the strokes: at such a target it cannot be. The bound holds for the
nominal geometry (the forms' points); a machine with defects is not judged (every row False).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from pkmkit.model.chains import JointChainModel


def _largest_abs_sine(low: float, high: float) -> float:
    """max |sin q| over ``[low, high]`` (rad; 1 for an unbounded or wide interval)."""
    if not (np.isfinite(low) and np.isfinite(high)) or high - low >= np.pi:
        return 1.0
    peaks = np.arange(np.ceil((low - np.pi / 2) / np.pi), np.floor((high - np.pi / 2) / np.pi)
                      + 1)
    return 1.0 if peaks.size else float(max(abs(np.sin(low)), abs(np.sin(high))))


def mirror_beyond_strokes(params: Mapping[str, Any], model: JointChainModel,
                          targets: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """``(N,)`` bool: no configuration of the TriMule puts its tool point at ``targets[:, :3]``
    (m) with tool lengths ``lengths (N,)`` (m) with every slide (Q1–Q3, L4) and the tilt Q5
    within their strokes (module docstring) — so no head branch there is within the strokes.
    All False for a machine with defects."""
    n = len(targets)
    out = np.zeros(n, dtype=bool)
    if model.defects.any():
        return out
    names = model.variables
    stroke = {name: (model.q_min[names.index(name)], model.q_max[names.index(name)])
              for name in ("Q1", "Q2", "Q3", "L4", "Q5")}
    sine = _largest_abs_sine(*stroke["Q5"])
    reach = np.abs(params["spindle"] + np.asarray(lengths, dtype=float))
    radial = abs(params["c2"]) + reach * sine
    axial = abs(params["c1"]) + reach  # |c1 − b_z + Lo cos Q5| with every b_z = 0
    half_big, half_small = params["L"] / 2, params["l"] / 2
    # (slide, base point A, |b_xy| of the platform point in the platform plane)
    legs = (("Q1", (half_big, 0.0, 0.0), half_small), ("Q2", (0.0, -params["H"], 0.0),
                                                        params["h"]),
            ("Q3", (-half_big, 0.0, 0.0), half_small), ("L4", (0.0, 0.0, 0.0), 0.0))
    point = np.asarray(targets, dtype=float)[:, :3]
    with np.errstate(invalid="ignore"):
        for name, base, planar in legs:
            low, high = stroke[name]
            if not 0 <= low <= high:  # |slide| beyond [low, high] is beyond it only then
                continue
            bound = np.hypot(radial + planar, axial)
            distance = np.linalg.norm(point - np.asarray(base), axis=1)
            out |= (distance - bound > high) | (distance + bound < low)
    return out
