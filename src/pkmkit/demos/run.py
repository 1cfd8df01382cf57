"""``pkmkit demo``: the main job — a kinematic summary and analysis of every built-in machine.

For each built-in preset and each of its reference poses: inverse model, direct model with its
assembly mode (and every real mode), J, velocity transmission factors, conditioning and the
singularity class, plus the machine's mobility. Printed as text, written as JSON
(``summary.json`` and one file per machine), with a drawing of each machine (PNG). Then the
analysis studies of :mod:`pkmkit.demos.analysis` (workspaces, maps, the seed studies), the
design studies of :mod:`pkmkit.demos.design` and the trajectories with actuator forces of
:mod:`pkmkit.demos.motion`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import click
import numpy as np

from pkmkit.boundary.describe import describe_machine
from pkmkit.io.atomic import check_output_dir, write_text_atomic
from pkmkit.io.json_io import to_jsonable
from pkmkit.machines.machine import Machine
from pkmkit.machines.registry import ALIASES, machine, machines
from pkmkit.plot.drawing import draw_machine
from pkmkit.status import Status

from .analysis import run_analysis_demo
from .design import run_design_demo
from .motion import run_motion_demo


def pose_summary(m: Machine, name: str, pose: np.ndarray) -> dict[str, Any]:
    """Kinematic summary of one pose (SI units)."""
    q = m.ik(pose)
    direct = m.fk(q, full_output=True)
    modes = m.fk_all(q)
    jac = m.jacobian(pose)
    return {
        "name": name,
        "pose": pose,
        "q": q,
        "fk": {
            "pose": direct.pose,
            "mode": direct.mode_label,
            "round_trip_error": float(np.abs(direct.pose - pose).max()),
            "status": Status(int(direct.status)).label,
        },
        "assembly_modes": [
            {"mode": modes.labels[k], "pose": modes.poses[k], "branches": modes.branches[k]}
            for k in range(2) if modes.valid[k]
        ],
        "J": jac.J,
        "transmission_factors": jac.singular_values,
        "condition": jac.condition,
        "det_A": jac.det_A,
        "det_B": jac.det_B,
        "singularity": jac.status,
    }


def machine_summary(m: Machine) -> dict[str, Any]:
    """Description plus a summary at each reference pose."""
    info = describe_machine(m, "m")
    info["poses"] = [pose_summary(m, k, v) for k, v in m.reference_poses().items()]
    return info


def run_demo(out_dir: Path, quick: bool = False) -> dict[str, Any]:
    """Run the demo into ``out_dir`` and return the summary written to ``summary.json``.

    ``quick``: the same studies on coarser grids and with a shorter Pareto search (a check
    that everything runs, for the test suite; the full demo is the reference)."""
    check_output_dir(out_dir)
    summaries = {}
    for ident in machines():
        if ident in ALIASES:
            continue
        m = machine(ident)
        if m.dims == 6:  # full-pose machines have their own demo section
            continue
        summary = machine_summary(m)
        summary["drawing"] = f"{ident}.png"
        draw_machine(m, m.home_pose, path=out_dir / f"{ident}.png")
        write_text_atomic(out_dir / f"{ident}.json", json.dumps(to_jsonable(summary), indent=2))
        summaries[ident] = summary
        _print_summary(summary)
    analysis = run_analysis_demo(out_dir, list(summaries), quick)
    design = run_design_demo(out_dir, quick)
    motion = run_motion_demo(out_dir)
    from .calibration import run_calibration_demo
    from .errors import error_summary
    from .machines import run_chain_demo, run_full_pose_demo

    full_pose = run_full_pose_demo(out_dir, quick)
    chains = run_chain_demo(out_dir, quick)
    from .stiffness import run_stiffness_demo

    stiffness = run_stiffness_demo(out_dir / "stiffness", quick)
    click.echo("\n== geometric errors (figures in errors/)")
    errors = error_summary(out_dir / "errors")
    _print_errors(errors)
    click.echo("\n== calibration studies (in calibration/)")
    calibration = run_calibration_demo(out_dir / "calibration", echo=True)
    total = {"pkmkit_demo": "kinematic summary, analysis, design, trajectories and dynamics of "
                            "the built-in machines; full-pose and joint-chain machines; "
                            "geometric errors and calibration",
             "units": "m", "quick": quick, "machines": summaries, "analysis": analysis,
             "design": design, "motion": motion, "full_pose": full_pose,
             "joint_chains": chains, "stiffness": stiffness, "errors": errors,
             "calibration": calibration}
    write_text_atomic(out_dir / "summary.json", json.dumps(to_jsonable(total), indent=2))
    click.echo(f"\nwrote {out_dir}/summary.json, one JSON and one PNG per machine, and the "
               "figures of the studies in analysis/, design/, motion/, full-pose/, "
               "joint-chains/, stiffness/, errors/ and calibration/ (each calibration with its "
               "report.html)")
    return total


def _print_errors(errors: dict[str, Any]) -> None:
    """One line per error study of the demo."""
    compat = errors["tripteor_compatibility"]
    orient, full = compat["orientation_only"], compat["with_positions"]
    click.echo(f"   Tripteor compatibility (orientation defects, as the thesis): "
               f"{len(orient['forced_zero'])} forced to zero ({', '.join(orient['forced_zero'])})"
               f"; compatible subspace {orient['compatible_dimension']} of "
               f"{orient['n_parameters']}; the thesis's leg-2 conditions "
               f"{', '.join(orient['thesis_leg_2_not_required'])} are not required")
    click.echo(f"   with position defects: also {', '.join(full['added_by_positions'])} = 0; "
               f"compatible {full['compatible_dimension']} of {full['n_parameters']}")
    ident = errors["tripteor_identifiability"]
    click.echo(f"   Tripteor identifiability from tool points: rank {ident['rank']} of "
               f"{ident['n_parameters']} (unseen: {', '.join(ident['unidentifiable'][:8])}, …)")
    acc = errors["hexapod_accuracy_map"]
    click.echo(f"   hexapod tolerance analysis: 95th-percentile tool error "
               f"{acc['p95_min_m'] * 1e6:.1f}..{acc['p95_max_m'] * 1e6:.1f} µm over the map "
               f"(first order {acc['first_order_p95_max_m'] * 1e6:.1f} µm)")


def _vec(v: Any, digits: int = 4) -> str:
    return "(" + ", ".join(f"{x:.{digits}f}" for x in np.ravel(v)) + ")"


def _print_summary(s: dict[str, Any]) -> None:
    g = s["mobility"]["grubler"]
    inst = s["mobility"]["instantaneous"]
    click.echo(f"\n== {s['id']}: {s['name']}")
    click.echo(f"   mobility: Grübler {g['mobility']}, rank-based {inst['mobility']} "
               f"(redundant constraints {inst['redundant_constraints']}); "
               f"working mode {s['assembly_modes']['working']!r}")
    for p in s["poses"]:
        modes = ", ".join(f"{a['mode']} {_vec(a['pose'])}" for a in p["assembly_modes"])
        click.echo(f"   {p['name']:<16} x {_vec(p['pose'])} m -> q {_vec(p['q'])} m")
        click.echo(f"   {'':<16} fk {_vec(p['fk']['pose'])} [{p['fk']['mode']}], "
                   f"round trip {p['fk']['round_trip_error']:.1e} m; all modes: {modes}")
        click.echo(f"   {'':<16} transmission factors {_vec(p['transmission_factors'], 3)}, "
                   f"condition {p['condition']:.3f}, {p['singularity']}")
