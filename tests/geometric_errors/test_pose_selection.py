"""Pose selection: better than random, reproducible, and the reported index is the index of
the chosen poses."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import IdentifiabilityError, InputError
from pkmkit.geometric_errors.identifiability import identifiability
from pkmkit.geometric_errors.pose_selection import select_poses


@pytest.mark.parametrize("index", ["O1", "O3", "O5"])
def test_selection_beats_random_and_reports_its_own_index(index):
    m = pkmkit.machine("linear-delta")
    sel = select_poses(m, "point", 10, index=index, parameters="dL*,dq*,du*", n_candidates=150)
    assert sel.gain > 1.2
    assert sel.value >= sel.greedy_value
    assert sel.value > sel.random_values.max()
    # the index recomputed from scratch on the chosen poses
    again = identifiability(m, "point", sel.q, parameters="dL*,dq*,du*")
    assert again.indices[index] == pytest.approx(sel.value, rel=1e-9)
    # the JSON summary reports the request and the result under its documented keys
    s = sel.summary()
    assert (s["n_poses"], s["n_candidates"], s["index"]) == (10, 150, index)
    assert s["value"] == sel.value and s["chosen"] == sel.chosen.tolist()


def test_bad_requests():
    m = pkmkit.machine("linear-delta")
    with pytest.raises(InputError, match="unknown index"):
        select_poses(m, "point", 5, index="O9")
    with pytest.raises(IdentifiabilityError, match="choose at least"):
        select_poses(m, "height", 3, parameters="dL*,dq*,du*", n_candidates=60)
    with pytest.raises(InputError, match="candidates"):
        select_poses(m, "point", 5, candidates=np.atleast_2d(m.home_q))
