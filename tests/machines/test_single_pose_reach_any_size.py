"""A single pose and a batch agree on where a machine's reach ends, for a Delta robot of any
size (issue 18 §9, plausible bugs: the crank's boundary tolerance of the single-pose path
divided by ℓ² instead of multiplied by it passed every test, all at the built-in size; on a
Delta of a thousandth of that size it answered poses 10⁻³ beyond the reach).

The reach along a ray from home is found by bisection with the batch path; a similarity
leaves it at the same fraction of the size (oracle: the 1 m robot's, times the scale)."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import UnreachablePoseError

SIZES = {"R": 0.2, "r": 0.045, "arm": 0.35, "forearm": 0.8, "parallelogram_width": 0.06}
RAY = np.array([0.6, 0.3, -1.0]) / np.linalg.norm([0.6, 0.3, -1.0])


def _delta(scale: float):
    return pkmkit.machine("delta").with_params(**{k: v * scale for k, v in SIZES.items()})


def _reach(m, scale: float) -> float:
    """Distance from home along RAY where the batch's inverse model stops (bisection)."""
    lo, hi = 0.0, 3.0 * scale
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        status = m.ik((m.home_pose + mid * RAY)[None], full_output=True,
                      strokes="ignore").status[0]
        lo, hi = (mid, hi) if status == 0 else (lo, mid)
    return lo


@pytest.fixture(scope="module")
def reach_1m():
    return _reach(_delta(1.0), 1.0)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_single_pose_and_batch_agree_at_the_reach(scale, reach_1m):
    m = _delta(scale)
    reach = _reach(m, scale)
    assert reach == pytest.approx(reach_1m * scale, rel=1e-9)
    inside = m.home_pose + reach * (1 - 1e-9) * RAY
    q_batch = m.ik(inside[None], strokes="ignore")[0]
    np.testing.assert_allclose(m.ik(inside, strokes="ignore"), q_batch, rtol=1e-9,
                               atol=1e-12)
    for beyond in (1e-7, 1e-5, 1e-3):
        pose = m.home_pose + reach * (1 + beyond) * RAY
        assert m.ik(pose[None], full_output=True, strokes="ignore").status[0] != 0
        with pytest.raises(UnreachablePoseError):
            m.ik(pose, strokes="ignore")
