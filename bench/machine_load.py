"""Benchmark: loading a machine again, and ``with_params``, against the former paths.

In one process, interleaved round by round so that both see the same load:

- ``pkmkit.machine(id)`` for a preset loaded before (the machine built then, copied:
  :mod:`pkmkit.machines.built_machines`) against the former path, which builds it from the file
  every time (``machine_from_document(read_machine_document(preset_path(id)))``, still public);
- ``m.with_params(...)`` (one build) against the former two steps (the kind's machine, then
  ``dataclasses.replace`` adding the kept poses: a second build), written out below.

Prints, per machine, the CPU time per call of each (the median of ``--rounds`` rounds of
``--calls`` calls) and the ratio former / now.

Usage::

    python bench/machine_load.py [--calls 50] [--rounds 7] [--machines orthoglide,verne]
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import replace

import pkmkit
from pkmkit.machines.registry import machine_from_document, preset_path
from pkmkit.model.machine_file import read_machine_document
from pkmkit.model.parameters import resolve_parameters


def former_load(machine_id: str):
    return machine_from_document(read_machine_document(preset_path(machine_id)),
                                 machine_id=machine_id)


def former_with_params(m, **overrides):
    params = resolve_parameters(m.kind.parameters, {**m.params, **overrides}, m.id)
    model = m.kind.build(params)
    rebuilt = type(m)(id=m.id, name=m.name, kind=m.kind, params=dict(params), model=model,
                      description=m.description, source=m.source,
                      extra_poses=m.kind.reference_poses(params, model))
    extra = {k: v for k, v in m.extra_poses.items() if k not in rebuilt.extra_poses}
    kept = ({"characteristic_length": m.characteristic_length}
            if getattr(m, "length_given", False) else {})
    return replace(rebuilt, extra_poses={**rebuilt.extra_poses, **extra}, **kept)


def cpu_per_call(func, calls: int) -> float:
    start = time.process_time()
    for _ in range(calls):
        func()
    return (time.process_time() - start) / calls


def compare(label: str, former, now, calls: int, rounds: int) -> None:
    former(), now()  # warm
    old, new = [], []
    for _ in range(rounds):
        old.append(cpu_per_call(former, calls))
        new.append(cpu_per_call(now, calls))
    a, b = statistics.median(old), statistics.median(new)
    print(f"{label:44s} former {a * 1e6:9.1f} us   now {b * 1e6:8.1f} us   x{a / b:7.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--calls", type=int, default=50)
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--machines", default=",".join(pkmkit.machines()))
    args = parser.parse_args()
    ids = args.machines.split(",")
    for machine_id in ids:
        compare(f"machine({machine_id!r})", lambda i=machine_id: former_load(i),
                lambda i=machine_id: pkmkit.machine(i), args.calls, args.rounds)
    for machine_id in ids:
        m = pkmkit.machine(machine_id)
        if m.kind is None or not hasattr(m.kind, "reference_poses") or m.family == "chain":
            continue  # a joint chain's with_params always built once
        name = next((k for k, v in m.params.items() if isinstance(v, float) and v > 0), None)
        if name is None:
            continue
        change = {name: m.params[name] * 1.01}
        compare(f"{machine_id}.with_params({name}=...)",
                lambda m=m, c=change: former_with_params(m, **c),
                lambda m=m, c=change: m.with_params(**c), max(args.calls // 5, 3), args.rounds)


if __name__ == "__main__":
    main()
