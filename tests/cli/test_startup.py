"""Start-up: ``import pkmkit`` and the kinematics commands import no plotting or optimisation
library (checked in ``sys.modules`` of a fresh interpreter, never by timing), and the lazily
imported commands are listed exactly as their modules define them."""

import json
import subprocess
import sys
import textwrap

import click
import pytest

from pkmkit.cli.lazy import LAZY_COMMANDS
from pkmkit.cli.main import cli

HEAVY = ("matplotlib", "pymoo", "cma", "mujoco", "scipy.optimize", "scipy.spatial", "pyarrow")


def _modules_after(code: str) -> set[str]:
    """Top-level names of the modules a fresh interpreter holds after running ``code``."""
    script = textwrap.dedent(code) + textwrap.dedent("""
        import json, sys
        print(json.dumps(sorted(sys.modules)))
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True).stdout
    return set(json.loads(out.splitlines()[-1]))


def _modules_after_cli(args: list[str]) -> set[str]:
    """The modules a fresh interpreter holds after running ``pkmkit ARGS`` in it."""
    return _modules_after(f"""
        from pkmkit.cli.main import cli
        try:
            cli({args!r}, standalone_mode=False)
        except SystemExit:
            pass
    """)


def _heavy(modules: set[str]) -> list[str]:
    return sorted(m for m in modules if any(m == h or m.startswith(h + ".") for h in HEAVY))


def test_import_pkmkit_is_light():
    assert _heavy(_modules_after("import pkmkit")) == []


@pytest.mark.parametrize("args", [
    ["--help"],
    ["show", "orthoglide"],
    ["ik", "linear-delta", "--pose", "0.25,0.25,0"],
    ["fk", "orthoglide", "--q", "0.31,0.31,0.31", "--all"],
    ["jacobian", "five-bar", "--pose", "1.05,0.05"],
])
def test_kinematics_commands_are_light(args):
    modules = _modules_after_cli(args)
    assert "pkmkit.cli.main" in modules
    assert _heavy(modules) == []


@pytest.mark.ci
def test_listing_machines_builds_them_without_the_heavy_packages():
    """``pkmkit machines`` builds every built-in machine; the full-pose and joint-chain ones use
    SciPy's rotations to assemble, nothing heavier."""
    modules = _modules_after("""
        from pkmkit.cli.main import cli
        cli(["machines"], standalone_mode=False)
    """)
    allowed = {"scipy.spatial"}
    assert [m for m in _heavy(modules) if not any(m == a or m.startswith(a + ".")
                                                  for a in allowed)] == []


@pytest.mark.ci
def test_a_lazy_command_still_runs_with_its_imports():
    """``path --help`` imports the command's module (and, since session 33, not matplotlib:
    the figures import it when they are drawn, ``tests/cli/test_startup_help.py``)."""
    modules = _modules_after("""
        from pkmkit.cli.main import cli
        cli(["path", "--help"], standalone_mode=False)
    """)
    assert "pkmkit.cli.motion_cmds" in modules
    assert "matplotlib" not in modules


def test_lazy_table_matches_the_commands():
    """Every command a module registers is in the table with its help, and nothing else."""
    import importlib

    modules = {entry.module for entry in LAZY_COMMANDS.values()}
    registered = {}
    for name in modules:
        group = click.Group()
        importlib.import_module(name).register(group)
        registered.update({k: (name, c) for k, c in group.commands.items()})
    assert set(registered) == set(LAZY_COMMANDS)
    for cmd_name, (module, command) in registered.items():
        entry = LAZY_COMMANDS[cmd_name]
        assert entry.module == module
        assert getattr(importlib.import_module(module), entry.attribute) is command
        for limit in (20, 45, 58, 74, 200):
            stand_in = click.Command(cmd_name, help=entry.short_help)
            assert stand_in.get_short_help_str(limit) == command.get_short_help_str(limit)


def test_help_lists_every_command(run):
    text = run("--help").output
    for name in [*LAZY_COMMANDS, "ik", "fk", "jacobian", "machines", "show", "demo"]:
        assert f"  {name} " in text
    assert set(LAZY_COMMANDS) <= set(cli.list_commands(click.Context(cli)))


@pytest.mark.parametrize("args", [
    ["--help"],
    ["ik", "linear-delta", "--pose", "0.25,0.25,0"],
    ["jacobian", "linear-delta", "--pose", "0,0,0"],
    ["jacobian", "gough-stewart", "--pose", "0,0,800,0,0,0"],
])
@pytest.mark.ci
def test_one_shot_commands_import_no_compiler(args):
    """A one-pose command never imports Numba (≈ 0.3 s of CPU, and its first compiled call
    loads SciPy's linear algebra: ≈ 0.6 s in all); ``--help`` and the translational ones not
    even a thread pool (``concurrent.futures``, imported by ``numerics.jit`` when a batch is
    spread over threads)."""
    modules = _modules_after_cli(args)
    assert "numba" not in modules
    if "gough-stewart" not in args:
        assert "concurrent" not in modules


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
@pytest.mark.ci
def test_a_rod_leg_batch_imports_no_compiler(tmp_path, suffix):
    """``pkmkit ik`` of a translational machine on a table runs the closed form's NumPy path
    (modes and statuses in the same pass): 5,000 rows — above the size from which the compiled
    kernels run once Numba is imported — without importing Numba (≈ 0.6–0.9 s of CPU on the
    first compiled call, more than the NumPy path costs on tens of millions of rows)."""
    import numpy as np

    from pkmkit.io.table import TableWriter

    rng = np.random.default_rng(0)
    x = rng.uniform(-0.2, 0.2, (5000, 3))
    source = tmp_path / f"poses{suffix}"
    with TableWriter(source) as writer:
        writer.write({"x": x[:, 0], "y": x[:, 1], "z": x[:, 2]})
    output = tmp_path / f"out{suffix}"
    args = ["ik", "linear-delta", "--input", str(source), "--output", str(output)]
    modules = _modules_after_cli(args)
    assert output.exists()
    assert "numba" not in modules


def _native_built() -> bool:
    import importlib.util

    return importlib.util.find_spec("pkmkit.native.kernels") is not None


@pytest.mark.skipif(not _native_built(), reason="pkmkit.native.kernels was not built")
@pytest.mark.parametrize("command", ["ik gough-stewart", "fk verne"])
def test_a_full_pose_batch_imports_no_compiler_with_the_c_kernels(tmp_path, command):
    """``pkmkit ik gough-stewart`` on 5,000 poses (above the size from which the compiled
    inverse runs) and ``pkmkit fk verne`` on 200 configurations (above the compiled solver's
    64 rows) run the C kernels of ``pkmkit.native``: Numba is never imported (its import and
    first compiled call cost ≈ 0.8–0.9 s of CPU)."""
    import numpy as np

    import pkmkit
    from pkmkit.io.table import TableWriter

    action, name = command.split()
    m = pkmkit.machine(name)
    rng = np.random.default_rng(0)
    if action == "ik":
        rows = m.home_pose + rng.uniform(-0.05, 0.05, (5000, 6))
        columns = ["x", "y", "z", "A", "B", "C"]
        rows[:, 3:] = np.degrees(rows[:, 3:])  # small angles: the file's convention
    else:
        rows = m.home_q + rng.uniform(-0.02, 0.02, (200, m.n_actuators))
        columns = [f"q{k + 1}" for k in range(m.n_actuators)]
    source = tmp_path / "in.csv"
    with TableWriter(source) as writer:
        writer.write({c: rows[:, k] for k, c in enumerate(columns)})
    output = tmp_path / "out.csv"
    args = [action, name, "--input", str(source), "--output", str(output)]
    modules = _modules_after_cli(args)
    assert output.exists() and len(output.read_text().splitlines()) > len(rows)
    assert "pkmkit.native.kernels" in modules
    assert "numba" not in modules


@pytest.mark.ci  # a fresh process: 2-5 s of CPU each
@pytest.mark.skipif(not _native_built(), reason="pkmkit.native.kernels was not built")
@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600"])
def test_a_chain_workspace_study_imports_no_compiler_with_the_c_kernels(name):
    """``pkmkit workspace tripteor-x7|trimule-600`` runs the closure's C twin at every batch
    size and never takes the one-pose path for its batches (whose constants import the Numba
    kernels): Numba is never imported (≈ 1 s of CPU with its cache)."""
    modules = _modules_after_cli(["workspace", name])
    assert "pkmkit.native.kernels" in modules
    assert "numba" not in modules
    assert "pkmkit.solve.chain_one_kernel" not in modules


@pytest.mark.parametrize("args", [
    ["ik", "gough-stewart", "--pose", "0.08,-0.04,0.84,10,0,5"],
    ["ik", "gough-stewart", "--pose", "0,0,0.8,30,20,10", "--angles", "ZYZ"],
    ["fk", "gough-stewart", "--q", "0.840576605,0.91933439,0.974075654,0.94315616,0.87964248,"
     "0.891357828"],
    ["jacobian", "gough-stewart", "--pose", "0.08,-0.04,0.84,10,0,5"],
    ["ik", "verne", "--pose", "0.15,0.1,-0.1"],
    ["fk", "verne", "--q", "1.3,1.1,1.2"],
    ["jacobian", "verne", "--pose", "0.15,0.1,-0.1"],
    ["ik", "dietmaier-hexapod", "--pose", "0.636,0.771,0.015,90,0,-75"],
    ["fk", "dietmaier-hexapod", "--q", "1.0,0.645275,1.086284,1.503439,1.281933,0.771071"],
    ["jacobian", "dietmaier-hexapod", "--pose", "0.636,0.771,0.015,90,0,-75"],
    ["fk", "dietmaier-hexapod", "--q", "1.0,0.645275,1.086284,1.503439,1.281933,0.771071",
     "--all"],
])
def test_full_pose_one_shot_commands_never_import_scipy_spatial(args):
    """The full-pose commands build their machine (reference poses from angles) and convert
    angles ↔ rotation vectors in NumPy (:mod:`pkmkit.spatial.euler`): importing
    ``scipy.spatial`` (its k-d tree, ``scipy.sparse``) costs ≈ 0.2 s, half a one-pose ``ik``."""
    modules = _modules_after_cli(args)
    assert "pkmkit.spatial.euler" in modules
    assert "scipy.spatial" not in modules


@pytest.mark.parametrize("command", ["ik gough-stewart", "fk gough-stewart", "ik verne",
                                     "fk verne", "fk dietmaier-hexapod"])
def test_full_pose_table_commands_never_import_scipy_spatial(tmp_path, command):
    """The same on small tables (``--input``/``--output``): the file's angles convert in NumPy."""
    import pkmkit

    action, name = command.split()
    m = pkmkit.machine(name)
    if action == "ik":
        rows = [[*m.home_pose[:3], 2.0, -1.0, 3.0], [*m.home_pose[:3], 0.0, 0.0, 0.0]]
        columns = ["x", "y", "z", "A", "B", "C"]
    else:
        rows = [list(m.home_q), list(m.home_q)]
        columns = [f"q{k + 1}" for k in range(m.n_actuators)]
    source = tmp_path / "in.csv"
    source.write_text(",".join(columns) + "\n"
                      + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows))
    output = tmp_path / "out.csv"
    args = [action, name, "--input", str(source), "--output", str(output)]
    modules = _modules_after_cli(args)
    assert output.exists()
    assert "scipy.spatial" not in modules
