"""Benchmark: fresh ``pkmkit`` processes of the commands whose compiled kernels have C twins
(issue 22 §5) — ``workspace gough-stewart|verne|orthoglide|five-bar`` and ``jacobian MACHINE
--input`` of translational rod-leg machines — against another source tree (a ``git worktree``
of the branch point) run alternately in the same minutes.

CPU time (user + system, ``getrusage(RUSAGE_CHILDREN)`` around each ``subprocess.run``) and
wall time, medians of ``--repeat`` runs, the load average noted: on a loaded machine the CPU
time estimates a quiet run's wall time. Each tree runs the shared ``pkmkit`` entry point with
its own ``src`` first on ``PYTHONPATH`` (build both trees' extensions first).

    python bench/fresh_commands.py --base /tmp/base --repeat 5 [--only workspace]
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]
JACOBIAN_MACHINES = ("orthoglide", "linear-delta", "five-bar-biglide")
WORKSPACES = ("gough-stewart", "verne", "orthoglide", "five-bar")


def _tables(folder: Path) -> dict[str, Path]:
    """5,000 poses around each machine's home (x, y[, z] CSV)."""
    sys.path.insert(0, str(HERE / "src"))
    import pkmkit

    out = {}
    for name in JACOBIAN_MACHINES:
        m = pkmkit.machine(name)
        x = m.home_pose + np.random.default_rng(0).uniform(-0.05, 0.05, (5000, m.dims))
        out[name] = folder / f"{name}.csv"
        np.savetxt(out[name], x, delimiter=",", header=",".join("xyz"[: m.dims]), comments="",
                   fmt="%.9g")
    return out


def _run(tree: Path, args: list[str]) -> tuple[float, float]:
    env = dict(os.environ, PYTHONPATH=str(tree / "src"))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    exe = Path(sys.executable).with_name("pkmkit")
    done = subprocess.run([str(exe) if exe.exists() else shutil.which("pkmkit") or "pkmkit",
                           *args], env=env,
                          capture_output=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in (0, 3):
        raise SystemExit(f"{tree}: pkmkit {' '.join(args)} failed:\n{done.stderr.decode()}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", type=Path, required=True, help="the other source tree")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--only", default="", help="run the commands whose label holds this")
    opts = parser.parse_args()
    trees = {"base": opts.base.resolve(), "this": HERE}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        tables = _tables(folder)
        commands = {f"workspace {w}": ["workspace", w] for w in WORKSPACES}
        for name, path in tables.items():
            commands[f"jacobian {name} --input (5,000)"] = [
                "jacobian", name, "--input", str(path), "--output", str(folder / "out.csv")]
        commands = {k: v for k, v in commands.items() if opts.only in k}
        times: dict[tuple[str, str], list[tuple[float, float]]] = {}
        loads = []
        for round_ in range(opts.repeat):
            order = ("base", "this") if round_ % 2 == 0 else ("this", "base")
            for label, args in commands.items():
                for tree in order:
                    loads.append(os.getloadavg()[0])
                    times.setdefault((label, tree), []).append(_run(trees[tree], args))
    print(f"load average during the runs: {min(loads):.1f}-{max(loads):.1f}")
    print(f"{'command':44s} {'CPU base':>9s} {'CPU this':>9s} {'wall base':>10s} "
          f"{'wall this':>10s}")
    for label in commands:
        base, this = times[(label, "base")], times[(label, "this")]

        def med(runs: list[tuple[float, float]], i: int) -> float:
            return statistics.median(r[i] for r in runs)

        print(f"{label:44s} {med(base, 0):9.3f} {med(this, 0):9.3f} {med(base, 1):10.3f} "
              f"{med(this, 1):10.3f}")


if __name__ == "__main__":
    main()
