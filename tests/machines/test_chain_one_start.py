"""The inverse model's default start of the joint chains (issue 22 §1): home moved to first
order towards the target (:func:`pkmkit.machines.chain_starts.inverse_starts`), the same bits
on the batch path and in the one-pose kernel, a start of second-order accuracy, tool-length
free, and never losing a row the start from home reaches."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import chain_one, chain_starts
from pkmkit.machines.chain_one_native import packed
from pkmkit.machines.joint_chain import machine_with_tool
from pkmkit.numerics import jit
from pkmkit.status import Status

pytestmark = pytest.mark.skipif(not jit.numba_available() or jit.mode() == "0",
                                reason="the one-pose paths run the compiled closure")

NAMES = ("tripteor-x7", "trimule-600")
#: m.ik(x) of one pose through the C extension: the batch row to rounding (test_chain_one.py).
IK_TOL = 1e-12


@pytest.fixture(scope="module", params=NAMES)
def machine(request):
    m = pkmkit.machine(request.param)
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):
        chain_one.usable(m, tag)
    return m


def poses(m, n: int, seed: int, spread: float = 0.8) -> np.ndarray:
    """Tool poses of ``n`` random actuator values over the middle ``spread`` of their strokes
    (beyond them where ``spread`` > 1), rows without assembly dropped."""
    rng = np.random.default_rng(seed)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (0.5 - spread / 2 + spread * rng.random((n, len(act))))
    x = m.fk(q, strokes="ignore")
    return x[np.isfinite(x).all(axis=1)]


def inverse_residual(m, u: np.ndarray, target: np.ndarray, tool: float) -> np.ndarray:
    """The residual of the inverse model (closure rows, then the tool rows) at ``u``."""
    from pkmkit.solve import chain_kernel, chain_rows

    model = m.model
    frames, types, evar, elements, offsets, position = chain_rows.model_arrays(
        model, np.arange(model.n_variables))
    head = np.array(model.head, dtype=np.int64)
    r = np.empty(6 * len(model.legs) + 6)
    jac = np.empty((len(r), len(u)))
    chain_kernel._evaluate_any(frames, types, evar, elements, offsets, position,
                               m._home["values"].copy(), u.copy(),
                               float(model.characteristic_length), r, jac,
                               chain_kernel._scratch(len(elements) + len(head)), head,
                               target, tool, True)
    return r


def test_the_start_closes_to_second_order(machine, monkeypatch):
    """The rates are the first-order ones: without the cutoff of the wrist's near-singular
    direction, targets moved from home by h along random directions (point and axis) leave a
    residual at the start that shrinks as h² (≈ 100× for 10× smaller h), from home only as h
    (10×)."""
    monkeypatch.setattr(chain_starts, "INVERSE_RATE_CUTOFF", 0.0)
    m = pkmkit.machine(machine.id)  # its own cache of the rates
    object.__setattr__(m, "_closed_start_ok", False)  # the first-order start (not the kind's)
    rng = np.random.default_rng(4)
    home = m.home_pose
    u_home = np.concatenate([m._home["platform"], m._home["values"]])
    for _ in range(5):
        direction = rng.standard_normal(6)
        direction[3:] *= 0.2  # a tool axis turned by a fifth of the point's move (rad per m)
        sizes = []
        for h in (1e-3, 1e-4):
            x = home + h * direction
            x[3:] /= np.linalg.norm(x[3:])
            start = chain_starts.inverse_starts(m, x[None], np.array([m.tool_length]))[0]
            sizes.append([np.linalg.norm(inverse_residual(m, u, x, m.tool_length))
                          for u in (start, u_home)])
        (start_big, home_big), (start_small, home_small) = sizes
        assert start_small < 0.03 * start_big  # second order
        assert home_small > 0.05 * home_big  # first order: the comparison is not empty
        assert start_big < 0.1 * home_big


def test_the_cutoff_drops_the_wrist_direction_alone(machine):
    """With the cutoff, the rates leave out one direction at home (the wrist's near
    singularity on both machines: ~0.004 of the largest singular value, the next ~0.07): the
    residual at the start is first order in h, along that direction — under half the start
    from home's at h = 1e-3 (seen 15–30 %)."""
    m = machine
    u_home, _, rates = chain_starts.inverse_rates(m)
    assert np.linalg.matrix_rank(rates, tol=1e-9) == 5
    rng = np.random.default_rng(5)
    for _ in range(5):
        direction = rng.standard_normal(6)
        direction[3:] *= 0.2
        x = m.home_pose + 1e-3 * direction
        x[3:] /= np.linalg.norm(x[3:])
        start = chain_starts.inverse_starts(m, x[None], np.array([m.tool_length]))[0]
        assert (np.linalg.norm(inverse_residual(m, start, x, m.tool_length))
                < 0.5 * np.linalg.norm(inverse_residual(m, u_home, x, m.tool_length)))


def test_a_rows_start_is_its_own_and_the_kernels(machine):
    """Bit for bit: a row's start in a batch, alone, and by the one-pose kernel."""
    from pkmkit.solve.chain_one_kernel import inverse_start

    m = machine
    x = poses(m, 60, seed=7, spread=1.1)
    x[:, 3:] /= np.linalg.norm(x[:, 3:], axis=1)[:, None]
    tools = np.random.default_rng(8).uniform(0.0, 0.4, len(x))
    batch = chain_starts.inverse_starts(m, x, tools)
    u_home, base, rates = chain_starts.inverse_rates(m)
    out = np.empty((1, len(u_home)))
    for k in range(len(x)):
        alone = chain_starts.inverse_starts(m, x[k:k + 1], tools[k:k + 1])
        inverse_start(u_home, base, rates, x[k:k + 1], tools[k:k + 1], out)
        closed = chain_starts.closed_starts(m, x[k:k + 1], tools[k:k + 1])
        # the kind's closed-form start where it answers (the TriMule), else the first-order
        if closed is not None and np.isfinite(closed).all():
            out = closed
        assert np.array_equal(alone[0], batch[k]) and np.array_equal(out[0], batch[k])
        out = np.empty((1, len(u_home)))


def test_a_tool_length_option_gives_the_machine_with_that_tool(machine):
    """The rates are in the flange point: ``m.ik(X, tool_length=ℓ)`` (batch) gives the bits of
    the one-pose path of the machine whose tool is ℓ long."""
    m = machine
    length = 0.8 * m.tool_length + 0.01
    other = machine_with_tool(m, length)
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):
        chain_one.usable(other, tag)
    x = poses(other, 20, seed=9)  # its own tool's poses: within the strokes
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        batch = m.ik(x, tool_length=length)
        fast = 0
        for k in range(len(x)):
            fast += chain_one.inverse(other, x[k], "flag") is not None
            one = other.ik(x[k])  # the C path where built: to rounding (test_chain_one.py)
            assert np.array_equal(np.isnan(one), np.isnan(batch[k]))
            assert np.nan_to_num(np.abs(one - batch[k])).max() <= IK_TOL
    assert fast > len(x) // 3


def test_the_default_start_never_loses_a_row(machine):
    """Against the start from home itself (``start=`` home's unknowns), over poses within and
    beyond the strokes: every row reached from home is reached; where both reach it, the same
    solution to 1e-9, or — where home's is outside the legs' home assembly modes — one inside
    them; fewer iterations."""
    m = machine
    x = poses(m, 600, seed=11, spread=1.1)
    u_home = np.concatenate([m._home["platform"], m._home["values"]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        default = m.ik(x, full_output=True)
        home = m.ik(x, full_output=True, start=u_home)
    ok_home, ok = home.status == Status.OK, default.status == Status.OK
    assert ok_home.sum() > 0.9 * len(x)
    assert not (ok_home & ~ok).any()
    both = ok_home & ok
    moved = np.abs(default.q - home.q).max(axis=1) > 1e-9
    # moved only from a home answer outside the legs' home modes into them (else the start
    # from home's answer: a first-order start leaving them is solved again from home)
    assert not (both & moved & m.in_home_modes(home.solution)).any()
    assert m.in_home_modes(default.solution[both & moved]).all()
    assert default.iterations[both].mean() < 0.85 * home.iterations[both].mean()


def test_rows_solved_again_from_home_are_the_batch_rows():
    """TriMule poses whose first-order start converges outside the legs' home modes (the
    first five found): the one-pose path solves them again from home as the batch path does
    (the same bits, the path taken); one (index 376) whose head's mirror, kept, leaves them:
    the batch path's (it solves it again from home). The closed-form start (from which none of
    them leaves the modes) is turned off here: the retry is what is checked."""
    m = pkmkit.machine("trimule-600")
    object.__setattr__(m, "_closed_start_ok", False)  # chain_starts.closed_starts: none
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):
        chain_one.usable(m, tag)
    c = chain_one.constants(m)
    x = poses(m, 400, seed=13, spread=1.0)[[26, 57, 64, 83, 86, 376]]
    from pkmkit.solve import chain_rows

    tools = np.full(len(x), m.tool_length)
    u = chain_rows.solve_inverse(m.model, x, chain_starts.inverse_starts(m, x, tools), tools)[0]
    assert list(m.in_home_modes(u)) == [False] * 5 + [True]  # the premises
    seen = []
    checked = c.in_home_modes
    c.in_home_modes = lambda u: seen.append(checked(u)) or seen[-1]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StrokeWarning)
            batch = m.ik(x, strokes="ignore")
            for k in range(len(x)):
                seen.clear()
                fast = chain_one.inverse(m, x[k], "ignore")
                assert seen == ([] if k < 5 else [False])  # the mirror's (from the start)
                assert (fast is None) == (k == 5)
                native = packed(m)  # the C path decides alike: the batch path for the last
                assert native is None or (native.ik(native.capsule, x[k], True, False) is None
                                          ) == (k == 5)
                one = m.ik(x[k], strokes="ignore")
                assert np.abs(one - batch[k]).max() <= IK_TOL
                assert np.array_equal(batch[k], m.ik(x[k:k + 1], strokes="ignore",
                                                     full_output=True).q[0])
    finally:
        del c.in_home_modes
