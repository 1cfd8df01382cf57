"""Benchmark: closed-form IK/FK on 10⁶ poses and engine FK on 10⁴ poses.

Each measurement is compared with a baseline run in the same process on the same inputs:

- closed forms: the same formulas written as a per-pose pure-Python loop (``math`` module),
  run on the first ``--loop-poses`` rows (throughputs are compared, the loop's answers are
  checked against the vectorised ones);
- engine FK: ``scipy.optimize.least_squares`` (MINPACK ``lm``, analytic Jacobian, same rod
  closure) called pose by pose on the first ``--scipy-poses`` rows.

Usage::

    python bench/kinematics.py [--poses 1000000] [--engine-poses 10000] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import time

import numpy as np
from scipy.optimize import least_squares

import pkmkit
from pkmkit.model.rods import SLIDE


def best_time(func, repeat: int) -> float:
    """Smallest wall time of ``repeat`` calls (s)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def loop_ik(machine: pkmkit.Machine, poses: np.ndarray) -> list[list[float]]:
    """Per-pose pure-Python closed-form inverse model (same formula as the library)."""
    model = machine.model
    dims = model.dims
    legs = []
    for i in range(model.n_legs):
        centre = (model.leg_base[i] - model.leg_platform[i])[:dims].tolist()
        axis = model.leg_axis[i][:dims].tolist()
        legs.append((centre, axis, float(model.leg_length[i]) ** 2, int(model.leg_branch[i])))
    out = []
    for pose in poses.tolist():
        q = []
        for centre, axis, length_sq, branch in legs:
            w = [p - c for p, c in zip(pose, centre, strict=True)]
            along = sum(a * b for a, b in zip(w, axis, strict=True))
            perp_sq = sum(a * a for a in w) - along * along
            q.append(along + branch * math.sqrt(length_sq - perp_sq))
        out.append(q)
    return out


def loop_fk(machine: pkmkit.Machine, qs: np.ndarray) -> list[list[float]]:
    """Per-pose pure-Python sphere (circle) intersection, working mode (same formula)."""
    model = machine.model
    dims = model.dims
    centre0 = (model.leg_base - model.leg_platform)[:, :dims].tolist()
    axis = model.leg_axis[:, :dims].tolist()
    lengths = model.leg_length.tolist()
    sign = machine.working_mode
    out = []
    for q in qs.tolist():
        c = [[c0 + qi * a for c0, a in zip(centre0[i], axis[i], strict=True)]
             for i, qi in enumerate(q)]
        r2 = [ell * ell for ell in lengths]
        if dims == 3:
            e1 = [c[1][k] - c[0][k] for k in range(3)]
            e2 = [c[2][k] - c[0][k] for k in range(3)]
            g11 = sum(v * v for v in e1)
            g12 = sum(a * b for a, b in zip(e1, e2, strict=True))
            g22 = sum(v * v for v in e2)
            h2 = 0.5 * (r2[0] - r2[1] + g11)
            h3 = 0.5 * (r2[0] - r2[2] + g22)
            gram = g11 * g22 - g12 * g12
            alpha = (h2 * g22 - h3 * g12) / gram
            beta = (h3 * g11 - h2 * g12) / gram
            w = [alpha * a + beta * b for a, b in zip(e1, e2, strict=True)]
            n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                 e1[0] * e2[1] - e1[1] * e2[0]]
        else:
            e = [c[1][0] - c[0][0], c[1][1] - c[0][1]]
            gram = e[0] * e[0] + e[1] * e[1]
            alpha = 0.5 * (r2[0] - r2[1] + gram) / gram
            w = [alpha * e[0], alpha * e[1]]
            n = [-e[1], e[0]]
        t = math.sqrt((r2[0] - sum(v * v for v in w)) / gram)
        out.append([c[0][k] + w[k] + sign * t * n[k] for k in range(dims)])
    return out


def scipy_fk(machine: pkmkit.Machine, qs: np.ndarray) -> np.ndarray:
    """Per-pose scipy.optimize.least_squares on the same rod closure (every rod)."""
    model = machine.model
    dims = model.dims
    slide = (model.rod_kind == SLIDE)[:, None]
    act = model.rod_actuator

    def rods(p, q):
        carriage = model.rod_base + np.where(slide, q[act][:, None], 0.0) * model.rod_axis
        return np.pad(p, (0, 3 - dims)) + model.rod_platform - carriage

    def residual(p, q):
        return np.linalg.norm(rods(p, q), axis=1) - model.rod_length

    def jacobian(p, q):
        d = rods(p, q)
        return (d / np.linalg.norm(d, axis=1)[:, None])[:, :dims]

    out = np.empty((qs.shape[0], dims))
    for k, q in enumerate(qs):
        guess = machine.home_pose + machine._home_jacobian @ (q - machine.home_q)
        out[k] = least_squares(residual, guess, jac=jacobian, args=(q,), method="lm",
                               xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    return out


def run(n_poses: int, n_engine: int, n_loop: int, n_scipy: int) -> list[dict]:
    results = []
    rng = np.random.default_rng(2026)
    for ident in ("linear-delta", "orthoglide", "five-bar"):
        m = pkmkit.machine(ident)
        half = 0.25 * float(m.model.leg_length.min())
        poses = m.home_pose + rng.uniform(-half, half, (n_poses, m.dims))
        m.ik(poses[:1000])  # warm up
        t_ik = best_time(lambda m=m, poses=poses: m.ik(poses), 5)
        q = m.ik(poses)
        t_fk = best_time(lambda m=m, q=q: m.fk(q), 3)
        sub = poses[:n_loop]
        t_loop_ik = best_time(lambda m=m, sub=sub: loop_ik(m, sub), 1) / len(sub)
        t_loop_fk = best_time(lambda m=m, qs=q[:n_loop]: loop_fk(m, qs), 1) / len(sub)
        err_ik = float(np.abs(np.array(loop_ik(m, sub[:1000])) - q[:1000]).max())
        err_fk = float(np.abs(np.array(loop_fk(m, q[:1000])) - poses[:1000]).max())
        # strokes="ignore": the poses fill a box beyond some strokes; a warning per call would
        # time the warnings machinery, not the inverse model
        t_api = best_time(lambda m=m, sub=sub: [m.ik(x, strokes="ignore") for x in sub[:2000]],
                          1) / 2000

        q_engine = q[:n_engine]
        m.fk(q_engine[:100], method="numeric")
        t_engine = best_time(lambda m=m, qe=q_engine: m.fk(qe, method="numeric"), 5)
        engine = m.fk(q_engine, method="numeric")
        t_scipy = best_time(lambda m=m, qe=q_engine[:n_scipy]: scipy_fk(m, qe), 1) / n_scipy
        err_engine = float(np.abs(engine - poses[:n_engine]).max())
        err_scipy = float(np.abs(scipy_fk(m, q_engine[:50]) - poses[:50]).max())
        results.append({
            "machine": ident,
            "ik_closed_poses_per_s": n_poses / t_ik,
            "ik_loop_poses_per_s": 1 / t_loop_ik,
            "ik_ratio_vs_loop": (n_poses / t_ik) * t_loop_ik,
            "ik_api_per_pose_poses_per_s": 1 / t_api,
            "ik_ratio_vs_api_per_pose": (n_poses / t_ik) * t_api,
            "fk_closed_poses_per_s": n_poses / t_fk,
            "fk_loop_poses_per_s": 1 / t_loop_fk,
            "fk_ratio_vs_loop": (n_poses / t_fk) * t_loop_fk,
            "engine_fk_poses_per_s": n_engine / t_engine,
            "scipy_fk_poses_per_s": 1 / t_scipy,
            "engine_ratio_vs_scipy": (n_engine / t_engine) * t_scipy,
            "max_error_loop_ik_m": err_ik,
            "max_error_loop_fk_m": err_fk,
            "max_error_engine_m": err_engine,
            "max_error_scipy_m": err_scipy,
        })
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--engine-poses", type=int, default=10_000)
    parser.add_argument("--loop-poses", type=int, default=50_000)
    parser.add_argument("--scipy-poses", type=int, default=500)
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()
    results = run(args.poses, args.engine_poses, args.loop_poses, args.scipy_poses)
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}")
    print(f"{args.poses} poses (closed forms), {args.engine_poses} poses (engine)")
    header = (f"{'machine':<13}{'IK Mposes/s':>12}{'xloop':>7}{'xAPI':>8}{'FK Mposes/s':>12}"
              f"{'xloop':>7}{'engine kposes/s':>16}{'scipy poses/s':>14}{'xscipy':>8}")
    print(header)
    for r in results:
        print(f"{r['machine']:<13}{r['ik_closed_poses_per_s'] / 1e6:>12.1f}"
              f"{r['ik_ratio_vs_loop']:>7.0f}{r['ik_ratio_vs_api_per_pose']:>8.0f}"
              f"{r['fk_closed_poses_per_s'] / 1e6:>12.2f}{r['fk_ratio_vs_loop']:>7.0f}"
              f"{r['engine_fk_poses_per_s'] / 1e3:>16.0f}{r['scipy_fk_poses_per_s']:>14.0f}"
              f"{r['engine_ratio_vs_scipy']:>8.0f}")
    worst = max(max(r[k] for k in r if k.startswith("max_error")) for r in results)
    print(f"largest disagreement between any two methods and the reference poses: {worst:.1e} m")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(results, handle, indent=2)


if __name__ == "__main__":
    main()
