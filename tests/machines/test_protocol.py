"""One machine protocol (issue 19): every built-in machine and a machine file of each family
answers the same calls with the same conventions and result shapes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError
from pkmkit.machines.protocol import FAMILIES

EXAMPLES = str(Path(__file__).resolve().parents[2] / "docs" / "examples") + "/"
FILES = {"my-machine.toml": "translational", "hexapod-6-6.toml": "full-pose",
         "planar-3rpr.toml": "chain"}
ATTRIBUTES = ("ik", "fk", "jacobian", "with_params", "mobility", "default_box",
              "reference_poses", "home_pose", "home_q", "pose_names", "actuator_names",
              "actuator_quantities", "angular_actuators", "dims", "n_actuators", "family")


def _machines():
    for name in pkmkit.machines():
        yield pytest.param(lambda name=name: pkmkit.machine(name), id=name)
    for file in FILES:
        yield pytest.param(lambda file=file: pkmkit.load(EXAMPLES + file), id=file)


@pytest.fixture(params=list(_machines()))
def machine(request):
    return request.param()


def test_every_machine_answers_the_protocol(machine):
    missing = [a for a in ATTRIBUTES if not hasattr(machine, a)]
    assert missing == []
    assert machine.family in FAMILIES
    n = machine.n_actuators
    assert len(machine.actuator_names) == n == len(machine.actuator_quantities)
    assert set(machine.actuator_quantities) <= {"length", "angle"}
    np.testing.assert_array_equal(machine.angular_actuators,
                                  [q == "angle" for q in machine.actuator_quantities])
    assert machine.home_q.shape == (n,)


def test_home_round_trip_with_the_same_shapes(machine):
    """ik of one pose gives (n,), of a batch (N, n); fk the reverse; home maps to home."""
    n = machine.n_actuators
    q = machine.ik(machine.home_pose)
    assert q.shape == (n,)
    np.testing.assert_allclose(q, machine.home_q, atol=1e-7)
    batch = machine.ik(np.vstack([machine.home_pose] * 3))
    assert batch.shape == (3, n)
    x = machine.fk(machine.home_q)
    assert x.shape == machine.home_pose.shape
    assert machine.fk(np.vstack([machine.home_q] * 2)).shape == (2, *machine.home_pose.shape)


def test_non_finite_input_is_a_typed_error(machine):
    bad = np.full(machine.home_pose.shape, np.nan)
    with pytest.raises(InputError):
        machine.ik(bad)
    with pytest.raises(InputError):
        machine.fk(np.full(machine.n_actuators, np.inf))


@pytest.mark.parametrize(("file", "family"), FILES.items())
def test_machine_files_of_each_family(file, family):
    assert pkmkit.load(EXAMPLES + file).family == family


# ---------------------------------------------------------------- one method set, one result type
PROTOCOL_METHODS = ("ik", "fk", "fk_all", "jacobian", "jacobian_dot", "joint_motion",
                    "in_working_mode", "with_params", "mobility", "default_box",
                    "reference_poses", "tool_frames", "tool_frames_linearised", "tool_inverse",
                    "tool_targets", "measurement_configurations", "unreachable_reason",
                    "out_of_stroke_reason", "inverse_rows")
PROTOCOL_PROPERTIES = ("home_pose", "home_q", "pose_names", "actuator_names",
                       "actuator_quantities", "angular_actuators", "dims", "n_actuators",
                       "family", "position_controlled", "six_dof", "closed_form_inverse",
                       "orientation_fixed", "length_scale",
                       "incompatible_defects", "kind", "id", "name", "model", "description",
                       "source", "tool_length", "default_tool_lengths", "export_layout",
                       "velocity_split", "measures_machined_parts")
#: What the geometric error analyses ask a machine (machines/error_faces.py, issue 19 §1).
ERROR_METHODS = ("closure_linearisation", "tool_sensitivity", "nominal_sensitivity",
                 "held_tool_actuators", "region_names", "region_sizes", "default_region",
                 "configurations_at", "mechanism_configurations", "loop_defect_mask",
                 "reference_joint_defect_mask", "sampled_tool_points", "tool_readings",
                 "part_actuators", "part_sensitivity")


def test_every_machine_answers_the_same_method_set(machine):
    for name in PROTOCOL_METHODS + ERROR_METHODS:
        assert callable(getattr(machine, name)), name
    for name in PROTOCOL_PROPERTIES:
        getattr(machine, name)  # no AttributeError, for every family
    assert isinstance(machine.position_controlled, bool)
    assert machine.orientation_fixed == (machine.dims < 6)
    assert np.isfinite(machine.length_scale) and machine.length_scale > 0
    for flag in ("six_dof", "closed_form_inverse", "incompatible_defects", "orientation_fixed",
                 "measures_machined_parts"):
        assert isinstance(getattr(machine, flag), bool), flag
    assert not (machine.six_dof and machine.position_controlled)
    from pkmkit.machines.export_layouts import EXPORT_LAYOUTS

    assert machine.export_layout in EXPORT_LAYOUTS
    assert isinstance(machine.velocity_split, bool)
    assert isinstance(machine.tool_length, float) and machine.tool_length >= 0
    assert machine.default_tool_lengths is None or all(
        length > 0 for length in machine.default_tool_lengths)
    assert isinstance(machine.description, str) and isinstance(machine.source, str)


def test_the_geometric_error_calls_give_the_same_result_types(machine):
    """The calls geometric_errors makes instead of testing the family: the same records and
    shapes on every family, consistent with one another at home."""
    from pkmkit.machines.defect_linearisation import ClosureLinearisation, ToolSensitivity

    n, d = machine.n_actuators, len(machine.defects())
    q = machine.home_q[None]
    sens = machine.tool_sensitivity(q)
    assert isinstance(sens, ToolSensitivity)
    assert sens.point.shape == sens.rotation.shape == (1, 3, d) and sens.pose.shape == (1, 6)
    lin = machine.closure_linearisation(machine.home_q)
    assert isinstance(lin, ClosureLinearisation)
    assert lin.defects.shape[::2] == (1, d) and lin.unknowns.shape[:2] == lin.defects.shape[:2]
    np.testing.assert_array_equal(lin.pose, sens.pose)
    point, rotation = machine.tool_readings(q)
    assert point.shape == rotation.shape == (1, 3)
    np.testing.assert_allclose(point, sens.pose[:, :3], atol=1e-9)
    exact = machine.sampled_tool_points(q, np.zeros((2, d)))
    assert exact.shape == (1, 2, 3)
    np.testing.assert_allclose(exact[0], np.vstack([point] * 2), atol=1e-9)
    for mask in (machine.loop_defect_mask(), machine.reference_joint_defect_mask()):
        assert mask.dtype == bool and mask.shape == (d,)
    vector = machine.parameters()
    first = [int(vector.index.select("nominal")[0])]
    cols = machine.nominal_sensitivity(vector, first, q, sens)
    assert list(cols) == first
    col_point, col_rotation, method = cols[first[0]]
    assert col_point.shape == col_rotation.shape == (1, 3)
    assert method in ("composition", "central-difference", "undefined")
    held = machine.held_tool_actuators(q, sens.pose, sens.point, sens.rotation)
    assert held.shape == (1, n, d)
    names = machine.region_names()
    assert all(isinstance(name, str) for name in names) and len(names) in machine.region_sizes()
    lo, hi = machine.default_region()
    assert lo.shape == hi.shape == (len(names),) and (lo <= hi).all()
    assert machine.configurations_at(((lo + hi) / 2)[None]).shape == (1, n)
    drawn = machine.mechanism_configurations(3, seed=0)
    assert drawn.shape == (3, n) and np.isfinite(drawn).all()
    measured = np.concatenate([point, rotation], axis=1) if machine.six_dof else point
    if not machine.measures_machined_parts:
        from pkmkit.exceptions import UnsupportedOperationError

        for call in (machine.part_actuators, machine.part_sensitivity):
            with pytest.raises(UnsupportedOperationError):
                call(measured)
        return
    np.testing.assert_allclose(machine.part_actuators(measured), q, atol=1e-7)
    assert machine.part_sensitivity(measured).shape == (1, n, d)


def _home_input(machine):
    """A pose every family's ik takes at home: the full home pose."""
    return machine.home_pose


def test_full_output_records_are_the_same_types(machine):
    """ik → InverseResult, fk → DirectResult, jacobian → VelocityModel, single and batched,
    whatever the family (the joint chains' were a tuple and a record of their own)."""
    from pkmkit.machines.results import DirectResult, InverseResult, VelocityModel

    n = machine.n_actuators
    inv = machine.ik(_home_input(machine), full_output=True)
    assert isinstance(inv, InverseResult)
    np.testing.assert_allclose(inv.q, machine.home_q, atol=1e-7)
    assert int(inv.status) == 0
    batch = machine.ik(np.vstack([_home_input(machine)] * 2), full_output=True)
    assert isinstance(batch, InverseResult) and batch.q.shape == (2, n)
    assert batch.status.shape == (2,)
    direct = machine.fk(machine.home_q, full_output=True)
    assert isinstance(direct, DirectResult)
    assert direct.pose.shape == machine.home_pose.shape and int(direct.status) == 0
    assert isinstance(machine.fk(np.vstack([machine.home_q] * 2), full_output=True),
                      DirectResult)
    for jac in (machine.jacobian(machine.home_pose), machine.jacobian(q=machine.home_q),
                machine.jacobian(machine.home_pose, q=machine.home_q)):
        assert isinstance(jac, VelocityModel)
        assert jac.J.shape[-1] == n and np.ndim(jac.condition) == 0
        assert bool(jac.exists)
        np.testing.assert_allclose(jac.q, machine.home_q, atol=1e-7)
    by_pose, by_q = machine.jacobian(machine.home_pose), machine.jacobian(q=machine.home_q)
    np.testing.assert_allclose(by_pose.J, by_q.J, rtol=1e-6, atol=1e-9)
    jacs = machine.jacobian(q=np.vstack([machine.home_q] * 3))
    assert isinstance(jacs, VelocityModel) and jacs.J.shape[0] == 3
    assert jacs.exists.shape == (3,)
    # home lies in the working mode, away from parallel singularities, for every family
    np.testing.assert_array_equal(machine.in_working_mode(jacs, 1e-6), [True] * 3)


def test_unsupported_operations_are_typed_errors_naming_why(machine):
    """fk_all, jacobian_dot and joint_motion either answer or raise UnsupportedOperationError
    (an InputError) naming the operation, the machine and why — never AttributeError."""
    from pkmkit.exceptions import UnsupportedOperationError
    from pkmkit.machines.results import JacobianRates

    calls = {
        "fk_all": lambda: machine.fk_all(machine.home_q),
        "jacobian_dot": lambda: machine.jacobian_dot(
            machine.home_pose, np.zeros(machine.home_pose.shape)),
        "joint_motion": lambda: machine.joint_motion(
            machine.home_pose[None, :min(3, machine.dims)],
            np.zeros((1, min(3, machine.dims))), np.zeros((1, min(3, machine.dims)))),
    }
    for name, call in calls.items():
        try:
            out = call()
        except UnsupportedOperationError as exc:
            assert isinstance(exc, InputError)
            assert exc.machine == machine.id and exc.family == machine.family
            assert exc.reason and machine.family == "chain", name
            continue
        assert machine.family != "chain", name
        if name == "jacobian_dot":
            assert isinstance(out, JacobianRates)
            assert np.asarray(out.J_dot).shape[-1] == machine.n_actuators
        if name == "joint_motion":
            assert out.failed is None
            np.testing.assert_allclose(out.q[0], machine.home_q, atol=1e-7)
            np.testing.assert_allclose(out.qd, 0.0, atol=1e-12)


def test_jacobian_without_pose_or_q_is_a_typed_error(machine):
    with pytest.raises(InputError):
        machine.jacobian()


def test_joint_chain_former_call_forms_still_work_with_a_deprecation_warning():
    """The chain machine's former ik tuple and positional jacobian(q) keep their meaning."""
    m = pkmkit.machine("tripteor-x7")
    inv = m.ik(m.home_pose, full_output=True)
    with pytest.warns(DeprecationWarning, match="ChainInverseResult"):
        q, direct = inv
    np.testing.assert_array_equal(q, inv.q)
    assert direct is inv.direct
    np.testing.assert_allclose(direct.pose, m.home_pose, atol=1e-9)
    with pytest.warns(DeprecationWarning, match=r"jacobian\(q=q\)"):
        old = m.jacobian(m.home_q)
    np.testing.assert_array_equal(old.J, m.jacobian(q=m.home_q).J)
    with pytest.raises(InputError, match="branches"):
        m.jacobian(m.home_pose, branches=[1, 1, 1])


def test_jacobian_refuses_q_that_does_not_fit_the_pose(machine):
    """On every family, q given with x must be x's configuration (single: InputError naming
    the misfit; batch: that row NaN, the others kept) — the full-pose and joint-chain
    machines computed a velocity model of no configuration."""
    q_off = machine.home_q + 0.01
    with pytest.raises(InputError, match="does not fit"):
        machine.jacobian(machine.home_pose, q=q_off)
    jac = machine.jacobian(np.vstack([machine.home_pose] * 2),
                           q=np.vstack([machine.home_q, q_off]))
    assert np.isfinite(jac.J[0]).all() and np.isnan(jac.J[1]).all()
    assert list(np.asarray(jac.exists)) == [True, False]


def test_the_shared_keywords_mean_the_same_on_every_family(machine):
    """ik(x, full_output=, strokes=), fk(q, full_output=, strokes=), jacobian(x, q=, tol=):
    the same keywords on every family, the same typed error for a bad value."""
    x, q = machine.home_pose, machine.home_q
    for mode in ("flag", "refuse", "ignore"):
        np.testing.assert_allclose(machine.ik(x, strokes=mode), q, atol=1e-7)
        np.testing.assert_allclose(machine.fk(q, strokes=mode), x, atol=1e-7)
    with pytest.raises(InputError):
        machine.ik(x, strokes="sometimes")
    with pytest.raises(InputError):
        machine.fk(q, strokes="sometimes")
    for tol in (0.0, -1.0, float("nan")):
        with pytest.raises(InputError):
            machine.jacobian(x, q=q, tol=tol)


# ---------------------------------------------------------------- what the families declared
def test_declared_attributes_say_what_the_family_tests_said(machine):
    """The attributes that replaced family tests outside machines/ answer as those tests did
    (export layouts, the split velocity model, measurement tools)."""
    chain = machine.family == "chain"
    planar = machine.family == "translational" and machine.dims == 2
    assert machine.export_layout == ("planar" if planar else machine.family)
    assert machine.velocity_split is (not chain)
    assert (machine.default_tool_lengths is not None) is chain
    assert machine.incompatible_defects is chain


# ---------------------------------------------------------------- the tool, on every family
def _target_width(machine) -> int:
    return 6 if machine.dims == 6 and not machine.position_controlled else 3


def test_the_tool_has_the_same_keywords_and_meaning_on_every_family(machine):
    """tool_targets / tool_inverse / tool_frames take tool_length (m, along the tool axis) on
    every family: they invert each other, the tip moves by exactly that length, the frames
    agree with the targets, and a rod machine's closed form refuses a closure start."""
    from pkmkit.exceptions import UnsupportedOperationError

    q = machine.home_q[None]
    for length in (None, 0.05):
        tl = None if length is None else np.array([length])
        x = machine.tool_targets(q, tl)
        assert x.shape == (1, _target_width(machine))
        np.testing.assert_allclose(machine.tool_inverse(x, tl), q, atol=1e-7)
        frames = machine.tool_frames(q, tl, rotation=True)
        np.testing.assert_allclose(frames.point, x[:, :3], atol=1e-12)
        r = frames.rotation[0]
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    bare = machine.tool_frames(q, np.array([0.0])).point
    tip = machine.tool_frames(q, np.array([0.05])).point
    assert np.linalg.norm(tip - bare) == pytest.approx(0.05, abs=1e-12)
    start = machine.tool_frames(q).start
    if machine.family == "chain":
        again = machine.tool_frames(q, start=start)
        np.testing.assert_allclose(again.point, machine.tool_frames(q).point, atol=1e-12)
    else:
        assert start is None
        with pytest.raises(UnsupportedOperationError, match="closed form"):
            machine.tool_frames(q, start=np.zeros((1, machine.dims)))


def test_the_linearised_tool_is_the_tool_with_its_defect_jacobians(machine):
    from pkmkit.geometric_errors.model import defect_set, tool_sensitivity

    q, tl = machine.home_q[None], np.array([0.05])
    sens = tool_sensitivity(machine, q, tool_length=tl)
    lin = machine.tool_frames_linearised(q, sens, tl, rotation=True)
    plain = machine.tool_frames(q, tl, rotation=True)
    np.testing.assert_allclose(lin.point, plain.point, atol=1e-9)
    np.testing.assert_allclose(lin.rotation, plain.rotation, atol=1e-9)
    d = len(defect_set(machine))
    assert lin.dpoint.shape == lin.drotation.shape == (1, 3, d)


def test_every_machine_reads_its_inverse_result_into_the_shared_rows(machine):
    """``inverse_rows`` gives the fields of boundary.kinematics.InverseRows, rows (N, …) for
    one pose as for many, status OK at home."""
    from dataclasses import fields

    from pkmkit.boundary.kinematics import InverseRows

    for x in (machine.home_pose, np.vstack([machine.home_pose] * 2)):
        rows = machine.inverse_rows(machine.ik(x, full_output=True, strokes="ignore"))
        assert set(rows) <= {f.name for f in fields(InverseRows)}
        assert rows["q"].shape == (np.atleast_2d(x).shape[0], machine.n_actuators)
        assert list(rows["status"]) == [0] * len(rows["q"])
        np.testing.assert_allclose(rows["q"], np.broadcast_to(machine.home_q, rows["q"].shape),
                                   atol=1e-7)
        passive = rows.get("passive")
        assert (passive is not None) is (machine.family == "chain")


def test_measurement_configurations_and_rejection_reasons(machine):
    """Every family draws its default measurement region and says why a sample is rejected."""
    from pkmkit.machines.measurement_models import within_strokes

    q = machine.measurement_configurations(3, np.random.default_rng(1))
    assert q.shape == (3, machine.n_actuators) and within_strokes(machine, q).all()
    far = machine.home_pose + np.r_[[10.0] * min(machine.dims, 3), [0.0] * (machine.dims - 3)]
    k, why = machine.unreachable_reason(far[None])
    assert k == 0 and isinstance(why, str) and why
    lo, hi = machine.home_q - 1.0, machine.home_q - 0.5
    k, why = machine.out_of_stroke_reason(machine.home_q[None], lo, hi, machine.actuator_names)
    assert k == 0 and isinstance(why, str) and why


# ---------------------------------------------------------------- one meaning of fk's x0
def test_a_joint_chain_takes_its_closure_start_as_start_and_x0_is_a_pose():
    """x0 is a warm-start pose on every machine; a joint chain's closure starts from its
    platform pose and passive joints, now ``start`` (x0 of that width: deprecated alias, the
    same result); a pose x0 is refused with a typed error naming why."""
    from pkmkit.exceptions import UnsupportedOperationError

    m = pkmkit.machine("tripteor-x7")
    q = m.home_q + 0.001
    home = m.fk(m.home_q, full_output=True)
    u = np.concatenate([np.ravel(home.platform), np.ravel(home.passive)])
    assert u.size == 6 + len(m.passive_names)
    by_start = m.fk(q, start=u, full_output=True)
    with pytest.warns(DeprecationWarning, match="start="):
        by_x0 = m.fk(q, x0=u, full_output=True)
    np.testing.assert_array_equal(by_start.pose, by_x0.pose)
    np.testing.assert_allclose(by_start.pose, m.fk(q), atol=1e-9)
    with pytest.raises(UnsupportedOperationError, match="platform pose and the passive"):
        m.fk(q, x0=m.home_pose)
    with pytest.raises(InputError, match="alone"):
        m.fk(q, x0=u, start=u)
    with pytest.raises(InputError, match="start"):
        m.fk(q, start=u[:-1])
