"""A pytest plugin that logs each test's wall and CPU time as it finishes (docs/testing.md,
"Suite time"): ``PYTHONPATH=tools DURLOG=times.tsv python -m pytest -p durlog ...`` appends
one line per test, ``wall_s<TAB>cpu_s<TAB>nodeid``, where CPU is user + system of the test
process and of the children it waited for (the documentation's commands). Unlike
``--durations`` it is written while the run goes on, and with pytest-xdist each worker writes
its own lines (the controller's lines have a CPU time near zero)."""

from __future__ import annotations

import os
import time

_FILE = os.environ.get("DURLOG", "durlog.tsv")
_started: dict[str, tuple[float, float]] = {}


def _cpu() -> float:
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def pytest_runtest_logstart(nodeid, location):
    _started[nodeid] = (time.perf_counter(), _cpu())


def pytest_runtest_logfinish(nodeid, location):
    start = _started.pop(nodeid, None)
    if start is None:
        return
    with open(_FILE, "a", encoding="utf-8") as out:
        out.write(f"{time.perf_counter() - start[0]:.3f}\t{_cpu() - start[1]:.3f}\t{nodeid}\n")
