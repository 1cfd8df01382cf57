import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.workspace import Criteria, check_region
from pkmkit.design.orthoglide import size_orthoglide
from pkmkit.errors import InputError


def test_seed_001_prototype():
    """Lw = 200 mm with [0.5, 2]: L ≈ 310 mm, stroke ≈ 257 mm, r ≈ 0.78 (seed 001 §4)."""
    res = size_orthoglide(0.2, (0.5, 2.0))
    assert res.L == pytest.approx(0.310, abs=0.001)
    assert res.stroke == pytest.approx(0.257, abs=0.0005)
    assert res.compactness == pytest.approx(0.78, abs=0.003)
    # Q1 and Q2 sit on the diagonal, Lw apart per axis, where the bounds are reached
    np.testing.assert_allclose(res.Q2 - res.Q1, 0.2, atol=1e-12)
    sv1 = res.machine.jacobian(res.Q1).singular_values
    sv2 = res.machine.jacobian(res.Q2).singular_values
    assert max(sv1[0] / 2, 0.5 / sv1[-1]) == pytest.approx(1.0, abs=1e-9)
    assert max(sv2[0] / 2, 0.5 / sv2[-1]) == pytest.approx(1.0, abs=1e-9)
    assert res.check.feasible and res.check.samples == 41**3


def test_independent_brute_force_of_the_whole_cube():
    """Not through the sizing code: a fresh machine, a fresh dense grid over the cube."""
    res = size_orthoglide(0.2, (0.5, 2.0))
    m = pkmkit.machine("orthoglide", L=res.L)
    g = np.linspace(res.Q1[0], res.Q2[0], 31)
    cube = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    sv = np.linalg.svd(m.jacobian(cube).J, compute_uv=False)
    assert sv.min() >= 0.5 - 1e-9 and sv.max() <= 2.0 + 1e-9
    q = m.ik(cube)
    assert (q.min(axis=0) >= res.q_min - 1e-12).all() and (q.max(axis=0) <= res.q_max + 1e-12).all()
    np.testing.assert_allclose(q.min(axis=0), res.q_min, atol=1e-4)
    np.testing.assert_allclose(q.max(axis=0), res.q_max, atol=1e-4)
    # the largest coordinate is reached inside a face (p_i at its maximum, the others at 0)
    top = res.Q2[0] + np.sqrt(res.L**2)
    assert res.q_max[0] == pytest.approx(top, abs=1e-9)
    # the sized machine's strokes are exactly what the cube needs
    assert check_region(res.machine, 0.5 * (res.Q1 + res.Q2), 0.2,
                        Criteria(bounds=(0.5, 2.0))).feasible


def test_scaling_and_bounds_sweep():
    """L scales with Lw; widening the bounds shrinks the machine (Lw/L grows) but the
    compactness Lw/stroke decreases — the seed's claim that r increases is not reproduced."""
    a, b = size_orthoglide(0.2, (0.5, 2.0), samples=15), size_orthoglide(0.4, (0.5, 2.0),
                                                                          samples=15)
    assert b.L == pytest.approx(2 * a.L) and b.compactness == pytest.approx(a.compactness)
    wide = size_orthoglide(0.2, (1 / 3, 3.0), samples=15)
    assert wide.side_over_L > a.side_over_L
    assert wide.compactness < a.compactness
    assert wide.compactness == pytest.approx(0.743, abs=0.002)


@pytest.mark.parametrize(
    "side, bounds, kwargs, message",
    [
        (0.2, (1.2, 2.0), {}, "exclude the isotropic configuration"),
        (0.2, (0.5, 0.9), {}, "exclude the isotropic configuration"),
        (0.2, (2.0, 0.5), {}, "0 < lo < hi"),
        (0.0, (0.5, 2.0), {}, "must be > 0"),
        (0.2, (0.5, 2.0), {"max_leg": 0.25}, "longer than the admissible"),
    ],
)
def test_infeasible_specifications(side, bounds, kwargs, message):
    with pytest.raises(InputError, match=message):
        size_orthoglide(side, bounds, **kwargs)
