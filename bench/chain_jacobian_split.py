"""Benchmark: where ``m.jacobian(x)`` of one pose of a joint-chain machine spends its time
(issue 22 §1), every part timed in the same process on the same poses, in interleaved rounds:

- the whole call reading ``J`` and ``condition`` (and reading ``J`` only, on a second copy of
  the machine whose records' ``condition`` is never read: since session 34 a machine runs the
  singular stage inside its one-pose C call once a record's ``condition`` was read);
- the fused C call alone (``chain_one_ik_jacobian``: the inverse, the velocity model with the
  closure's Jacobian handed over, and the singular stage), the floor of the whole call, in the
  record layout the machine's call takes since session 35 (one read-only array, q its last row)
  and in the flat one (``(q, out)``);
- since session 35, the whole call on a third copy of the machine held to session 34's record
  (its pack's ``records`` false: the flat array and the tuple, each field a slice, a reshape and
  a read-only view), and its ratio to the whole call (the same C work);
- the C inverse alone (``chain_one_ik(..., full=True)``: chainiter's part, the floor of the
  call);
- the velocity model's C call alone at the inverse solutions (``chain_one_jacobian``) and the
  singular stage alone (``chain_one_velocity(pack, None, out)``);
- Python's share: the whole minus the fused C call (the machine's ``jacobian``, the record and
  reading its two fields), and the whole minus the three separate C calls (as session 33);
- the issue's peer: Pinocchio's frame Jacobian (``computeFrameJacobian``) of the machine's
  open URDF tree (no closure; :func:`single_call.pinocchio_jacobian_peer`).

CPU µs per call (the process's CPU time: the 2 cores are shared), the minimum and the median
of the rounds; ratios against the C inverse and against the peer from the same rounds.
``--profile`` adds cProfile's internal times of the whole call (the Python functions' shares).
``--whole-loop N`` only makes the whole call (+ ``J`` + ``condition``) N times over the poses,
for an instruction count of the whole call with its Python (``valgrind --tool=callgrind
--callgrind-out-file=/dev/null python bench/chain_jacobian_split.py --machines trimule-600
--whole-loop 3``, and ``--whole-loop 1``: the difference / 2 / the poses is one call's count;
it runs with an older tree's ``PYTHONPATH`` too). ``--loop N`` only calls the velocity C call N
times over the solutions, for a profiler of the C share (``perf record -o perf.data python
bench/chain_jacobian_split.py --machines tripteor-x7 --loop 3000``, then ``perf report --sort
symbol``).

Usage::

    python bench/chain_jacobian_split.py [--poses 300] [--rounds 5] [--profile]
        [--machines tripteor-x7,trimule-600] [--loop N] [--whole-loop N]
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import pkmkit
from pkmkit.machines import chain_one, chain_one_native
from pkmkit.machines import chain_one_velocity as cov


def cpu_per_call(fun, items, repeats: int = 5) -> float:
    """The median over ``repeats`` of the CPU µs per call of ``fun`` over ``items``."""
    times = []
    for _ in range(repeats):
        start = time.process_time()
        for item in items:
            fun(item)
        times.append((time.process_time() - start) / len(items) * 1e6)
    return statistics.median(times)


def rows_of(m, count: int) -> list[np.ndarray]:
    """Tool poses of random configurations within every stroke (as bench/single_call.py)."""
    rng = np.random.default_rng(2)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (0.1 + 0.8 * rng.random((count, len(act))))
    poses = m.fk(q, strokes="ignore")
    inside = np.isfinite(m.ik(poses, strokes="refuse")).all(axis=1)
    return list(poses[inside])


def split(name: str, count: int, rounds: int, profile: bool, loop: int = 0,
          whole_loop: int = 0) -> None:
    m = pkmkit.machine(name)
    rows = rows_of(m, count)
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):  # past the first (batch) call
        chain_one.usable(m, tag)
    assert m.jacobian(rows[0]).condition > 0
    if whole_loop:  # the whole call alone, for an instruction count (module docstring)
        for _ in range(whole_loop):
            for x in rows:
                (r := m.jacobian(x)).J is r.condition  # noqa: B015
        return
    mj = pkmkit.machine(name)  # J only: no condition read on this copy
    assert mj.jacobian(rows[0]).J.shape[0] == 6
    mf = pkmkit.machine(name)  # session 34's flat record (the pack's records false)
    flat = cov.pack(mf)
    records = flat is not None and flat.records
    if records:
        flat.records = False
        assert mf.jacobian(rows[0]).condition > 0
    ik = chain_one_native.packed(m)
    p = cov.pack(m)
    if ik is None or p is None:
        print(f"{name}: no C extension")
        return
    solved = [ik.ik(ik.capsule, x, True, True) for x in rows]
    through = sum(isinstance(m.jacobian(x), cov.OnePoseChainJacobians) for x in rows)
    outs = [p.jacobian(p.pack, s[1], 2e-6) for s in solved]
    outs = [o for o in outs if isinstance(o, np.ndarray)]
    if loop:  # the velocity C call alone, for a profiler
        for _ in range(loop):
            for s in solved:
                p.jacobian(p.pack, s[1], 2e-6)
        return
    from single_call import pinocchio_jacobian_peer

    peer = pinocchio_jacobian_peer(m, len(rows))
    parts = {
        "whole: m.jacobian(x) + J + condition": (
            lambda x: (r := m.jacobian(x)).J is r.condition, rows),
        "whole: m.jacobian(x) + J (never condition)": (lambda x: mj.jacobian(x).J, rows),
        "fused C call (+ singular stage)": (
            (lambda x: p.ik_jacobian(ik.capsule, p.pack, x, 2e-6, 1e-12, True, True)) if records
            else (lambda x: p.ik_jacobian(ik.capsule, p.pack, x, 2e-6, 1e-12, True)), rows),
        "the C inverse alone (chain_one_ik, full)": (
            lambda x: ik.ik(ik.capsule, x, True, True), rows),
        "velocity C call alone (chain_one_jacobian)": (
            lambda s: p.jacobian(p.pack, s[1], 2e-6), solved),
        "singular stage alone": (lambda o: p.call(p.pack, None, o), outs),
    }
    if records:
        parts["fused C call, flat (q, out)"] = (
            lambda x: p.ik_jacobian(ik.capsule, p.pack, x, 2e-6, 1e-12, True), rows)
        parts["whole, session 34's flat record"] = (
            lambda x: (r := mf.jacobian(x)).J is r.condition, rows)
    got = {k: [] for k in parts}
    if peer is not None:
        got["Pinocchio frame Jacobian (peer)"] = []
    for _ in range(rounds):
        for k, (fun, items) in parts.items():
            got[k].append(cpu_per_call(fun, items))
        if peer is not None:
            got["Pinocchio frame Jacobian (peer)"].append(peer()[1])
    print(f"{name}: {len(rows)} poses, {through} through the C velocity kernel; load average "
          f"{os.getloadavg()[0]:.2f}; CPU µs per call, min / median of {rounds} rounds")
    low = {k: min(v) for k, v in got.items()}
    for k, v in got.items():
        print(f"  {k:48s} {min(v):7.2f} / {statistics.median(v):7.2f}")
    whole = low["whole: m.jacobian(x) + J + condition"]
    c_parts = (low["the C inverse alone (chain_one_ik, full)"]
               + low["velocity C call alone (chain_one_jacobian)"] + low["singular stage alone"])
    after = whole - low["the C inverse alone (chain_one_ik, full)"]
    print(f"  after the inverse (whole - C inverse): {after:.2f}; Python's share (whole - the "
          f"fused C call): {whole - low['fused C call (+ singular stage)']:.2f} (whole - the "
          f"three C calls: {whole - c_parts:.2f}); the inverse / whole "
          f"{low['the C inverse alone (chain_one_ik, full)'] / whole:.2f}")
    if records:
        old = low["whole, session 34's flat record"]
        fused = low["fused C call, flat (q, out)"] / low["fused C call (+ singular stage)"]
        print(f"  whole with session 34's flat record / whole: {old / whole:.3f}; the fused "
              f"call flat / record layout {fused:.3f}")
    if peer is not None:
        pin = low["Pinocchio frame Jacobian (peer)"]
        print(f"  whole / Pinocchio {whole / pin:.1f}; after the inverse / Pinocchio "
              f"{after / pin:.1f}")
    if profile:
        prof = cProfile.Profile()
        prof.enable()
        for _ in range(5):
            for x in rows:
                parts["whole: m.jacobian(x) + J + condition"][0](x)
        prof.disable()
        stats = pstats.Stats(prof)
        total = sum(v[2] for v in stats.stats.values())
        print("  cProfile, internal time shares of the whole call (with cProfile's overhead):")
        top = sorted(stats.stats.items(), key=lambda kv: -kv[1][2])[:10]
        for (file, line, func), v in top:
            print(f"    {100 * v[2] / total:5.1f} %  {Path(file).name}:{line}({func})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=300)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--machines", default="tripteor-x7,trimule-600")
    parser.add_argument("--loop", type=int, default=0)
    parser.add_argument("--whole-loop", type=int, default=0)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    for name in args.machines.split(","):
        split(name, args.poses, args.rounds, args.profile, args.loop, args.whole_loop)


if __name__ == "__main__":
    main()
