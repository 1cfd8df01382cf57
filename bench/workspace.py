"""Where a default workspace study spends its time (issue 22 §3): ``pkmkit workspace MACHINE``
run in this process, with the CPU time of each stage and the rows sent to the inverse and
velocity models by each.

Stages: ``enclosing_frame`` (the default box widened on coarse grids until the workspace fits),
``evaluate_grid`` (the criteria on every point of a grid), ``flood_grid`` (the criteria by a
flood fill from home, joint chains: :mod:`pkmkit.analysis.flood`), ``refine_box`` (the
inscribed cube refined beyond the grid: SLSQP on a 25³ lattice; analytic slack gradients for
full-pose machines, finite differences otherwise), ``check_region`` (the refined cube
checked densely, with its actuator extremes refined by ``_q_extremes``); per study, the points
evaluated against the grids' points.

``--ab-shell ROUNDS``: the study's ``refine_box`` call run again ROUNDS times in this process,
its optimiser constraining the lattice's faces (``inscribed.lattice_shell``, the default since
session 32) and the whole lattice (the rule before) alternately: CPU time of each, their ratio
and the cube found by each.

Run: ``python bench/workspace.py gough-stewart verne tripteor-x7`` (each study once: they take
seconds to minutes; the machine is shared, so compare CPU seconds, not wall time). The
command's own output is printed last, to compare with the documented figures.
"""

from __future__ import annotations

import argparse
import collections
import os
import time
from collections.abc import Callable
from typing import Any

from click.testing import CliRunner

import pkmkit
import pkmkit.analysis.region_check as region_check
import pkmkit.analysis.workspace as workspace
import pkmkit.cli.analysis_cmds as analysis_cmds
import pkmkit.cli.grid_options as grid_options
from pkmkit.cli.main import cli

STAGES = ("enclosing_frame", "evaluate_grid", "flood_grid", "refine_box", "check_region",
          "_q_extremes")


def _timed(module: Any, name: str, seconds: collections.Counter, calls: collections.Counter,
           label: str) -> None:
    """Replace ``module.name`` by a wrapper adding its CPU time to ``seconds[label]``."""
    function: Callable = getattr(module, name)

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        start = time.process_time()
        try:
            return function(*args, **kwargs)
        finally:
            seconds[label] += time.process_time() - start
            calls[label] += 1

    setattr(module, name, wrapper)


SECONDS: collections.Counter = collections.Counter()
CALLS: collections.Counter = collections.Counter()
#: per grid of the study (label): [points evaluated, grid points], summed over its grids
POINTS: dict[str, list[int]] = {}


def _counted(module: Any, label: str) -> None:
    """Replace ``module.compute_workspace`` by a wrapper adding the points its maps evaluated
    and their grids' points to ``POINTS[label]``."""
    function: Callable = module.compute_workspace

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        wmap = function(*args, **kwargs)
        totals = POINTS.setdefault(label, [0, 0])
        totals[0] += wmap.points_evaluated
        totals[1] += wmap.grid.size
        return wmap

    module.compute_workspace = wrapper


def study(machine: str, extra: list[str]) -> None:
    """One ``pkmkit workspace`` study, its CPU time per stage printed."""
    SECONDS.clear()
    CALLS.clear()
    POINTS.clear()
    start, wall = time.process_time(), time.perf_counter()
    result = CliRunner().invoke(cli, ["workspace", machine, *extra])
    total, elapsed = time.process_time() - start, time.perf_counter() - wall
    print(f"{machine}: {total:.2f} s of CPU ({elapsed:.1f} s wall), load average "
          f"{os.getloadavg()[0]:.2f}")
    for name in STAGES:
        if CALLS[name]:
            print(f"  {name:16s} {SECONDS[name]:7.2f} s  ({CALLS[name]} calls)")
    for label, (evaluated, size) in POINTS.items():
        print(f"  {label}: {evaluated:,} points evaluated of {size:,} grid points")
    print("  " + result.output.replace("\n", "\n  ").rstrip())
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("machines", nargs="*", default=["gough-stewart"])
    parser.add_argument("--args", default="", help="extra workspace arguments, e.g. "
                        "'--no-strokes --resolution 31'")
    parser.add_argument("--ab-direct", type=int, default=0, metavar="ROUNDS",
                        help="joint chains: run each study ROUNDS times in this process with "
                        "the inverse record's direct model computed at once (what every batch "
                        "paid before issue 22 §3's fifth pass) and when read, alternately")
    parser.add_argument("--ab-shell", type=int, default=0, metavar="ROUNDS",
                        help="refine_box with its optimiser on the lattice's faces and on the "
                        "whole lattice, alternately, ROUNDS times each (module doc)")
    options = parser.parse_args()
    print(f"pkmkit {pkmkit.__version__} (stages nest: check_region holds _q_extremes, "
          "refine_box and enclosing_frame hold grid evaluations)")
    for module, name in ((analysis_cmds, "enclosing_frame"), (workspace, "evaluate_grid"),
                         (workspace, "flood_grid"), (workspace, "refine_box"),
                         (workspace, "check_region"),
                         (analysis_cmds, "check_region"), (region_check, "_q_extremes")):
        _timed(module, name, SECONDS, CALLS, name)
    _counted(analysis_cmds, "study grid")
    _counted(grid_options, "frame search grids")
    if options.ab_direct:
        _ab_direct(options.machines, options.args.split(), options.ab_direct)
        return
    if options.ab_shell:
        for machine in options.machines:
            _ab_shell(machine, options.args.split(), options.ab_shell)
        return
    for machine in options.machines:
        study(machine, options.args.split())


def _ab_direct(machines: list[str], extra: list[str], rounds: int) -> None:
    """Each study alternately with the joint-chain inverse record's direct model read at once
    and left to be computed when read (the first study of the process also loads the compiled
    kernels: run a warm-up machine first to compare like with like)."""
    import importlib

    joint_chain = importlib.import_module("pkmkit.machines.joint_chain")

    lazy = joint_chain.inverse_record

    def eager(*args: Any, **kwargs: Any) -> Any:
        record = lazy(*args, **kwargs)
        _ = record.direct  # computed at once
        return record

    for machine in machines:
        for _round in range(rounds):
            for label, assemble in (("direct at once", eager), ("direct when read", lazy)):
                joint_chain.inverse_record = assemble
                print(f"[{label}]", end=" ")
                study(machine, extra)
    joint_chain.inverse_record = lazy


def _ab_shell(machine: str, extra: list[str], rounds: int) -> None:
    """The study's ``refine_box`` call again, with the optimiser on the lattice's faces and on
    the whole lattice alternately (in this process, after the study has loaded everything)."""
    import statistics

    from pkmkit.analysis.inscribed import lattice_offsets

    calls: list[tuple] = []
    timed = workspace.refine_box  # the stage timer's wrapper (main)

    def recorded(*args: Any, **kwargs: Any) -> Any:
        calls.append((args, kwargs))
        return timed(*args, **kwargs)

    workspace.refine_box = recorded
    try:
        study(machine, extra)
    finally:
        workspace.refine_box = timed
    if not calls:
        print(f"{machine}: no refine_box call (a joint chain, or no inscribed cube)")
        return
    args, kwargs = calls[0]
    shell = workspace.lattice_shell
    times: dict[str, list[float]] = {"faces": [], "whole lattice": []}
    boxes = {}
    for _round in range(rounds):
        for label, offsets in (("faces", shell), ("whole lattice", lattice_offsets)):
            workspace.lattice_shell = offsets
            start = time.process_time()
            boxes[label] = timed(*args, **kwargs)
            times[label].append(time.process_time() - start)
    workspace.lattice_shell = shell
    faces, whole = (statistics.median(times[k]) for k in ("faces", "whole lattice"))
    print(f"{machine} refine_box, median of {rounds} (CPU s, load average "
          f"{os.getloadavg()[0]:.2f}): faces {faces:.3f}, whole lattice {whole:.3f}, "
          f"x{faces / whole:.2f}")
    for label, box in boxes.items():
        print(f"  {label:14s} side {box.side!r}, centre {box.center.tolist()!r}")


if __name__ == "__main__":
    main()
