"""A pytest plugin that logs each test's wall and CPU time as it finishes (docs/testing.md,
"Suite time"): ``PYTHONPATH=tools DURLOG=times.tsv python -m pytest -p durlog ...`` appends
one line per test, ``wall_s<TAB>cpu_s<TAB>fork_cpu_s<TAB>nodeid``, where CPU is user + system
of the test process and of the children it waited for, and fork_cpu that of the children the
documentation's fork server ran for the test (``tests/docs/fork_server.py``: the server waits
for its children, so their CPU reaches the test process only when the server itself is
reaped, in whichever test or teardown that happens — a documentation block's CPU is in
fork_cpu, not in cpu). Unlike ``--durations`` it is written while the run goes on, and with
pytest-xdist each worker writes its own lines (the controller's lines have a CPU time near
zero)."""

from __future__ import annotations

import os
import sys
import time

_FILE = os.environ.get("DURLOG", "durlog.tsv")
_started: dict[str, tuple[float, float, float]] = {}


def _cpu() -> float:
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def _fork_cpu() -> float:
    """CPU of the fork servers' children so far (0 before the documentation tests ran)."""
    runner = sys.modules.get("tests.docs.test_docs_run")
    return float(sum(server.cpu for server in getattr(runner, "_SERVER", ())))


def pytest_runtest_logstart(nodeid, location):
    _started[nodeid] = (time.perf_counter(), _cpu(), _fork_cpu())


def pytest_runtest_logfinish(nodeid, location):
    start = _started.pop(nodeid, None)
    if start is None:
        return
    with open(_FILE, "a", encoding="utf-8") as out:
        out.write(f"{time.perf_counter() - start[0]:.3f}\t{_cpu() - start[1]:.3f}\t"
                  f"{_fork_cpu() - start[2]:.3f}\t{nodeid}\n")
