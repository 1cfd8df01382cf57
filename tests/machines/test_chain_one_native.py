"""One pose per call on the joint-chain machines through the C extension
(machines/chain_one_native.py, native/chain_one*.c; issue 22 §1): ``m.ik(x)`` and ``m.fk(q)``
equal the batch path's rows to rounding (the solve by block elimination) — and to the bit with
the dense solve packed instead, which checks the C port of the one-pose rules apart from the
solver — and every unusual input reaches the batch path's typed errors."""

from __future__ import annotations

import copy
import pickle
import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import ConvergenceError, InputError, OutOfStrokeError, StrokeWarning
from pkmkit.machines import chain_one, chain_one_native, chain_starts
from pkmkit.numerics import jit

native = jit.native_kernels()
pytestmark = pytest.mark.skipif(native is None or not hasattr(native, "chain_one_pack"),
                                reason="the C extension (with chain_one.c) is not built")

NAMES = ("tripteor-x7", "trimule-600")
#: The solve by block elimination against the batch path's dense Cholesky: measured max
#: |difference| over 1,000 workspace poses 1.1e-15 (Tripteor) and 7.2e-14 (TriMule) for ik
#: (m, rad), 8.9e-16 and 8.1e-15 for fk; checked to 1e-12.
TOL = 1e-12


def batch(call, *args, **options):
    """``call(*args)`` (``m.ik`` / ``m.fk``) on the batch path: neither one-pose path."""
    saved, packed = chain_one.constants, chain_one.packed
    chain_one.constants = lambda m, tag="chain_ik": None
    chain_one.packed = lambda m: None
    try:
        return call(*args, **options)
    finally:
        chain_one.constants, chain_one.packed = saved, packed


def workspace(m, n: int, seed: int = 0, margin: float = 0.05):
    """``(q, x)``: ``n`` random actuator values within their strokes and their tool poses (rows
    without assembly dropped)."""
    rng = np.random.default_rng(seed)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (margin + (1 - 2 * margin) * rng.random((n, len(act))))
    x = m.fk(q, strokes="ignore")
    keep = np.isfinite(x).all(axis=1)
    return q[keep], x[keep]


def repacked(m, structured: bool):
    """A :class:`~pkmkit.machines.chain_one_native.Packed` of ``m`` with the solve chosen."""
    return chain_one_native.Packed(
        native.chain_one_pack(*chain_one_native.pack_arguments(m, structured)), native)


@pytest.fixture(scope="module", params=NAMES)
def machine(request):
    return pkmkit.machine(request.param)


def test_the_machines_solve_by_blocks(machine):
    c = chain_one_native.packed(machine)
    assert native.chain_one_structured(c.capsule)
    assert not native.chain_one_structured(repacked(machine, False).capsule)


def differences(m, q, x, c) -> tuple[float, float, int, int]:
    """Largest |difference| of ``c``'s ik and fk answers from the batch rows (answers taken)
    and how many rows each answered."""
    ik_ref = m.ik(x, strokes="ignore")
    fk_ref = m.fk(q, strokes="ignore")
    ik_one = [c.ik(c.capsule, row, True, False) for row in x]
    fk_one = [c.fk(c.capsule, row, True, True) for row in q]
    ik_rows = [k for k, v in enumerate(ik_one) if v is not None]
    fk_rows = [k for k, v in enumerate(fk_one) if v is not None]
    d_ik = max(np.abs(ik_one[k] - ik_ref[k]).max() for k in ik_rows)
    d_fk = max(np.abs(fk_one[k] - fk_ref[k]).max() for k in fk_rows)
    return d_ik, d_fk, len(ik_rows), len(fk_rows)


def test_answers_are_the_batch_rows_on_1000_workspace_poses(machine):
    q, x = workspace(machine, 1000)
    d_ik, d_fk, n_ik, n_fk = differences(machine, q, x, chain_one_native.packed(machine))
    assert d_ik <= TOL and d_fk <= TOL
    assert n_ik >= 0.99 * len(x) and n_fk >= 0.99 * len(q)  # the C path answers nearly all
    for k in range(0, len(x), 97):  # and m.ik / m.fk take it
        assert np.abs(machine.ik(x[k], strokes="ignore")
                      - batch(machine.ik, x[k], strokes="ignore")).max() <= TOL


def test_the_dense_solve_gives_the_batch_bits(machine):
    """Packed with the dense solve (chain.c's pk_chain_rows, the batch path's): the same bits
    as the batch rows — the C port of the start, the retry, the modes, the wrapping, the
    branch rule and the strokes checked apart from the block elimination."""
    q, x = workspace(machine, 300, seed=1)
    dense = repacked(machine, False)
    ik_ref = machine.ik(x, strokes="ignore")
    one = np.array([dense.ik(dense.capsule, row, True, False) for row in x])
    act = np.flatnonzero(machine.model.actuated)
    turns = np.array([machine.model.elements[machine.model.variable_element(v)].type == "R"
                      for v in act]) if hasattr(machine.model, "variable_element") else \
        np.array([machine.element_of(int(v)).type == "R" for v in act])
    if chain_starts.closed_starts(machine, x[:1], np.array([machine.tool_length])) is not None:
        # the TriMule's closed-form start: its sines, arcsines and arctangents are libm's in C,
        # NumPy's on the batch path; from the solution to ~1e-15 the solve stops at once, so
        # the start's last bits are the answer's: ≤ 1e-14 (measured 1.7e-15), not the bits
        assert np.abs(one - ik_ref).max() <= 1e-14
        return
    np.testing.assert_array_equal(one[:, ~turns], ik_ref[:, ~turns])
    # the revolute actuators wrapped by libm's atan2, NumPy's on the batch path: 1 ulp at most
    assert (np.abs(one[:, turns] - ik_ref[:, turns]) <= np.spacing(np.abs(ik_ref[:, turns]))
            ).all()
    fk_ref = machine.fk(q, strokes="ignore")
    fk_one = np.array([dense.fk(dense.capsule, row, True, True) for row in q])
    np.testing.assert_allclose(fk_one, fk_ref, rtol=0, atol=1e-14)  # start formed in C


def test_a_machine_from_a_chain_file(tmp_path):
    from pkmkit.machines.chain_file import machine_file_text

    for name in NAMES:
        path = tmp_path / f"{name}.toml"
        path.write_text(machine_file_text(pkmkit.machine(name)))
        m = pkmkit.load(path)
        q, x = workspace(m, 200, seed=2)
        d_ik, d_fk, n_ik, n_fk = differences(m, q, x, chain_one_native.packed(m))
        assert d_ik <= TOL and d_fk <= TOL and n_ik >= 0.99 * len(x) and n_fk == len(q)


def test_beyond_a_stroke_the_batch_path_warns_or_refuses(machine):
    q = machine.home_q.copy()
    q[0] = machine.model.q_max[np.flatnonzero(machine.model.actuated)[0]] + 0.002
    c = chain_one_native.packed(machine)
    assert c.fk(c.capsule, q, False, True) is None
    assert c.fk(c.capsule, q, True, True) is not None
    with pytest.warns(StrokeWarning):
        machine.fk(q)
    with pytest.raises(OutOfStrokeError):
        machine.fk(q, strokes="refuse")
    x = machine.fk(q, strokes="ignore")
    assert c.ik(c.capsule, x, False, False) is None
    with pytest.warns(StrokeWarning):
        machine.ik(x)
    with pytest.raises(OutOfStrokeError):
        machine.ik(x, strokes="refuse")
    np.testing.assert_allclose(c.ik(c.capsule, x, True, False),
                               batch(machine.ik, x, strokes="ignore"), rtol=0, atol=TOL)


@pytest.mark.parametrize("bad", [[np.nan, 0, 1, 0, 0, 1], [0.1, 0.2, 1.0, 0, np.inf, 1],
                                 [0, 0, 1, 0, 0, 0], [2e9, 0, 1, 0, 0, 1],
                                 [0.1, 0.2, 1.0, 0, 0, 1, 0], [0.1, 0.2, 1.0, 0, 0],
                                 [0.1, 0.2, 1.0, 0, 0, None]])
def test_bad_poses_take_the_batch_paths_typed_errors(machine, bad):
    c = chain_one_native.packed(machine)
    assert c.ik(c.capsule, bad, False, False) is None
    with pytest.raises(InputError):
        machine.ik(bad)
    if all(isinstance(v, float | int) for v in bad):
        assert c.ik(c.capsule, np.array(bad, dtype=float), False, False) is None
        with pytest.raises(InputError):
            machine.ik(np.array(bad, dtype=float))


def test_bad_configurations_take_the_batch_paths_typed_errors(machine):
    c = chain_one_native.packed(machine)
    for bad in ([*machine.home_q[:-1], np.nan], list(machine.home_q[:-1]),
                [*machine.home_q, 0.0], [*machine.home_q[:-1], None]):
        assert c.fk(c.capsule, bad, False, True) is None
        with pytest.raises(InputError):
            machine.fk(bad)
    # not plain numbers but no error: the batch path's answers (a batch of one, a string)
    x = machine.fk(machine.home_q)
    for other, shape in (([[*x]], (1, len(machine.home_q))), ([*x[:5], str(x[5])], None)):
        assert c.ik(c.capsule, other, True, False) is None
        assert c.fk(c.capsule, other[:1] if shape else other, True, True) is None
        assert np.shape(machine.ik(other, strokes="ignore")) == (shape or (len(machine.home_q),))


def test_plain_numbers_of_every_accepted_kind(machine):
    x = workspace(machine, 5, seed=6)[1][0]
    ref = machine.ik(x)
    for form in (x, list(x), tuple(x), x[::-1][::-1], np.repeat(x, 2)[::2]):  # a strided view
        np.testing.assert_array_equal(machine.ik(form), ref)
    c = chain_one_native.packed(machine)
    a, b = c.ik(c.capsule, [*x[:5], 1], True, False), c.ik(c.capsule, [*x[:5], 1.0], True, False)
    assert (a is None and b is None) or np.array_equal(a, b)  # a Python int read as a float
    assert c.ik(c.capsule, [True, 0, 1, 0, 0, 1], True, False) is None  # bools are not plain
    assert c.ik(c.capsule, x.astype(np.float32), True, False) is None  # another buffer
    np.testing.assert_allclose(machine.ik(x.astype(np.float32)),  # the Python paths' answer
                               batch(machine.ik, x.astype(np.float32).astype(float)),
                               rtol=0, atol=TOL)


def test_a_pose_off_the_workspace_raises_the_batch_paths_convergence_error(machine):
    far = machine.fk(machine.home_q).copy()
    far[0] += 1e6  # a thousand kilometres away: the legs' closure does not converge
    c = chain_one_native.packed(machine)
    assert c.ik(c.capsule, far, True, False) is None
    with pytest.raises(ConvergenceError):
        machine.ik(far)


def test_two_threads_calling_one_machine(machine):
    q, x = workspace(machine, 60, seed=3)
    ik_ref, fk_ref = machine.ik(x, strokes="ignore"), machine.fk(q, strokes="ignore")

    def work(part: int) -> bool:
        ok = True
        for _ in range(5):
            for k in range(part, len(x), 2):
                ok &= bool(np.abs(machine.ik(x[k], strokes="ignore") - ik_ref[k]).max() <= TOL)
                ok &= bool(np.abs(machine.fk(q[k], strokes="ignore") - fk_ref[k]).max() <= TOL)
        return ok

    with ThreadPoolExecutor(2) as pool:
        assert all(pool.map(work, range(2)))


def test_a_machine_pickles_and_copies_after_a_call(machine):
    x = machine.fk(machine.home_q + 0.01)
    q = machine.ik(x)
    assert isinstance(machine.__dict__["_chain_one_native"], chain_one_native.Packed)
    for other in (pickle.loads(pickle.dumps(machine)), copy.deepcopy(machine)):
        assert other.__dict__.get("_chain_one_native") is None  # packed again when called
        np.testing.assert_array_equal(other.ik(x), q)
        assert isinstance(other.__dict__["_chain_one_native"], chain_one_native.Packed)


def test_the_start_option_and_the_full_answer(machine):
    """``chain_one_ik``'s ``start`` (a previous solution) and ``full`` (q, u, iterations,
    residual) against the batch record of the same start."""
    _, x = workspace(machine, 20, seed=4)
    c = chain_one_native.packed(machine)
    for row in x[1:]:
        first = batch(machine.ik, x[0], full_output=True, strokes="ignore")
        ref = batch(machine.ik, row, full_output=True, strokes="ignore", start=first.solution)
        found = c.ik(c.capsule, row, True, True, first.solution)
        if found is None:
            continue
        one, u, iterations, residual = found
        assert np.abs(one - ref.q).max() <= TOL
        assert np.abs(u - ref.solution).max() <= TOL
        assert iterations == ref.iterations and residual <= 1e-9
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        assert c.ik(c.capsule, x[0], True, True, [np.nan] * len(first.solution)) is None


@pytest.mark.parametrize("plant", ["base", "rates", "lower", "wrist", "tool", "closed"])
def test_planted_wrong_constants_are_caught(plant):
    """A packed constant slightly wrong: the answers leave the batch rows (or the C path stops
    answering where it should)."""
    m = pkmkit.machine("trimule-600")
    q, x = workspace(m, 150, seed=5)
    args = list(chain_one_native.pack_arguments(m))
    where = {"base": 12, "rates": 13, "tool": 14, "lower": 21, "wrist": 24, "closed": 33}[plant]
    planted = args[where] + 1e-6 if plant == "tool" else args[where].copy()
    if plant in ("base", "rates"):  # the first-order start: the closed one's off (session 33)
        args[33] = None
    if plant == "closed":
        planted[1] += 1e-4  # the eccentricity c2 of the closed-form start: more iterations
    elif plant == "base":
        planted[0] += 1e-4
    elif plant == "rates":
        planted[:6] *= 0.0  # the platform's first-order rates: more iterations, other branch
    elif plant == "lower":
        planted[np.flatnonzero(m.model.actuated)[0]] += 0.05  # a stroke 5 cm too short
    elif plant == "wrist":
        planted[4] = 1.0 - planted[4]  # the turn's reach misjudged
    # tool: 1 µm longer, fk's tool point and ik's target off by as much
    args[where] = planted
    c = chain_one_native.Packed(native.chain_one_pack(*args), native)
    ik_ref = m.ik(x, strokes="ignore")
    fk_ref = m.fk(q, strokes="ignore")
    strokes_ignored = plant != "lower"
    ik = [c.ik(c.capsule, row, strokes_ignored, True) for row in x]
    fk = [c.fk(c.capsule, row, True, True) for row in q]
    wrong = sum(v is None or np.abs(v[0] - ik_ref[k]).max() > TOL
                or v[2] != batch(m.ik, x[k], full_output=True, strokes="ignore").iterations
                for k, v in enumerate(ik))
    wrong += sum(v is None or np.abs(v - fk_ref[k]).max() > TOL for k, v in enumerate(fk))
    assert wrong > 0


def test_fks_regularity_bound_never_exceeds_the_closures_conditioning(machine):
    """Oracle: σ_min/σ_max of the closure Jacobian at the solution by NumPy's SVD. With the
    threshold just above that ratio the C call must not certify the closure (a bound above the
    ratio would answer where the batch path calls the closure singular); well below, it does."""
    from pkmkit.solve import chain_rows

    q, _ = workspace(machine, 8, seed=7)
    res = machine.fk(q, full_output=True, strokes="ignore")
    passive = np.asarray(machine.passive_variables, dtype=int)
    values = np.tile(machine._home["values"], (len(q), 1))
    values[:, np.flatnonzero(machine.model.actuated)] = q
    values[:, passive] = res.passive
    cu = chain_rows.closure_jacobian(machine.model, values, res.platform, passive)
    sv = np.linalg.svd(cu, compute_uv=False)
    ratio = sv[:, -1] / sv[:, 0]
    args = list(chain_one_native.pack_arguments(machine))
    for k in range(len(q)):
        for threshold, answered in ((ratio[k] * (1 + 1e-9), False), (ratio[k] / 40, True)):
            args[30] = threshold
            c = chain_one_native.Packed(native.chain_one_pack(*args), native)
            assert (c.fk(c.capsule, q[k], True, True) is not None) == answered, (k, threshold)
            assert c.fk(c.capsule, q[k], True, False) is not None  # no check asked


def test_fks_regularity_bound_is_the_frobenius_product_of_the_singular_values(machine):
    """Oracle: the bound 1 / sqrt(||J||_F^2 ||J^+||_F^2) = 1 / sqrt(sum σ_i^2 sum σ_i^-2) from
    NumPy's SVD of the closure Jacobian at the solution; the C call answers with the threshold
    just below it and declines just above (session 32: the bound from the trace of J'J and L^-1
    by rows; a bound off by a factor of 2 passes the test above but not this one)."""
    from pkmkit.solve import chain_rows

    q, _ = workspace(machine, 8, seed=7)
    res = machine.fk(q, full_output=True, strokes="ignore")
    passive = np.asarray(machine.passive_variables, dtype=int)
    values = np.tile(machine._home["values"], (len(q), 1))
    values[:, np.flatnonzero(machine.model.actuated)] = q
    values[:, passive] = res.passive
    cu = chain_rows.closure_jacobian(machine.model, values, res.platform, passive)
    sv = np.linalg.svd(cu, compute_uv=False)
    bound = 1.0 / np.sqrt((sv**2).sum(axis=1) * (sv**-2.0).sum(axis=1))
    args = list(chain_one_native.pack_arguments(machine))
    for k in range(len(q)):
        for threshold, answered in ((bound[k] * (1 - 1e-7), True), (bound[k] * (1 + 1e-7), False)):
            args[30] = threshold
            c = chain_one_native.Packed(native.chain_one_pack(*args), native)
            assert (c.fk(c.capsule, q[k], True, True) is not None) == answered, (k, threshold)


#: A leg joint of each machine (its index in u) that, turned by a quarter turn and 0.3 rad from
#: a solved configuration, leads the raw solve to a closure outside the legs' home assembly modes
#: (found by trying each leg joint on 20 poses: 20 of 20 on the Tripteor, 14 of 20 on the TriMule).
OTHER_MODE_JOINT = {"Tripteor": 16, "TriMule": 18}


def test_a_start_from_a_solved_neighbour_finds_the_batch_root(machine):
    """The premise of a start table (docs/benchmarks.md, "a better start measured"): the C call
    started from a neighbouring pose's solution (a table node) returns the batch row's root —
    to 1e-12 on the Tripteor, to the solver's ``xtol`` on the TriMule (measured 3e-12: the same
    root, another stopping point) — and a planted wrong node, a leg in another assembly mode,
    is harmless: the raw solve from it converges outside the legs' home modes, the home-mode
    test retries from home and the answer is the batch row again (skipping the retry in C fails
    this test)."""
    _, x = workspace(machine, 40, seed=7)
    _, nodes = workspace(machine, 40, seed=8)
    c = chain_one_native.packed(machine)
    ref = machine.ik(x, strokes="ignore")
    family = machine.name.split()[0]
    tol = TOL if family == "Tripteor" else 1e-10
    chain_one.usable(machine, "chain_ik")
    k1 = chain_one.constants(machine)
    w = chain_one._work(k1)
    other_mode = 0
    for k, row in enumerate(x):
        near = int(np.argmin(np.abs(nodes[:, :3] - row[:3]).sum(axis=1)))
        node = c.ik(c.capsule, nodes[near], True, True)[1]
        found = c.ik(c.capsule, row, True, True, node)
        assert found is not None and np.abs(found[0] - ref[k]).max() <= tol
        wrong = c.ik(c.capsule, row, True, True)[1]  # planted: the answer, one leg turned
        wrong[OTHER_MODE_JOINT[family]] += np.pi / 2 + 0.3
        w.u_inv[0], w.target[0] = wrong, row
        (k1.from_kernel.call or k1.from_kernel.first)(*k1.first_args, w.u_inv, w.target,
                                                      k1.tool_row, w.info)
        other_mode += w.info[0] == 0 and w.info[3] == 0.0  # converged, other assembly mode
        found = c.ik(c.capsule, row, True, False, wrong)
        assert found is not None and np.abs(found - ref[k]).max() <= TOL
    assert other_mode >= len(x) // 2  # the plant bites: without the retry these answers differ
