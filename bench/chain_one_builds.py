"""Benchmark: two builds of the C extension's joint-chain one-pose calls in one process.

Loads two compiled ``pkmkit.native.kernels`` files (for example the worktree's build before
and after a change to ``native/chain_one*.c`` or ``chain.c``, copied aside), packs each
machine with each (``chain_one_pack``), and prints whether ``chain_one_ik`` (q, u, iterations,
residual) and ``chain_one_fk`` answers are bit-identical on the same poses, and the CPU µs per
call of each build (medians of interleaved rounds, so both see the same load); with
``--jacobian``, also ``m.jacobian(x)``'s C part: the first build's two calls
(``chain_one_ik`` with the full answer, then ``chain_one_jacobian`` at its solution) against
the second's one ``chain_one_ik_jacobian`` where it has it (else its two calls), the output
arrays compared bit for bit (``--two-calls-first``: the first build's two calls even where it
has the fused one — the same build twice gives the fused call's own gain). ``--calls N``
with ``--only BUILD`` instead runs N rounds of ``chain_one_ik`` then ``chain_one_fk`` of one
build alone (for an instruction count: ``valgrind --tool=callgrind
--toggle-collect=pk_py_chain_one_ik python bench/chain_one_builds.py A B --only A --calls 1``,
or ``--toggle-collect=pk_py_chain_one_fk``).

Usage::

    python bench/chain_one_builds.py BEFORE.so AFTER.so [--poses 400] [--rounds 7] [--machines a,b]
"""

from __future__ import annotations

import argparse
import importlib.machinery
import importlib.util
import os
import time

import numpy as np

import pkmkit
from pkmkit.machines import chain_one_native, chain_one_velocity


def load(path: str):
    """The extension module compiled at ``path`` (not registered in ``sys.modules``)."""
    loader = importlib.machinery.ExtensionFileLoader("pkmkit.native.kernels", path)
    spec = importlib.util.spec_from_file_location("pkmkit.native.kernels", path, loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def poses(m, count: int) -> tuple[list, list]:
    """Actuator values uniform over 10-90 % of the strokes and their tool poses."""
    rng = np.random.default_rng(2)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (0.1 + 0.8 * rng.random((count, len(act))))
    x = m.fk(q, strokes="ignore")
    keep = np.isfinite(x).all(axis=1)
    return list(x[keep]), list(q[keep])


def identical(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    if isinstance(a, tuple):
        return all(identical(u, v) for u, v in zip(a, b, strict=True))
    if a is False or b is False:
        return a is b
    return np.array_equal(a, b, equal_nan=True)  # (the jacobian's singular values: NaN)


def cpu_per_call(fun, capsule, rows, *flags) -> float:
    t = time.process_time()
    for row in rows:
        fun(capsule, row, *flags)
    return (time.process_time() - t) / len(rows) * 1e6


def jacobian_call(mod, cap, vpack, two_calls: bool = False):
    """m.jacobian(x)'s C part with build ``mod``: one fused call where it has it."""
    fused = None if two_calls else getattr(mod, "chain_one_ik_jacobian", None)
    if fused is not None:
        return lambda x: fused(cap, vpack, x, 2e-9, 1e-12)

    def two(x):
        got = mod.chain_one_ik(cap, x, True, True)
        return None if got is None else (got[0], mod.chain_one_jacobian(vpack, got[1], 2e-9))
    return two


def compare_jacobian(m, builds: list, caps: list, xs: list, rounds: int,
                     two_calls_first: bool) -> None:
    vargs = list(chain_one_velocity.pack_arguments(m).values())
    calls = [jacobian_call(b, c, b.chain_velocity_pack(*vargs), two_calls_first and i == 0)
             for i, (b, c) in enumerate(zip(builds, caps, strict=True))]
    same = all(identical(*(f(x) for f in calls)) for x in xs)
    times: list[list[float]] = [[], []]
    for _ in range(rounds):
        for i, f in enumerate(calls):
            t = time.process_time()
            for x in xs:
                f(x)
            times[i].append((time.process_time() - t) / len(xs) * 1e6)
    a, b = (float(np.median(t)) for t in times)
    label = "one fused call" if hasattr(builds[1], "chain_one_ik_jacobian") else "two calls"
    print(f"  jacobian C part (the second: {label}), bit-identical answers {same}: "
          f"CPU µs first build {a:.2f}, second {b:.2f} (x{a / b:.3f})")
    # the singular stage (condition, singular values: read later) on each build's own arrays
    packs = [b.chain_velocity_pack(*vargs) for b in builds]
    outs = [[got[1] for got in (f(x) for x in xs) if got is not None
             and isinstance(got[1], np.ndarray)] for f in calls]
    for b, p, o in zip(builds, packs, outs, strict=True):
        for out in o:
            b.chain_one_velocity(p, None, out)
    same = all(np.array_equal(u, v) for u, v in zip(*outs, strict=True))
    times = [[], []]
    for _ in range(rounds):
        for i, (b, p, o) in enumerate(zip(builds, packs, outs, strict=True)):
            t = time.process_time()
            for out in o:
                b.chain_one_velocity(p, None, out)
            times[i].append((time.process_time() - t) / len(o) * 1e6)
    a, b = (float(np.median(t)) for t in times)
    print(f"  singular stage C call, bit-identical answers {same}: CPU µs first build {a:.2f}, "
          f"second {b:.2f} (x{a / b:.3f})")
    if "record=False" in (getattr(builds[1], "chain_one_ik_jacobian", None).__doc__ or ""):
        record_layout(builds, caps, packs, calls[0], xs, rounds)


def record_layout(builds: list, caps: list, packs: list, first, xs: list, rounds: int) -> None:
    """Since session 35: the second build's record layout (``chain_one_ik_jacobian(...,
    singular=True, record=True)``: one read-only (R, n) array, q its last row) against the
    first build's flat fused call with the singular stage (its tuple ``(q, out)``), the rows
    compared with the flat answer bit for bit."""
    fused = getattr(builds[0], "chain_one_ik_jacobian", None)
    if fused is None or "singular" not in (fused.__doc__ or ""):
        return
    rec = builds[1].chain_one_ik_jacobian
    flat_call = lambda x: fused(caps[0], packs[0], x, 2e-9, 1e-12, True)  # noqa: E731
    rec_call = lambda x: rec(caps[1], packs[1], x, 2e-9, 1e-12, True, True)  # noqa: E731
    same = True
    for x in xs:
        flat, rows = flat_call(x), rec_call(x)
        if flat is None or not isinstance(flat[1], np.ndarray):
            same &= not isinstance(rows, np.ndarray)
            continue
        q, out = flat
        n = len(q)
        k = min(6, n)
        s = 1 if k < n else 2
        same &= (np.array_equal(rows[:12].ravel(), out[:12 * n])
                 and np.array_equal(rows[12:12 + s].ravel()[:k + 1], out[12 * n:12 * n + k + 1])
                 and np.array_equal(rows[12 + s:-1].ravel(), out[12 * n + k + 1:])
                 and np.array_equal(rows[-1], q))
    times: list[list[float]] = [[], []]
    for _ in range(rounds):
        for i, f in enumerate((flat_call, rec_call)):
            t = time.process_time()
            for x in xs:
                f(x)
            times[i].append((time.process_time() - t) / len(xs) * 1e6)
    a, b = (float(np.median(t)) for t in times)
    print(f"  fused call with the singular stage, the first build's (q, out) against the second's "
          f"record layout, the same entries {same}: CPU µs {a:.2f}, {b:.2f} (x{a / b:.3f})")


def pack(build, m):
    """``chain_one_pack`` of machine ``m`` with ``build``; a build older than session 34 takes
    the closed-form start's constants without the family's code, and the TriMule's alone: it
    is packed so (its own start: the first-order start on the Tripteor)."""
    args = chain_one_native.pack_arguments(m)
    try:
        return build.chain_one_pack(*args)
    except ValueError:
        closed = args[-1]
        older = closed[1:] if closed is not None and closed[0] == 1.0 else None
        return build.chain_one_pack(*args[:-1], older)


def compare(name: str, builds: list, count: int, rounds: int = 7,
            jacobian: bool = False, two_calls_first: bool = False) -> None:
    m = pkmkit.machine(name)
    caps = [pack(b, m) for b in builds]
    xs, qs = poses(m, count)
    (a, ca), (b, cb) = zip(builds, caps, strict=True)
    same_ik = all(identical(a.chain_one_ik(ca, x, True, True), b.chain_one_ik(cb, x, True, True))
                  for x in xs)
    same_fk = all(identical(a.chain_one_fk(ca, v, True, True), b.chain_one_fk(cb, v, True, True))
                  for v in qs)
    times = {k: [] for k in ("ik 1", "ik 2", "fk 1", "fk 2")}
    for _ in range(rounds):
        for i, (mod, cap) in enumerate(zip(builds, caps, strict=True), 1):
            times[f"ik {i}"].append(cpu_per_call(mod.chain_one_ik, cap, xs, True, False))
            times[f"fk {i}"].append(cpu_per_call(mod.chain_one_fk, cap, qs, True, True))
    med = {k: float(np.median(v)) for k, v in times.items()}
    gap = max((float(np.abs(one[0] - two[0]).max()) for one, two in (
        (a.chain_one_ik(ca, x, True, True), b.chain_one_ik(cb, x, True, True)) for x in xs)
        if one is not None and two is not None), default=0.0)
    print(f"{name}: {len(xs)} poses; bit-identical answers: ik {same_ik}, fk {same_fk}; "
          f"ik's largest |Δq| {gap:.1e}")
    for f in ("ik", "fk"):
        print(f"  {f} C call, CPU µs: first build {med[f + ' 1']:.2f}, second "
              f"{med[f + ' 2']:.2f} (x{med[f + ' 1'] / med[f + ' 2']:.3f})")
    if jacobian:
        compare_jacobian(m, builds, caps, xs, rounds, two_calls_first)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("first")
    parser.add_argument("second")
    parser.add_argument("--poses", type=int, default=400)
    parser.add_argument("--machines", default="tripteor-x7,trimule-600")
    parser.add_argument("--rounds", type=int, default=7, help="interleaved rounds (medians)")
    parser.add_argument("--only", help="one of the two paths: run its ik and fk alone")
    parser.add_argument("--calls", type=int, default=1, help="rounds with --only")
    parser.add_argument("--jacobian", action="store_true",
                        help="also m.jacobian(x)'s C part (module docstring)")
    parser.add_argument("--two-calls-first", action="store_true",
                        help="with --jacobian: the first build's two calls (module docstring)")
    args = parser.parse_args()
    if args.only:
        build = load(args.only)
        for name in args.machines.split(","):
            m = pkmkit.machine(name)
            cap = pack(build, m)
            xs, qs = poses(m, args.poses)
            for _ in range(args.calls):
                for x in xs:
                    build.chain_one_ik(cap, x, True, False)
                for q in qs:
                    build.chain_one_fk(cap, q, True, True)
        return
    print("load average:", " ".join(f"{v:.1f}" for v in os.getloadavg()))
    builds = [load(args.first), load(args.second)]
    for name in args.machines.split(","):
        compare(name, builds, args.poses, args.rounds, args.jacobian, args.two_calls_first)
    print("load average:", " ".join(f"{v:.1f}" for v in os.getloadavg()))


if __name__ == "__main__":
    main()
