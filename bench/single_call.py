"""Benchmark: one pose per call (issue 22 §1), quiet and with a competing process.

For each translational built-in machine (every 3-DOF family of the registry: the Orthoglide,
the linear Delta, the five-bar and the biglide five-bar, the Delta robot with cranks), the cost
of one call ``m.ik(x)`` and ``m.fk(q)`` from Python (with the C extension one C call each,
``native/rod_one.c``; ``strokes="ignore"``, and the default ``strokes="flag"`` in its own
rows), against, in the same process and on the same poses:

- the C call alone (``rod_ik_one``, ``rod_fk_one`` on the machine's pack) — the floor of the
  one-pose path: what remains is the Python of ``Machine.ik`` / ``fk`` around it;

- the batch path with one row, ``m.ik(x[None])`` — what every single call cost before;
- the formula in plain Python for one pose, leg constants precomputed (slide legs) — the floor
  of any Python-level implementation;
- a compiled kernel called from Python on one preallocated row
  (:func:`pkmkit.machines.kernels.inverse`, slides and struts only) — what a user's Numba or C
  kernel costs per call.

``m.jacobian(x)`` of one pose (every machine): the call alone (each field is computed when
first read, from only the pieces it needs), the call and reading ``J``, ``condition`` or
``singularity``, against the batch path of one row and reading ``J``; for the translational
machines also with the C extension disabled (``PKMKIT_NATIVE=0``: the plain-Python path).

For the six-axis machines (hexapod, Verne module's full poses, Dietmaier's general platform):
``m.ik(x)``, ``m.fk(q)`` and ``m.jacobian(x)`` (with the C extension one C call each,
``PoseOne`` of ``native/pose_one.c``) against the batch path with one row — for ``fk`` the
NumPy engine (``PKMKIT_COMPILED=0``), what a single call cost before — the compiled solve
called through ``DirectKernel.solve_one`` on one row, and the ``PoseOne`` calls alone
(:func:`pose_one_rows`). ``--agreement POSES`` prints instead the largest differences of the
one-pose answers from the batch path's rows (:func:`agreement`).

Medians of interleaved repeats (each method sees the same load); each figure is the wall time
per call and, in brackets, the CPU time of the process per call (what the call costs when the
2 cores are shared); the load average is printed before each condition. The peer of the
issue, Pinocchio (``pin``, in the ``test`` extra), runs in the same rounds where pkmkit exports
the machine to URDF: forward kinematics with frame placements of that URDF's open tree
(:func:`pinocchio_peer`).

``--alternate``: the 3-DOF machines' one-pose ``ik``, ``fk``, ``jacobian`` (and + ``J``)
only, the machines timed in turn in every round (:func:`alternate`; whether one machine's call
costs more than another's, free of the order in which the bench measures them).

Usage::

    python bench/single_call.py [--calls 20000] [--load none|busy|both] [--json FILE]
    python bench/single_call.py --agreement 1000 [--machines gough-stewart,verne]
    python bench/single_call.py --alternate [--calls 400] [--machines a,b]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from load import conditions

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import full_pose_one, kernels
from pkmkit.machines.closed_form import BOUNDARY_TOL
from pkmkit.model.rods import CRANK, SLIDE
from pkmkit.numerics import jit


def per_call(fun, poses, repeats: int = 5) -> tuple[float, float]:
    """Medians over ``repeats`` of the mean wall and CPU times (µs) of ``fun(pose)`` over
    ``poses``."""
    times, cpu = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        for p in poses:
            fun(p)
        times.append((time.perf_counter() - start) / len(poses) * 1e6)
        cpu.append((time.process_time() - start_cpu) / len(poses) * 1e6)
    return statistics.median(times), statistics.median(cpu)


def plain_formula(m):
    """The slide-leg inverse model of one pose in plain Python, constants precomputed once."""
    model = m.model
    dims = model.dims
    legs = [((model.leg_base[i] - model.leg_platform[i])[:dims].tolist(),
             model.leg_axis[i][:dims].tolist(), float(model.leg_length[i]) ** 2,
             float(model.leg_branch[i])) for i in range(model.n_legs)]

    def ik(pose):
        q = []
        for centre, axis, length_sq, branch in legs:
            w = [p - c for p, c in zip(pose, centre, strict=True)]
            along = sum(a * b for a, b in zip(w, axis, strict=True))
            q.append(along + branch * math.sqrt(length_sq - (sum(a * a for a in w)
                                                              - along * along)))
        return q

    return ik


def pinocchio_peer(m, calls: int):
    """The issue's peer: Pinocchio's forward kinematics with the frame placements
    (``framesForwardKinematics``, then reading the last frame's translation) of the open tree
    of pkmkit's own URDF export of ``m``, at random configurations; None where Pinocchio is
    missing or ``m`` has no URDF export. (A serial tree's forward pass: the work of one pose
    per call, not a closed chain's solve; a joint chain's export is the spanning tree of its
    legs and head, :func:`pkmkit.export.urdf_chains.chain_urdf_export`.)"""
    try:
        import pinocchio as pin

        from pkmkit.export.urdf import urdf_export
        from pkmkit.export.urdf_chains import chain_urdf_export
        export = (chain_urdf_export if hasattr(m, "passive_variables") else urdf_export)(m)
    except Exception:  # no Pinocchio, or no URDF export of this machine
        return None
    model = pin.buildModelFromXML(export.urdf)
    data = model.createData()
    frame = model.nframes - 1
    qs = tree_configurations(pin, model, calls)

    def forward(q):
        pin.framesForwardKinematics(model, data, q)
        return data.oMf[frame].translation

    return lambda: per_call(forward, qs)


def tree_configurations(pin, model, calls: int) -> list:
    """``calls`` random configurations of a Pinocchio model (joints 0.1 rad or m around
    neutral; a two-number joint as its cosine and sine)."""
    rng = np.random.default_rng(3)
    qs = []
    for _ in range(calls):
        q = pin.neutral(model)
        for jid in range(1, model.njoints):
            joint, v = model.joints[jid], 0.1 * rng.standard_normal()
            q[joint.idx_q:joint.idx_q + joint.nq] = ([np.cos(v), np.sin(v)] if joint.nq == 2
                                                     else v)
        qs.append(q)
    return qs


def machine_rows(name: str, calls: int) -> dict:
    m = pkmkit.machine(name)
    lo, hi = m.default_box()
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    rng = np.random.default_rng(0)
    poses = centre + 0.3 * half * (2 * rng.random((calls, m.dims)) - 1)
    poses = poses[np.isfinite(m.ik(poses, strokes="ignore")).all(axis=1)]
    rows = [p for p in poses]
    ones = [p[None] for p in poses]
    closed = m._closed
    branch = np.asarray(m.model.leg_branch, dtype=float)
    out = np.empty((m.model.n_legs, 1))
    slide = m.model.leg_kind == SLIDE
    has_crank = bool((m.model.leg_kind == CRANK).any())
    qs = [q for q in m.ik(poses, strokes="ignore")]
    q_ones = [q[None] for q in qs]
    within = [k for k, q in enumerate(qs) if m.within_strokes(q.tolist())]
    inside, q_inside = [rows[k] for k in within], [qs[k] for k in within]
    pack = m._one_pack  # the one-pose C entries' constants (closed_form_one.one_pose_pack)
    native = jit.native_kernels_now() if pack is not None else None
    m.ik(rows[0], strokes="ignore")
    figures: dict = {"poses": len(rows)}
    peer = pinocchio_peer(m, len(rows))
    for _ in range(2):  # interleaved: every method twice, the second round kept
        if peer is not None:
            figures["Pinocchio FK + frame (URDF tree, peer)"] = peer()
        figures["ik one pose"] = per_call(lambda p: m.ik(p, strokes="ignore"), rows)
        if inside:  # within the strokes: the default strokes="flag" warns nothing
            figures["ik one pose, default strokes"] = per_call(m.ik, inside)
            figures["fk one, default strokes"] = per_call(m.fk, q_inside)
        figures["ik batch of one (before)"] = per_call(lambda p: m.ik(p, strokes="ignore"), ones)
        figures["fk one"] = per_call(lambda q: m.fk(q, strokes="ignore"), qs)
        if native is not None:
            figures["ik, the C call alone"] = per_call(
                lambda p: native.rod_ik_one(pack, p, "ignore"), rows)
            figures["fk, the C call alone"] = per_call(
                lambda q: native.rod_fk_one(pack, q, 1, "ignore"), qs)
        figures["fk batch of one (before)"] = per_call(lambda q: m.fk(q, strokes="ignore"),
                                                       q_ones)
        jacobian_rows(m, figures, rows, without_c=True)
        if (m.model.leg_kind == SLIDE).all():
            plain = plain_formula(m)
            lists = [p.tolist() for p in rows]
            figures["ik plain-Python formula"] = per_call(plain, lists)
        if not has_crank:
            figures["ik compiled kernel, one row"] = per_call(
                lambda p: kernels.inverse(p, closed.basis, closed.basis_offset,
                                          m.model.leg_length, slide, branch, BOUNDARY_TOL, out),
                ones)
    return figures


def six_axis_rows(name: str, calls: int) -> dict:
    """``ik``, ``fk``, ``jacobian`` of one full pose, against the batch path of one row."""
    m = pkmkit.machine(name)
    rng = np.random.default_rng(1)
    if m.position_controlled:
        positions = m.home_pose[:3] + rng.uniform(-0.1, 0.1, (calls, 3))
        poses = m.ik(positions, full_output=True, strokes="ignore").pose
    else:
        poses = np.tile(m.home_pose, (calls, 1))
        poses[:, :3] += rng.uniform(-0.05, 0.05, (calls, 3))
        poses[:, 3:] += rng.uniform(-0.05, 0.05, (calls, 3))
    q = m.ik(poses, strokes="ignore")
    good = np.isfinite(q).all(axis=1) & np.isfinite(poses).all(axis=1)
    rows, qs = list(poses[good]), list(q[good])
    ones, q_ones = [p[None] for p in rows], [v[None] for v in qs]
    kernel = m.direct_kernel()
    m.fk(qs[0])
    figures = {"poses": len(rows)}
    peer = pinocchio_peer(m, len(rows))
    for _ in range(2):
        if peer is not None:
            figures["Pinocchio FK + frame (URDF tree, peer)"] = peer()
        figures["ik one pose"] = per_call(lambda p: m.ik(p, strokes="ignore"), rows)
        figures["ik batch of one (before)"] = per_call(lambda p: m.ik(p, strokes="ignore"), ones)
        figures["fk one"] = per_call(lambda v: m.fk(v, strokes="ignore"), qs)
        os.environ["PKMKIT_COMPILED"] = "0"
        try:
            figures["fk batch of one, NumPy engine (before)"] = per_call(
                lambda v: m.fk(v, strokes="ignore"), q_ones[: len(q_ones) // 10])
        finally:
            os.environ.pop("PKMKIT_COMPILED")
        figures["fk compiled solve, one row"] = per_call(kernel.solve_one, qs)
        jacobian_rows(m, figures, rows)
        pose_one_rows(m, figures, rows, qs)
    return figures


def pose_one_rows(m, figures: dict, rows: list, qs: list) -> None:
    """The C calls of the six-axis one-pose paths alone (``PoseOne.ik``, ``.fk``,
    ``.jacobian`` and its first field: the floor under ``m.ik``, ``m.fk``, ``m.jacobian``)
    and the jacobian call with J, condition and singularity all read."""
    one = full_pose_one.native_one(m)
    if one is None:
        return
    tol = 1e-6

    def fields(p):
        j = m.jacobian(p)
        return j.J, j.condition, j.singularity

    figures["jacobian one pose, call + J, condition, singularity"] = per_call(fields, rows)
    figures["ik C call alone (PoseOne.ik)"] = per_call(lambda p: one.ik(p, True), rows)
    figures["fk C call alone (PoseOne.fk)"] = per_call(lambda v: one.fk(v, True), qs)
    figures["jacobian C call + J alone (PoseOne)"] = per_call(
        lambda p: one.jacobian(p, tol, True, m._jacobian_row).field("J"), rows)


def agreement(name: str, count: int) -> dict:
    """Largest differences between the one-pose answers and the batch path's rows over
    ``count`` poses around home (those within the strokes): ``ik`` and ``fk`` (m, rad), each
    field of ``jacobian`` relative to the field's scale (max(1, its largest entry)), and how
    many rows are bit for bit equal."""
    m = pkmkit.machine(name)
    rng = np.random.default_rng(5)
    if m.position_controlled:
        positions = m.home_pose[:3] + rng.uniform(-0.1, 0.1, (count, 3))
        poses = m.ik(positions, full_output=True, strokes="ignore").pose
    else:
        poses = m.home_pose + rng.uniform(-0.05, 0.05, (count, 6))
    q = m.ik(poses)
    good = np.isfinite(q).all(axis=1)
    poses, q = poses[good], q[good]
    out = {"poses": len(poses)}
    one_q = np.array([m.ik(p) for p in poses])
    one_x = np.array([m.fk(v) for v in q])
    out["ik max |diff|"] = float(np.abs(one_q - q).max())
    out["ik rows equal"] = int((one_q == q).all(axis=1).sum())
    batch_x = m.fk(q)
    out["fk max |diff|"] = float(np.abs(one_x - batch_x).max())
    out["fk rows equal"] = int((one_x == batch_x).all(axis=1).sum())
    batch = m.jacobian(poses, q=q)
    worst = {}
    for k, p in enumerate(poses):
        j = m.jacobian(p)
        for field in ("J", "J_inv", "singular_values", "condition", "det_A",
                      "parallel_measure", "serial_measure", "singularity"):
            got, want = np.asarray(getattr(j, field), float), np.asarray(getattr(batch, field)[k],
                                                                         float)
            scale = max(1.0, float(np.abs(want).max()))
            worst[field] = max(worst.get(field, 0.0),
                               float(np.nan_to_num(np.abs(got - want).max(), nan=np.inf)) / scale)
    out.update({f"jacobian {k} max rel. diff": v for k, v in worst.items()})
    return out


def chain_rows(name: str, calls: int) -> dict:
    """The joint-chain machines (5 axes: ``ik``, ``fk``, ``jacobian`` of one pose through one
    compiled call, :mod:`pkmkit.machines.chain_one`; ``ik``, ``fk`` one C call each where the
    extension is built, :mod:`pkmkit.machines.chain_one_native`) against the batch path of one
    row (what a single call cost before), the C call alone (``chain_one_ik`` /
    ``chain_one_fk``: the call without the machine's Python), the Numba one-pose kernel alone
    on the preallocated row (the compiled-kernel baseline: the batch path's dense solve from
    its start) and Pinocchio's forward pass of the machine's spanning tree (the peer)."""
    from pkmkit.machines import chain_one, chain_one_native
    from pkmkit.numerics import jit

    m = pkmkit.machine(name)
    rng = np.random.default_rng(2)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (0.1 + 0.8 * rng.random((calls, len(act))))
    poses = m.fk(q, strokes="ignore")
    # within every stroke, as ik and as fk judge them
    inside = (np.isfinite(m.ik(poses, strokes="refuse")).all(axis=1)
              & np.isfinite(m.fk(q, strokes="refuse")).all(axis=1))
    rows, qs = list(poses[inside]), list(q[inside])
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):  # past the first (batch) call
        chain_one.usable(m, tag)
    c = chain_one.constants(m)
    fast = sum(chain_one.inverse(m, x, "flag") is not None for x in rows)
    m.fk(qs[0]), m.jacobian(rows[0]).condition
    ones, q_ones = [p[None] for p in rows], [v[None] for v in qs]
    few = max(1, len(rows) // 10)

    w = chain_one._work(c)

    def ik_kernel(x):
        w.target[0] = x  # from the default (first-order) start
        (c.first_kernel.call or c.first_kernel.first)(*c.first_args, w.u_inv, w.target,
                                                     c.tool_row, w.info)

    def fk_kernel(v):
        w.q[:] = v
        (c.direct_kernel.call or c.direct_kernel.first)(*c.direct_args, w.values, w.delta, w.q,
                                                        True, w.u_dir, w.pose, w.info)

    native = chain_one_native.packed(m)
    ext = jit.native_kernels()
    dense = None if native is None else chain_one_native.Packed(
        ext.chain_one_pack(*chain_one_native.pack_arguments(m, False)), ext)
    # the same C call with the batch path's dense solve (pk_chain_rows): the block
    # elimination's share
    peer = pinocchio_peer(m, len(rows))
    path = toolpath(m, calls)
    first = m.ik(path[0], full_output=True).solution

    def along(record: bool):  # each call started from the previous call's solution
        def run(_):
            solution = first
            for x in path[1:]:
                solution = m.ik(x, start=solution, full_output=True).solution if record else \
                    m.ik(x, start=solution)
        return run

    figures = {"poses": len(rows), "fast": fast}
    peer = pinocchio_jacobian_peer(m, len(rows))
    if native is not None:  # the C answers against the batch rows (the same poses)
        ik_batch, fk_batch = m.ik(np.array(rows)), m.fk(np.array(qs))
        ik_c = [native.ik(native.capsule, p, False, False) for p in rows]
        fk_c = [native.fk(native.capsule, v, False, True) for v in qs]
        counts = np.array([native.ik(native.capsule, p, False, True)[2] for p in rows])
        batch_counts = m.ik(np.array(rows), full_output=True).iterations
        figures["iterations"] = (counts.mean(), counts.min(), counts.max(),
                                 int((counts == batch_counts).sum()))
        fk_counts = m.fk(np.array(qs), strokes="ignore", full_output=True).iterations
        figures["fk iterations"] = (fk_counts.mean(), fk_counts.min(), fk_counts.max())
        figures["agreement"] = tuple(
            max((float(np.abs(a - b).max()) for a, b in zip(c, ref, strict=True)
                 if a is not None), default=math.nan)
            for c, ref in ((ik_c, ik_batch), (fk_c, fk_batch)))
    for _ in range(2):  # interleaved: every method twice, the second round kept
        figures["ik one pose"] = per_call(lambda p: m.ik(p), rows)
        # the Numba one-pose path (full_output; and the call without the C extension), the
        # kind's closed start by its compiled twin (session 35; the NumPy function before)
        figures["ik one pose, full_output"] = per_call(lambda p: m.ik(p, full_output=True), rows)
        figures["ik one pose, Numba path (no C)"] = per_call(
            lambda p: chain_one.inverse(m, p, "flag"), rows)
        figures["ik along a toolpath, default start"] = per_call(lambda p: m.ik(p), path[1:])
        figures["ik along it, start=previous, full_output"] = tuple(
            v * (1 / (len(path) - 1)) for v in per_call(along(True), [None]))
        figures["ik batch of one (before)"] = per_call(lambda p: m.ik(p), ones[:few])
        if native is not None:
            figures["ik C call alone"] = per_call(
                lambda p: native.ik(native.capsule, p, False, False), rows)
            figures["ik C call alone, dense solve"] = per_call(
                lambda p: dense.ik(dense.capsule, p, False, False), rows)
        figures["ik Numba kernel alone (baseline)"] = per_call(ik_kernel, rows)
        figures["fk one"] = per_call(lambda v: m.fk(v), qs)
        figures["fk batch of one (before)"] = per_call(lambda v: m.fk(v), q_ones[:few])
        if native is not None:
            figures["fk C call alone"] = per_call(
                lambda v: native.fk(native.capsule, v, False, True), qs)
            figures["fk C call alone, dense solve"] = per_call(
                lambda v: dense.fk(dense.capsule, v, False, True), qs)
        figures["fk Numba solve + bound alone (baseline)"] = per_call(fk_kernel, qs)
        if peer is not None:
            figures["pinocchio tree fk + frame (peer)"] = peer()
        figures["jacobian one pose, call"] = per_call(m.jacobian, rows)
        figures["jacobian one pose, call + J"] = per_call(lambda p: m.jacobian(p).J, rows)
        figures["jacobian one pose, call + condition"] = per_call(
            lambda p: m.jacobian(p).condition, rows)
        figures["jacobian batch of one + J (before)"] = per_call(lambda p: m.jacobian(p).J,
                                                                 ones[:few])
        velocity_rows(m, figures, rows, peer)
    return figures


def pinocchio_jacobian_peer(m, calls: int):
    """The issue's peer for one-pose Jacobians of a joint chain: Pinocchio's frame Jacobian
    (``computeFrameJacobian``: forward kinematics and the Jacobian of the tool point's frame,
    world-aligned) of the open tree of pkmkit's URDF export of ``m`` (legs cut at the
    platform: a serial tree's work, no closure), at random configurations; None without
    Pinocchio."""
    try:
        import pinocchio as pin

        from pkmkit.export.urdf_chains import chain_urdf_export
        export = chain_urdf_export(m)
    except Exception:  # no Pinocchio, or no URDF export of this machine
        return None
    model = pin.buildModelFromXML(export.urdf)
    data = model.createData()
    frame = model.getFrameId("tool_point")
    qs = tree_configurations(pin, model, calls)
    frame_jacobian, aligned = pin.computeFrameJacobian, pin.LOCAL_WORLD_ALIGNED

    def jacobian(q):
        return frame_jacobian(model, data, q, frame, aligned)

    return lambda: per_call(jacobian, qs)


def velocity_rows(m, figures: dict, rows: list, peer) -> None:
    """``m.jacobian(x)`` of a joint chain: the call reading ``J`` and ``condition``; the same
    with the velocity model in Numba (``PKMKIT_NATIVE=0``: the direct model solved again, then
    the velocity kernel — what the call cost before the C kernel); the velocity part alone
    (:func:`pkmkit.machines.chain_one_velocity.record` at the inverse solutions, and its C call
    alone on a preallocated buffer); Pinocchio's frame Jacobian of the machine's open tree."""
    from pkmkit.machines import chain_one
    from pkmkit.machines import chain_one_velocity as cov

    c = chain_one.constants(m, "chain_jacobian")
    found = [chain_one._inverse_values(c, list(map(float, x))) for x in rows]
    args = [(c.actuators(f[0]), f[1], f[3]) for f in found if f is not None]
    p = cov.pack(m)
    if p is None:
        return
    out = np.empty(p.size)
    call, pack = p.call, p.pack

    def part(a):
        r = cov.record(m, a[0], a[1], a[2], 1e-6, 2.0, c.expected_rank)
        return r.J, r.condition

    if peer is not None:
        figures["Pinocchio frame Jacobian (URDF tree, peer)"] = peer()
    figures["jacobian one pose, call + J + condition"] = per_call(
        lambda x: (r := m.jacobian(x)).J is r.condition, rows)
    os.environ["PKMKIT_NATIVE"] = "0"
    try:
        figures["the same, velocity in Numba (before)"] = per_call(
            lambda x: (r := m.jacobian(x)).J is r.condition, rows)
    finally:
        os.environ.pop("PKMKIT_NATIVE")
    figures["velocity part alone: record + J + cond."] = per_call(part, args)
    figures["velocity part alone: record + J"] = per_call(
        lambda a: cov.record(m, a[0], a[1], a[2], 1e-6, 2.0, c.expected_rank).J, args)
    figures["velocity part alone: the C call"] = per_call(lambda a: call(pack, a[1], out), args)
    figures["the C call without the singular stage"] = per_call(
        lambda a: call(pack, a[1], out, False), args)


def toolpath(m, n: int) -> np.ndarray:
    """``n`` poses 0.5 mm apart on a circle of radius 4 mm around the pose of mid-stroke
    actuators (the wrist tilted by 0.3 rad), the tool axis swinging by up to 3° (the path of
    tests/machines/test_chain_one_warm.py)."""
    act = np.flatnonzero(m.model.actuated)
    centre = 0.5 * (m.model.q_min[act] + m.model.q_max[act])
    centre[4] = 0.3
    pose = m.fk(centre)
    t = np.arange(n) * 0.125
    x = np.tile(pose, (n, 1))
    x[:, 0] += 0.004 * np.cos(t)
    x[:, 1] += 0.004 * np.sin(t)
    side = np.cross(pose[3:], [0.0, 0.0, 1.0])
    x[:, 3:] += np.radians(3.0) * np.sin(t / 3)[:, None] * side / np.linalg.norm(side)
    x[:, 3:] /= np.linalg.norm(x[:, 3:], axis=1)[:, None]
    return x


def jacobian_rows(m, figures: dict, rows: list, before_rows: list | None = None,
                  without_c: bool = False) -> None:
    """``m.jacobian(x)`` of one pose: the call (the fields are computed when read, each from
    only the pieces it needs), the call and reading ``J``, ``condition`` or ``singularity``,
    against the batch path of one row (``m.jacobian(x[None])`` and reading ``J``, what a
    single call cost before)."""
    within = [p for p in rows if type(m.jacobian(p)).__name__.startswith("OnePose")]
    figures["jacobian one pose (fast path)"] = (len(within), len(rows))
    figures["jacobian one pose, call"] = per_call(m.jacobian, within)
    figures["jacobian one pose, call + J"] = per_call(lambda p: m.jacobian(p).J, within)
    figures["jacobian one pose, call + condition"] = per_call(lambda p: m.jacobian(p).condition,
                                                              within)
    figures["jacobian one pose, call + singularity"] = per_call(
        lambda p: m.jacobian(p).singularity, within)
    if without_c:  # the same calls without the C extension (the plain-Python path)
        os.environ["PKMKIT_NATIVE"] = "0"
        try:
            figures["jacobian one pose, call + J, no C"] = per_call(lambda p: m.jacobian(p).J,
                                                                    within)
            figures["jacobian one pose, call + condition, no C"] = per_call(
                lambda p: m.jacobian(p).condition, within)
        finally:
            os.environ.pop("PKMKIT_NATIVE")
    before = (before_rows or within)[: max(1, len(within) // 10)]
    figures["jacobian batch of one + J (before)"] = per_call(lambda p: m.jacobian(p[None]).J,
                                                             before)


def alternate(names: list[str], calls: int, rounds: int = 7) -> None:
    """``ik``, ``fk``, ``jacobian`` and ``jacobian`` + ``J`` of one pose of each machine, the
    machines timed in turn in every round (each sees the same load; the bench's machines are
    otherwise measured one after the other): CPU µs per call, minimum and median of the
    rounds. With ``PKMKIT_NATIVE=0``: the plain-Python one-pose paths."""
    warnings.simplefilter("ignore", StrokeWarning)
    data = {}
    for name in names:
        m = pkmkit.machine(name)
        lo, hi = m.default_box()
        centre, half = (lo + hi) / 2, (hi - lo) / 2
        poses = centre + 0.3 * half * (2 * np.random.default_rng(0).random((calls, m.dims)) - 1)
        rows = [p for p in poses[np.isfinite(m.ik(poses, strokes="ignore")).all(axis=1)]
                if type(m.jacobian(p)).__name__.startswith("OnePose")]  # within the strokes
        data[name] = (m, rows, [m.ik(p) for p in rows])
    times: dict = {name: {} for name in names}
    for _ in range(rounds):
        for name, (m, rows, qs) in data.items():
            for label, fun, given in (("ik", m.ik, rows), ("fk", m.fk, qs),
                                      ("jacobian", m.jacobian, rows),
                                      ("jacobian + J", lambda p, m=m: m.jacobian(p).J, rows)):
                times[name].setdefault(label, []).append(per_call(fun, given, repeats=1)[1])
    print(f"== alternate, {rounds} rounds (load average {os.getloadavg()[0]:.2f}), CPU µs "
          "per call, min / median")
    for name, rows in times.items():
        print(f"  {name:14s} " + ", ".join(
            f"{label} {min(v):.2f} / {statistics.median(v):.2f}" for label, v in rows.items()))


def json_ready(value):
    """``value`` (the report: dicts, lists, tuples of numbers and strings) with NumPy scalars
    and arrays replaced by Python numbers and lists, which ``json`` serialises (the counts of
    the report are ``numpy.int64``: ``json.dumps`` refused them). Anything else: TypeError."""
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"json_ready: {type(value).__name__} is not a report value")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--load", default="both", choices=("none", "busy", "both"))
    parser.add_argument("--json")
    parser.add_argument("--machines", help="comma-separated subset of the machines")
    parser.add_argument("--agreement", type=int, metavar="POSES",
                        help="print the one-pose paths' largest differences from the batch "
                             "path's rows over POSES poses per six-axis machine, then stop")
    parser.add_argument("--alternate", action="store_true",
                        help="only the 3-DOF one-pose calls, the machines timed in turn")
    args = parser.parse_args()
    if args.agreement:
        for name in (args.machines or "gough-stewart,verne,dietmaier-hexapod").split(","):
            print(name, json.dumps(json_ready(agreement(name, args.agreement)), indent=1))
        return
    if args.alternate:
        alternate((args.machines or "orthoglide,linear-delta,five-bar,five-bar-biglide,delta")
                  .split(","), args.calls)
        return
    warnings.simplefilter("ignore", StrokeWarning)  # the batch path's, beyond a stroke
    names = [n for n in ("orthoglide", "linear-delta", "five-bar", "five-bar-biglide", "delta")]
    six = ("gough-stewart", "verne", "dietmaier-hexapod")
    chains = ("tripteor-x7", "trimule-600")
    if args.machines:
        wanted = set(args.machines.split(","))
        names, six, chains = ([n for n in group if n in wanted] for group in (names, six, chains))
    report = {}
    for label, context in conditions(args.load):
        with context():
            load = os.getloadavg()[0]
            report[label] = {n: machine_rows(n, args.calls) for n in names}
            report[label].update({n: six_axis_rows(n, args.calls // 4) for n in six})
            report[label].update({n: chain_rows(n, args.calls // 4) for n in chains})
            after = os.getloadavg()[0]
        print(f"== {label} (load average {load:.2f} before, {after:.2f} after)")
        for n, f in report[label].items():
            print(f"  {n}")
            for k, v in f.items():
                if k == "jacobian one pose (fast path)":
                    print(f"    {k:38s} {v[0]} of {v[1]} poses (the others beyond a stroke)")
                elif k == "agreement":
                    print(f"    C call against the batch rows: max |difference| ik {v[0]:.1e}, "
                          f"fk {v[1]:.1e} (m, rad) over {f['poses']} poses")
                elif k == "iterations":
                    print(f"    ik iterations (C call): mean {v[0]:.2f}, {v[1]} to {v[2]}; the "
                          f"batch rows' count on {v[3]} of {f['poses']} poses")
                elif k == "fk iterations":
                    print(f"    fk iterations (batch rows; the C call starts alike): mean "
                          f"{v[0]:.2f}, {v[1]} to {v[2]}")
                elif k == "fast":
                    print(f"    one-pose path taken by ik on {v} of {f['poses']} poses within "
                          "the strokes")
                elif k != "poses":
                    print(f"    {k:38s} {v[0]:8.2f} µs  (CPU {v[1]:7.2f} µs)")
            if n in chains:
                if "the same, velocity in Numba (before)" in f:
                    call = f["jacobian one pose, call + J + condition"]
                    before = f["the same, velocity in Numba (before)"]
                    ik = f["ik one pose"]
                    print(f"    velocity part (call + J + condition − ik): "
                          f"{call[0] - ik[0]:.2f} µs (CPU {call[1] - ik[1]:.2f} µs), before "
                          f"{before[0] - ik[0]:.2f} µs (CPU {before[1] - ik[1]:.2f} µs); "
                          f"the call {before[1] / call[1]:.2f}× faster (CPU)")
                    if "Pinocchio frame Jacobian (URDF tree, peer)" in f:
                        peer_cpu = f["Pinocchio frame Jacobian (URDF tree, peer)"][1]
                        print(f"    velocity part alone / Pinocchio frame Jacobian (CPU): "
                              f"{f['velocity part alone: record + J + cond.'][1] / peer_cpu:.1f}×")
                    if "the C call without the singular stage" in f:
                        lazy = f["the C call without the singular stage"][1]
                        full = f["velocity part alone: the C call"][1]
                        just_j = f["velocity part alone: record + J"][1]
                        both = f["velocity part alone: record + J + cond."][1]
                        print(f"    the C call without / with the singular stage (CPU): "
                              f"{lazy / full:.2f}; record + J / record + J + condition: "
                              f"{just_j / both:.2f}")
                continue
            ik_before = f["ik batch of one (before)"][0]
            fk_before = f.get("fk batch of one (before)",
                              f.get("fk batch of one, NumPy engine (before)"))[0]
            jac_before = f["jacobian batch of one + J (before)"][1]
            print(f"    speed-up (wall): ik {ik_before / f['ik one pose'][0]:.0f}×, "
                  f"fk {fk_before / f['fk one'][0]:.0f}×; (CPU) jacobian + J "
                  f"{jac_before / f['jacobian one pose, call + J'][1]:.0f}×")
            peer = f.get("Pinocchio FK + frame (URDF tree, peer)")
            if peer is not None:  # CPU per call over the peer's, in the same rounds
                print("    over Pinocchio (CPU): " + ", ".join(
                    f"{label} {f[row][1] / peer[1]:.2f}×" for label, row in (
                        ("ik", "ik one pose"), ("fk", "fk one"),
                        ("jacobian + J", "jacobian one pose, call + J"),
                        ("+ condition", "jacobian one pose, call + condition"),
                        ("+ singularity", "jacobian one pose, call + singularity"))))
    if args.json:
        Path(args.json).write_text(json.dumps(json_ready(report), indent=2))


if __name__ == "__main__":
    main()
