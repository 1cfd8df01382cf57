import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import ParameterError
from pkmkit.model.rods import SLIDE, STRUT, LegSpec, build_rod_model


def legs3(**changes):
    legs = [
        LegSpec(f"leg {i + 1}", i, "slide", base=np.eye(3)[i], platform=(0, 0, 0), length=1.0,
                axis=np.eye(3)[i])
        for i in range(3)
    ]
    if changes:
        legs[0] = LegSpec(**{**legs[0].__dict__, **changes})
    return legs


def test_parallelogram_makes_two_offset_rods():
    legs = legs3(parallelogram_width=0.2, parallelogram_direction=(0, 0, 2))
    model = build_rod_model(legs, dims=3, actuator_names=("a", "b", "c"), home_pose=(0, 0, 0))
    assert model.n_rods == 4 and model.n_legs == 3
    first = model.rod_leg == 0
    np.testing.assert_allclose(model.rod_base[first] - model.rod_platform[first],
                               np.tile(model.leg_base[0] - model.leg_platform[0], (2, 1)))
    np.testing.assert_allclose(model.rod_platform[first][:, 2], [-0.1, 0.1])
    assert model.rod_kind.tolist() == [SLIDE] * 4
    # the documented integer columns, and the default pose names
    for column in (model.leg_kind, model.rod_kind, model.rod_leg, model.leg_actuator):
        assert column.dtype.kind == "i"
    assert model.pose_names == ("x", "y", "z")
    named = build_rod_model(legs, dims=3, actuator_names=("a", "b", "c"), home_pose=(0, 0, 0),
                            pose_names=("u", "v", "w"))
    assert named.pose_names == ("u", "v", "w")
    with pytest.raises(ValueError):
        model.leg_base[0, 0] = 3.0  # immutable


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"kind": "rotary"}, "kind must be one of"),
        ({"kind": "crank"}, "pivot must be 3 finite numbers"),
        ({"axis": (0, 0, 0)}, "zero vector"),
        ({"axis": (1, 0)}, "3 finite numbers"),
        ({"platform": (1, 0)}, r"^legs\.0\.platform must be"),
        ({"base": (0, np.nan, 0)}, r"^legs\.0\.base must be"),
        ({"length": -1.0}, "length must be > 0"),
        ({"branch": 2}, "branch must be"),
        ({"parallelogram_width": -1.0}, "width must be >= 0"),
    ],
)
def test_invalid_legs(changes, message):
    with pytest.raises(ParameterError, match=message):
        build_rod_model(legs3(**changes), dims=3, actuator_names=("a", "b", "c"),
                        home_pose=(0, 0, 0))


def test_counts_and_planar_geometry_checked():
    with pytest.raises(ParameterError, match="exactly one leg"):
        build_rod_model(legs3()[:2], dims=3, actuator_names=("a", "b", "c"), home_pose=(0, 0, 0))
    raised = [LegSpec(f"leg {i}", i, "slide", base=(i, 0, 0.5), platform=(0, 0, 0), length=1.0,
                      axis=(1, 0, 0)) for i in range(2)]
    with pytest.raises(ParameterError, match="z = 0"):
        build_rod_model(raised, dims=2, actuator_names=("a", "b"), home_pose=(0, 0))
    with pytest.raises(ParameterError, match="home pose"):
        build_rod_model(legs3(), dims=3, actuator_names=("a", "b", "c"), home_pose=(0, 0))


def test_strut_has_no_axis():
    legs = [LegSpec(f"s{i}", i, "strut", base=np.eye(3)[i], platform=(0, 0, 0), length=1.0)
            for i in range(3)]
    model = build_rod_model(legs, dims=3, actuator_names=("a", "b", "c"), home_pose=(0, 0, 0))
    assert (model.leg_kind == STRUT).all() and not model.leg_axis.any()


def test_pad_gives_the_platform_position_of_every_kind_of_pose():
    """Positions (N, 3): a full pose's first three coordinates, a planar pose with z = 0."""
    full = pkmkit.machine("gough-stewart").model
    np.testing.assert_array_equal(full.pad(np.array([[1.0, 2.0, 3.0, 0.1, 0.2, 0.3]])),
                                  [[1.0, 2.0, 3.0]])
    planar = pkmkit.machine("five-bar").model
    np.testing.assert_array_equal(planar.pad(np.array([[1.0, 2.0]])), [[1.0, 2.0, 0.0]])
