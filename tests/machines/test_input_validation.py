"""Bad and edge-case input: typed errors, flagged rows, no warnings, no silent wrong numbers."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError, NoAssemblyError, ParameterError
from pkmkit.status import Status
from tests.conftest import random_poses


@pytest.fixture(scope="module")
def delta():
    return pkmkit.machine("linear-delta")


def test_jacobian_rejects_q_that_does_not_fit_the_pose():
    ortho = pkmkit.machine("orthoglide")
    with pytest.raises(InputError, match="misses its length"):
        ortho.jacobian([0, 0, 0], q=[0.5, 0.5, 0.5])
    with pytest.raises(InputError, match="not finite"):
        ortho.jacobian([0, 0, 0], q=[np.nan] * 3)
    batch = ortho.jacobian([[0, 0, 0], [0, 0, 0]], q=[[0.31] * 3, [0.5] * 3])
    assert batch.status == ["regular", "unreachable"] and np.isnan(batch.J[1]).all()
    with pytest.raises(InputError, match="not finite"):
        ortho.jacobian_dot([0, 0, 0], [np.nan] * 3)
    with pytest.raises(InputError, match=r"^q\b"):  # the message names the argument
        ortho.jacobian([0, 0, 0], q=[0.31, 0.31])


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda m: m.ik([0, 0, 0], branches="ab"), "branches"),
        (lambda m: m.ik([0, 0, 0], branches=[1.5, 1, 1]), "branches"),
        (lambda m: m.ik([0, 0, 0], branches=[True, 1, 1]), "branches"),
        (lambda m: m.fk(m.home_q, mode=np.array([1, 1])), "unknown assembly mode"),
        (lambda m: m.fk(m.home_q, mode=True), "unknown assembly mode"),
        (lambda m: m.fk(m.home_q, method="numeric", dof="rot"), "dof"),
        (lambda m: m.fk(np.stack([m.home_q] * 3), method="numeric", x0=np.zeros((2, 3))),
         "rows"),
        (lambda m: m.ik(np.zeros((3, 3)), method="numeric", q0=np.ones((2, 3))), "rows"),
        (lambda m: m.jacobian([0, 0, 0], tol="a"), "tol"),
        (lambda m: m.jacobian([0, 0, 0], tol=float("nan")), "tol"),
        (lambda m: m.jacobian([0, 0, 0], tol=-1.0), "tol"),
        (lambda m: m.ik([1e200, 0, 0]), "beyond"),
        (lambda m: m.fk([1e200, 1, 1]), "beyond"),
    ],
)
def test_typed_api_errors(delta, call, message):
    with pytest.raises(InputError, match=message):
        call(delta)


def test_mode_given_as_sign_string(delta):
    other = delta.fk(delta.home_q, mode="other")
    np.testing.assert_allclose(delta.fk(delta.home_q, mode="1"), other)
    np.testing.assert_allclose(delta.fk(delta.home_q, mode=-1 * delta.working_mode), other)
    np.testing.assert_allclose(delta.fk(delta.home_q, mode="-1"), delta.home_pose, atol=1e-12)


def test_non_finite_and_huge_rows_are_flagged_without_warnings(delta):
    q = np.array([[np.inf] * 3, delta.home_q, [1e200, 1.0, 1.0]])
    assert delta.fk(q, full_output=True).status.tolist() == [
        Status.INVALID_INPUT, Status.OK, Status.INVALID_INPUT]
    assert delta.fk_all(q).status.tolist() == [Status.INVALID_INPUT, Status.OK,
                                               Status.INVALID_INPUT]
    numeric = delta.fk(q, method="numeric", full_output=True)
    assert numeric.status.tolist() == [Status.INVALID_INPUT, Status.OK, Status.INVALID_INPUT]
    x = np.array([[np.inf, 0, 0], [0, 0, 0], [1e200, 0, 0]])
    for method in ("closed", "numeric"):
        res = delta.ik(x, method=method, full_output=True)
        assert res.status.tolist() == [Status.INVALID_INPUT, Status.OK, Status.INVALID_INPUT]


def test_unreachable_far_pose_reports_a_finite_shortfall(delta):
    with pytest.raises(pkmkit.UnreachablePoseError) as info:
        delta.ik([1e8, 0, 0])
    assert np.isfinite(info.value.shortfall) and info.value.shortfall > 9e7


def test_boundary_poses_are_reachable():
    """Poses exactly on the workspace boundary (a leg perpendicular to its slide) must not be
    rejected because the radicand rounds to -1e-17."""
    ortho = pkmkit.machine("orthoglide")
    length = ortho.params["L"]
    rng = np.random.default_rng(0)
    angle = rng.uniform(0.2, 1.3, 200)
    x = np.column_stack([rng.uniform(0.0, 0.05, 200), length * np.cos(angle),
                         length * np.sin(angle)])
    res = ortho.ik(x, full_output=True)
    reach = res.shortfall.max(axis=1) <= 0
    assert (res.status[reach] == Status.OK).all()
    assert reach.sum() > 100
    np.testing.assert_allclose(res.q[reach, 0], x[reach, 0], atol=1e-7)
    jac = ortho.jacobian(x[reach][0])
    assert "serial" in jac.status


def test_configurations_in_the_other_assembly_mode_are_reported():
    """A pose the inverse model reaches may lie beyond a parallel singularity (other mode):
    the result says so, and fk in that mode returns the pose."""
    ortho = pkmkit.machine("orthoglide")
    x = np.array([0.15, 0.15, 0.15])  # past the singularity at L/√6 on the diagonal
    res = ortho.ik(x, full_output=True)
    assert res.status == Status.OK and res.mode == -ortho.working_mode
    assert not np.allclose(ortho.fk(res.q), x)
    np.testing.assert_allclose(ortho.fk(res.q, mode=int(res.mode)), x, atol=1e-12)
    assert ortho.jacobian(x).mode == -ortho.working_mode


def test_strut_lengths_cannot_be_negative(tmp_path):
    path = tmp_path / "struts.toml"
    path.write_text(
        '[machine]\nkind = "rod-legs"\nhome = [0, 0, -0.8]\n'
        + "".join(f'[[legs]]\ntype = "strut"\nbase = [{np.cos(a):.6f}, {np.sin(a):.6f}, 0]\n'
                  "platform = [0, 0, 0]\nlength = 1.2\n"
                  for a in np.radians([0.0, 120.0, 240.0]))
    )
    m = pkmkit.load(path)
    # a file machine without a name is named after its file, and has no description
    assert m.id == m.name == "struts" and m.description == m.source == ""
    # struts are never too short: their shortfall is −inf whatever the pose
    far = m.ik([[0.0, 0.0, -0.8], [5.0, 0.0, -0.8]], full_output=True)
    assert (far.shortfall == -np.inf).all() and far.status.tolist() == [Status.OK] * 2
    q = m.home_q.copy()
    q[:2] -= 1.4  # rod lengths 1.2 + q < 0
    assert m.fk(q[None], full_output=True).status[0] == Status.NO_ASSEMBLY
    with pytest.raises(NoAssemblyError):
        m.fk(q)
    assert m.fk_all(q).count == 0


@pytest.mark.parametrize(
    "ident, params, message",
    [
        ("linear-delta", {"R": 0.1500001}, "parallel singularity"),
        ("linear-delta", {"angles": (0.0, 1e-7, 4.18)}, "distinct|singularity"),
        ("five-bar", {"alpha2": 1e-4}, "nearly parallel"),
        ("linear-delta", {"L": 1e300}, "beyond"),
        ("linear-delta", {"L": True}, "numeric"),
    ],
)
def test_near_degenerate_dimensions_are_refused(ident, params, message):
    with pytest.raises(ParameterError, match=message):
        pkmkit.machine(ident, **params)


def test_numeric_solutions_in_other_modes_and_branches(delta):
    x = random_poses(delta, 20, seed=4)
    q = delta.ik(x)
    other = delta.fk_all(q).poses[:, 1]
    res = delta.fk(q, method="numeric", mode="other", full_output=True)
    assert (res.status == Status.OK).all()
    np.testing.assert_allclose(res.pose, other, atol=1e-9)
    # the engine reports its work per row: a few Gauss–Newton steps each
    assert res.iterations.shape == (20,) and (res.iterations >= 1).all()
    assert (res.iterations < 50).all()
    branches = [1, -1, 1]
    closed = delta.ik(x, branches=branches)
    numeric = delta.ik(x, method="numeric", branches=branches, full_output=True)
    assert (numeric.status == Status.OK).all()
    np.testing.assert_allclose(numeric.q, closed, atol=1e-9)


def test_biglide_home_carriages_lie_on_the_rails():
    m = pkmkit.machine("five-bar-biglide")
    jac = m.jacobian(m.home_pose)
    carriages = m.home_pose - jac.A
    np.testing.assert_allclose(carriages[:, 1], 0.0, atol=1e-15)
    # parallelogram offsets perpendicular to the legs
    offsets = m.model.rod_platform[m.model.rod_leg == 0]
    assert abs(np.dot(offsets[0, :2], jac.A[0])) < 1e-15


def test_direct_model_near_parallel_singularity_is_flagged_not_wrong():
    """Found by fuzzing: Orthoglide carriages all near q = 0 put the sphere centres nearly
    together; rounding then gave a 'solution' 1 mm off every leg. Such rows are flagged."""
    import pkmkit
    from pkmkit.status import Status

    m = pkmkit.machine("orthoglide")
    q = np.array([[1e-5, 0.0, 1e-12], [0.31, 0.31, 0.31]])
    modes = m.fk_all(q)
    assert modes.status[0] == Status.SINGULAR and not modes.valid[0].any()
    assert modes.status[1] == Status.OK
    res = m.fk(q, full_output=True)
    assert res.status[0] == Status.SINGULAR and np.isnan(res.pose[0]).all()
    with pytest.raises(pkmkit.SingularConfigurationError, match="nearly"):
        m.fk(q[0])
