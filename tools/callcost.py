"""A pytest plugin that counts the calls of named functions and their own CPU over a run
(docs/testing.md, "Fifth round, product side"): ``PYTHONPATH=src:tools CALLCOST=FILE python -m
pytest -p callcost ...`` wraps, at the start of the run, each ``module:attribute`` of
``CALLCOST_NAMES`` (comma-separated; default ``pkmkit.machines.registry:load``,
``pkmkit.machines.registry:machine_from_document`` and the three machine classes'
``with_params``; ``module:Class.method`` for a method) and writes to FILE one line per name,
``calls<TAB>cpu_s<TAB>name``, where ``cpu_s`` is the process CPU of the calls that were not
inside another wrapped call (no time counted twice).

A module attribute is replaced in its module, so it is counted when it is called through the
module (``registry.load`` from ``registry.machine``, or after ``from pkmkit.machines import
registry``); a name imported before the run (``from pkmkit import machine``) keeps the
original, which the calls it makes inside the module still reach."""

from __future__ import annotations

import functools
import importlib
import os
import time
from typing import Any

_DEFAULT = ("pkmkit.machines.registry:load,pkmkit.machines.registry:machine_from_document,"
            "pkmkit.machines.machine:Machine.with_params,"
            "pkmkit.machines.full_pose:FullPoseMachine.with_params,"
            "pkmkit.machines.joint_chain:JointChainMachine.with_params")
_counts: dict[str, list[float]] = {}
_depth = [0]


def _wrapped(name: str, function: Any) -> Any:
    counts = _counts.setdefault(name, [0, 0.0])

    @functools.wraps(function)
    def counted(*args: Any, **kwargs: Any) -> Any:
        outer = _depth[0] == 0
        _depth[0] += 1
        start = time.process_time()
        try:
            return function(*args, **kwargs)
        finally:
            _depth[0] -= 1
            counts[0] += 1
            if outer:
                counts[1] += time.process_time() - start

    return counted


def pytest_configure(config: Any) -> None:
    for spec in os.environ.get("CALLCOST_NAMES", _DEFAULT).split(","):
        module_name, _, attribute = spec.strip().partition(":")
        owner: Any = importlib.import_module(module_name)
        *path, last = attribute.split(".")
        for part in path:
            owner = getattr(owner, part)
        setattr(owner, last, _wrapped(spec.strip(), getattr(owner, last)))


def pytest_unconfigure(config: Any) -> None:
    with open(os.environ.get("CALLCOST", "callcost.tsv"), "a", encoding="utf-8") as out:
        for name, (calls, cpu) in _counts.items():
            out.write(f"{int(calls)}\t{cpu:.3f}\t{name}\n")
