import numpy as np
import pytest

import pkmkit
from pkmkit.model.rods import LegSpec, build_rod_model
from pkmkit.solve.rod_closure import (
    _pose_columns,
    _q_columns,
    _unit_rods,
    rod_vectors,
    split_pose,
)
from pkmkit.spatial.rotation import compose_rotvec


def mixed_model():
    """Two slide legs (one a parallelogram) and a strut, offsets everywhere."""
    legs = [
        LegSpec("a", 0, "slide", base=(0.6, 0.1, 0.0), platform=(0.1, 0.05, 0.02), length=1.1,
                axis=(0.1, 0.2, 1.0), parallelogram_width=0.1, parallelogram_direction=(0, 1, 0)),
        LegSpec("b", 1, "slide", base=(-0.3, 0.5, 0.1), platform=(-0.05, 0.1, 0.0), length=1.0,
                axis=(0.0, 0.3, 1.0)),
        LegSpec("c", 2, "strut", base=(-0.3, -0.5, 1.2), platform=(0.0, -0.1, 0.0), length=0.9),
    ]
    return build_rod_model(legs, dims=3, actuator_names=("q1", "q2", "q3"), home_pose=(0, 0, 0))


def residual(model, u, q, dof):
    p, rot = split_pose(model, u, dof)
    v = rod_vectors(model, p, q, rot)
    return v.dist - v.length


@pytest.mark.parametrize("dof", ["translation", "full"])
def test_pose_jacobian_matches_finite_differences(dof):
    model = mixed_model()
    rng = np.random.default_rng(0)
    n = 3 if dof == "translation" else 6
    u = np.concatenate([rng.normal(0, 0.1, (3, 4)), rng.normal(0, 0.3, (n - 3, 4))])
    q = rng.normal(1.0, 0.1, (3, 4))
    p, rot = split_pose(model, u, dof)
    v = rod_vectors(model, p, q, rot)
    jac = _pose_columns(model, v, _unit_rods(v), dof)  # (m, n, k)
    h = 1e-7
    for j in range(n):
        step = np.zeros((n, 4))
        step[j] = h
        if j < 3:
            up, um = u + step, u - step
        else:  # left rotation increment
            up, um = u.copy(), u.copy()
            up[3:] = compose_rotvec(step[3:].T, u[3:].T).T
            um[3:] = compose_rotvec(-step[3:].T, u[3:].T).T
        fd = (residual(model, up, q, dof) - residual(model, um, q, dof)) / (2 * h)
        np.testing.assert_allclose(jac[:, j], fd, atol=1e-7)


def test_q_jacobian_matches_finite_differences():
    model = mixed_model()
    rng = np.random.default_rng(1)
    u = rng.normal(0, 0.1, (3, 5))
    q = rng.normal(1.0, 0.1, (3, 5))
    v = rod_vectors(model, u, q)
    jac = _q_columns(model, _unit_rods(v), q)
    h = 1e-7
    for j in range(3):
        dq = np.zeros((3, 5))
        dq[j] = h
        fd = (residual(model, u, q + dq, "translation") -
              residual(model, u, q - dq, "translation")) / (2 * h)
        np.testing.assert_allclose(jac[:, j], fd, atol=1e-7)


def test_rotation_is_recovered_when_rods_fix_it():
    """Parallelogram legs fix the orientation: a full-pose solve returns R = I."""
    m = pkmkit.machine("linear-delta")
    q = m.ik([[0.1, -0.2, 0.3]])
    res = m.fk(q, method="numeric", dof="full", full_output=True)
    np.testing.assert_allclose(res.rotation, 0.0, atol=1e-12)
    np.testing.assert_allclose(res.pose, [[0.1, -0.2, 0.3]], atol=1e-12)


def test_inverse_with_a_rotated_platform():
    """solve_inverse with platform rotations R: every rod closes, |p + R b − a(q)| = ℓ, checked
    here from the model's points (and the answer differs from the unrotated one)."""
    from pkmkit.solve.rod_closure import solve_inverse
    from pkmkit.spatial.rotation import rotvec_to_matrix

    legs = [
        LegSpec("a", 0, "slide", base=(0.6, 0.1, 0.0), platform=(0.1, 0.05, 0.02), length=1.1,
                axis=(0.1, 0.2, 1.0)),
        LegSpec("b", 1, "slide", base=(-0.3, 0.5, 0.1), platform=(-0.05, 0.1, 0.0), length=1.0,
                axis=(0.0, 0.3, 1.0)),
        LegSpec("c", 2, "strut", base=(-0.3, -0.5, 1.2), platform=(0.0, -0.1, 0.0), length=0.9),
    ]
    model = build_rod_model(legs, dims=3, actuator_names=("q1", "q2", "q3"),
                            home_pose=(0, 0, 0))
    rng = np.random.default_rng(5)
    pose = rng.normal(0, 0.05, (4, 3))
    rot = rotvec_to_matrix(rng.normal(0, 0.1, (4, 3)))
    q0 = np.ones((4, 3))
    res = solve_inverse(model, pose, q0, rotation=rot)
    plain = solve_inverse(model, pose, q0)
    assert (res.status == 0).all() and np.abs(res.u - plain.u).max() > 1e-3
    q = res.u
    for k in range(4):
        for j in range(model.n_rods):
            i = model.rod_actuator[j]
            a = model.rod_base[j] + (q[k, i] * model.rod_axis[j] if model.rod_kind[j] == 0
                                     else 0.0)
            length = model.rod_length[j] + (q[k, i] if model.rod_kind[j] != 0 else 0.0)
            tip = pose[k] + rot[k] @ model.rod_platform[j]
            assert np.linalg.norm(tip - a) == pytest.approx(length, abs=1e-12)


@pytest.mark.parametrize("name", ["delta", "linear-delta"])
def test_defect_columns_match_central_differences_of_the_exact_model(name):
    """∂r/∂δ of every rod defect (base points, crank pivots and axes, slide directions,
    offsets, lengths) against central differences of the residual of the machine with the
    defect applied exactly, at poses away from home."""
    from pkmkit.geometric_errors.model import _rod_index, with_defects
    from pkmkit.solve.rod_closure import defect_columns

    m = pkmkit.machine(name)
    index = _rod_index(m)
    x = np.atleast_2d(m.home_pose)[:, :3] + np.array([[0.02, -0.03, 0.01], [-0.01, 0.02, 0.03]])
    q = np.asarray(m.ik(x, strokes="ignore"))
    _, cols = defect_columns(m.model, index, x, None, q)
    h = 1e-6
    for i in range(len(index)):
        step = np.zeros(len(index))
        step[i] = h
        plus = defect_columns(with_defects(m, step).model, index, x, None, q)[0]
        minus = defect_columns(with_defects(m, -step).model, index, x, None, q)[0]
        np.testing.assert_allclose(cols[:, :, i], (plus - minus) / (2 * h), atol=1e-8,
                                   err_msg=index.names[i])
