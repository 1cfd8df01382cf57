"""Identifiable parameters, gauges and the compatible subspace: synthetic matrices with known
structure, and the Tripteor X7 against the structural facts of seed 002 (notes §3.9, §4.5)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration.identifiability import (
    compatible_directions,
    identifiable_parameters,
    prune_weak,
)
from pkmkit.calibration.simulate import default_configurations
from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.model import defect_set, tool_sensitivity


def test_dependent_and_zero_columns_are_reported_with_their_combination():
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((2, 40))
    scale = np.array([1e-4, 1e-3, 1e-4, 1e-4])
    # columns in SI: c = 2 a + 0.5 b (a combination), z = 0 (no effect)
    jac = np.column_stack([a, b, 2 * a + 0.5 * b, np.zeros(40)])
    ident = identifiable_parameters(jac, ["a", "b", "c", "z"], scale)
    assert ident.rank == 2
    assert ident.reasons["z"] == "no effect on these measurements"
    unselected = [n for n in ("a", "b", "c") if n not in ident.selected_names]
    assert len(unselected) == 1
    name = unselected[0]
    assert "combination" in ident.reasons[name]
    # the reported coefficients rebuild the column exactly (SI units)
    deps = ident.dependencies[name]
    rebuilt = sum(c * jac[:, "abcz".index(n)] for n, c in deps.items())
    np.testing.assert_allclose(rebuilt, jac[:, "abcz".index(name)], atol=1e-12)
    # base values: the selected ones absorb the dependent one (c = 2a + 0.5b)
    values = np.array([1.0, 2.0, 3.0, 4.0])
    base = ident.base_values(values)
    np.testing.assert_allclose(jac[:, ident.selected] @ base, jac @ values, atol=1e-10)


def test_priority_groups_make_gauges_of_later_columns():
    rng = np.random.default_rng(1)
    frame = rng.standard_normal((30, 2))
    machine = np.column_stack([frame[:, 0] * 3.0, rng.standard_normal(30)])
    jac = np.column_stack([frame, machine])
    ident = identifiable_parameters(jac, ["f1", "f2", "m1", "m2"], np.ones(4),
                                    groups=[0, 0, 1, 1], group_labels={0: "the frame"})
    assert set(ident.selected_names) == {"f1", "f2", "m2"}
    assert ident.reasons["m1"].startswith("gauge: absorbed by the frame")
    np.testing.assert_allclose(ident.dependencies["m1"]["f1"], 3.0)


def test_rank_threshold_is_relative_to_tolerance_scaled_columns():
    base = np.linspace(0, 1, 20)
    jac = np.column_stack([base, base + 1e-9 * np.cos(7 * base)])
    assert identifiable_parameters(jac, ["a", "b"], np.ones(2), rcond=1e-7).rank == 1
    assert identifiable_parameters(jac, ["a", "b"], np.ones(2), rcond=1e-12).rank == 2
    with pytest.raises(InputError, match="non-finite"):
        identifiable_parameters(np.array([[np.nan]]), ["a"], np.ones(1))
    with pytest.raises(InputError):
        identifiable_parameters(np.ones((3, 2)), ["a"], np.ones(2))


def test_compatible_directions_name_the_conditions():
    # conditions: δ1 − δ2 = 0 and δ3 = 0 (any scaling of the rows)
    rows = np.array([[1.0, -1.0, 0.0, 0.0], [0.0, 0.0, 5.0, 0.0], [2.0, -2.0, 1.0, 0.0]])
    comp = compatible_directions(rows, ["d1", "d2", "d3", "d4"], np.ones(4))
    assert comp.basis.shape == (4, 2)
    np.testing.assert_allclose(rows @ comp.basis, 0.0, atol=1e-12)
    assert "d3" in {["d1", "d2", "d3", "d4"][k] for k in comp.dependent}
    assert comp.describe("d3").endswith("must be 0)")
    dep = next(n for n in comp.relations if n in ("d1", "d2"))
    other = "d2" if dep == "d1" else "d1"
    assert comp.relations[dep] == pytest.approx({other: 1.0})


def test_prune_weak_drops_what_noise_hides():
    jac = np.diag([10.0, 0.5, 3.0])
    out = prune_weak(jac, np.ones(3), sigma=1.0)
    assert list(out.kept) == [0, 2]
    assert out.dropped[1][0] == pytest.approx(2.0)
    assert list(prune_weak(jac, np.ones(3), sigma=1.0, keep=[1]).kept) == [0, 1, 2]


@pytest.fixture(scope="module")
def tripteor_jacobians():
    m = pkmkit.machine("tripteor-x7")
    q = default_configurations(m, 60, np.random.default_rng(2))
    tools = np.where(np.arange(60) % 2, 0.110006, 0.169889)
    sens = tool_sensitivity(m, q, tool_length=tools)
    return m, sens


def test_tripteor_compatibility_has_fourteen_conditions(tripteor_jacobians):
    """Notes §3.9: with positions, 14 independent conditions (the 12 orientation conditions of
    Table 4.6 for legs 1/3 plus the ψ1/ψ3 collinearity da13 = dc13 = 0)."""
    m, sens = tripteor_jacobians
    ds = defect_set(m)
    scale = np.array([1e-4 if u == "m" else 5e-3 for u in ds.units])
    comp = compatible_directions(sens.closure_defect, ds.names, scale)
    assert comp.dependent.size == 14
    # the leg-1/leg-3 orientation conditions of Table 4.6 are among the fixed directions:
    # each of them has no compatible component on its own
    for name in ("dK41", "dI51", "dK51", "dI53", "dK53"):
        k = ds.index(name)
        assert np.allclose(comp.basis[k], 0.0, atol=1e-9), name
    # leg 2 is not in the hyperstatic loop: its defects are all free (notes §3.9)
    leg2 = [n for n in ds.names if n[-2:] in ("12", "22", "32", "42", "52", "62")]
    assert all(ds.index(n) in set(comp.free) for n in leg2)


def test_tripteor_pose_insensitive_defects_match_seed_002(tripteor_jacobians):
    """Notes §4.5: exactly these defects do not move the tool point (passive joints absorb
    them): J21, J41, a51, J12, K12, J22, K22, J32, K32, I42, J42, I52, a52, J23, J43, a53 —
    plus the tool frame's spin about its own axis."""
    m, sens = tripteor_jacobians
    ds = defect_set(m)
    scale = np.array([1e-4 if u == "m" else 5e-3 for u in ds.units])
    ident = identifiable_parameters(sens.stacked("point"), ds.names, scale)
    none = {n for n, r in ident.reasons.items() if r.startswith("no effect")}
    expected = {"dJ21", "dJ41", "da51", "dJ12", "dK12", "dJ22", "dK22", "dJ32", "dK32", "dI42",
                "dJ42", "dI52", "da52", "dJ23", "dJ43", "da53", "dST"}
    assert none == expected
