"""The generated LinuxCNC module of a joint-chain machine, compiled with the system C compiler
against the stand-in headers (``linuxcnc_stub/``) and called through ctypes, against pkmkit's
own direct and inverse models: the Tripteor X7, the TriMule 600 and the crank–slider, nominal
and with calibration-sized compatible defects."""

from __future__ import annotations

import ctypes
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.calibration.simulate import random_defects
from pkmkit.exceptions import ExportCheckError, UnsupportedExportError
from pkmkit.export.linuxcnc import linuxcnc_source, module_name
from pkmkit.export.linuxcnc_check import check_linuxcnc_source
from pkmkit.model.defects_table import apply_defect_vector
from pkmkit.status import Status

from .c_build import STUB, build_shared
from .test_linuxcnc import FLAGS, _compiler

CHAINS = ["tripteor-x7", "trimule-600", "crank-slider"]
MM = 1e-3
TOL = 1e-9  # m, rad
#: Codes of the module's refusals.
REFUSED = {-1, -2, -5, -6}


def defects(machine, seed: int) -> np.ndarray:
    """Random compatible defects of calibration size (≤ 0.08 mm, 0.08 mrad): their
    second-order closure misfit stays below pkmkit's 1e-9 m."""
    return 0.01 * random_defects(machine, np.random.default_rng(seed))


def calibrated(machine, seed: int):
    """The machine with :func:`defects`."""
    delta = defects(machine, seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return apply_defect_vector(machine, delta)


class ChainModule:
    """A compiled joint-chain module: batch calls in SI (poses: pkmkit's tool point and axis;
    joints: m, rad)."""

    def __init__(self, machine, directory: Path):
        cc = _compiler()
        self.machine = machine
        self.n = machine.n_actuators
        self.joint_scale = np.where(np.array(machine.actuator_quantities) == "angle",
                                    np.pi / 180.0, MM)
        name = module_name(machine.id)
        source = directory / f"{name}.c"
        source.write_text(linuxcnc_source(machine), encoding="utf-8")
        lib = directory / f"{name}.so"
        build_shared(cc, FLAGS, [source, STUB / "harness.c"], lib)  # once per same inputs
        self.lib = ctypes.CDLL(str(lib))
        ptr = np.ctypeslib.ndpointer
        arr = ptr(np.float64, flags="C")
        status = ptr(np.int32, flags="C")
        for f in ("pkm_batch_inverse", "pkm_batch_inverse_from_home"):
            getattr(self.lib, f).argtypes = [ctypes.c_long, ctypes.c_int, arr, arr, status]
        for f in ("pkm_batch_forward", "pkm_batch_forward_from_home"):
            getattr(self.lib, f).argtypes = [ctypes.c_long, ctypes.c_int, arr, arr, arr, status]
        self.lib.pkm_home.argtypes = [arr, arr]

    @staticmethod
    def world(x: np.ndarray) -> np.ndarray:
        """Tool points and axes (N, 6) → LinuxCNC worlds X Y Z (mm) A B (deg), C = 0."""
        a = x[:, 3:] / np.linalg.norm(x[:, 3:], axis=1)[:, None]
        out = np.zeros((len(x), 6))
        out[:, :3] = x[:, :3] / MM
        out[:, 3] = np.degrees(np.arctan2(-a[:, 1], np.hypot(a[:, 0], a[:, 2])))
        out[:, 4] = np.degrees(np.arctan2(a[:, 0], a[:, 2]))
        return out

    @staticmethod
    def pose(world: np.ndarray) -> np.ndarray:
        """LinuxCNC worlds → tool points and axes (scipy: the axis Ry(B) Rx(A) ez)."""
        axis = Rotation.from_euler("xy", world[:, 3:5], degrees=True).apply([0.0, 0.0, 1.0])
        return np.concatenate([world[:, :3] * MM, axis], axis=1)

    def inverse(self, x: np.ndarray, from_home: bool = True) -> tuple[np.ndarray, np.ndarray]:
        q = np.full((len(x), self.n), np.nan)
        status = np.zeros(len(x), dtype=np.int32)
        f = self.lib.pkm_batch_inverse_from_home if from_home else self.lib.pkm_batch_inverse
        f(len(x), self.n, np.ascontiguousarray(self.world(x)), q, status)
        return q * self.joint_scale, status

    def forward(self, q: np.ndarray, from_home: bool = True) -> tuple[np.ndarray, np.ndarray]:
        world = np.zeros((len(q), 6))
        status = np.zeros(len(q), dtype=np.int32)
        f = self.lib.pkm_batch_forward_from_home if from_home else self.lib.pkm_batch_forward
        f(len(q), self.n, np.ascontiguousarray(q / self.joint_scale), np.zeros((len(q), 6)),
          world, status)
        return self.pose(world), status


def actuator_draw(machine, n: int, seed: int, beyond: float = 0.2) -> np.ndarray:
    """Actuator sets across the strokes (±0.3 about home where unlimited), ``beyond`` of the
    stroke past each end: some sets out of stroke."""
    act = np.flatnonzero(machine.model.actuated)
    lo, hi = machine.model.q_min[act], machine.model.q_max[act]
    lo = np.where(np.isfinite(lo), lo, machine.home_q - 0.3)
    hi = np.where(np.isfinite(hi), hi, machine.home_q + 0.3)
    rng = np.random.default_rng(seed)
    return lo + rng.uniform(-beyond, 1 + beyond, (n, len(act))) * (hi - lo)


@pytest.fixture(scope="module", params=[(m, c) for m in CHAINS for c in (False, True)],
                ids=lambda p: p[0] + ("-calibrated" if p[1] else ""))
def module(request, tmp_path_factory):
    name, is_calibrated = request.param
    machine = pkmkit.machine(name)
    if is_calibrated:
        machine = calibrated(machine, seed=len(name))
        assert 0 < machine.home_closure_residual <= TOL
    return ChainModule(machine, tmp_path_factory.mktemp(name))


@pytest.mark.ci
def test_forward_matches_pkmkit_and_refuses_where_it_does(module):
    """From home: the same tool point and axis (1e-9 m, rad) and the same refusals as pkmkit's
    direct model refusing strokes (actuators beyond theirs, passive joints beyond theirs)."""
    m = module.machine
    q = actuator_draw(m, 600 if m.id.startswith("trimule") else 1500, seed=1)
    ref = m.fk(q, full_output=True, strokes="refuse")
    ok = np.asarray(ref.status) == Status.OK
    assert 0.05 < ok.mean() < 0.95 or m.n_actuators == 1
    pose, status = module.forward(q)
    assert np.array_equal(status == 0, ok)
    assert set(np.unique(status[~ok])) <= REFUSED
    assert np.abs(pose[ok] - ref.pose[ok]).max() <= TOL


def _poses(m, n: int, seed: int) -> np.ndarray:
    """Tool points and axes: reached ones (pkmkit's direct model at actuator sets, some out of
    stroke) and, a quarter more, those moved a few cm and degrees (mostly out of reach)."""
    rng = np.random.default_rng(seed)
    x = m.fk(actuator_draw(m, n, seed), strokes="ignore")
    moved = x[: n // 4] + rng.normal(0, 1, (n // 4, 6)) * [0.03, 0.03, 0.03, 0.1, 0.1, 0.1]
    x = np.concatenate([x, moved])
    x = x[np.isfinite(x).all(axis=1)]
    x[:, 3:] /= np.linalg.norm(x[:, 3:], axis=1)[:, None]
    return x


def test_inverse_matches_pkmkit_from_home(module):
    """After kinematicsHome the module starts from home, as pkmkit's inverse model: the same
    joints (1e-9 m, rad) and the same refusals (out of reach, out of stroke). The TriMule's
    head has two branches (Q4, Q5) and (Q4 ± π, −Q5): both take the one whose Q4 is nearest
    the start's (before that rule, from home, a third of the TriMule's poses came out on the
    other branch in one of them)."""
    m = module.machine
    x = _poses(m, 400 if m.id.startswith("trimule") else 1200, seed=2)
    ref = m.ik(x, full_output=True, strokes="refuse")
    q, status = module.inverse(x)
    ok = np.asarray(ref.status) == Status.OK
    assert ok.sum() >= 50 and (~ok).sum() >= 50
    assert set(np.unique(status[status != 0])) <= REFUSED
    reached = m.fk(q[status == 0], strokes="refuse", full_output=True)
    assert (np.asarray(reached.status) == Status.OK).all()
    assert np.abs(reached.pose - x[status == 0]).max() <= TOL
    assert np.array_equal(status == 0, ok)
    assert np.abs(q[ok] - ref.q[ok]).max() <= TOL


def test_inverse_along_a_path_follows_the_previous_configuration(module):
    """Along a path (LinuxCNC calls it every servo period) the module starts from its last
    solution: the joints are pkmkit's inverse model started from the previous joints."""
    m = module.machine
    rng = np.random.default_rng(3)
    q_path = m.home_q + np.cumsum(rng.normal(0, 1, (300, m.n_actuators)), axis=0) * np.where(
        np.array(m.actuator_quantities) == "angle", 2e-3, 2e-5)
    act = np.flatnonzero(m.model.actuated)  # kept within the strokes
    q_path = np.clip(q_path, m.model.q_min[act] + 1e-6, m.model.q_max[act] - 1e-6)
    x = m.fk(q_path, strokes="ignore")
    module.lib.pkm_home(np.zeros(6), np.zeros(module.n))
    q, status = module.inverse(x, from_home=False)
    assert (status == 0).all()
    previous = np.vstack([m.home_q, q[:-1]])
    ref = m.ik(x, q0=previous)
    assert np.abs(q - ref).max() <= TOL
    assert np.abs(q - q_path).max() <= 1e-8  # the path's own joints: the branch followed
    pose, status = module.forward(q, from_home=False)
    assert (status == 0).all() and np.abs(pose - x).max() <= TOL


def test_home_type_and_invalid_inputs(module):
    m = module.machine
    world, joints = np.zeros(6), np.zeros(module.n)
    assert module.lib.pkm_home(world, joints) == 0
    assert module.lib.pkm_type() == 4  # KINEMATICS_BOTH
    assert module.lib.pkm_app_main() == 0
    assert np.abs(joints * module.joint_scale - m.home_q).max() <= TOL
    assert np.abs(module.pose(world[None])[0] - m.home_pose).max() <= TOL
    x = np.tile(m.home_pose, (3, 1))
    x[0, 0], x[1, 1], x[2, 2] = np.nan, np.inf, 1e12
    assert (module.inverse(x)[1] == -4).all()
    q = np.tile(m.home_q, (2, 1))
    q[0, 0], q[1, -1] = np.nan, np.inf
    assert (module.forward(q)[1] == -4).all()


@pytest.mark.ci
def test_the_module_carries_the_calibrated_geometry(tmp_path):
    """The nominal Tripteor's module misses a calibrated Tripteor by more than the defects'
    effect: the defects did reach the calibrated file (whose round trips are above)."""
    nominal = pkmkit.machine("tripteor-x7")
    bent = calibrated(nominal, seed=11)
    module = ChainModule(nominal, tmp_path)
    x = bent.fk(actuator_draw(bent, 50, seed=4, beyond=-0.1))
    q, status = module.inverse(x)
    assert (status == 0).all()
    assert np.abs(q - bent.ik(x)).max() > 1e-5


def test_incompatible_defects_are_refused(tmp_path):
    """A defect the hyperstatic legs absorb only in least squares: refused, nothing written."""
    from pkmkit.cli.main import cli
    from pkmkit.io.machine_defects import write_machine_with_defects
    from pkmkit.machines.registry import preset_path

    nominal = pkmkit.machine("tripteor-x7")
    m = nominal.with_defects({"dK21": 1e-3})
    with pytest.raises(UnsupportedExportError, match="least squares"):
        linuxcnc_source(m)
    path = tmp_path / "bent.toml"
    write_machine_with_defects(path, preset_path("tripteor-x7"), nominal, m.model.defects)
    out = tmp_path / "bentkins.c"
    result = CliRunner().invoke(cli, ["export", str(path), "--to", "linuxcnc", "--out", str(out)])
    assert result.exit_code == 1 and "least squares" in result.output
    assert not out.exists()


@pytest.mark.parametrize("planted", ["element_position", "home_values", "tool_length"])
def test_the_read_back_catches_a_wrong_number(planted):
    """The export's self-check reads the element frames, home joints and tool length back: a
    number changed in any of them is caught."""
    m = pkmkit.machine("tripteor-x7")
    text = linuxcnc_source(m)
    assert check_linuxcnc_source(m, text) <= TOL
    start = text.index(f"{planted}[" if planted != "tool_length" else "tool_length =")
    head, tail = text[:start], text[start:]
    number = tail.index("= ") + 2
    number += tail[number:].index(next(c for c in tail[number:] if c in "-0123456789"))
    bad = head + tail[:number] + "1" + tail[number:]
    with pytest.raises(ExportCheckError):
        check_linuxcnc_source(m, bad)


def test_command_line_exports_the_calibrated_tripteor(tmp_path):
    from pkmkit.cli.main import cli
    from pkmkit.io.machine_defects import write_machine_with_defects
    from pkmkit.machines.registry import preset_path

    m = pkmkit.machine("tripteor-x7")
    path = tmp_path / "bent.toml"
    write_machine_with_defects(path, preset_path("tripteor-x7"), m, defects(m, seed=5))
    out = tmp_path / "tripteorkins.c"
    result = CliRunner().invoke(cli, ["export", str(path), "--to", "linuxcnc", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "5 joints" in result.output and "chains close" in result.output
    text = out.read_text()
    for word in ("kinematicsForward", "kinematicsInverse", "kinematicsType", "kinematicsHome",
                 "psi1", "COORDINATES = XYZAB", "MIN_LIMIT = 975"):
        assert word in text
