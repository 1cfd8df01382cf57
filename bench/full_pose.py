"""Benchmark: full-pose (6-DOF) rod machines, quiet and with a competing process.

For each condition (``quiet``; ``loaded`` with one process keeping a core and the memory bus busy,
:mod:`load`) and each figure, the timing and its baselines are interleaved and the median of
``--repeat`` runs is reported:

- **inverse model** — ``m.ik(X)`` on ``--poses`` full poses (closed form rod by rod, the compiled
  kernel for large batches) of the hexapod and of the Verne-type module (full poses it reaches,
  whose rods are checked for consistency): poses/s, the ratio to the same formula written per
  pose in pure Python (``math``, on a 20 000-pose sample) and the ratios to a plain copy of the
  input (``X.copy()``, the memory-bandwidth limit of a pass over the data, with the page faults
  of a fresh array; ``m.ik``'s own output is recycled memory since session 34,
  ``jit.batch_output``) and to a copy into a preallocated array
  (``np.copyto``: the memory traffic alone, the issue's limit), and ``m.ik(X, out=Q)`` with
  ``Q`` reused call after call (no fresh pages; whether §2's ≤ 3× the preallocated copy is
  met with it and without it), all measured interleaved in
  the same condition (quiet, or beside the competing process); then the CPU time
  per pose on one thread (best of ``--repeat``) against the copy's CPU time, and whether the
  C kernel runs vectorised (``pkmkit.native.kernels.simd()``);
- **engine direct model** — ``m.fk(Q)`` (batched Levenberg–Marquardt over the six rods, from the
  first-order guess) on ``--configurations`` hexapod configurations against
  ``scipy.optimize.least_squares(method="lm")`` per configuration with the analytic Jacobian of
  the same residual from the same guesses (on a 300-configuration sample); the largest
  disagreement is printed;
- **C against Numba** (``--backends``, only these rows) — the same ``m.ik`` and ``m.fk`` on one
  thread by the C kernels of :mod:`pkmkit.native` and by the Numba ones (``PKMKIT_NATIVE=0``)
  in this process, warm: CPU time;
- **threads** (``--threads``, only these rows) — CPU accounting of ``m.ik(X)`` on one and on
  two threads, for scaling that wall time cannot show on a loaded machine: the kernel's CPU
  (``time.thread_time`` around each kernel call, per thread) against the calling thread's CPU
  outside the kernel (the serial part: validation, allocation, Python, joins), the serial
  fraction and the two-thread speed-up it allows (Amdahl); and the kernel alone on
  preallocated arrays, the batch halved over one and two threads (CPU per pose; were the
  two threads bound by memory bandwidth their CPU per pose would rise);
- **block widths** (``--widths``, only these rows) — the C inverse kernel alone on
  preallocated arrays, one thread, scalar (libm's sin and cos) and per vector width the CPU
  has (4 poses per AVX2 block, 8 per AVX-512 one; their own sincos, or up to 1 rad the
  Taylor series of sin θ / θ and cos θ), against a copy of the
  input into a preallocated array: CPU per pose;
- **accuracy** (``--accuracy``, only these rows, no timing) — q of the vectorised kernel, of
  the scalar C kernel and of the NumPy path on ``--poses`` hexapod poses and up to 10⁶ Verne
  module ones: the largest differences in metres and in ulps of the leg, statuses differing;
- **every assembly mode** — ``m.fk_all(q)`` of Dietmaier's general hexapod (40 real modes) and of
  random general 6-6 configurations: seconds per configuration, count, worst residual.

    python bench/full_pose.py [--poses 1000000] [--configurations 10000] [--repeat 5]
                              [--load none|busy|both] [--backends] [--ik-only] [--threads]
                              [--widths] [--accuracy]
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import resource
import statistics
import sys
import threading
import time
from pathlib import Path

import numpy as np
import scipy
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).parent))

from load import conditions

import pkmkit
from pkmkit.numerics import jit
from pkmkit.spatial import pose_from_angles


def _median(fun, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fun()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def python_ik(model, poses: np.ndarray) -> list[list[float]]:
    """The rod-by-rod inverse model written per pose in pure Python (slides and struts)."""
    base, plat, axis = model.rod_base.tolist(), model.rod_platform.tolist(), model.rod_axis.tolist()
    length = model.rod_length.tolist()
    kinds = model.rod_kind.tolist()
    out = []
    for x, y, z, wx, wy, wz in poses.tolist():
        theta = math.sqrt(wx * wx + wy * wy + wz * wz)
        a = math.sin(theta) / theta if theta > 1e-12 else 1.0
        b = (1.0 - math.cos(theta)) / theta**2 if theta > 1e-12 else 0.5
        rot = [[1 - b * (wy * wy + wz * wz), b * wx * wy - a * wz, b * wx * wz + a * wy],
               [b * wx * wy + a * wz, 1 - b * (wx * wx + wz * wz), b * wy * wz - a * wx],
               [b * wx * wz - a * wy, b * wy * wz + a * wx, 1 - b * (wx * wx + wy * wy)]]
        row = []
        for j in range(len(kinds)):
            p = [(x, y, z)[i] + sum(rot[i][c] * plat[j][c] for c in range(3)) for i in range(3)]
            w = [p[i] - base[j][i] for i in range(3)]
            if kinds[j] == 1:
                row.append(math.sqrt(sum(v * v for v in w)) - length[j])
            else:
                s = sum(w[i] * axis[j][i] for i in range(3))
                row.append(s + math.sqrt(length[j] ** 2 - sum(v * v for v in w) + s * s))
        out.append(row)
    return out


def _cpu_median(fun, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.process_time()
        fun()
        times.append(time.process_time() - start)
    return statistics.median(times)


def inverse_rows(label: str, m, poses: np.ndarray, repeat: int) -> None:
    m.ik(poses[:5000])  # compile / warm up
    sample = poses[:20000]
    t_api, t_one, t_copy, t_loop, c_api, c_one, c_copy = [], [], [], [], [], [], []
    t_pre, target = [], np.empty_like(poses)
    np.copyto(target, poses)  # its pages touched once: the copy's memory traffic alone
    t_out, c_out, reused = [], [], m.ik(poses)  # out=: q into an array reused call after call
    c_one_out = []
    for _ in range(repeat):
        t_api.append(_median(lambda: m.ik(poses), 1))
        t_out.append(_median(lambda: m.ik(poses, out=reused), 1))
        c_out.append(_cpu_median(lambda: m.ik(poses, out=reused), 1))
        c_api.append(_cpu_median(lambda: m.ik(poses), 1))
        os.environ["PKMKIT_THREADS"] = "1"
        t_one.append(_median(lambda: m.ik(poses), 1))
        c_one.append(_cpu_median(lambda: m.ik(poses), 1))
        c_one_out.append(_cpu_median(lambda: m.ik(poses, out=reused), 1))
        del os.environ["PKMKIT_THREADS"]
        t_copy.append(_median(lambda: poses.copy(), 1))
        c_copy.append(_cpu_median(lambda: poses.copy(), 1))
        t_pre.append(_median(lambda: np.copyto(target, poses), 1))
        t_loop.append(_median(lambda: python_ik(m.model, sample), 1) * len(poses) / len(sample))
    api, one, copy, loop, cpu = (statistics.median(t) for t in (t_api, t_one, t_copy, t_loop,
                                                                  c_api))
    first_rods = [int(np.flatnonzero(m.model.rod_actuator == k)[0])
                  for k in range(m.n_actuators)]
    loop_q = np.array(python_ik(m.model, sample[:2000]))[:, first_rods]
    check = np.abs(loop_q - m.ik(sample[:2000])).max()
    print(f"  IK {label:<14} {len(poses) / api / 1e6:6.2f} Mposes/s ({jit.thread_count()} threads;"
          f" one thread {len(poses) / one / 1e6:.2f}; {len(poses) / cpu / 1e6:.2f} per CPU "
          f"second)   ×loop {loop / api:6.0f}   time / copy {api / copy:5.1f}, / preallocated "
          f"copy {api / statistics.median(t_pre):4.1f}   (largest difference to the loop "
          f"{check:.1e} m)")
    lanes = jit.native_kernels().simd() if hasattr(jit.native_kernels(), "simd") else 0
    print(f"     one thread, CPU: {min(c_one) / len(poses) * 1e9:.1f} ns per pose (best of "
          f"{repeat}), copy {min(c_copy) * 1e3:.2f} ms, CPU / copy "
          f"{min(c_one) / min(c_copy):.1f} (vectorised C kernel: {lanes or 'no'} lanes)")
    pre, out = statistics.median(t_pre), statistics.median(t_out)
    print(f"     m.ik(X, out=Q), Q reused: {len(poses) / out / 1e6:6.2f} Mposes/s "
          f"({len(poses) / statistics.median(c_out) / 1e6:.2f} per CPU second), / preallocated "
          f"copy {out / pre:4.1f} (the plain m.ik(X) {api / pre:4.1f}, out= / plain "
          f"{out / api:4.2f}); issue 22 §2's ≤ 3× the preallocated copy: with out= "
          f"{'met' if out / pre <= 3.0 else 'NOT met'}, plain "
          f"{'met' if api / pre <= 3.0 else 'NOT met'}")
    print(f"     one thread, CPU: m.ik(X, out=Q) {min(c_one_out) / len(poses) * 1e9:.1f} ns per "
          f"pose against the plain call's {min(c_one) / len(poses) * 1e9:.1f} (best of "
          f"{repeat}; out= / plain {min(c_one_out) / min(c_one):.2f}); minor page faults per "
          f"call {_faults(lambda: m.ik(poses)):.0f} plain, "
          f"{_faults(lambda: m.ik(poses, out=reused)):.0f} with out= (q {reused.nbytes / 1e6:.0f}"
          " MB)")


def _faults(fun, calls: int = 3) -> float:
    """Minor page faults of this process per call of ``fun`` (fresh pages mapped and cleared;
    memory malloc recycles from an earlier call has none)."""
    start = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(calls):
        fun()
    return (resource.getrusage(resource.RUSAGE_SELF).ru_minflt - start) / calls


def accuracy_rows(label: str, m, poses: np.ndarray) -> None:
    """q of the vectorised C kernel (its own sincos), of the scalar C kernel (libm's sin and
    cos) and of the NumPy path (``PKMKIT_COMPILED=0``) on ``poses``, in slices of 10⁶: the
    largest differences in metres and in ulps of the leg (the actuator's first rod's length or
    |q|, whichever is larger), and the rows whose statuses differ."""
    native = jit.native_kernels()
    if native is None or not native.simd():
        print(f"  {label}: no vectorised C kernel here, nothing to compare")
        return
    rod = m.model.rod_length[[int(np.flatnonzero(m.model.rod_actuator == k)[0])
                              for k in range(m.n_actuators)]]
    worst = {"vector": [0.0, 0.0], "scalar": [0.0, 0.0], "vector/scalar": [0.0, 0.0]}
    statuses = 0
    lanes = native.simd()
    for start in range(0, len(poses), 1_000_000):
        x = poses[start:start + 1_000_000]
        out = {}
        for key, env, simd in (("vector", "1", True), ("scalar", "1", False),
                               ("numpy", "0", True)):
            os.environ["PKMKIT_COMPILED"] = env
            native.simd(simd)
            try:
                out[key] = m.ik(x, full_output=True, strokes="ignore")
            finally:
                native.simd(True)
                del os.environ["PKMKIT_COMPILED"]
        statuses += int((out["vector"].status != out["numpy"].status).sum())
        for key, (a, b) in {"vector": ("vector", "numpy"), "scalar": ("scalar", "numpy"),
                            "vector/scalar": ("vector", "scalar")}.items():
            both = (out[a].status == 0) & (out[b].status == 0)
            qa, qb = np.asarray(out[a].q)[both], np.asarray(out[b].q)[both]
            gap = np.abs(qa - qb)
            ulp = np.spacing(np.maximum(np.abs(qb), rod))
            worst[key] = [max(worst[key][0], float(gap.max(initial=0.0))),
                          max(worst[key][1], float((gap / ulp).max(initial=0.0)))]
    print(f"  IK {label:<14} {len(poses)} poses, {lanes} lanes: largest |q difference| "
          + "; ".join(f"{key} {'against NumPy' if key != 'vector/scalar' else ''} "
                      f"{v[0]:.1e} m = {v[1]:.1f} ulp of the leg" for key, v in worst.items())
          + f"; statuses differing from NumPy's: {statuses} rows")


def engine_rows(m, q: np.ndarray, repeat: int) -> None:
    model = m.model
    guesses = np.array(m.fk(q, full_output=True).pose)  # reference answers
    t_api = _median(lambda: m.fk(q), repeat)
    c_api = _cpu_median(lambda: m.fk(q), repeat)
    os.environ["PKMKIT_THREADS"] = "1"
    t_single = _median(lambda: m.fk(q), repeat)
    del os.environ["PKMKIT_THREADS"]
    os.environ["PKMKIT_COMPILED"] = "0"
    t_numpy = _median(lambda: m.fk(q), repeat)
    numpy_poses = m.fk(q)
    del os.environ["PKMKIT_COMPILED"]
    gap_numpy = np.nanmax(np.abs(numpy_poses - guesses))
    print(f"  FK hexapod (one mode, compiled per-pose LM) {t_api / len(q) * 1e6:5.2f} µs per pose "
          f"({jit.thread_count()} threads; one thread {t_single / len(q) * 1e6:.2f} µs; "
          f"{c_api / len(q) * 1e6:.2f} µs of CPU); NumPy engine {t_numpy / len(q) * 1e6:.2f} µs "
          f"(×{t_numpy / t_api:.0f}; largest difference {gap_numpy:.1e})")
    sample = q[:300]
    start = m.first_order_pose(sample)

    def residual(u, qk):
        rot = Rotation.from_rotvec(u[3:]).as_matrix()
        rb = model.rod_platform @ rot.T
        d = u[:3] + rb - model.rod_base
        return np.linalg.norm(d, axis=1) - qk

    def jac(u, qk):
        rot = Rotation.from_rotvec(u[3:]).as_matrix()
        rb = model.rod_platform @ rot.T
        d = u[:3] + rb - model.rod_base
        unit = d / np.linalg.norm(d, axis=1)[:, None]
        return np.concatenate([unit, np.cross(rb, unit)], axis=1)  # ω = left increment, ≈ φ

    def scipy_all():
        out = []
        for k in range(len(sample)):
            out.append(least_squares(residual, start[k], jac=jac, args=(sample[k],),
                                     method="lm", xtol=1e-14, ftol=1e-14).x)
        return np.array(out)

    t_scipy = _median(scipy_all, max(1, repeat // 2)) * len(q) / len(sample)
    found = scipy_all()
    gap = np.abs(found[:, :3] - guesses[:300, :3]).max()
    print(f"  FK hexapod {len(q) / t_api / 1e3:8.1f} kconfigs/s   ×scipy "
          f"{t_scipy / t_api:6.0f}   (largest position difference to scipy {gap:.1e} m)")


def backend_rows(label: str, m, poses: np.ndarray, q: np.ndarray, repeat: int) -> None:
    """Steady state (machine loaded, kernels warm) in this process, one thread: CPU time of
    ``m.ik(poses)`` and ``m.fk(q)`` by the C kernels of ``pkmkit.native`` and by the Numba
    kernels (``PKMKIT_NATIVE=0``), interleaved, median of ``repeat``."""
    saved = {k: os.environ.get(k) for k in ("PKMKIT_THREADS", "PKMKIT_NATIVE")}
    backends = {"C": "1", "Numba": "0"}
    cpu = {(b, call): [] for b in backends for call in ("ik", "fk")}
    os.environ["PKMKIT_THREADS"] = "1"
    try:
        for _ in range(repeat + 1):  # the first round compiles / warms up, not counted
            for backend, value in backends.items():
                os.environ["PKMKIT_NATIVE"] = value
                cpu[backend, "ik"].append(_cpu_median(lambda: m.ik(poses, strokes="ignore"), 1))
                cpu[backend, "fk"].append(_cpu_median(lambda: m.fk(q, strokes="ignore"), 1))
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
    med = {key: statistics.median(v[1:]) for key, v in cpu.items()}
    if jit.native_kernels() is None:
        print(f"  {label}: pkmkit.native.kernels not built, no C row")
        return
    print(f"  {label} one thread, CPU: IK ({len(poses)} poses) C "
          f"{len(poses) / med['C', 'ik'] / 1e6:.2f} Mposes/s, Numba "
          f"{len(poses) / med['Numba', 'ik'] / 1e6:.2f} (C/Numba time "
          f"{med['C', 'ik'] / med['Numba', 'ik']:.2f}); FK ({len(q)} configurations) C "
          f"{med['C', 'fk'] / len(q) * 1e6:.2f} µs per pose, Numba "
          f"{med['Numba', 'fk'] / len(q) * 1e6:.2f} µs (C/Numba time "
          f"{med['C', 'fk'] / med['Numba', 'fk']:.2f})")


def _traced_kernel(log: list) -> tuple:
    """Replace ``jit.kernel`` so that the inverse kernel's calls append ``(thread, CPU s,
    rows)`` to ``log``; returns the real ``jit.kernel`` and a dict that keeps the rod
    arguments of the last call."""
    real = jit.kernel
    kept: dict = {}

    def kernel(module, name):
        fun = real(module, name)
        if name != "inverse_poses":
            return fun

        def traced(x, *rest):
            kept["rods"] = rest[:-2]
            start = time.thread_time()
            fun(x, *rest)
            log.append((threading.get_ident(), time.thread_time() - start, x.shape[0]))
        return traced

    jit.kernel = kernel
    return real, kept


def _accounted_ik(m, poses: np.ndarray, log: list) -> dict:
    """One ``m.ik(poses)``: process CPU, the calling thread's CPU outside the kernel (serial),
    the kernel's CPU summed and per thread."""
    log.clear()
    me = threading.get_ident()
    cpu0, mine0 = time.process_time(), time.thread_time()
    m.ik(poses)
    total, mine = time.process_time() - cpu0, time.thread_time() - mine0
    per: dict = {}
    for ident, cpu, _ in log:
        per[ident] = per.get(ident, 0.0) + cpu
    return {"total": total, "serial": mine - per.get(me, 0.0), "kernel": sum(per.values()),
            "per": sorted(per.values()), "calls": len(log)}


def _kernel_alone(fun, rods, poses: np.ndarray, n: int, threads: int) -> tuple[float, list]:
    """The kernel on preallocated arrays (written once before), the batch cut in ``threads``
    equal parts run at once: process CPU and each thread's CPU."""
    q = np.empty((len(poses), n))
    status = np.empty(len(poses), dtype=np.int64)
    fun(poses, *rods, q, status)
    edges = np.linspace(0, len(poses), threads + 1).astype(int)
    cpu = [0.0] * threads

    def part(i):
        start = time.thread_time()
        lo, hi = edges[i], edges[i + 1]
        fun(poses[lo:hi], *rods, q[lo:hi], status[lo:hi])
        cpu[i] = time.thread_time() - start

    cpu0 = time.process_time()
    workers = [threading.Thread(target=part, args=(i,)) for i in range(threads)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    return time.process_time() - cpu0, cpu


def thread_rows(label: str, m, poses: np.ndarray, repeat: int) -> None:
    """CPU accounting of ``m.ik`` on one and two threads (module docstring, ``--threads``)."""
    log: list = []
    real, kept = _traced_kernel(log)
    saved = os.environ.get("PKMKIT_THREADS")
    try:
        m.ik(poses[:70000])
        m.ik(poses)
        rows = {1: [], 2: []}
        alone = {1: [], 2: []}
        fun = real("pkmkit.machines.full_pose_kernels", "inverse_poses")
        for _ in range(repeat):  # one and two threads alternated
            for threads in (1, 2):
                os.environ["PKMKIT_THREADS"] = str(threads)
                rows[threads].append(_accounted_ik(m, poses, log))
                alone[threads].append(_kernel_alone(fun, kept["rods"], poses, m.n_actuators,
                                                    threads))
    finally:
        jit.kernel = real
        if saved is None:
            os.environ.pop("PKMKIT_THREADS", None)
        else:
            os.environ["PKMKIT_THREADS"] = saved
    n = len(poses)
    for threads in (1, 2):
        best = min(rows[threads], key=lambda r: r["total"])
        serial = best["serial"] / best["total"]
        bound = 1.0 / (serial + (1.0 - serial) / 2.0)
        cpu, per = min(alone[threads])
        print(f"  IK {label:<14} {threads} thread{'s' if threads > 1 else ' '}: m.ik "
              f"{best['total'] / n * 1e9:5.1f} ns of CPU per pose, serial (calling thread "
              f"outside the kernel) {best['serial'] * 1e3:5.2f} ms = {serial:5.1%} -> two-thread "
              f"bound ×{bound:.2f}; kernel {best['kernel'] * 1e3:5.1f} ms in {best['calls']} "
              f"calls, per thread {'/'.join(f'{c * 1e3:.1f}' for c in best['per'])} ms; "
              f"kernel alone (preallocated) {cpu / n * 1e9:5.1f} ns per pose, per thread "
              f"{'/'.join(f'{c * 1e3:.1f}' for c in per)} ms")


def width_rows(label: str, m, poses: np.ndarray, repeat: int) -> None:
    """The C kernel alone on preallocated arrays, one thread, per block width the CPU has
    (0: the scalar kernel, libm's sin and cos; 4: AVX2; 8: AVX-512), interleaved with a copy
    of the input into a preallocated array: CPU per pose, best of ``repeat`` rounds of 3."""
    native = jit.native_kernels()
    if native is None:
        print(f"  {label}: pkmkit.native.kernels not built")
        return
    log: list = []
    real, kept = _traced_kernel(log)
    saved = os.environ.get("PKMKIT_THREADS")
    os.environ["PKMKIT_THREADS"] = "1"
    try:
        m.ik(poses[:jit.MIN_ROWS])
    finally:
        jit.kernel = real
        if saved is None:
            del os.environ["PKMKIT_THREADS"]
        else:
            os.environ["PKMKIT_THREADS"] = saved
    widths = [w for w in (0, 4, 8) if w == 0 or (native.simd(w) == w)]
    native.simd(True)
    q = np.empty((len(poses), m.n_actuators))
    status = np.empty(len(poses), dtype=np.int64)
    target = np.empty_like(poses)
    best = dict.fromkeys([*widths, "copy"], math.inf)
    try:
        for _ in range(repeat):
            for w in widths:
                native.simd(w)
                for _ in range(3):
                    start = time.thread_time()
                    native.inverse_poses(poses, *kept["rods"], q, status)
                    best[w] = min(best[w], time.thread_time() - start)
            for _ in range(3):
                start = time.thread_time()
                np.copyto(target, poses)
                best["copy"] = min(best["copy"], time.thread_time() - start)
    finally:
        native.simd(True)
    per = {k: v / len(poses) * 1e9 for k, v in best.items()}
    names = {0: "scalar (libm)", 4: "AVX2", 8: "AVX-512"}
    print(f"  IK {label:<14} kernel alone, {len(poses)} poses, one thread, CPU per pose: "
          + ", ".join(f"{names[w]} {per[w]:.1f} ns" for w in widths)
          + f"; preallocated copy {per['copy']:.1f} ns (widest / copy "
          f"{per[widths[-1]] / per['copy']:.1f})")


def all_modes_rows(repeat: int) -> None:
    general = pkmkit.machine("dietmaier-hexapod")
    start = time.perf_counter()
    modes = general.fk_all(general.home_q)
    first = time.perf_counter() - start
    t = _median(lambda: general.fk_all(general.home_q), repeat)
    print(f"  every mode, Dietmaier: {int(modes.count)} real of {int(modes.n_finite)}, worst "
          f"residual {np.nanmax(modes.residual):.1e} m, {t * 1000:.0f} ms per configuration "
          f"(first call {first * 1000:.0f} ms)")
    rng = np.random.default_rng(5)
    base = rng.normal(size=(20, 6, 3))
    plat = rng.normal(size=(20, 6, 3)) * 0.6
    position = rng.normal(size=(20, 3)) + np.array([0.0, 0.0, 2.0])
    pose = np.concatenate([position, rng.normal(size=(20, 3)) * 0.3], axis=1)
    rot = Rotation.from_rotvec(pose[:, 3:]).as_matrix()
    lengths = np.linalg.norm(pose[:, None, :3] + np.einsum("kab,kjb->kja", rot, plat) - base,
                             axis=2)
    from pkmkit.solve.six_rod_direct import six_rod_direct_all

    t = _median(lambda: six_rod_direct_all(base, plat, lengths), max(1, repeat // 2))
    sols = six_rod_direct_all(base, plat, lengths)
    print(f"  every mode, 20 random 6-6 configurations (batched): {t / 20 * 1000:.0f} ms each, "
          f"{int(sols.count.min())}–{int(sols.count.max())} real, finite {int(sols.n_finite.min())}"
          f"–{int(sols.n_finite.max())}, worst residual {np.nanmax(sols.residual):.1e} m")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--configurations", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--load", choices=("none", "busy", "both"), default="both")
    parser.add_argument("--no-modes", action="store_true", help="skip the every-mode rows")
    parser.add_argument("--ik-only", action="store_true", help="only the inverse-model rows")
    parser.add_argument("--threads", action="store_true",
                        help="only the CPU accounting of m.ik on one and two threads")
    parser.add_argument("--widths", action="store_true",
                        help="only the C kernel alone per block width (scalar, AVX2, AVX-512)")
    parser.add_argument("--accuracy", action="store_true",
                        help="only the vectorised kernel's q against the scalar C and NumPy "
                             "paths (no timing)")
    parser.add_argument("--backends", action="store_true",
                        help="only the C against Numba kernel rows (steady state, one thread)")
    args = parser.parse_args()
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, scipy {scipy.__version__}, "
          f"Python {platform.python_version()}, {platform.machine()}")
    rng = np.random.default_rng(0)
    hexapod = pkmkit.machine("gough-stewart")
    verne = pkmkit.machine("verne")
    poses = pose_from_angles(hexapod.home_pose[:3] + rng.uniform(-0.1, 0.1, (args.poses, 3)),
                             rng.uniform(-8, 8, (args.poses, 3)), "xyz", degrees=True)
    positions = rng.uniform(-0.15, 0.15, (min(args.poses, 20000), 3))
    reached = verne.ik(positions, full_output=True).pose
    verne_poses = np.ascontiguousarray(np.resize(reached, (args.poses, 6)))
    q = hexapod.ik(poses[:args.configurations])
    if args.widths:
        for label, context in conditions(args.load):
            print(f"{label} (load average {os.getloadavg()[0]:.2f} before):")
            with context():
                width_rows("hexapod", hexapod, poses, args.repeat)
                width_rows("Verne (poses)", verne, verne_poses, args.repeat)
        return
    if args.accuracy:  # the Verne module's poses solved anew, not repeated (≤ 10⁶)
        positions = rng.uniform(-0.15, 0.15, (min(args.poses, 1_000_000), 3))
        unique = np.ascontiguousarray(verne.ik(positions, full_output=True).pose)
        accuracy_rows("hexapod", hexapod, poses)
        accuracy_rows("Verne (poses)", verne, unique[np.isfinite(unique).all(axis=1)])
        return
    if args.threads:
        for label, context in conditions(args.load):
            print(f"{label} (load average {os.getloadavg()[0]:.2f} before):")
            with context():
                thread_rows("hexapod", hexapod, poses, args.repeat)
                thread_rows("Verne (poses)", verne, verne_poses, args.repeat)
            print(f"  (load average {os.getloadavg()[0]:.2f} after)")
        return
    if args.backends:
        verne_q = verne.ik(verne_poses[:args.configurations], strokes="ignore")
        for label, context in conditions(args.load):
            print(f"{label} (load average {os.getloadavg()[0]:.2f} before):")
            with context():
                backend_rows("hexapod", hexapod, poses, q, args.repeat)
                backend_rows("Verne", verne, verne_poses, verne_q, args.repeat)
        return
    for label, context in conditions(args.load):
        print(f"{label} (load average {os.getloadavg()[0]:.2f} before):")
        with context():
            inverse_rows("hexapod", hexapod, poses, args.repeat)
            inverse_rows("Verne (poses)", verne, verne_poses, args.repeat)
            if args.ik_only:
                continue
            engine_rows(hexapod, q, args.repeat)
            if not args.no_modes:
                all_modes_rows(args.repeat)


if __name__ == "__main__":
    main()
