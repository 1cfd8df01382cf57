"""The calibration verdict (pkmkit.calibration.verdict): the χ² and ratio noise check on known
cases, the condition and magnitude checks, and how alternatives become likely causes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pkmkit.calibration.verdict import (
    ALPHA,
    CONDITION_MAX,
    Alternative,
    condition_check,
    judge,
    magnitude_check,
    noise_check,
)


def test_chi2_upper_tail_against_the_closed_form_for_two_degrees_of_freedom():
    # χ² with 2 degrees of freedom is exponential: P(χ² ≥ x) = exp(−x/2)
    for x in (0.5, 3.0, 12.0):
        _, p = noise_check(x, 2)
        assert p == pytest.approx(math.exp(-x / 2), rel=1e-12)


@pytest.mark.ci
def test_chi2_tails_agree_with_scipy_stats():
    from scipy.stats import chi2

    for x, dof in ((150.0, 100), (14_400.0, 10_000), (0.5, 50)):
        check, p = noise_check(x, dof)
        assert p == pytest.approx(chi2.sf(x, dof), rel=1e-10)
        assert check.value == pytest.approx(math.sqrt(x / dof))


def test_noise_at_the_assumed_level_passes():
    check, p = noise_check(100.0, 100)
    assert check.passed and not check.warning
    assert check.value == pytest.approx(1.0)
    assert 0.3 < p < 0.7


def test_noise_three_times_the_assumed_one_fails():
    check, p = noise_check(9.0 * 100, 100)  # σ̂/σ = 3
    assert not check.passed and check.value == pytest.approx(3.0)
    assert p < ALPHA
    assert "3× the assumed one" in check.reason


def test_model_error_below_the_ratio_bound_passes_even_when_chi2_rejects():
    # 10 000 readings with σ̂/σ = 1.2: the χ² test alone rejects it (p ≈ 0), the ratio does not
    check, p = noise_check(1.44 * 10_000, 10_000)
    assert p < 1e-100 and check.passed


def test_a_large_ratio_by_chance_with_one_degree_of_freedom_passes():
    # σ̂/σ = √5 ≈ 2.24 > 2, but P(χ²₁ ≥ 5) = 0.025 is no evidence at 10⁻³
    check, p = noise_check(5.0, 1)
    assert p == pytest.approx(math.erfc(math.sqrt(5.0 / 2)), rel=1e-12)  # χ²₁ tail
    assert check.passed


def test_noise_far_below_the_stated_one_is_a_warning_not_a_failure():
    check, _ = noise_check(0.01 * 50, 50)
    assert check.passed and check.warning
    assert "--sigma" in check.reason


def test_a_non_finite_residual_fails():
    check, _ = noise_check(float("nan"), 10)
    assert not check.passed


def test_condition_bound():
    assert condition_check(1e3).passed
    assert not condition_check(10 * CONDITION_MAX).passed
    assert not condition_check(float("inf")).passed


def test_magnitudes_against_the_machine_size_and_the_tolerances():
    tol = np.array([1e-4, 5e-3])
    units = ("m", "rad")
    ok = magnitude_check(("dL1", "dS1"), np.array([1e-3, 1e-3]), units, tol, 1.0)
    assert ok.passed and not ok.warning
    # 10 cm on a 1 m machine: no built machine is that wrong
    bad = magnitude_check(("dL1", "dS1"), np.array([0.1, 1e-3]), units, tol, 1.0)
    assert not bad.passed and "dL1" in bad.reason and "100 mm" in bad.reason
    # 0.2 rad (11°) of an angle defect
    bad = magnitude_check(("dL1", "dS1"), np.array([1e-3, 0.2]), units, tol, 1.0)
    assert not bad.passed and "dS1" in bad.reason
    # 3 mm: plausible, but 30 tolerances: a warning
    warn = magnitude_check(("dL1", "dS1"), np.array([3e-3, 1e-3]), units, tol, 1.0)
    assert warn.passed and warn.warning and "dL1" in warn.reason
    # reasons in the command's unit
    assert "0.1 m" in magnitude_check(("dL1",), np.array([0.1]), ("m",), tol[:1], 1.0,
                                      length_unit="m").reason


def _judge(chi2, dof, alternatives=(), values=(1e-4,), size=1.0):
    return judge(chi2=chi2, dof=dof, sigma=1e-5, condition=100.0, names=("dL1",),
                 values=np.array(values), units=("m",), tolerances=np.array([1e-4]),
                 machine_size=size, rms=1e-2, alternatives=alternatives)


def test_a_passing_verdict_has_no_cause():
    v = _judge(100.0, 100, alternatives=[Alternative("frame", "x", rms=1e-6)])
    assert v.passed and v.causes == ()
    assert v.headline() == "verdict: PASSED"
    assert v.to_dict()["passed"] is True and v.to_dict()["sigma_ratio"] == pytest.approx(1.0)


def test_alternatives_that_explain_become_the_likely_causes_best_first():
    alts = [Alternative("unit", "unit story", rms=5e-4),   # 20× better: explains
            Alternative("frame", "frame story", rms=1e-4),  # 100× better: the best
            Alternative("weak-parameters", "weak story", rms=5e-3)]  # 2× only: not
    v = _judge(1e6, 100, alts)
    assert not v.passed and v.headline() == "verdict: FAILED (noise)"
    assert [c.cause for c in v.causes] == ["frame", "unit"]
    # an alternative much worse than the best is not listed
    v = _judge(1e6, 100, [Alternative("unit", "u", rms=5e-4), Alternative("frame", "f",
                                                                           rms=1e-5)])
    assert [c.cause for c in v.causes] == ["frame"]
    text = "\n".join(v.lines())
    assert "✗ noise" in text and "likely cause (frame): f" in text


def test_an_alternative_whose_own_noise_matches_explains():
    alt = Alternative("weak-parameters", "keep them", rms=5e-3, sigma_posterior=1.1e-5)
    v = _judge(1e6, 100, [alt])
    assert [c.cause for c in v.causes] == ["weak-parameters"]


def test_an_alternative_beyond_any_machine_error_does_not_explain():
    # 10× better, but still 20 cm on a 1 m machine
    v = judge(chi2=1e12, dof=100, sigma=1e-5, condition=100.0, names=("dL1",),
              values=np.array([1e-4]), units=("m",), tolerances=np.array([1e-4]),
              machine_size=1.0, rms=2.0, alternatives=[Alternative("unit", "u", rms=0.2)])
    assert [c.cause for c in v.causes] == ["noise-or-model"]


def test_fallback_causes_name_noise_condition_and_magnitude():
    v = _judge(1e6, 100)
    assert [c.cause for c in v.causes] == ["noise-or-model"]
    assert "--sigma" in v.causes[0].message
    v = judge(chi2=100.0, dof=100, sigma=1e-5, condition=1e12, names=("dL1",),
              values=np.array([1e-4]), units=("m",), tolerances=np.array([1e-4]),
              machine_size=1.0, rms=1e-5)
    assert v.headline() == "verdict: FAILED (condition)"
    assert [c.cause for c in v.causes] == ["undetermined"]
    v = _judge(100.0, 100, values=(0.5,))
    assert v.headline() == "verdict: FAILED (magnitude)"
    assert [c.cause for c in v.causes] == ["implausible"]


def test_largest_correlation_is_never_a_parameter_with_itself():
    from pkmkit.calibration.results import _max_correlation

    # an undetermined parameter's row is 0 (NaN on the diagonal): the old |corr − I| took
    # its diagonal, |0 − 1| = 1, and reported it against itself with +0.000
    for diagonal in (0.0, np.nan):
        corr = np.array([[1.0, 0.3, 0.0], [0.3, 1.0, 0.0], [0.0, 0.0, diagonal]])
        out = _max_correlation(corr, ["a", "b", "c"])
        assert out == {"pair": ["a", "b"], "value": pytest.approx(0.3)}
    corr = np.array([[1.0, -0.9], [-0.9, 1.0]])
    assert _max_correlation(corr, ["a", "b"])["value"] == pytest.approx(-0.9)


def test_parameters_along_an_undetermined_direction_are_flagged():
    from pkmkit.calibration.identify import _undetermined

    rng = np.random.default_rng(0)
    j = rng.normal(size=(30, 3))
    assert not _undetermined(j).any()
    j[:, 2] = j[:, 0] + j[:, 1]  # column 2 is a combination of 0 and 1: all three undetermined
    assert _undetermined(j).all()
    j = rng.normal(size=(30, 3))
    j[:, 2] = 0.0  # a column with no effect: only that parameter
    np.testing.assert_array_equal(_undetermined(j), [False, False, True])


def test_an_identification_that_did_not_converge_fails_with_its_reason():
    """The convergence check appears only when the identification did not converge, and
    always fails; without an alternative that explains, the likely cause is named
    ``diverged`` (not the noise: the residual is the nominal machine's)."""
    assert [c.name for c in _judge(100.0, 100).checks] == ["noise", "condition", "magnitude"]
    v = judge(chi2=1e9, dof=100, sigma=1e-5, condition=100.0, names=(), values=np.zeros(0),
              units=(), tolerances=np.zeros(0), machine_size=1.0, rms=0.3,
              convergence="the identification did not converge (why)")
    assert v.headline() == "verdict: FAILED (noise, convergence)"
    assert v.checks[-1].name == "convergence" and "(why)" in v.checks[-1].reason
    assert [c.cause for c in v.causes] == ["diverged"]
    # nothing was identified: the noise check judges the nominal model, and says so
    assert "the nominal model does not explain" in v.checks[0].reason
    assert "identified model" in _judge(1e9, 100).checks[0].reason
    v = judge(chi2=100.0, dof=100, sigma=1e-5, condition=100.0, names=(), values=np.zeros(0),
              units=(), tolerances=np.zeros(0), machine_size=1.0, rms=0.3,
              convergence="why", alternatives=[Alternative("unit", "inches", rms=1e-3)])
    assert not v.passed and [c.cause for c in v.causes] == ["unit"]


def test_an_accepted_iterate_beyond_the_bound_stops_the_solve():
    """The identification's divergence guard: a Jacobian asked beyond ``bound`` (an accepted
    iterate with defects no built machine has) ends the solve as NOT_CONVERGED there."""
    from pkmkit.calibration.solver import Diverged, ScaledProblem, solve_scaled
    from pkmkit.status import Status

    class Line:  # r = θ − 5 (one reading), the optimum beyond a bound of 1
        sigma = np.array([1.0])
        data = (0,)

        def residuals(self, machine, setup, *, jacobian):
            theta = machine
            return (np.array([[theta - 5.0]]), np.ones((1, 1, 1)) if jacobian else None,
                    np.zeros((1, 1, 0)) if jacobian else None)

    problem = ScaledProblem(machine=None, model=Line(), basis=np.eye(1),
                            setup_index=np.zeros(0, dtype=int), setup_base=np.zeros(0),
                            scale=np.ones(1), prior=False, weights=np.ones(1),
                            bound=np.array([1.0]))
    problem.machine_at = lambda delta: float(delta[0])
    with pytest.raises(Diverged):
        problem.evaluate(np.array([2.0]), jacobian=True)
    assert problem.evaluate(np.array([2.0]), jacobian=False)[0] is not None
    sol = solve_scaled(problem, np.zeros(1), 60)
    assert sol.status == Status.NOT_CONVERGED and abs(sol.u[0]) > 1.0
    problem.bound = np.array([10.0])
    sol = solve_scaled(problem, np.zeros(1), 60)
    assert sol.status == Status.OK and sol.u[0] == pytest.approx(5.0)
