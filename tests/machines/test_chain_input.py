"""Bad input for joint-chain machines (issue 9 §6): joint values out of stroke, actuator values
without assembly (which leg misses the platform, by how much), singular closures; typed errors
for single calls, per-row statuses and messages for batches, which keep their good rows."""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import (
    ClosureMissError,
    InputError,
    NoAssemblyError,
    OutOfStrokeError,
    PkmError,
    SingularConfigurationError,
    StrokeWarning,
)
from pkmkit.machines import trimule_forms as forms
from pkmkit.status import Status

EXAMPLE = Path(__file__).parents[2] / "docs" / "examples" / "crank-slider.toml"


def crank_slider_file(tmp_path, rod_mm, homes):
    """The example crank-slider with another rod length L2 (mm) and passive home guesses."""
    text = EXAMPLE.read_text()
    text = text.replace("point = [300, 0, 0]", f"point = [{rod_mm}, 0, 0]")
    for old, new in zip(("-39.59406822686046", "9.59406822686046", "232.40652953342465"),
                        homes, strict=True):
        text = text.replace(f"home = {old}", f"home = {new}")
    path = tmp_path / f"crank-slider-{rod_mm}.toml"
    path.write_text(text)
    return pkmkit.load(path)


@pytest.fixture(scope="module")
def trimule():
    return pkmkit.machine("trimule-600")


@pytest.fixture
def short_rod(tmp_path):
    """Crank 400 mm, rod 300 mm: the rod cannot reach the slider's line when the crank is
    near 90°."""
    text = EXAMPLE.read_text().replace("point = [100, 0, 0]", "point = [400, 0, 0]")
    for old, new in (("-39.59406822686046", "-70"), ("9.59406822686046", "40"),
                     ("232.40652953342465", "400")):
        text = text.replace(f"home = {old}", f"home = {new}")
    path = tmp_path / "crank-slider-long-crank.toml"
    path.write_text(text)
    return pkmkit.load(path)


@pytest.fixture
def folding(tmp_path):
    """Crank and rod of equal lengths (100 mm): at θ1 = 90° the rod folds onto the crank, a
    singular closure."""
    return crank_slider_file(tmp_path, 100, ("-60", "30", "23.2"))


# ----------------------------------------------------------------------------- strokes
def test_actuator_beyond_its_stroke_is_flagged_by_default(trimule):
    beyond = np.r_[forms.actuators(trimule.params, 1.25, 0.0, 0.0)[0], 0.0, 0.0]
    assert beyond[0] > trimule.model.q_max[trimule.model.variables.index("Q1")]
    with pytest.warns(StrokeWarning, match=r"Q1 = 1262\.19 mm is beyond its stroke \[785, "
                      r"1240\] mm by 22\.1906 mm"):
        pose = trimule.fk(beyond)
    # the geometry is still computed (the closed form agrees)
    expected = forms.direct(trimule.params, beyond, trimule.tool_length)[0]
    assert np.abs(pose - expected).max() < 1e-12
    batch = trimule.fk(np.array([trimule.home_q, beyond]), full_output=True)
    assert batch.status.tolist() == [Status.OK, Status.OK]
    assert batch.out_of_stroke.tolist() == [False, True]
    assert batch.messages[0] == "" and "Q1" in batch.messages[1]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        trimule.fk(beyond, strokes="ignore")


def test_refuse_mode_gives_nan_rows_and_a_typed_error(trimule):
    beyond = np.r_[forms.actuators(trimule.params, 1.0, 0.0, 0.0)[0], 0.0, math.radians(50)]
    with pytest.raises(OutOfStrokeError) as info:
        trimule.fk(beyond, strokes="refuse")
    err = info.value
    assert err.joint == "Q5" and err.value == pytest.approx(math.radians(50))
    assert err.stroke == pytest.approx((-math.radians(45), math.radians(45)))
    assert "Q5 = 50° is beyond its stroke [-45, 45]°" in str(err)
    assert isinstance(err, PkmError)
    result = trimule.fk(np.array([beyond, trimule.home_q]), strokes="refuse", full_output=True)
    assert result.status.tolist() == [Status.OUT_OF_STROKE, Status.OK]
    assert np.isnan(result.pose[0]).all() and np.isfinite(result.pose[1]).all()


def test_passive_joint_beyond_its_limit_is_named(trimule):
    """ψ1 = 35° is beyond the measured leg's ±30° although every actuator is in stroke."""
    q = np.r_[forms.actuators(trimule.params, 0.95, math.radians(35.0), 0.0)[0], 0.0, 0.0]
    model = trimule.model
    act = model.actuated
    assert ((q >= model.q_min[act]) & (q <= model.q_max[act])).all()
    with pytest.warns(StrokeWarning):
        result = trimule.fk(q, full_output=True)
    assert result.status == Status.OK and result.out_of_stroke
    assert result.messages == "psi1 = 35° is beyond its stroke [-30, 30]° by 5°"
    with pytest.raises(OutOfStrokeError, match="psi1"):
        trimule.fk(q, strokes="refuse")


def test_inverse_model_checks_the_strokes_of_its_solution(trimule):
    q = np.r_[forms.actuators(trimule.params, 1.25, 0.0, 0.0)[0], 0.0, 0.0]
    target = forms.direct(trimule.params, q, trimule.tool_length)[0]
    with pytest.warns(StrokeWarning, match="Q1"):
        found = trimule.ik(target, q0=q)
    assert np.abs(found - q).max() < 1e-9
    with pytest.raises(OutOfStrokeError, match="Q1"):
        trimule.ik(target, q0=q, strokes="refuse")
    both = trimule.ik(np.array([target, trimule.home_pose]), q0=np.array([q, trimule.home_q]),
                      strokes="refuse")
    assert np.isnan(both[0]).all() and np.abs(both[1] - trimule.home_q).max() < 1e-9


def test_unknown_stroke_mode(trimule):
    with pytest.raises(InputError, match="strokes must be one of flag, refuse, ignore"):
        trimule.fk(trimule.home_q, strokes="clip")
    with pytest.raises(InputError, match="strokes"):
        trimule.ik(trimule.home_pose, strokes="clip")


# ----------------------------------------------------------------------------- no assembly
def test_no_assembly_names_the_leg_and_the_miss(short_rod):
    """Crank 400 mm, rod 300 mm: at θ1 = 90° the piston's line is 100 mm out of the rod's
    reach; the least-squares platform splits the gap between the two legs."""
    with pytest.raises(ClosureMissError) as info:
        short_rod.fk([math.pi / 2])
    err = info.value
    assert isinstance(err, NoAssemblyError)
    assert err.leg_name in ("crank and rod", "slider") and err.leg in (0, 1)
    assert 0.02 < err.translation < 0.1 and err.residual > 0.01
    assert "misses the platform by" in str(err) and "mm" in str(err)


def test_batches_keep_their_good_rows(short_rod):
    q = np.array([[0.5], [math.pi / 2], [np.nan], [-0.3], [np.inf]])
    result = short_rod.fk(q, full_output=True)
    assert result.status.tolist() == [Status.OK, Status.NO_ASSEMBLY, Status.INVALID_INPUT,
                                      Status.OK, Status.INVALID_INPUT]
    assert np.isnan(result.pose[[1, 2, 4]]).all() and np.isnan(result.passive[1]).all()
    for i in (0, 3):
        alone = short_rod.fk(q[i], full_output=True)
        assert np.array_equal(result.pose[i], alone.pose)
        assert np.array_equal(result.passive[i], alone.passive)
        assert result.messages[i] == ""
    assert "crank and rod" in result.messages[1] and "slider" in result.messages[1]
    assert "not finite" in result.messages[2]
    jac = short_rod.jacobian(q)
    assert jac.status.tolist() == result.status.tolist()
    assert np.isfinite(jac.J[[0, 3]]).all() and np.isnan(jac.J[[1, 2, 4]]).all()
    with pytest.raises(ClosureMissError):
        short_rod.jacobian([math.pi / 2])


def test_nominal_misfit_is_no_assembly_but_defects_are_least_squares(trimule):
    q = trimule.home_q.copy()
    q[0] += 0.5  # Q1 far too long: the three actuated legs cannot meet the measured leg
    result = trimule.fk(q[None], full_output=True, strokes="ignore")
    assert result.status[0] == Status.NO_ASSEMBLY and result.closure_residual[0] > 1e-3
    # an incompatible defect: the machine still assembles (in least squares)
    tilted = trimule.with_defects({"dJ21": 1e-3})  # θ1's axis out of the ring's plane
    assert tilted.home_closure_residual > 1e-6
    rows = np.array([trimule.home_q, trimule.reference_poses()["tilt-psi1"], q])
    direct = tilted.fk(rows, full_output=True, strokes="ignore")
    assert (direct.status == Status.INCONSISTENT).all() and np.isfinite(direct.pose).all()
    # the misfit tells them apart: bounded, the unreachable row has no assembly
    assert direct.closure_residual[1] < 2 * tilted.home_closure_residual
    assert direct.closure_residual[2] > 20 * tilted.home_closure_residual
    bounded = tilted.fk(rows, full_output=True, strokes="ignore",
                        max_misfit=10 * tilted.home_closure_residual)
    assert bounded.status.tolist() == [Status.INCONSISTENT] * 2 + [Status.NO_ASSEMBLY]
    assert np.isnan(bounded.pose[2]).all() and "misses the platform" in bounded.messages[2]


# ----------------------------------------------------------------------------- singular
def test_singular_closure(folding):
    folded = [math.pi / 2]
    with pytest.raises(SingularConfigurationError, match="singular closure"):
        folding.fk(folded)
    with pytest.raises(SingularConfigurationError):
        folding.jacobian(folded)
    q = np.array([[math.radians(60)], folded, [math.radians(91)]])
    batch = folding.fk(q, full_output=True, check_singular=True)
    assert batch.status.tolist() == [Status.OK, Status.SINGULAR, Status.OK]
    assert np.isfinite(batch.pose).all()  # the folded assembly exists; it is not determined
    assert "singular closure" in batch.messages[1]
    jac = folding.jacobian(q)
    assert jac.status.tolist() == [Status.OK, Status.SINGULAR, Status.OK]
    assert np.isnan(jac.J[1]).all() and np.isfinite(jac.J[[0, 2]]).all()
    # a batch does not pay for the check unless asked
    assert folding.fk(q, full_output=True).status.tolist() == [Status.OK] * 3


def test_singular_check_does_not_flag_regular_configurations(trimule):
    rng = np.random.default_rng(5)
    n = 50
    q = np.column_stack([forms.actuators(trimule.params, rng.uniform(0.85, 1.15, n),
                                         np.radians(rng.uniform(-12, 12, n)),
                                         np.radians(rng.uniform(-12, 12, n))),
                         rng.uniform(-3, 3, n), rng.uniform(-0.7, 0.7, n)])
    result = trimule.fk(q, full_output=True, check_singular=True)
    assert (result.status == Status.OK).all()


# ----------------------------------------------------------------------------- shapes
def test_malformed_arrays(trimule):
    with pytest.raises(InputError, match="5 components"):
        trimule.fk([1.0, 1.0, 1.0])
    with pytest.raises(InputError, match="not finite"):
        trimule.fk([np.nan, 1.0, 1.0, 0.0, 0.0])
    with pytest.raises(InputError, match="tool axis"):
        trimule.ik([0.0, 0.0, 1.4, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="tool_length"):
        trimule.fk(np.array([trimule.home_q] * 3), tool_length=[0.1, 0.2])
