"""The generated LinuxCNC kinematics module, compiled with the system C compiler against a stand-in
for LinuxCNC's headers (``linuxcnc_stub/``) and called through ctypes, against pkmkit's own models:
10⁶ random poses through the inverse model, 10⁴ actuator sets through the direct model, on every
built-in machine the format supports, nominal and with calibrated defects."""

from __future__ import annotations

import ctypes
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.export.base import UnsupportedExportError
from pkmkit.export.linuxcnc import linuxcnc_source, module_name
from pkmkit.machines.registry import ALIASES
from pkmkit.model.defects_table import apply_defect_vector, defect_index
from pkmkit.model.rods import CRANK, STRUT
from pkmkit.status import Status

from .c_build import STUB, build_shared

SUPPORTED = ["delta", "dietmaier-hexapod", "five-bar-biglide", "five-bar-isotropic",
             "gough-stewart", "linear-delta-ch3", "linear-delta-table-iv1", "orthoglide"]
MM = 1e-3
TOL = 1e-9  # m


def _compiler() -> str:
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    return cc


FLAGS = ["-fPIC", "-O2", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", f"-I{STUB}"]


def _build(cc: str, source: Path, lib: Path) -> None:
    """``gcc -O2 -Werror`` of the module with the harness, once per machine state for the same
    inputs (:mod:`tests.export.c_build`): a module built again (the same machine in another
    test, process or run) is a copy of the first library, its own file, so its own handle and
    static state when loaded."""
    build_shared(cc, FLAGS, [source, STUB / "harness.c"], lib)


class Module:
    """A compiled module: batch inverse/forward in SI (poses: pkmkit's; joints: m, or rad for
    cranks, which LinuxCNC turns in degrees)."""

    def __init__(self, machine, directory: Path, units: str = "mm"):
        cc = _compiler()
        self.machine = machine
        self.full = machine.dims == 6
        self.n = machine.n_actuators
        self.scale = {"mm": MM, "m": 1.0, "in": 0.0254}[units]
        crank = machine.model.actuator_kind == CRANK
        self.joint_scale = np.where(crank, np.pi / 180.0, self.scale)
        name = module_name(machine.id)
        source = directory / f"{name}.c"
        source.write_text(linuxcnc_source(machine, units=units), encoding="utf-8")
        lib = directory / f"{name}.so"
        _build(cc, source, lib)
        self.lib = ctypes.CDLL(str(lib))
        ptr = np.ctypeslib.ndpointer
        self.lib.pkm_batch_inverse.argtypes = [ctypes.c_long, ctypes.c_int,
                                               ptr(np.float64, flags="C"),
                                               ptr(np.float64, flags="C"),
                                               ptr(np.int32, flags="C")]
        self.lib.pkm_batch_forward.argtypes = [ctypes.c_long, ctypes.c_int,
                                               ptr(np.float64, flags="C"),
                                               ptr(np.float64, flags="C"),
                                               ptr(np.float64, flags="C"),
                                               ptr(np.int32, flags="C")]
        self.lib.pkm_home.argtypes = [ptr(np.float64, flags="C"), ptr(np.float64, flags="C")]

    def world(self, x: np.ndarray) -> np.ndarray:
        """pkmkit poses (N, dims) → LinuxCNC worlds (N, 6) in the module's units."""
        out = np.zeros((x.shape[0], 6))
        out[:, :min(3, self.machine.dims)] = x[:, :3] / self.scale
        if self.full:
            out[:, 3:] = Rotation.from_rotvec(x[:, 3:]).as_euler("xyz", degrees=True)
        return out

    def pose(self, world: np.ndarray) -> np.ndarray:
        """LinuxCNC worlds → pkmkit poses (independent conversion: scipy)."""
        if not self.full:
            return world[:, :self.machine.dims] * self.scale
        rot = Rotation.from_euler("xyz", world[:, 3:], degrees=True).as_rotvec()
        return np.concatenate([world[:, :3] * self.scale, rot], axis=1)

    def inverse(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        world = np.ascontiguousarray(self.world(x))
        q = np.full((x.shape[0], self.n), np.nan)
        status = np.zeros(x.shape[0], dtype=np.int32)
        self.lib.pkm_batch_inverse(x.shape[0], self.n, world, q, status)
        return q * self.joint_scale, status

    def forward(self, q: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        joints = np.ascontiguousarray(q / self.joint_scale)
        world = np.zeros((q.shape[0], 6))
        status = np.zeros(q.shape[0], dtype=np.int32)
        self.lib.pkm_batch_forward(q.shape[0], self.n, joints,
                                   np.ascontiguousarray(self.world(start)), world, status)
        return self.pose(world), status


def _calibrated(machine, seed: int):
    """The machine with random defects of calibration size (0.2 mm, 1 mrad)."""
    index = defect_index(machine)
    rng = np.random.default_rng(seed)
    delta = np.where(np.asarray(index.units) == "m", 2e-4, 1e-3) * rng.standard_normal(
        len(index.names))
    return apply_defect_vector(machine, delta)


def _random_poses(machine, n: int, seed: int, spread: float = 1.6) -> np.ndarray:
    """Poses around home, a fraction of them out of reach; orientations within ±15°."""
    rng = np.random.default_rng(seed)
    lo, hi = machine.default_box()
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo) * spread
    if spread > 1:  # beyond the box, far enough for slide and crank rods to fall short
        half = np.maximum(half, 1.2 * float(machine.model.leg_length.max()))
    x = centre + rng.uniform(-1, 1, (n, len(centre))) * half
    if machine.dims in (2, 3):
        return x
    rot = Rotation.from_rotvec(rng.uniform(-1, 1, (n, 3)) * np.radians(15))
    rot = rot * Rotation.from_rotvec(machine.home_pose[3:])
    return np.concatenate([x, rot.as_rotvec()], axis=1)


def _joint_points(machine, x: np.ndarray) -> np.ndarray:
    """Platform joint centres (N, rods, 3) of poses: a metric for full poses (m)."""
    if machine.dims in (2, 3):
        return x[:, None, :]
    rot = Rotation.from_rotvec(x[:, 3:]).as_matrix()
    return x[:, None, :3] + np.einsum("kab,jb->kja", rot, machine.model.rod_platform)


@pytest.fixture(scope="module", params=[(m, c) for m in SUPPORTED for c in (False, True)],
                ids=lambda p: p[0] + ("-calibrated" if p[1] else ""))
def module(request, tmp_path_factory):
    name, calibrated = request.param
    machine = pkmkit.machine(name)
    if calibrated:
        machine = _calibrated(machine, seed=len(name))
    module = Module(machine, tmp_path_factory.mktemp(name))
    module.calibrated = calibrated
    return module


def test_the_supported_presets_are_exactly_these():
    """Every preset is either exported or refused with the typed error (never anything else)."""
    exported = []
    # joint chains (test_linuxcnc_chains.py) and the Verne-type module (test_linuxcnc_verne.py)
    chains = ["crank-slider", "trimule-600", "tripteor-x7", "verne"]
    for name in pkmkit.machines():
        if name in ALIASES:
            continue
        try:
            linuxcnc_source(pkmkit.machine(name))
        except UnsupportedExportError as exc:
            assert exc.format == "linuxcnc" and exc.reason
            continue
        exported.append(name)
    assert exported == sorted(SUPPORTED + chains)


@pytest.mark.ci
def test_inverse_matches_pkmkit_on_a_million_poses(module):
    """Same joints (1e-9 m) and same refusals: out of reach, and poses of the other assembly
    mode (pkmkit's ``mode``, the sign of det A). A hexapod's modes come from pkmkit's full
    output on the first 10⁵ poses (it costs 15 s on 10⁶), its joints on all. 10⁶ poses on the
    nominal machines, 2·10⁵ more on the calibrated ones (the same code with other numbers)."""
    m = module.machine
    x = _random_poses(m, 200_000 if module.calibrated else 1_000_000, seed=1)
    q_c, status = module.inverse(x)
    n_modes = len(x) if m.dims != 6 else 100_000
    assert len(x) >= n_modes
    res = m.ik(x[:n_modes], full_output=True)
    ok = np.asarray(res.status) == Status.OK
    working = ok & (np.asarray(res.mode) == m.working_mode)
    other = ok & (np.asarray(res.mode) == -m.working_mode)
    # the draw must exercise every outcome (struts reach every pose: only slides refuse)
    assert working.sum() > 0.1 * n_modes
    assert (~ok).sum() > 1000 or (m.model.leg_kind == 1).all()
    assert np.array_equal(status[:n_modes] == 0, working)
    assert np.array_equal(status[:n_modes] == -1, np.asarray(res.status) == Status.UNREACHABLE)
    assert np.array_equal(status[:n_modes] == -3, other)
    q = m.ik(x)  # every row: the joints, NaN out of reach
    assert np.array_equal(np.isnan(q).any(axis=1), status == -1)
    assert set(np.unique(status)) <= {0, -1, -3}
    good = status == 0
    assert np.abs(q_c[good] - q[good]).max() <= TOL


def test_forward_matches_pkmkit_from_the_previous_position(module):
    m = module.machine
    rng = np.random.default_rng(2)
    x = _random_poses(m, 20_000, seed=3, spread=1.0)
    res = m.ik(x, full_output=True)
    keep = (np.asarray(res.status) == Status.OK) & (np.asarray(res.mode) == m.working_mode)
    x, q = x[keep][:8000], res.q[keep][:8000]
    # and up to 2000 actuator sets without any assembly (pkmkit's direct model finds none):
    # a carriage moved far, a strut given a negative length, cranks turned at random
    kind = m.model.actuator_kind
    reach = float(np.abs(m.home_q).max() + m.model.rod_length.max())
    cand = np.tile(q[:1], (20_000, 1)) + np.where(
        kind == CRANK, rng.uniform(-np.pi, np.pi, (20_000, m.n_actuators)),
        rng.uniform(-3, 3, (20_000, m.n_actuators)) * reach)
    cand[:, kind == STRUT] = np.minimum(cand[:, kind == STRUT],
                                        -m.model.leg_length[kind == STRUT] - 0.01 * reach)
    none = (np.asarray(m.fk(cand, full_output=True).status) == Status.NO_ASSEMBLY
            if m.dims != 6 else np.ones(len(cand), dtype=bool))
    bad = cand[none][:2000]
    assert len(bad) >= 500
    q_all = np.concatenate([q, bad])
    start = np.concatenate([x, x[:len(bad)]])
    start[:, :3] += rng.normal(0, 1e-3, start[:, :3].shape)  # the previous position, 1 mm off
    if m.dims == 6:
        start[:, 3:] = (Rotation.from_rotvec(rng.normal(0, np.radians(0.5), (len(start), 3)))
                        * Rotation.from_rotvec(start[:, 3:])).as_rotvec()
    pose_c, status = module.forward(q_all, start)
    if m.dims == 6:
        ref = m.fk(q_all, x0=start, full_output=True)
        found = (np.asarray(ref.status) == Status.OK) & (np.asarray(ref.mode) == m.working_mode)
    else:
        ref = m.fk(q_all, full_output=True)
        found = np.asarray(ref.status) == Status.OK
    assert found[:8000].all() and not found[8000:].any()
    assert np.array_equal(status == 0, found)
    assert set(np.unique(status[~found])) <= {-1, -2, -3, -5}
    gap = np.linalg.norm(_joint_points(m, pose_c[found]) - _joint_points(m, ref.pose[found]),
                         axis=2).max()
    assert gap <= TOL


def test_forward_from_the_unset_position_finds_the_same_pose_or_refuses(module):
    """From LinuxCNC's unset all-zero position the module starts from home. A translational
    machine has two assembly modes told apart by det A: whatever the start, the module finds
    pkmkit's working-mode pose or refuses, never another pose. A hexapod has up to 40: Newton
    finds the one its start leads to (as genhexkins), so poses are drawn nearer home."""
    m = module.machine
    spread = 0.3 if m.dims == 6 else 0.8
    x = _random_poses(m, 3000, seed=4, spread=spread)
    res = m.ik(x, full_output=True)
    keep = (np.asarray(res.status) == Status.OK) & (np.asarray(res.mode) == m.working_mode)
    x, q = x[keep], res.q[keep]
    start = np.zeros_like(x)
    if m.dims != 6:  # any start: a far one too
        start[len(x) // 2:] = m.home_pose + float(m.model.leg_length.max())
    pose_c, status = module.forward(q, start)
    assert (status == 0).mean() > 0.9
    gap = np.linalg.norm(_joint_points(m, pose_c[status == 0]) - _joint_points(m, x[status == 0]),
                         axis=2)
    assert gap.max() <= TOL


def test_home_and_type(module):
    m = module.machine
    world, joints = np.zeros(6), np.zeros(module.n)
    assert module.lib.pkm_home(world, joints) == 0
    assert module.lib.pkm_type() == 4  # KINEMATICS_BOTH
    assert module.lib.pkm_app_main() == 0
    assert np.abs(joints * module.joint_scale - m.home_q).max() <= TOL
    assert np.abs(module.pose(world[None])[0] - m.home_pose).max() <= TOL


def test_invalid_inputs_are_refused(module):
    m = module.machine
    x = np.tile(m.home_pose, (3, 1))
    x[0, 0], x[1, 1], x[2, 1] = np.nan, np.inf, 1e12
    _, status = module.inverse(x)
    assert (status == -4).all()
    q = np.tile(m.home_q, (2, 1))
    q[0, 0], q[1, -1] = np.nan, np.inf
    _, status = module.forward(q, np.tile(m.home_pose, (2, 1)))
    assert (status == -4).all()


def test_the_module_carries_the_calibrated_geometry(tmp_path):
    """A calibrated machine's module differs from the nominal one's and matches its own model
    (the round trips above); here: the nominal module misses the calibrated machine by more
    than the defects' size, so the defects did reach the file."""
    nominal = pkmkit.machine("linear-delta-ch3")
    calibrated = _calibrated(nominal, seed=7)
    module = Module(nominal, tmp_path)
    x = _random_poses(calibrated, 1000, seed=5, spread=0.5)
    q_true = calibrated.ik(x)
    q_c, status = module.inverse(x)
    assert (status == 0).all()
    assert np.abs(q_c - q_true).max() > 1e-5


def test_the_source_names_pkmkit_parameters_and_the_build_line():
    text = linuxcnc_source(pkmkit.machine("orthoglide"))
    assert "halcompile --install orthoglidekins.c" in text
    for word in ("kinematicsForward", "kinematicsInverse", "kinematicsType", "kinematicsHome",
                 "legs[j].base", "rod_length", "MODULE_LICENSE"):
        assert word in text


def test_a_hexapod_below_its_base_is_the_other_assembly_mode(tmp_path):
    """The hexapod mirrored through its base plane: pkmkit puts it in the other assembly mode,
    the module refuses it (−3) rather than drive the struts there."""
    m = pkmkit.machine("gough-stewart")
    module = Module(m, tmp_path)
    x = np.tile(m.home_pose, (2, 1))
    x[1, 2] = -x[1, 2]
    res = m.ik(x, full_output=True)
    assert list(res.mode) == [m.working_mode, -m.working_mode]
    _, status = module.inverse(x)
    assert list(status) == [0, -3]


@pytest.mark.parametrize("units", ["in", "m"])
def test_a_module_in_inches_or_metres(tmp_path, units):
    """LINEAR_UNITS other than mm: the same joints and poses, in those units."""
    m = pkmkit.machine("gough-stewart")
    module = Module(m, tmp_path, units=units)
    x = _random_poses(m, 10_000, seed=6, spread=0.5)
    q_c, status = module.inverse(x)
    assert (status == 0).all()
    assert np.abs(q_c - m.ik(x)).max() <= TOL
    pose, status = module.forward(q_c, x)
    assert (status == 0).all()
    assert np.abs(_joint_points(m, pose) - _joint_points(m, x)).max() <= TOL


@pytest.mark.ci
def test_a_six_slide_hexapod(tmp_path):
    """Full-pose slides (no built-in has them): inverse on 10⁵ poses, forward on 10³."""
    from .six_slides import six_slide_machine

    m = six_slide_machine(tmp_path)
    module = Module(m, tmp_path)
    x = _random_poses(m, 100_000, seed=8, spread=1.0)
    q_c, status = module.inverse(x)
    res = m.ik(x, full_output=True)
    working = (np.asarray(res.status) == Status.OK) & (np.asarray(res.mode) == m.working_mode)
    assert working.mean() > 0.1 and (np.asarray(res.status) == Status.UNREACHABLE).any()
    assert np.array_equal(status == 0, working)
    assert np.abs(q_c[working] - res.q[working]).max() <= TOL
    x, q = x[working][:1000], res.q[working][:1000]
    # away from parallel singularities, where two assemblies come within a millimetre
    regular = m.jacobian(x, q=q).parallel_measure >= 1e-3
    assert regular.mean() > 0.5
    x, q = x[regular], q[regular]
    rng = np.random.default_rng(9)
    start = x.copy()
    start[:, :3] += rng.normal(0, 1e-3, (len(x), 3))
    pose, status = module.forward(q, start)
    ref = m.fk(q, x0=start)
    assert (status == 0).all()
    assert np.abs(_joint_points(m, pose) - _joint_points(m, ref)).max() <= TOL
