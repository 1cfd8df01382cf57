"""Motion part of ``pkmkit demo``: seed 000's trajectories on the Table IV.1 linear Delta with
actuator forces, the two facing strategies, and arm sizing (figures in ``OUT/motion/``).

Every study here is also a worked example of docs/motion.md (``docs/make_figures.py`` calls the
same functions), so the numbers in the docs are the numbers the demo prints.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import click
import numpy as np

from pkmkit.dynamics.arms import Material, seed_tables, size_arm
from pkmkit.dynamics.defaults import default_masses
from pkmkit.dynamics.inverse import ForceResult, inverse_dynamics
from pkmkit.dynamics.masses import mass_properties
from pkmkit.dynamics.trajectory import PathResult, simulate_path
from pkmkit.machines.registry import machine
from pkmkit.motion.joints import joint_trajectory
from pkmkit.motion.paths import circle, helix, line, raster
from pkmkit.motion.timelaw import constant_speed
from pkmkit.plot.motion_figures import plot_joint_motion, plot_tool_path

#: The seed's Chapter IV machine and move parameters: 120 mm/s along the path; acceleration and
#: jerk limits are not given by the seed (1 m/s², 10 m/s³ chosen, gentle for a machine tool).
SEED_MACHINE = "linear-delta-table-iv1"
FEED, ACCEL, JERK, PERIOD = 0.12, 1.0, 10.0, 0.005


def _cruise(result: PathResult, feed: float) -> np.ndarray:
    """Samples of the constant-feed phase (no start/stop ramp): ``(N,)`` bool."""
    speed = np.linalg.norm(result.motion.xd, axis=1)
    return np.abs(speed - feed) <= 1e-6 * feed


def _force_range(result: PathResult, mask: np.ndarray) -> list[float]:
    f = result.forces.force[mask]
    return [float(f.min()), float(f.max())]


def _summary(result: PathResult, feed: float) -> dict[str, Any]:
    s = result.summary()
    s["total_mass"] = result.masses.total_mass
    s["cruise_force_range"] = _force_range(result, _cruise(result, feed))
    return s


def seed_circle(out: Path | None) -> dict[str, Any]:
    """Ø300 mm circle 200 mm above the base plane at 120 mm/s, with the default masses; the
    inertial share of the forces (same move without gravity) shows what the seed's 3260 N
    'maximum force, identical for circle and spiral' can and cannot be."""
    m = machine(SEED_MACHINE)
    masses = default_masses(m)
    path = circle([0.0, 0.0, 0.2], 0.15)
    result = simulate_path(m, path, feed=FEED, accel=ACCEL, jerk=JERK, period=PERIOD,
                           masses=masses)
    weightless = dataclasses.replace(masses, gravity=np.zeros(3))
    inertial = simulate_path(m, path, feed=FEED, accel=ACCEL, jerk=JERK, period=PERIOD,
                             masses=weightless)
    s = _summary(result, FEED)
    s["inertial_force_max"] = np.abs(inertial.forces.force).max(axis=0)
    s["inertial_cruise_force_max"] = float(
        np.abs(inertial.forces.force[_cruise(inertial, FEED)]).max())
    if out is not None:
        plot_joint_motion(result.motion, m.actuator_names, forces=result.forces.force,
                          title=f"{m.name}: Ø300 mm circle at 120 mm/s, default masses",
                          length_unit="mm", path=out / "seed000-circle-motion.png")
        plot_tool_path(result.motion, title="Ø300 mm circle, z = 200 mm", length_unit="mm",
                       path=out / "seed000-circle-path.png")
        s["figures"] = ["seed000-circle-motion.png", "seed000-circle-path.png"]
    s["seed"] = {"stroke_mm": 190, "speed_range_mm_s": [69, 82], "force_max_N": 3260}
    return s


def seed_helix(out: Path | None) -> dict[str, Any]:
    """Ø300 mm helix of pitch 20 mm at 120 mm/s (10 turns: the seed gives no count)."""
    m = machine(SEED_MACHINE)
    result = simulate_path(m, helix([0.0, 0.0, 0.0], 0.15, pitch=0.02, turns=10), feed=FEED,
                           accel=ACCEL, jerk=JERK, period=PERIOD)
    s = _summary(result, FEED)
    if out is not None:
        plot_joint_motion(result.motion, m.actuator_names, forces=result.forces.force,
                          title=f"{m.name}: Ø300 mm helix, pitch 20 mm, 10 turns",
                          length_unit="mm", path=out / "seed000-helix-motion.png")
        s["figures"] = ["seed000-helix-motion.png"]
    s["seed"] = {"stroke_mm": 390, "speed_range_mm_s": [55, 73]}
    return s


def _constant_speed_forces(machine, path, speed: float, masses) -> ForceResult:
    motion = joint_trajectory(machine, constant_speed(path, speed=speed, period=0.01))
    return inverse_dynamics(machine, masses, motion.x, motion.xd, motion.xdd, motion.q,
                            motion.qd, motion.qdd)


def seed_line(out: Path | None) -> dict[str, Any]:
    """Chapter IV's straight move X = Y = 10t, Z = 1000 + 10t mm, t = 0…10 s, at the seed's
    constant 17.32 mm/s (no ramps, as its MATLAB model), with three mass sets: the default one,
    carriages alone (7.2 kg each, everything else massless), and 7.2 kg carriages with a 1 kg
    nacelle — what the seed's narrow 70.5–72 N band allows. Then the same move as a machine
    would run it (jerk-limited start and stop) with the default masses."""
    m = machine(SEED_MACHINE)
    start, end = np.array([0.0, 0.0, 1.0]), np.array([0.1, 0.1, 1.1])
    speed = float(np.linalg.norm(end - start)) / 10.0
    path = line(start, end)
    # the seed's move runs with the carriages up to 2.03 m: above the default 1.7 m stroke
    ramped = simulate_path(m, path, feed=speed, accel=ACCEL, jerk=JERK, period=PERIOD)
    tall = m.with_params(q_max=np.full(3, 2.1))
    s = _summary(ramped, speed)
    s["stroke_violations_default_machine"] = s["violations"]
    for key, masses in (("constant_speed_default_masses", default_masses(tall)),
                        ("carriages_only_7.2kg", mass_properties(tall, carriage=7.2)),
                        ("carriages_7.2kg_nacelle_1kg",
                         mass_properties(tall, carriage=7.2, platform=1.0))):
        force = _constant_speed_forces(tall, path, speed, masses).force
        s[key] = {"force_range": [float(force.min()), float(force.max())]}
    if out is not None:
        plot_joint_motion(ramped.motion, m.actuator_names, forces=ramped.forces.force,
                          title=f"{m.name}: X = Y = 10t, Z = 1000 + 10t mm, default masses",
                          length_unit="mm", path=out / "seed000-line-motion.png")
        s["figures"] = ["seed000-line-motion.png"]
    s["seed"] = {"force_range_N": [70.5, 72.0]}
    return s


def facing(out: Path | None) -> dict[str, Any]:
    """Seed 000's two facing strategies (5 passes over a 300 × 200 mm face at z = 200 mm, feed
    50 mm/s, rapids 250 mm/s, 20 mm retract): one-way with retract and rapid return, and
    zig-zag. The seed only says the second is faster."""
    m = machine(SEED_MACHINE)
    rows = {}
    for strategy in ("one-way", "zigzag"):
        path = raster([-0.15, -0.1, 0.2], 0.3, 0.2, 5, strategy=strategy, clearance=0.02)
        result = simulate_path(m, path, feed=0.05, rapid_feed=0.25, accel=ACCEL, jerk=JERK,
                               period=PERIOD)
        rows[strategy] = {"duration": result.motion.trajectory.duration,
                          "length": path.length, "cutting_length": path.cutting_length,
                          "force_max": np.abs(result.forces.force).max(axis=0)}
        if out is not None:
            plot_tool_path(result.motion, title=f"facing, 5 passes, {strategy}",
                           length_unit="mm", path=out / f"seed000-facing-{strategy}.png")
    rows["zigzag_saving"] = 1.0 - rows["zigzag"]["duration"] / rows["one-way"]["duration"]
    return rows


def arms(leg_axial_max: float) -> dict[str, Any]:
    """Seed Tables IV.2/IV.3 recomputed, and a steel arm sized for the dynamics' rod load."""
    rows = seed_tables()
    rod_load = leg_axial_max / 2  # each parallelogram leg has two rods
    design = size_arm(axial_force=rod_load, length=1.04, material=Material())
    a = design.analysis
    return {"seed_tables": rows,
            "mass_error_g_max": max(abs(r["mass_g"] - r["seed_mass_g"]) for r in rows),
            "stress_ratio_range": [min(r["stress_ratio"] for r in rows),
                                   max(r["stress_ratio"] for r in rows)],
            "sized_for_rod_load_N": rod_load,
            "sized_arm": {"diameter": a.outer_diameter, "mass": a.mass,
                          "buckling_safety": a.buckling_safety,
                          "stress_safety": a.stress_safety, "feasible": design.feasible}}


def run_motion_demo(out_dir: Path) -> dict[str, Any]:
    """All of the above; prints a few lines."""
    out = out_dir / "motion"
    out.mkdir(parents=True, exist_ok=True)
    click.echo("\n== motion and dynamics, seed 000 Table IV.1 linear Delta (figures in motion/)")
    c = seed_circle(out)
    click.echo(f"   Ø300 mm circle at 120 mm/s: {c['duration']:.3f} s, stroke "
               f"{c['stroke'].max() * 1e3:.2f} mm (seed ≈ 190), motor speeds within "
               f"±{c['qd_max'].max() * 1e3:.2f} mm/s (seed 69–82); forces "
               f"{c['force_range'][0].min():.1f}..{c['force_range'][1].max():.1f} N with "
               f"{c['total_mass']:.1f} kg moving; inertia alone ≤ "
               f"{c['inertial_cruise_force_max']:.2f} N at constant feed, "
               f"{c['inertial_force_max'].max():.1f} N in the start/stop ramps")
    h = seed_helix(out)
    click.echo(f"   Ø300 mm helix, pitch 20 mm, 10 turns: stroke {h['stroke'].max() * 1e3:.1f} mm"
               f" (seed ≈ 390), speeds {h['qd_range'][0].min() * 1e3:.1f}.."
               f"{h['qd_range'][1].max() * 1e3:.1f} mm/s")
    s = seed_line(out)
    light = s["carriages_only_7.2kg"]["force_range"]
    lo, hi = s["constant_speed_default_masses"]["force_range"]
    click.echo(f"   X = Y = 10t, Z = 1000 + 10t mm: carriages up to {s['q_max'].max() * 1e3:.1f}"
               f" mm ({len(s['stroke_violations_default_machine'])} stroke limit(s) of the "
               f"default machine exceeded); forces at constant speed {lo:.1f}..{hi:.1f} N "
               f"(default masses), {light[0]:.2f}.."
               f"{light[1]:.2f} N with 7.2 kg carriages alone (seed 70.5–72)")
    f = facing(out)
    click.echo(f"   facing 5 passes: one-way {f['one-way']['duration']:.1f} s, zig-zag "
               f"{f['zigzag']['duration']:.1f} s ({f['zigzag_saving']:.0%} faster)")
    a = arms(float(c["leg_axial_max"].max()))
    arm = a["sized_arm"]
    click.echo(f"   arms: seed Tables IV.2/IV.3 masses within {a['mass_error_g_max']:.3f} g at "
               f"1000 kg/m³, printed stresses / (F/A) = {a['stress_ratio_range'][0]:.2f}.."
               f"{a['stress_ratio_range'][1]:.2f}; steel rod for {a['sized_for_rod_load_N']:.0f}"
               f" N: Ø{arm['diameter'] * 1e3:.1f} mm, {arm['mass'] * 1e3:.0f} g")
    return {"circle": c, "helix": h, "line": s, "facing": f, "arms": a, "units": "SI"}
