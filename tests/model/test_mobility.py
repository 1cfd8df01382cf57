import numpy as np

import pkmkit
from pkmkit.model.mobility import grubler_count
from pkmkit.model.rods import LegSpec, build_rod_model


def test_linear_delta_count_matches_seed_000():
    """Seed 000 L1296-1316: 15 joints (12 S + 3 P), sum f = 39, m_int = 6, m = 3.

    The thesis counts 11 parts "base excluded"; the bodies are 10 moving + the base = 11.
    """
    g = grubler_count(pkmkit.machine("linear-delta").model)
    assert g.bodies == 11 and g.joints == 15 and g.joint_freedoms == 39
    assert g.internal_mobilities == 6 and g.joints_by_type == {"P": 3, "S": 12}
    assert g.mobility == 3 and g.motion_space == 6
    assert 6 * (11 - 1 - 15) + 39 - 6 == g.mobility


def test_planar_parallelogram_five_bar_is_undercounted_by_grubler():
    m = pkmkit.machine("five-bar")
    g = m.mobility()["grubler"]
    inst = m.mobility()["instantaneous"]
    assert g.motion_space == 3 and g.mobility == 1
    assert inst.mobility == 2 and inst.redundant_constraints == 1
    assert inst.platform_freedom_locked == 0


def test_single_rod_delta_leaves_platform_rotation_free():
    """Without parallelograms the rods do not fix the platform orientation."""
    theta = np.radians([0, 120, 240])
    legs = [
        LegSpec(f"leg {i}", i, "slide", base=(0.7 * np.cos(t), 0.7 * np.sin(t), 0),
                platform=(0.15 * np.cos(t), 0.15 * np.sin(t), 0), length=1.3, axis=(0, 0, 1))
        for i, t in enumerate(theta)
    ]
    model = build_rod_model(legs, dims=3, actuator_names=("a", "b", "c"), home_pose=(0, 0, 0))
    m = pkmkit.Machine(id="x", name="x", kind=None, params={}, model=model)
    assert grubler_count(model).mobility == 6 * (5 - 1 - 6) + 3 + 18 - 3 == 6
    inst = m.mobility()["instantaneous"]
    assert inst.mobility == 6 and inst.platform_freedom_locked == 3


def test_strut_hexapod_like_count():
    legs = [LegSpec(f"s{i}", i, "strut", base=np.eye(3)[i], platform=(0, 0, 0), length=1.0)
            for i in range(3)]
    model = build_rod_model(legs, dims=3, actuator_names=("a", "b", "c"), home_pose=(0, 0, 0))
    g = grubler_count(model)
    # 1 base + 1 platform + 3 x (cylinder + piston); joints U, P, S per strut
    assert g.bodies == 8 and g.joints == 9 and g.joint_freedoms == 18 and g.mobility == 6
