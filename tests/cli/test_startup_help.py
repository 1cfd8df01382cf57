"""Start-up of every subcommand's ``--help`` (issue 22 §5): in a fresh interpreter, ``pkmkit CMD
--help`` (and ``pkmkit GROUP SUB --help`` for each command of a group) imports none of Numba,
SciPy, pyarrow or matplotlib — checked in ``sys.modules``, never by timing.

The commands come from the click group itself (the lazily imported ones included), so a command
added later is covered without editing this file. An import of one of those packages at the top
of a command's module (or of a library module it imports) makes its case fail, naming the package.

A run's figures: ``python bench/cli_startup.py`` (docs/benchmarks.md, "Session 33: start-up of
every subcommand").
"""

import json
import os
import subprocess
import sys
import textwrap
import warnings

import click
import numpy as np
import pytest

from pkmkit.cli.main import cli

#: What no ``--help`` may import (each ≈ 0.1–0.7 s of a fresh process here).
HEAVY = ("numba", "scipy", "pyarrow", "matplotlib")

COMMANDS = cli.list_commands(click.Context(cli))

needs_fork = pytest.mark.skipif(not hasattr(os, "fork"), reason="the children are forked")

_SCRIPT = textwrap.dedent("""
    import contextlib, io, json, os, sys

    import click

    from pkmkit.cli.main import cli

    HEAVY = {heavy!r}

    def heavy():
        return sorted(m for m in sys.modules if m.split(".")[0] in HEAVY)

    def help_of(args):
        text = io.StringIO()
        with contextlib.redirect_stdout(text):
            try:
                cli([*args, "--help"], standalone_mode=False)
            except SystemExit:
                pass
        return text.getvalue()

    def report(name):
        rows = [[name, "Usage:" in help_of([name]), heavy()]]
        command = cli.get_command(click.Context(cli), name)
        if isinstance(command, click.Group):
            for sub in command.list_commands(click.Context(command)):
                rows.append([f"{{name}} {{sub}}", "Usage:" in help_of([name, sub]), heavy()])
        return rows

    reports = {{}}
    for name in cli.list_commands(click.Context(cli)):
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # a child as fresh as any `pkmkit` process once the CLI is imported
            os.close(read)
            os.write(write, json.dumps(report(name)).encode())
            os._exit(0)
        os.close(write)
        with os.fdopen(read, "rb") as pipe:
            data = pipe.read()
        os.waitpid(pid, 0)
        reports[name] = json.loads(data) if data else [[name, False, ["(the child failed)"]]]
    print(json.dumps({{"before": heavy(), "reports": reports}}))
""").format(heavy=HEAVY)


def _short(modules: list[str]) -> list[str]:
    """``scipy.spatial.transform._rotation`` → ``scipy.spatial``: the packages, for messages."""
    return sorted({".".join(m.split(".")[:2]) for m in modules})


@pytest.fixture(scope="module")
def help_reports() -> dict:
    """One fresh interpreter imports the command line (``pkmkit.cli.main``, what every
    ``pkmkit`` process imports first) and forks a child per listed command, which runs
    ``pkmkit NAME --help`` then ``pkmkit NAME SUB --help`` for each command of a group: for each,
    the command, whether a usage text was printed, the heavy modules loaded so far. (One
    interpreter instead of one per command: the suite pays the common imports once.)"""
    out = subprocess.run([sys.executable, "-c", _SCRIPT], capture_output=True, text=True,
                         check=True).stdout
    return json.loads(out.splitlines()[-1])


@needs_fork
def test_the_commands_are_listed_without_importing_them(help_reports):
    """The parametrisation below sees every command, the lazily imported ones included; the
    command line itself loads none of the heavy packages before a command is chosen."""
    assert {"ik", "fk", "jacobian", "workspace", "path", "design", "calibrate",
            "export"} <= set(COMMANDS)
    assert len(COMMANDS) >= 24
    assert sorted(help_reports["reports"]) == sorted(COMMANDS)
    assert help_reports["before"] == []


@needs_fork
@pytest.mark.parametrize("name", COMMANDS)
def test_help_imports_no_heavy_package(name, help_reports):
    for command, printed, heavy in help_reports["reports"][name]:
        assert printed, f"pkmkit {command} --help printed no usage"
        assert heavy == [], f"pkmkit {command} --help imports {_short(heavy)}"


@needs_fork
def test_a_group_s_subcommands_are_covered(help_reports):
    """``design`` is a group: its three sizing rules' ``--help`` run too."""
    commands = [row[0] for row in help_reports["reports"]["design"]]
    assert commands == ["design", "design five-bar", "design linear-delta", "design orthoglide"]


def test_registration_angles_match_scipy():
    """``Registration.to_dict`` reports the rotation vector and xyz angles in NumPy
    (:mod:`pkmkit.spatial.euler`, so ``pkmkit register`` imports no SciPy); SciPy's ``Rotation``
    is the oracle, gimbal locks and half turns included."""
    from scipy.spatial.transform import Rotation

    from pkmkit.calibration.registration import Registration

    special = Rotation.from_euler("xyz", [[0, 90, 0], [10, -90, 30], [180, 0, 0], [0, 0, 0],
                                          [0, 0, 180], [45, 90, 5]], degrees=True)
    rotations = [*special, *Rotation.random(60, random_state=3)]
    for rotation in rotations:
        matrix = rotation.as_matrix()
        out = Registration(matrix, np.zeros(3), np.zeros((0, 3)), np.zeros(0)).to_dict()
        expected = Rotation.from_matrix(matrix)
        rotvec = np.degrees(expected.as_rotvec())
        got = np.array(out["rotation_vector_deg"])
        if np.isclose(np.linalg.norm(rotvec), 180.0):  # a half turn: ±axis are the same rotation
            assert min(np.abs(got - rotvec).max(), np.abs(got + rotvec).max()) < 1e-9
        else:
            np.testing.assert_allclose(got, rotvec, atol=1e-9)
        with warnings.catch_warnings():  # SciPy warns of the gimbal locks
            warnings.simplefilter("ignore")
            angles = expected.as_euler("xyz", degrees=True)
        np.testing.assert_allclose(out["euler_xyz_deg"], angles, atol=1e-7)


def test_orthonormal_matrices_take_the_numpy_path_with_scipy_s_answer():
    """``matrix_to_rotvec`` (used to build joint-chain machines) answers rotations in NumPy and
    other matrices through SciPy (which first projects them onto the rotations): both agree with
    SciPy's ``Rotation.as_rotvec``."""
    from scipy.spatial.transform import Rotation

    from pkmkit.spatial.rotation import matrix_to_rotvec

    rng = np.random.default_rng(0)
    rotations = Rotation.random(500, random_state=4).as_matrix()
    np.testing.assert_allclose(matrix_to_rotvec(rotations),
                               Rotation.from_matrix(rotations).as_rotvec(), atol=1e-13)
    skewed = rotations + 1e-6 * rng.normal(size=rotations.shape)
    np.testing.assert_allclose(matrix_to_rotvec(skewed),
                               Rotation.from_matrix(skewed).as_rotvec(), atol=1e-13)
    np.testing.assert_array_equal(matrix_to_rotvec(np.eye(3)), [[0.0, 0.0, 0.0]])
    # each row takes its own path: a rotation's answer is the same bits beside a failed (NaN)
    # row and a skewed one as alone (a batch and its pieces agree, issue 22 §6)
    # (a rotation whose two paths differ in the last bits, so the check can tell them apart)
    alone = matrix_to_rotvec(rotations)
    k = int(np.flatnonzero((alone != Rotation.from_matrix(rotations).as_rotvec()).any(axis=1))[0])
    mixed = np.stack([rotations[k], np.full((3, 3), np.nan), skewed[1]])
    out = matrix_to_rotvec(mixed)
    np.testing.assert_array_equal(out[0], alone[k])
    assert np.isnan(out[1]).all()
    np.testing.assert_array_equal(out[2], matrix_to_rotvec(skewed[1:2])[0])



#: One-pose commands (and `machines`, which builds every machine): none loads the heavy packages.
ONE_POSE = [
    ["machines"],
    ["show", "tripteor-x7"],
    ["ik", "linear-delta", "--pose", "0.25,0.25,0"],
    ["ik", "gough-stewart", "--pose", "0.08,-0.04,0.84,10,0,5"],
    ["ik", "tripteor-x7", "--pose",
     "-0.103203582,-0.458476529,1.83342075,0.0103095056,0.17988607,0.983633426"],
    ["fk", "tripteor-x7", "--q", "0.982802,1.06375,0.989454,5,10"],
    ["jacobian", "five-bar", "--pose", "1.05,0.05"],
    ["analyze", "orthoglide", "--pose", "0,0,0"],
    ["stiffness", "orthoglide", "--pose", "0,0,0"],
    ["arm-sizing", "--force", "1000", "--length", "0.5", "--diameter", "0.03"],
    ["errors", "five-bar"],
    ["register", "--measured", "{tmp}/measured.csv", "--nominal", "{tmp}/nominal.csv"],
]

_RUN_SCRIPT = textwrap.dedent("""
    import contextlib, io, json, os, sys

    from pkmkit.cli.main import cli

    HEAVY = {heavy!r}
    reports = []
    for args in json.loads(sys.argv[1]):
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(read)
            text = io.StringIO()
            with contextlib.redirect_stdout(text), contextlib.redirect_stderr(io.StringIO()):
                try:
                    cli(args, standalone_mode=False)
                    code = 0
                except SystemExit as exc:
                    code = exc.code
                except Exception as exc:
                    code = repr(exc)
            heavy = sorted(m for m in sys.modules if m.split(".")[0] in HEAVY)
            os.write(write, json.dumps([code, bool(text.getvalue()), heavy]).encode())
            os._exit(0)
        os.close(write)
        with os.fdopen(read, "rb") as pipe:
            data = pipe.read()
        os.waitpid(pid, 0)
        reports.append(json.loads(data) if data else ["the child failed", False, []])
    print(json.dumps(reports))
""").format(heavy=HEAVY)


@needs_fork
def test_one_pose_commands_import_no_heavy_package(tmp_path):
    """A one-pose command of every family (the joint chains build their home through
    ``matrix_to_rotvec``), ``register`` of 4 points, ``analyze``, ``stiffness``, ``errors`` and
    an arm analysed: each in a forked child of one fresh interpreter, exit status 0, some output,
    none of Numba, SciPy, pyarrow, matplotlib in ``sys.modules``."""
    (tmp_path / "nominal.csv").write_text("x,y,z\n0,0,0\n1,0,0\n0,1,0\n0,0,1\n")
    (tmp_path / "measured.csv").write_text("x,y,z\n0.1,0,0\n1.1,0,0\n0.1,1,0\n0.1,0,1\n")
    runs = [[a.format(tmp=tmp_path) for a in args] for args in ONE_POSE]
    out = subprocess.run([sys.executable, "-c", _RUN_SCRIPT, json.dumps(runs)],
                         capture_output=True, text=True, check=True).stdout
    for args, (code, printed, heavy) in zip(ONE_POSE, json.loads(out.splitlines()[-1]),
                                            strict=True):
        assert code in (0, None) and printed, f"pkmkit {' '.join(args)}: {code}"
        assert heavy == [], f"pkmkit {' '.join(args)} imports {_short(heavy)}"
