"""Benchmark: start-up of every ``pkmkit`` subcommand as a fresh process (issue 22 §5).

Two tables, measured in the same run, in rounds (each round runs every command once, in turn,
so a drift of the machine's speed hits all of them alike):

- ``--help`` of every command the click group lists (the lazily imported ones included, and each
  command of a group such as ``design``): a user waits for it before anything else;
- the lightest real invocation of each command (one pose, a small file; a coarse grid for the
  workspace studies). Rows marked ``one-pose`` are held to issue 22's ≤ 0.3 s; the others
  compute more than a start-up (a grid, an optimisation, a calibration) and are shown for scale.

Columns: median wall time, minimum wall time and median CPU time (user + system, the whole
process) over ``--repeat`` rounds; ``x python`` = wall / ``python -c pass`` and ``x help`` =
wall / ``pkmkit --help``, each ratio taken within a round and its median printed. On a loaded
machine the CPU time estimates a quiet run's wall time (``met in cpu``: over 0.3 s of wall
time, within it in CPU time); the load average is printed before and after. Where a command's
time goes: ``python -X importtime -m pkmkit.cli.main CMD --help``.

    python bench/cli_startup.py [--repeat 5] [--only TEXT[,TEXT...]] [--no-real] [--base TREE]

With ``--base TREE`` (another source tree, e.g. ``git archive`` of the branch point with the C
extension built or copied in) every row also runs with ``PYTHONPATH=TREE/src``, in turn with
this tree's (which runs with the environment as it is: put ``src`` first on ``PYTHONPATH``), and
``x base`` is this tree's wall over the base's, round by round. A last table times the floors
(``python -c pass``, ``import numpy``) and the peer (Pinocchio importing, building a 6-joint
model and placing its frames at one configuration) in the same rounds.

The runs go through :func:`cli_io.run_times` (one run each), the harness of the batch and
start-up table of ``bench/cli_io.py``.
"""

from __future__ import annotations

import argparse
import compileall
import importlib.util
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import click
from cli_io import _pkmkit_command, run_times

import pkmkit as pkmkit_package
from pkmkit.cli.main import cli

#: The lightest real invocation of each command: (label, arguments, held to ≤ 0.3 s).
#: ``{tmp}`` is the folder of the inputs :func:`make_inputs` writes.
REAL = [
    ("machines", ["machines"], False),
    ("show", ["show", "orthoglide"], True),
    ("ik (rod legs)", ["ik", "linear-delta", "--pose", "0.25,0.25,0"], True),
    ("ik (full pose)", ["ik", "gough-stewart", "--pose", "0.08,-0.04,0.84,10,0,5"], True),
    ("ik (joint chain)", ["ik", "tripteor-x7", "--pose",
                          "-0.1,-0.5,1.8,-0.00490948,0.00700943,0.999963"], True),
    ("fk", ["fk", "orthoglide", "--q", "0.31,0.31,0.31", "--all"], True),
    ("jacobian", ["jacobian", "five-bar", "--pose", "1.05,0.05"], True),
    ("analyze", ["analyze", "orthoglide", "--pose", "0,0,0"], True),
    ("stiffness", ["stiffness", "orthoglide", "--pose", "0,0,0"], True),
    ("arm-sizing (analyse one)", ["arm-sizing", "--force", "1000", "--length", "0.5",
                                  "--diameter", "0.03"], True),
    ("export", ["export", "linear-delta", "--to", "klipper", "--out", "{tmp}/printer.cfg"], True),
    ("errors", ["errors", "five-bar"], True),
    ("register (4 points)", ["register", "--measured", "{tmp}/measured.csv", "--nominal",
                             "{tmp}/nominal.csv"], True),
    ("simulate-measurements (5)", ["simulate-measurements", "orthoglide", "--measure", "point",
                                   "--poses", "5", "--out", "{tmp}/m5.csv"], True),
    ("machined-part program", ["machined-part", "program", "orthoglide", "--out",
                               "{tmp}/part.nc"], True),
    ("compensate (2 targets)", ["compensate", "orthoglide", "--calibrated",
                                "{tmp}/cal/orthoglide-calibrated.toml", "--targets",
                                "{tmp}/targets.csv", "--out", "{tmp}/comp.csv"], True),
    ("view", ["view", "five-bar", "--out", "{tmp}/view.html"], False),
    ("design orthoglide", ["design", "orthoglide", "--cube", "0.2", "--bounds", "0.5,2"], False),
    ("path (one line)", ["path", "orthoglide", "--line", "0,0,0:0.05,0,0", "--feed", "0.1",
                         "--accel", "1"], False),
    ("workspace (20 points a side)", ["workspace", "five-bar", "--resolution", "20"], False),
    ("map (20, png)", ["map", "five-bar", "--index", "condition", "--resolution", "20", "--out",
                       "{tmp}/map.png"], False),
    ("useful-workspace (20)", ["useful-workspace", "five-bar", "--resolution", "20"], False),
    ("identifiability (20 poses)", ["identifiability", "orthoglide", "--measure", "point",
                                    "--poses", "20"], False),
    ("select-poses (6 of 30)", ["select-poses", "orthoglide", "--measure", "point", "--n", "6",
                                "--candidates", "30", "--out", "{tmp}/sel.csv"], False),
    ("calibrate (30 points)", ["calibrate", "orthoglide", "--measure", "point",
                               "--measurements", "{tmp}/meas.csv", "--no-view"], False),
]
TARGET = 0.3

#: Floors and a peer, fresh processes in the same rounds: the interpreter, NumPy (which every
#: command but ``--help`` needs), and Pinocchio (issue 22's peer for one-pose calls) importing,
#: building a 6-joint model and placing its frames at one configuration.
PINOCCHIO_ONE_POSE = ("import pinocchio as pin; m = pin.buildSampleModelManipulator(); "
                      "d = m.createData(); pin.forwardKinematics(m, d, pin.neutral(m)); "
                      "pin.updateFramePlacements(m, d)")


def help_commands() -> list[list[str]]:
    """``[CMD]`` for every listed command and ``[GROUP, SUB]`` for every command of a group."""
    out = []
    for name in cli.list_commands(click.Context(cli)):
        out.append([name])
        command = cli.get_command(click.Context(cli), name)
        if isinstance(command, click.Group):
            out.extend([name, sub] for sub in command.list_commands(click.Context(command)))
    return out


def make_inputs(folder: Path, pkmkit: list[str]) -> None:
    """The small files the real invocations read (made by pkmkit itself, not timed)."""
    (folder / "nominal.csv").write_text("x,y,z\n0,0,0\n1,0,0\n0,1,0\n0,0,1\n")
    (folder / "measured.csv").write_text("x,y,z\n0.1,0,0\n1.1,0,0\n0.1,1,0\n0.1,0,1\n")
    (folder / "targets.csv").write_text("x,y,z\n0.01,0.02,0.0\n0,0,0.05\n")
    for args in (["simulate-measurements", "orthoglide", "--measure", "point", "--poses", "30",
                  "--defects", "random", "--out", str(folder / "meas.csv")],
                 ["calibrate", "orthoglide", "--measure", "point", "--measurements",
                  str(folder / "meas.csv"), "--no-view", "--out", str(folder / "cal")]):
        subprocess.run([*pkmkit, *args], check=True, capture_output=True)


def load() -> str:
    return " ".join(f"{v:.2f}" for v in os.getloadavg())


def measure(rows: dict[str, list[str]], trees: dict[str, Path | None],
            repeat: int) -> dict[tuple[str, str], dict[str, list[float]]]:
    """Wall and CPU time of each row's command in each tree (``None``: the environment as it
    is), ``repeat`` rounds after a warm-up round, every row of every tree once a round."""
    envs = {name: None if tree is None else dict(os.environ, PYTHONPATH=str(tree / "src"))
            for name, tree in trees.items()}
    times = {(label, name): {"wall": [], "cpu": []} for label in rows for name in trees}
    for round_ in range(repeat + 1):  # the first round warms the caches and is not counted
        for label, cmd in rows.items():
            for name in trees:
                wall, cpu = run_times(cmd, 1, env=envs[name])
                if round_:
                    times[label, name]["wall"].append(wall)
                    times[label, name]["cpu"].append(cpu)
    return times


def _chosen(label: str, only: str) -> bool:
    return any(text in label for text in only.split(","))


def _ratio(a: list[float], b: list[float]) -> float:
    return statistics.median(x / y for x, y in zip(a, b, strict=True))


def report(title: str, times, labels, marks: dict[str, bool], base: bool) -> None:
    py, helps = times["python -c pass", "this"]["wall"], times["pkmkit --help", "this"]["wall"]
    extra = f" {'base s':>7} {'base min':>8} {'base cpu':>8} {'x base':>6}" if base else ""
    print(f"\n{title:<44} {'wall s':>7} {'min s':>6} {'cpu s':>6} {'x python':>8} {'x help':>6}"
          f"{extra}  ≤ 0.3 s")
    for label in labels:
        wall, cpu = times[label, "this"]["wall"], times[label, "this"]["cpu"]
        median, cpu_s = statistics.median(wall), statistics.median(cpu)
        target = "-"
        if marks.get(label):  # loaded, the CPU time stands for a quiet run's wall time
            target = "met" if median <= TARGET else "met in cpu" if cpu_s <= TARGET else "not met"
        line = (f"{label:<44} {median:7.3f} {min(wall):6.3f} {cpu_s:6.3f} "
                f"{_ratio(wall, py):8.1f} {_ratio(wall, helps):6.2f}")
        if base:
            old = times[label, "base"]
            line += (f" {statistics.median(old['wall']):7.3f} {min(old['wall']):8.3f}"
                     f" {statistics.median(old['cpu']):8.3f} {_ratio(wall, old['wall']):6.2f}")
        print(f"{line}  {target}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="rounds (default 5)")
    parser.add_argument("--only", default="", help="only the rows whose label holds one of "
                        "these comma-separated texts")
    parser.add_argument("--no-real", action="store_true", help="only the --help table")
    parser.add_argument("--base", type=Path, help="another source tree (e.g. the branch "
                        "point, its extension built) run in turn with this one: x base")
    opts = parser.parse_args()
    exe = Path(sys.executable).with_name("pkmkit")  # the entry point a user runs
    pkmkit = [str(exe)] if exe.exists() else _pkmkit_command()
    trees: dict[str, Path | None] = {"this": None}
    if opts.base:
        trees["base"] = opts.base.resolve()
    # compiled bytecode as an installed package has it (PYTHONDONTWRITEBYTECODE may be set):
    # otherwise a tree whose sources changed since its last run compiles them on every start
    for package in (Path(pkmkit_package.__file__).parent,
                    *([trees["base"] / "src" / "pkmkit"] if opts.base else [])):
        compileall.compile_dir(package, quiet=1)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        rows = {"python -c pass": [sys.executable, "-c", "pass"],
                "pkmkit --help": [*pkmkit, "--help"],
                "python -c 'import numpy'": [sys.executable, "-c", "import numpy"]}
        if importlib.util.find_spec("pinocchio") is not None:
            rows["peer: Pinocchio import + one pose"] = [sys.executable, "-c", PINOCCHIO_ONE_POSE]
        floors = [label for label in rows if not label.startswith("pkmkit")]
        helps = [f"pkmkit {' '.join(args)} --help" for args in help_commands()]
        rows.update({label: [*pkmkit, *label.split()[1:]] for label in helps
                     if _chosen(label, opts.only)})
        marks = {}
        if not opts.no_real:
            make_inputs(folder, pkmkit)
            for label, args, one_pose in REAL:
                if _chosen(label, opts.only):
                    rows[label] = [*pkmkit, *(a.format(tmp=tmp) for a in args)]
                    marks[label] = one_pose
        print(f"pkmkit start-up, {opts.repeat} rounds; python {sys.version.split()[0]}; "
              f"{pkmkit[0]}; {os.cpu_count()} CPUs; load average before: {load()}")
        times = measure(rows, trees, opts.repeat)
        print(f"load average after: {load()}")
        report("--help (fresh process)", times, [r for r in rows if r.endswith("--help")],
               {r: True for r in rows if r.endswith("--help")}, bool(opts.base))
        if marks:
            report("lightest real invocation", times, list(marks), marks, bool(opts.base))
        report("floors and peer (fresh process)", times, floors, {}, bool(opts.base))


if __name__ == "__main__":
    main()
