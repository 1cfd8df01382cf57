"""The rod defect Jacobian of a machine that *carries* defects is the derivative of the defect
rule (defects applied to the nominal geometry, :mod:`pkmkit.model.defect_rule`), checked by
central differences of ``with_defects(nominal, δ ± h e_k)``'s direct model.

Far from the nominal geometry two terms matter that vanish at it: an actuator offset dq moves
the carriage by ``(q + dq)`` along a tilted slide (or turns a crank by ``q + dq``), and a
direction tilted past 45° keeps its nominal parametrisation (the component that follows from
the unit norm is the nominal's largest). Linearised on the current rods instead, an
identification far from nominal (readings in a wrong unit) stepped along a wrong Jacobian
(issue 18 §1)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.geometric_errors.model import defect_set, tool_sensitivity
from pkmkit.machines.strokes import stroke_limits
from pkmkit.model.defect_rule import with_defects

#: Large defects: offsets of centimetres (degrees for cranks), a slide/crank axis tilted past
#: 45° (its largest component changes), rod ends moved.
CASES = {
    "linear-delta": {"dq1": 0.05, "du1x": 0.3, "du1y": -0.1, "du2x": 0.8, "dq2": -0.04,
                     "dA3x": 0.01, "dL3": 0.02, "du3y": 0.2, "dq3": 0.03},
    "delta": {"dq1": 0.2, "dw1y": 0.3, "dP1x": 0.01, "dq2": -0.15, "dw2x": 0.3, "dP2z": 0.01,
              "dA3x": 0.005, "dq3": 0.1, "dw3z": 0.1},
    "verne": {"dq1": 0.04, "du1x": 0.3, "dq2": -0.03, "du2y": 0.2, "dA3x": 0.005, "dq3": 0.02},
}


def _fk_point(machine, q: np.ndarray) -> np.ndarray:
    x = np.atleast_2d(machine.fk(q))
    return x[:, :3] if x.shape[1] >= 3 else np.pad(x, ((0, 0), (0, 3 - x.shape[1])))


@pytest.mark.parametrize("machine_id", sorted(CASES))
def test_defect_jacobian_of_a_machine_with_large_defects_is_the_rules(machine_id):
    nominal = pkmkit.machine(machine_id)
    dset = defect_set(nominal)
    delta = dset.vector(CASES[machine_id])
    moved = with_defects(nominal, delta)
    lo, hi = stroke_limits(nominal)
    q = np.atleast_2d(0.5 * (lo + hi))  # mid-stroke: the moved machine assembles there
    assert np.isfinite(q).all()
    analytic = tool_sensitivity(moved, q).point[0]  # (3, d)
    h = 1e-6
    numeric = np.zeros_like(analytic)
    for k in range(len(dset)):
        e = np.zeros(len(dset))
        e[k] = h
        numeric[:, k] = (_fk_point(with_defects(nominal, delta + e), q)[0]
                         - _fk_point(with_defects(nominal, delta - e), q)[0]) / (2 * h)
    err = np.abs(analytic - numeric).max(axis=0)
    worst = int(np.argmax(err))
    assert err[worst] <= 1e-6 * max(1.0, np.abs(numeric).max()), (
        f"{dset.names[worst]}: analytic {analytic[:, worst]}, differences {numeric[:, worst]}")
