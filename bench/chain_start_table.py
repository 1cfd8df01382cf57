"""Benchmark: a start table for the joint-chain one-pose inverse (issue 22 §1, session 31).

``m.ik(x)`` of one pose on a joint-chain machine is one C call (``chain_one_ik``) that starts
Levenberg-Marquardt from the batch path's first-order start (home moved to first order towards
the target). This measures whether a better start would pay: a table of solved configurations
over the workspace (a grid of ``--grid`` values per actuator over 10-90 % of each stroke, each
node's tool pose solved by the C call, its first-order rates du/dx by forward differences of the
C call started from the node), the call started from the nearest node (tool-flange point and
axis) moved to first order (``start=`` of ``chain_one_ik``). Printed per machine: the table's
build time (CPU; built here in Python around the C calls), the iteration counts of the C call
(the batch rules included: a retry from home, the head's mirror) from both starts, the CPU µs
of the C call alone from both starts in the same process (the nearest-node search excluded:
starts precomputed), and the largest difference of the answers q from the first-order start's
(the batch rows' to ~1e-13, tests/machines/test_chain_one_native.py). Beside the rules'
counts, the head's mirror rule (turn far from home's, or beyond a stroke) judged on the start
against the same rule on the solution (session 32: could the mirror's solve be decided before
the first solve?); ``--rules-only`` prints those counts alone, from the first-order start.

Usage::

    python bench/chain_start_table.py [--poses 1000] [--grid 3] [--machines tripteor-x7,trimule-600]
    python bench/chain_start_table.py --rules-only --poses 2000 --machines trimule-600
    python bench/chain_start_table.py --closed --machines trimule-600   # session 33
    python bench/chain_start_table.py --closed --machines tripteor-x7 --spread 1.1  # session 34
    python bench/chain_start_table.py --compiled [--spread 1.1]  # session 35

``--compiled`` (session 35): the kind's closed-form start by its compiled twin
(:func:`pkmkit.machines.chain_starts.compiled_start`) against its NumPy function (what the
one-pose Numba path and the batch rows ran before), in one process: the NumPy function put
back in the machine's one-pose constants and in ``chain_starts`` for the "before" figures
(:func:`compiled`).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import pkmkit
from pkmkit.machines import chain_one_native


def flange(x: np.ndarray, tool: float) -> np.ndarray:
    """The table's key: the flange point (tool point moved back along the axis) and the axis."""
    return np.concatenate([x[:3] - tool * x[3:], x[3:]])


def table(m, p, grid: int, h: float = 1e-6):
    """``(keys, us, rates)`` of the nodes the C call solves (module docstring)."""
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    axes = [np.linspace(a + 0.1 * (b - a), b - 0.1 * (b - a), grid) for a, b in zip(lo, hi,
                                                                                    strict=True)]
    q = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, len(act))
    xs = m.fk(q, strokes="ignore")
    keys, us, rates = [], [], []
    for x in xs[np.isfinite(xs).all(axis=1)]:
        s = p.ik(p.capsule, x, True, True)
        if s is None:
            continue
        k, cols = flange(x, m.tool_length), []
        for j in range(6):
            k2 = k.copy()
            k2[j] += h
            s2 = p.ik(p.capsule, np.concatenate([k2[:3] + m.tool_length * k2[3:], k2[3:]]),
                      True, True, s[1])
            if s2 is None:
                break
            cols.append((s2[1] - s[1]) / h)
        if len(cols) == 6:
            keys.append(k)
            us.append(s[1])
            rates.append(np.array(cols).T)
    return np.array(keys), np.array(us), np.array(rates)


def rules(m, xs: list, starts: list | None = None) -> dict:
    """Which of the batch path's rules fire on the poses ``xs`` (from the first-order start,
    or ``starts``): the Numba one-pose path's pieces (:mod:`pkmkit.machines.chain_one`, the
    same rules as the C call), counted: the first solve's iterations, the retries from home
    (first solve not converged or outside the legs' home modes), the head's mirror solved
    because the turn is far from home's or because the kept solution is beyond a stroke, and
    the mirror kept."""
    import math

    from pkmkit.machines import chain_one

    chain_one.usable(m, "chain_ik")  # past the first (batch) call: the constants built
    c = chain_one.constants(m)
    w = chain_one._work(c)
    out = {"first iterations": [], "retry": 0, "far": 0, "beyond": 0, "mirror kept": 0,
           "start says": np.zeros((2, 2), int), "start says kept": np.zeros((2, 2), int)}
    packed = chain_one_native.pack_arguments(m)
    u_home, base, inv_rates, tool = (np.asarray(packed[k], float) for k in (11, 12, 13, 14))
    for i, x in enumerate(xs):
        norm = math.sqrt(float(x[3:] @ x[3:]))
        w.target[0] = (*x[:3], *(x[3:] / norm))
        axis = x[3:] / norm
        start = (u_home + inv_rates @ np.r_[x[:3] - tool * axis - base[:3], axis - base[3:]]
                 if starts is None else np.asarray(starts[i]))
        kernel = c.first_kernel if starts is None else c.from_kernel
        if starts is not None:
            w.u_inv[0] = starts[i]
        (kernel.call or kernel.first)(*c.first_args, w.u_inv, w.target, c.tool_row, w.info)
        out["first iterations"].append(int(w.info[2]))
        first = w.info[0] == 0 and w.info[3] == 1.0
        if not first:
            out["retry"] += 1
            u = chain_one._solve_inverse(c, w, c.u_home)
            if u is None:
                continue
        else:
            u = w.u_inv[0].tolist()
        if c.wrist is None:
            continue
        turn, home_turn = c.wrist[0], c.wrist[1]
        far = abs(chain_one._turn_offset(u[6 + turn] - home_turn)) > chain_one._FAR
        inside = c.within(chain_one._wrapped(c, u[6:]))
        out["far"] += far
        out["beyond"] += (not far) and c.wrist[4] and not inside
        found = (chain_one._wrapped(c, u[6:]), u, 0, 0.0)
        kept = chain_one._nearest_branch(c, found, first)
        out["mirror kept"] += kept is not None and kept[1] is not u
        # the same rule judged on the start (turn far from home's, or beyond a stroke) against
        # the rule on the solution: rows the start's verdict, columns the solution's
        says = abs(chain_one._turn_offset(start[6 + turn] - home_turn)) > chain_one._FAR
        says = says or bool(c.wrist[4] and not c.within(chain_one._wrapped(c, list(start[6:]))))
        out["start says"][int(says), int(far or bool(c.wrist[4] and not inside))] += 1
        out["start says kept"][int(says), int(kept is not None and kept[1] is not u)] += 1
    return out


def per_call(fun, args, repeats: int = 5) -> float:
    """Median over ``repeats`` of the mean CPU µs of ``fun(*a)`` over ``args``."""
    cpu = []
    for _ in range(repeats):
        t = time.process_time()
        for a in args:
            fun(*a)
        cpu.append((time.process_time() - t) / len(args) * 1e6)
    return float(np.median(cpu))


def run(name: str, poses: int, grid: int) -> None:
    m = pkmkit.machine(name)
    p = chain_one_native.packed(m)
    rng = np.random.default_rng(0)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (0.05 + 0.9 * rng.random((poses, len(act))))
    xs = m.fk(q, strokes="ignore")
    xs = [x for x in xs[np.isfinite(xs).all(axis=1)]
          if p.ik(p.capsule, x, True, True) is not None]
    t = time.process_time()
    keys, us, rates = table(m, p, grid)
    build = time.process_time() - t
    starts = []
    for x in xs:
        d = flange(x, m.tool_length) - keys
        j = int(np.argmin((d * d).sum(axis=1)))
        starts.append(us[j] + rates[j] @ d[j])
    first = [p.ik(p.capsule, x, True, True) for x in xs]
    fromt = [p.ik(p.capsule, x, True, True, s) for x, s in zip(xs, starts, strict=True)]
    it0 = np.array([r[2] for r in first])
    it1 = np.array([-1 if r is None else r[2] for r in fromt])
    dq = max(float(np.abs(a[0] - b[0]).max()) for a, b in zip(first, fromt, strict=True)
             if b is not None)
    plain = [(p.capsule, x, True, False) for x in xs]
    tabled = [(p.capsule, x, True, False, s) for x, s in zip(xs, starts, strict=True)]
    for _ in range(2):  # interleaved, the second round kept
        c0, c1 = per_call(p.ik, plain), per_call(p.ik, tabled)
    print(f"{name}: {len(xs)} poses; table {len(keys)} nodes ({grid} per actuator), "
          f"built in {build * 1e3:.0f} ms CPU (Python around the C calls)")
    print(f"  iterations, first-order start: mean {it0.mean():.2f} (min {it0.min()}, "
          f"max {it0.max()})")
    print(f"  iterations, table start:       mean {it1[it1 >= 0].mean():.2f} (min "
          f"{it1[it1 >= 0].min()}, max {it1.max()}), declined {(it1 < 0).sum()}")
    print(f"  largest |q difference| between the two starts' answers: {dq:.1e}")
    for label, r in (("first-order start", rules(m, xs)), ("table start", rules(m, xs, starts))):
        f = np.array(r["first iterations"])
        print(f"  rules from the {label}: first solve mean {f.mean():.2f} iterations (max "
              f"{f.max()}); retried from home {r['retry']}; mirror solved {r['far'] + r['beyond']}"
              f" (turn far from home's {r['far']}, kept solution beyond a stroke "
              f"{r['beyond']}); mirror kept {r['mirror kept']}")
        if r["far"] + r["beyond"] or r["start says"][1].sum():
            a, k = r["start says"], r["start says kept"]
            print(f"    the rule judged on the start instead: mirror needed by both {a[1, 1]}, by "
                  f"the start only {a[1, 0]}, by the solution only {a[0, 1]}, by neither "
                  f"{a[0, 0]}; of the mirrors kept, the start says far/beyond on {k[1, 1]}, "
                  f"not on {k[0, 1]}")
    print(f"  C call alone, CPU µs: first-order start {c0:.1f}, table start {c1:.1f} "
          f"(x{c0 / c1:.2f})")


def rules_only(name: str, poses: int) -> None:
    """The rules' counts from the first-order start, with the head's rule judged on the start
    beside it (whether the mirror's solve could be decided before the first solve)."""
    m = pkmkit.machine(name)
    p = chain_one_native.packed(m)
    rng = np.random.default_rng(0)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (0.05 + 0.9 * rng.random((poses, len(act))))
    xs = m.fk(q, strokes="ignore")
    xs = [x for x in xs[np.isfinite(xs).all(axis=1)]
          if p.ik(p.capsule, x, True, True) is not None]
    r = rules(m, xs)
    a, k = r["start says"], r["start says kept"]
    print(f"{name}: {len(xs)} poses; retried from home {r['retry']}; mirror solved "
          f"{r['far'] + r['beyond']} (turn far from home's {r['far']}, kept solution beyond a "
          f"stroke {r['beyond']}); mirror kept {r['mirror kept']}")
    print(f"  the rule judged on the start instead: mirror needed by both {a[1, 1]}, by the "
          f"start only {a[1, 0]}, by the solution only {a[0, 1]}, by neither {a[0, 0]}; of the "
          f"mirrors kept, the start says far/beyond on {k[1, 1]}, not on {k[0, 1]}")


def closed(name: str, poses: int, rounds: int, spread: float = 0.9) -> None:
    """Session 33: the kind's closed-form start (the TriMule's,
    :func:`pkmkit.machines.chain_starts.closed_starts`) against the first-order start, in one
    process: the same C build packed with and without its constants (``chain_one_pack``'s
    34th argument; without, the C call is the code before it), and ``m.ik(x)`` of the machine
    against a copy with the closed start turned off (its batch path, Numba and C paths all
    take the first-order start then). Printed: iterations per pose (the mirror's included),
    the first solve's alone and the mirror solves (the Numba one-pose pieces), the largest
    difference of the answers, CPU µs per call (median of ``rounds`` interleaved rounds). The
    actuators uniform over the middle ``spread`` of their strokes (0.9: 5-95 %; above 1,
    beyond them: the edges, and on the Tripteor the wrist's singularity at Q5 = 0, where the
    closed start declines)."""
    import math

    from pkmkit.machines import chain_one

    m = pkmkit.machine(name)
    off = pkmkit.machine(name)
    object.__setattr__(off, "_closed_start_ok", False)
    p = chain_one_native.packed(m)
    args = chain_one_native.pack_arguments(m)
    if args[-1] is None:
        print(f"{name}: no closed-form start")
        return
    first_order = p.ik.__self__.chain_one_pack(*args[:-1])
    rng = np.random.default_rng(0)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * ((1 - spread) / 2 + spread * rng.random((poses, len(act))))
    xs = m.fk(q, strokes="ignore")
    xs = [x for x in xs[np.isfinite(xs).all(axis=1)]
          if p.ik(p.capsule, x, True, True) is not None
          and p.ik(first_order, x, True, True) is not None]
    new = [p.ik(p.capsule, x, True, True) for x in xs]
    old = [p.ik(first_order, x, True, True) for x in xs]
    it_new = np.array([r[2] for r in new])
    it_old = np.array([r[2] for r in old])
    dq = max(float(np.abs(a[0] - b[0]).max()) for a, b in zip(new, old, strict=True))
    # the first solve and the mirror apart (the Numba one-pose pieces, the same rules)
    chain_one.usable(m, "chain_ik")
    c = chain_one.constants(m)
    firsts, mirrors, declined = [], 0, 0
    for x in xs:
        found = chain_one._inverse_values(c, list(x))
        w = chain_one._work(c)
        u = found[1]
        turn, home_turn = c.wrist[0], c.wrist[1]
        far = abs(chain_one._turn_offset(u[6 + turn] - home_turn)) > chain_one._FAR
        mirrors += far or bool(c.wrist[4] and not c.within(found[0]))
        norm = math.sqrt(float(x[3:] @ x[3:]))
        w.target[0] = (*x[:3], *(x[3:] / norm))
        start = chain_one._closed_start(c, w.target, None)
        declined += start is None
        kernel = c.first_kernel if start is None else c.from_kernel
        if start is not None:
            w.u_inv[0] = start
        (kernel.call or kernel.first)(*c.first_args, w.u_inv, w.target, c.tool_row, w.info)
        firsts.append(int(w.info[2]))
    plain = [(p.capsule, x, True, False) for x in xs]
    base = [(first_order, x, True, False) for x in xs]
    c_new, c_old, m_new, m_old = [], [], [], []
    for _ in range(rounds):  # interleaved
        c_old.append(per_call(p.ik, base, 1))
        c_new.append(per_call(p.ik, plain, 1))
        m_old.append(per_call(lambda x: off.ik(x, strokes="ignore"), [(x,) for x in xs], 1))
        m_new.append(per_call(lambda x: m.ik(x, strokes="ignore"), [(x,) for x in xs], 1))
    f_old, f_new = [], []  # full_output: the Numba one-pose path (the kind's NumPy start)
    for _ in range(max(1, rounds // 3)):
        f_old.append(per_call(lambda x: off.ik(x, strokes="ignore", full_output=True),
                              [(x,) for x in xs[:200]], 1))
        f_new.append(per_call(lambda x: m.ik(x, strokes="ignore", full_output=True),
                              [(x,) for x in xs[:200]], 1))
    batch = np.array(xs)
    b_old, b_new = [], []
    for _ in range(3):  # the batch path over every pose, one call each way
        t = time.process_time()
        off.ik(batch, strokes="ignore")
        b_old.append(time.process_time() - t)
        t = time.process_time()
        m.ik(batch, strokes="ignore")
        b_new.append(time.process_time() - t)
    b_old, b_new = float(np.median(b_old)), float(np.median(b_new))
    med = [float(np.median(v)) for v in (c_old, c_new, m_old, m_new)]
    print(f"{name}: {len(xs)} poses")
    print(f"  iterations per pose (C call, mirror included): first-order start mean "
          f"{it_old.mean():.2f} ({it_old.min()} to {it_old.max()}), closed start mean "
          f"{it_new.mean():.2f} ({it_new.min()} to {it_new.max()})")
    zero = np.mean(np.array(firsts) == 0)
    print(f"  closed start: declined on {declined} poses (the first-order start there); first "
          f"solve mean {np.mean(firsts):.2f} (0 on {zero:.1%} of poses); mirror solved on "
          f"{mirrors} poses ({mirrors / len(xs):.1%})")
    print(f"  largest |q difference| between the two starts' answers: {dq:.1e}")
    print(f"  C call alone, CPU µs: first-order start {med[0]:.2f}, closed start {med[1]:.2f} "
          f"(x{med[0] / med[1]:.2f})")
    print(f"  m.ik(x), CPU µs: first-order start {med[2]:.2f}, closed start {med[3]:.2f} "
          f"(x{med[2] / med[3]:.2f})")
    f_old, f_new = float(np.median(f_old)), float(np.median(f_new))
    print(f"  m.ik(x, full_output=True) (Numba one-pose path), CPU µs: first-order start "
          f"{f_old:.2f}, closed start {f_new:.2f} (x{f_old / f_new:.2f})")
    print(f"  m.ik(X) of the {len(xs)} poses (batch path), CPU ms: first-order start "
          f"{b_old * 1e3:.1f}, closed start {b_new * 1e3:.1f} (x{b_old / b_new:.2f})")


def compiled(name: str, poses: int, rounds: int, spread: float = 0.9) -> None:
    """Session 35: the one-pose Numba path (``m.ik(x, full_output=True)``, and ``m.ik(x)`` and
    ``m.fk(q)`` without the C extension: :func:`pkmkit.machines.chain_one.inverse`,
    :func:`~pkmkit.machines.chain_one.direct` — before, ``fk``'s kernel started from first
    order, with no closed start) and the batch rows
    with the kind's closed start computed by its NumPy function (before) and by its compiled
    twin (after), and from the first-order start (the closed start off: what the calls cost
    before the closed starts landed); the largest difference of the answers q and the
    iteration counts of the two starts; CPU µs per call (median of ``rounds`` interleaved
    rounds), the batch's CPU ms and the start alone over the batch."""
    import numba  # noqa: F401 - the compiled paths

    from pkmkit.machines import chain_one, chain_starts

    m = pkmkit.machine(name)
    off = pkmkit.machine(name)
    object.__setattr__(off, "_closed_start_ok", False)
    object.__setattr__(off, "_closed_direct_ok", False)
    rng = np.random.default_rng(0)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * ((1 - spread) / 2 + spread * rng.random((poses, len(act))))
    xs = m.fk(q, strokes="ignore")
    xs = xs[np.isfinite(xs).all(axis=1)]
    for machine in (m, off):
        machine.ik(xs[0], strokes="ignore", full_output=True)  # builds the constants
        machine.ik(xs[0], strokes="ignore", full_output=True)
    c = chain_one.constants(m)
    twin, numpy_start = c.closed, (m.kind.inverse_start, dict(m.params))
    direct_twin = c.closed_direct
    real = chain_starts.compiled_start

    def before() -> None:  # the one-pose fk: the kernel's first-order start, as before
        c.closed, c.closed_direct = numpy_start, None
        chain_starts.compiled_start = lambda *a: None

    def after() -> None:
        c.closed, c.closed_direct = twin, direct_twin
        chain_starts.compiled_start = real

    fast = [x for x in xs if chain_one.inverse(m, x, "ignore") is not None]
    answers, iterations = [], []
    for switch in (before, after):
        switch()
        rec = [m.ik(x, strokes="ignore", full_output=True) for x in fast]
        answers.append(np.array([r.q for r in rec]))
        iterations.append(np.array([int(r.iterations) for r in rec]))
        answers.append(m.ik(xs, strokes="ignore"))
    print(f"{name}: {len(xs)} poses, {len(fast)} on the one-pose Numba path")
    print(f"  largest |q difference|, NumPy start against the twin: one-pose "
          f"{np.abs(answers[0] - answers[2]).max():.1e}, batch "
          f"{np.nanmax(np.abs(answers[1] - answers[3])):.1e}; NaN rows alike "
          f"{np.array_equal(np.isnan(answers[1]), np.isnan(answers[3]))}; iterations alike on "
          f"{np.mean(iterations[0] == iterations[1]):.1%} (mean {iterations[1].mean():.2f})")
    rows = [(x,) for x in fast[:200]]
    cases = {"full_output": lambda mm: (lambda x: mm.ik(x, strokes="ignore", full_output=True)),
             "no C": lambda mm: (lambda x: chain_one.inverse(mm, x, "ignore")),
             "fk no C": lambda mm: (lambda x, mm=mm: chain_one.direct(
                 mm, actuators[id(x)], "ignore", None))}
    actuators = {id(x): np.asarray(m.ik(x, strokes="ignore")) for x in fast[:200]}
    for mm in (m, off):  # the fk's one-pose constants (past the first single call)
        for _ in range(2):
            chain_one.direct(mm, actuators[id(fast[0])], "ignore", None)
    times: dict = {}
    for _ in range(rounds):  # interleaved
        for label, make in cases.items():
            times.setdefault((label, "first-order"), []).append(per_call(make(off), rows, 1))
            before()
            times.setdefault((label, "NumPy"), []).append(per_call(make(m), rows, 1))
            after()
            times.setdefault((label, "twin"), []).append(per_call(make(m), rows, 1))
    med = {key: float(np.median(v)) for key, v in times.items()}
    for label in cases:
        old, new, first = med[label, "NumPy"], med[label, "twin"], med[label, "first-order"]
        call = {"full_output": "m.ik(x, full_output=True)",
                "no C": "m.ik(x) without C (chain_one.inverse)",
                "fk no C": "m.fk(q) without C (chain_one.direct; before: no closed start)"}[label]
        print(f"  {call}, CPU µs: NumPy start {old:.2f}, compiled twin {new:.2f} "
              f"(x{old / new:.2f}); first-order start {first:.2f} (twin x{first / new:.2f})")
    batch = {"NumPy": [], "twin": [], "start NumPy": [], "start twin": []}
    tools = np.full(len(xs), m.tool_length)
    for _ in range(3):
        for switch, label in ((before, "NumPy"), (after, "twin")):
            switch()
            t = time.process_time()
            m.ik(xs, strokes="ignore")
            batch[label].append(time.process_time() - t)
            t = time.process_time()
            chain_starts.closed_starts(m, xs, tools)
            batch["start " + label].append(time.process_time() - t)
    after()
    b = {k: float(np.median(v)) * 1e3 for k, v in batch.items()}
    print(f"  m.ik(X) of the {len(xs)} poses (batch path), CPU ms: NumPy start {b['NumPy']:.1f}, "
          f"twin {b['twin']:.1f} (x{b['NumPy'] / b['twin']:.2f}); the start alone "
          f"{b['start NumPy']:.2f} against {b['start twin']:.2f} "
          f"(x{b['start NumPy'] / b['start twin']:.1f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1000)
    parser.add_argument("--grid", type=int, default=3)
    parser.add_argument("--rules-only", action="store_true",
                        help="the rules' counts from the first-order start alone (no table)")
    parser.add_argument("--machines", default="tripteor-x7,trimule-600")
    parser.add_argument("--closed", action="store_true",
                        help="the closed-form start against the first-order one (session 33)")
    parser.add_argument("--compiled", action="store_true",
                        help="the closed start's compiled twin against its NumPy function "
                             "(session 35)")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--spread", type=float, default=0.9,
                        help="with --closed: the middle fraction of the strokes (1.1: beyond)")
    args = parser.parse_args()
    print("load average:", " ".join(f"{v:.1f}" for v in os.getloadavg()))
    for name in args.machines.split(","):
        if args.compiled:
            compiled(name, args.poses, args.rounds, args.spread)
        elif args.closed:
            closed(name, args.poses, args.rounds, args.spread)
        elif args.rules_only:
            rules_only(name, args.poses)
        else:
            run(name, args.poses, args.grid)


if __name__ == "__main__":
    main()
