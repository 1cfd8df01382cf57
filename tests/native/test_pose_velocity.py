"""The C one-pose velocity model of six-rod full-pose machines (``pkmkit.native.kernels``
``pose_velocity``; issue 22 §1) against the Numba one-pose kernel it twins
(:mod:`pkmkit.machines.full_pose_velocity_kernel`, ``PKMKIT_NATIVE=0``) and the batch path's
row (NumPy, LAPACK: the independent oracle), at random poses, far poses and poses near parallel
singularities: the plain arithmetic (A, B, J⁻¹, the serial measure) bit for bit with Numba's;
the parallel measure and J's singular values (the C kernel's Jacobi in round-robin order,
Numba's cyclic) to 1e-12 of their scale; J and the determinants, which the C kernel takes
from its own LU
factorisation where Numba and NumPy call LAPACK, to 1e-12 of their scale (× cond A near a
parallel singularity); the flags equal. Also: its refusals, a refused row handed to the batch
path, and a fresh process's first one-pose Jacobian of a hexapod without Numba."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import full_pose, full_pose_one, full_pose_velocity_one
from pkmkit.machines.full_pose_velocity_one import FIELDS
from tests.conftest import near_parallel_singular_poses

try:
    from pkmkit.native import kernels as _kernels
except ImportError:
    _kernels = None

pytestmark = [pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "pose_velocity"),
                                 reason="pkmkit.native.kernels was not built"),
              pytest.mark.filterwarnings("ignore::pkmkit.exceptions.StrokeWarning")]

SIX_RODS = [name for name in pkmkit.machines()
            if pkmkit.machine(name).family == "full-pose"
            and pkmkit.machine(name).direct_kernel().geom.shape[0] == 6] + ["delta6"]
#: Fields of plain arithmetic on A and B: the Numba kernel's bits.
EXACT = ("A", "B", "J_inv", "serial_measure", "tolerance", "q", "characteristic_length")


def _poses(m, n, seed, spread):
    rng = np.random.default_rng(seed)
    if m.position_controlled:
        positions = m.home_pose[:3] + rng.uniform(-2 * spread, 2 * spread, (n, 3))
        x = m.ik(positions, full_output=True, strokes="ignore").pose
    else:
        x = np.tile(m.home_pose, (n, 1)) + rng.uniform(-spread, spread, (n, 6))
    return x[np.isfinite(x).all(axis=1)]


def _record(m, x, tol):
    """The one-pose record of pose x whatever its strokes (as m.jacobian builds it), or None
    where its inverse model refuses it."""
    q = m.one_pose_inverse()(x)
    if q is None:
        return None
    evaluation = full_pose_velocity_one.OnePoseFullVelocity(
        m.direct_kernel().geom, m.n_actuators, float(m.characteristic_length), list(x), q,
        tol, lambda: pytest.fail("the kernel refused the row"))
    return type(m.jacobian(m.home_pose))(evaluation)


def _fields(m, x, tol, native, monkeypatch):
    """Every field of a fresh one-pose record per field, C (native) or Numba; None where the
    inverse model refuses the pose. Native: the record ``m.jacobian`` builds
    (``PoseOne.jacobian``, tests/native/test_pose_one.py), checked bit for bit against the one
    of ``pose_velocity`` (the same kernel, pk_pose_fill)."""
    monkeypatch.setenv("PKMKIT_NATIVE", "1" if native else "0")
    try:
        if _record(m, x, tol) is None:
            return None
        fields = {name: getattr(_record(m, x, tol), name) for name in FIELDS}
        if native:
            one = full_pose_one.native_one(m)
            for name in FIELDS:
                evaluation = one.jacobian(x, tol, False, lambda *a: pytest.fail("refused"))
                got, want = evaluation.field(name), fields[name]
                assert type(got) is type(want) and np.array_equal(
                    np.asarray(got), np.asarray(want), equal_nan=True), name
        return fields
    finally:
        monkeypatch.delenv("PKMKIT_NATIVE")


@pytest.fixture
def no_pose_one(monkeypatch):
    """``m.jacobian`` of one pose through OnePoseFullVelocity and its ``pose_velocity`` twin
    (the path of poses PoseOne does not take: float32 or int32 arrays)."""
    monkeypatch.setattr(full_pose, "native_one", lambda machine: None)


def _close(got, want, name, where, kappa=1.0):
    assert type(got) is type(want) or (isinstance(got, np.ndarray)
                                       and isinstance(want, np.ndarray)), (name, where)
    got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    assert got.shape == want.shape, (name, where)
    if np.array_equal(got, want, equal_nan=True):
        return  # the same numbers, NaN where NaN: what follows holds (and costs ≈ 0.3 ms)
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want), err_msg=f"{name} {where}")
    scale = max(1.0, float(np.abs(want[np.isfinite(want)]).max(initial=0.0)))
    if name in ("J", "J_homogeneous", "J_inv", "singular_values", "condition",
                "translation_singular_values", "rotation_singular_values"):
        scale *= kappa
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * scale,
                               err_msg=f"{name} {where}")


def _compare(m, poses, tol, monkeypatch, where):
    """C = Numba (bits for EXACT, the flags; 1e-12 otherwise) and C ≈ the batch row."""
    compared, pairs = 0, []
    for k, x in enumerate(poses):
        c = _fields(m, x.tolist(), tol, True, monkeypatch)
        numba = _fields(m, x.tolist(), tol, False, monkeypatch)
        if c is None or numba is None:
            assert c is None and numba is None, (where, k)
            continue
        pairs.append((k, c, numba))
    if not pairs:
        return 0
    # the batch rows from one batch call (docs/testing.md, "Sixth round (session 34, suite3a)")
    rows = [k for k, _, _ in pairs]
    batch = m.jacobian(poses[rows], q=np.array([np.asarray(c["q"]) for _, c, _ in pairs]),
                       tol=tol)
    for row, (k, c, numba) in enumerate(pairs):
        a = np.asarray(c["A"])
        kappa = max(1.0, float(np.linalg.cond(a / np.linalg.norm(a[:, :3], axis=1)[:, None])))
        for name in FIELDS:
            if name in EXACT:
                assert np.array_equal(np.asarray(c[name]), np.asarray(numba[name]),
                                      equal_nan=True), (where, k, name)
            if name == "mode" and abs(float(c["det_A"])) <= 1e-12 * np.abs(a).max() ** 6:
                continue  # the sign of a determinant at rounding level
            _close(c[name], numba[name], name, f"{where} pose {k} (Numba)", kappa)
            want = getattr(batch, name)
            want = want[row] if np.ndim(want) and name not in (
                "tolerance", "characteristic_length") else want
            _close(c[name], want, name, f"{where} pose {k} (batch)", kappa)
        assert int(c["singularity"]) == int(numba["singularity"]), (where, k)
        compared += 1
    return compared


def _machine(name):
    """A built-in machine, or ``delta6``: the Delta robot's six forearm rods on a free
    platform (cranks; as tests/native/test_kernels.py)."""
    if name != "delta6":
        return pkmkit.machine(name)
    from pkmkit.machines.full_pose import FullPoseMachine
    from pkmkit.model.rods import build_rod_model, leg_specs

    delta = pkmkit.machine("delta")
    model = build_rod_model(leg_specs(delta.model), dims=6, actuator_names=("q1", "q2", "q3"),
                            home_pose=(*delta.home_pose, 0.0, 0.0, 0.0))
    return FullPoseMachine(id="delta6", name="delta6", kind=None, params={}, model=model)


@pytest.mark.parametrize("name", SIX_RODS)
def test_random_and_far_poses(name, monkeypatch):
    m = _machine(name)
    compared = 0
    for spread, tol in ((0.05, 1e-6), (0.2, 0.02), (0.5, 0.3)):
        compared += _compare(m, _poses(m, 15, seed=31, spread=spread), tol, monkeypatch,
                             f"{name} spread {spread}")
    assert compared >= 20


def test_near_parallel_singularities(monkeypatch):
    m, x, measure = near_parallel_singular_poses(200, np.random.default_rng(32))
    order = np.argsort(measure)[:20]  # the nearest (μ from below 1e-4)
    x, measure = x[order], measure[order]
    for tol in (1e-6, float(np.median(measure))):  # half of them flagged
        assert _compare(m, x, tol, monkeypatch, f"near-singular tol {tol}") >= 15


def test_the_c_kernel_answered(monkeypatch, no_pose_one):
    m = pkmkit.machine("gough-stewart")
    calls = []
    real = _kernels.pose_velocity

    def counted(*args):
        calls.append(args[-1])
        return real(*args)

    monkeypatch.setattr(full_pose_velocity_one, "_native_twin", lambda geom: counted)
    jac = m.jacobian((m.home_pose + 0.01).tolist())
    assert type(jac).__name__.startswith("OnePose")
    assert jac.J.shape == (6, 6) and jac.condition >= 1.0  # matrices, then singular values
    assert jac.translation_singular_values.shape == (3,)  # then those of J's rows
    assert 0.0 < jac.parallel_measure <= 1.0  # then the measure itself
    assert calls == [0, 1, 3, 7]


def test_a_refused_row_goes_to_the_batch_path(monkeypatch, no_pose_one):
    m = pkmkit.machine("dietmaier-hexapod")
    x = m.home_pose + 0.01
    monkeypatch.setattr(full_pose_velocity_one, "_native_twin",
                        lambda geom: lambda *args: None)
    fast = m.jacobian(x.tolist())
    assert type(fast).__name__.startswith("OnePose")
    batch = m.jacobian(x[None], q=np.asarray(fast.q)[None])
    for name in ("J", "condition", "det_A", "singularity"):
        assert np.array_equal(getattr(fast, name), getattr(batch, name)[0])


def test_refusals():
    m = pkmkit.machine("gough-stewart")
    geom = m.direct_kernel().geom
    x = (m.home_pose + 0.01).tolist()
    q = m.ik(np.array(x)).tolist()
    pv = _kernels.pose_velocity
    bad_geom = geom.copy()
    bad_geom[0, 14] = 6.0  # actuator index out of range
    for error, call in [
        (TypeError, lambda: pv(geom, x, q, 1.0, 1e-6)),
        (TypeError, lambda: pv(geom, x, np.array(q), 1.0, 1e-6, False)),
        (TypeError, lambda: pv(geom, [1, 2, 3, 4, 5, 6], q, 1.0, 1e-6, False)),
        (ValueError, lambda: pv(geom, x[:5], q, 1.0, 1e-6, False)),
        (ValueError, lambda: pv(geom, x, [], 1.0, 1e-6, False)),
        (ValueError, lambda: pv(geom, x, q, 0.0, 1e-6, False)),
        (ValueError, lambda: pv(geom, x, q, 1.0, float("nan"), False)),
        (ValueError, lambda: pv(geom[:5], x, q, 1.0, 1e-6, False)),
        (ValueError, lambda: pv(geom.astype(np.float32), x, q, 1.0, 1e-6, False)),
        (TypeError, lambda: pv(geom[:, ::2], x, q, 1.0, 1e-6, False)),
        (TypeError, lambda: pv(list(geom), x, q, 1.0, 1e-6, False)),
        (ValueError, lambda: pv(bad_geom, x, q, 1.0, 1e-6, False)),
    ]:
        with pytest.raises(error):
            call()
    assert pv(geom, [float("nan"), *x[1:]], q, 1.0, 1e-6, False) is None  # not finite
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        assert pv(geom, x, q, 1.0, 1e-6, True) is not None


def test_a_fresh_process_imports_no_numba():
    code = ("import sys, pkmkit\n"
            "m = pkmkit.machine('gough-stewart')\n"
            "j = m.jacobian((m.home_pose + 0.01).tolist())\n"
            "j.J, j.condition, j.singularity\n"
            "print('numba' in sys.modules, type(j).__name__.startswith('OnePose'))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "True"]


def _c_inverse(m, pose):
    """q of one pose by the C inverse (``PoseOne.ik``, no stroke test) as a list, or None."""
    q = full_pose_one.native_one(m).ik(pose, False)
    return None if q is None else q.tolist()


@pytest.mark.parametrize("name", SIX_RODS)
def test_c_inverse_is_one_pose_inverse_bit_for_bit(name):
    """The C inverse model (``pose_velocity.c``'s ``pk_pose_inverse_one``, which ``m.ik``,
    ``m.jacobian`` of one pose run through ``PoseOne``) against
    :class:`~pkmkit.machines.full_pose_one.OnePoseInverse`: the same q, the same refusals (rods
    that cannot close, rods of one actuator that disagree: the Verne module's and delta6's
    pairs), on reachable poses, poses nudged off the Verne's constraint and far ones; lists,
    tuples and arrays alike (tests/native/test_pose_one.py: the other entries)."""
    m = _machine(name)
    inverse = m.one_pose_inverse()
    rng = np.random.default_rng(33)
    if m.position_controlled:
        x = m.ik(m.home_pose[:3] + rng.uniform(-0.3, 0.3, (300, 3)), full_output=True,
                 strokes="ignore").pose
        x = x[np.isfinite(x).all(axis=1)]
        x = np.vstack([x, x + rng.normal(scale=1e-7, size=x.shape)])
    else:
        x = m.home_pose + rng.uniform(-0.4, 0.4, (300, 6))
    refused = 0
    for pose in x.tolist():
        want = inverse(pose)
        assert _c_inverse(m, pose) == want, pose
        assert _c_inverse(m, tuple(pose)) == want
        assert _c_inverse(m, np.array(pose)) == want
        refused += want is None
    assert 0 < refused < len(x) or not m.position_controlled


@pytest.mark.parametrize("name", ["verne", "delta6"])
def test_c_inverse_at_the_edge_of_reach(name):
    """Poses bisected onto the edge of reach (slides: the radicand's clamp within the boundary
    tolerance; cranks: the cosine's clamp to ±1) from both sides: the same q and refusals."""
    m = _machine(name)
    inverse = m.one_pose_inverse()
    rng = np.random.default_rng(34)

    def pose_at(t, d):
        if m.position_controlled:  # the pose its rods impose at that position
            return m.ik((m.home_pose[:3] + t * d)[None], full_output=True,
                        strokes="ignore").pose[0]
        return m.home_pose + t * d

    edge = 0
    for _ in range(8):
        d = rng.normal(size=3 if m.position_controlled else 6)
        d /= np.linalg.norm(d)
        lo, hi = 0.0, 4.0
        if inverse(pose_at(hi, d).tolist()) is not None:
            continue
        poses = []
        for _ in range(52):
            mid = 0.5 * (lo + hi)
            pose = pose_at(mid, d)
            if not np.isfinite(pose).all():
                hi = mid
                continue
            poses.append(pose.tolist())
            lo, hi = (mid, hi) if inverse(pose.tolist()) is not None else (lo, mid)
        for pose in poses[-20:]:
            assert _c_inverse(m, pose) == inverse(pose), pose
        edge += 1
    assert edge >= 3


def test_state_array_refusals():
    m = pkmkit.machine("gough-stewart")
    x = (m.home_pose + 0.01).tolist()
    state = _kernels.pose_velocity(m.direct_kernel().geom, x, m.ik(np.array(x)).tolist(), 1.0,
                                   1e-6, 0)
    size = len(state) // 8
    a = _kernels.state_array(state, 0, 6, 6)
    assert a.shape == (6, 6) and a.flags.writeable and a.flags.c_contiguous
    assert np.array_equal(a.ravel(), np.frombuffer(state)[:36])
    assert _kernels.state_array(state, size - 2, 2, 0).shape == (2,)
    for error, args in [(ValueError, (state, size - 1, 2, 0)), (ValueError, (state, -1, 1, 1)),
                        (ValueError, (state, 0, 0, 1)), (TypeError, (bytes(state), 0, 1, 1)),
                        (TypeError, (state, 0, 1))]:
        with pytest.raises(error):
            _kernels.state_array(*args)


def test_the_kernel_runs_once_per_record_and_level(monkeypatch, no_pose_one):
    m = pkmkit.machine("gough-stewart")
    calls = []
    real = _kernels.pose_velocity

    def counted(*args):
        calls.append(args[-1])
        return real(*args)

    monkeypatch.setattr(full_pose_velocity_one, "_native_twin", lambda geom: counted)
    jac = m.jacobian((m.home_pose + 0.01).tolist())
    for name in ("J", "A", "B", "J_inv", "J_homogeneous", "det_A", "mode", "singularity",
                 "serial_measure"):
        getattr(jac, name)
    assert calls == [0]
    jac.condition, jac.singular_values  # noqa: B018
    assert calls == [0, 1]
