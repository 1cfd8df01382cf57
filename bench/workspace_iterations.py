"""Benchmark: the inverse model's iterations per pose of a joint-chain workspace (issue 22 §3,
session 35).

Runs ``pkmkit workspace ARGS`` in this process with every ``ik(..., full_output=True)`` of a
joint-chain machine counted: rows, the engine's iterations (each row's, summed), the rows of
calls given ``start=`` (the grid's continuation from neighbours, :mod:`pkmkit.analysis.flood`
and :mod:`pkmkit.analysis.continuation`), and the CPU time of the command. The command's own
output goes to stdout as usual (``cmp`` it against another tree's); the counts to stderr.

Usage::

    python bench/workspace_iterations.py tripteor-x7 > out.txt
    python bench/workspace_iterations.py trimule-600 --whole-grid > out.txt
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

from pkmkit.machines import joint_chain


def main() -> None:
    counts = {"rows": 0, "iterations": 0, "started": 0}
    real = joint_chain.JointChainMachine.ik

    def counted(self, x, *args, **kwargs):
        out = real(self, x, *args, **kwargs)
        if kwargs.get("full_output") and hasattr(out, "iterations"):
            it = np.atleast_1d(out.iterations)
            counts["rows"] += len(it)
            counts["iterations"] += int(it.sum())
            counts["started"] += len(it) if kwargs.get("start") is not None else 0
        return out

    joint_chain.JointChainMachine.ik = counted
    args = sys.argv[1:]
    sys.argv = ["pkmkit", "workspace", *args]
    from pkmkit.cli.main import main as cli

    load = os.getloadavg()[0]
    cpu = time.process_time()
    try:
        cli()
    except SystemExit:
        pass
    cpu = time.process_time() - cpu
    print(f"workspace {' '.join(args)}: {counts['rows']} rows through ik(full_output), "
          f"{counts['iterations']} iterations ({counts['iterations'] / max(counts['rows'], 1):.2f}"
          f" per row; {counts['started']} rows in calls with start=); CPU {cpu:.2f} s; load "
          f"average {load:.1f}", file=sys.stderr)


if __name__ == "__main__":
    main()
