"""Commands imported when they are used.

The analysis, design and motion commands pull in SciPy's optimisers, matplotlib and pymoo (about
a second of imports); ``pkmkit --help`` and the kinematics commands need none of it, and
``pkmkit --help`` needs neither NumPy nor the machine library that the kinematics commands
import (≈ 0.1 s each). The group below lists every command but ``demo`` by name with its
one-line help and imports a command's module only when that command runs (or its own
``--help`` is asked for).

``tests/cli/test_startup.py`` checks that this table matches what each module's ``register``
adds, help text included, so the table cannot drift from the commands.
"""

from __future__ import annotations

import importlib
from typing import NamedTuple

import click


class LazyCommand(NamedTuple):
    """Where a command lives and the start of its help (``pkmkit --help`` shortens it as click
    does)."""

    module: str
    attribute: str
    short_help: str


#: Commands defined outside ``cli/main.py``, imported on first use.
LAZY_COMMANDS: dict[str, LazyCommand] = {
    "machines": LazyCommand(
        "pkmkit.cli.kinematics_cmds", "machines_cmd", "List the built-in machines."),
    "show": LazyCommand(
        "pkmkit.cli.kinematics_cmds", "show",
        "Describe a machine: parameters, legs, home configuration, assembly modes, mobility."),
    "ik": LazyCommand(
        "pkmkit.cli.kinematics_cmds", "ik",
        "Inverse kinematics: actuator coordinates of a pose (or of every row of --input)."),
    "fk": LazyCommand(
        "pkmkit.cli.kinematics_cmds", "fk",
        "Direct kinematics: platform pose of actuator coordinates (or of every row of "
        "--input)."),
    "jacobian": LazyCommand(
        "pkmkit.cli.kinematics_cmds", "jacobian",
        "Velocity model at a pose: A, B, J, transmission factors, conditioning, singularity."),
    "analyze": LazyCommand(
        "pkmkit.cli.analysis_cmds", "analyze",
        "All kinetostatic indices at a pose: transmission factors, conditioning, ellipsoid, "
        "distances to singularities."),
    "map": LazyCommand(
        "pkmkit.cli.analysis_cmds", "map_cmd",
        "Iso-contours of an index (or actuator coordinates) over a plane."),
    "workspace": LazyCommand(
        "pkmkit.cli.analysis_cmds", "workspace",
        "Workspace over a box or a plane: area/volume, largest inscribed square/cube, "
        "transmission factors inside it, global conditioning index, and (with --cube/--center) "
        "whether a prescribed one is feasible (in the --slice plane when one is given)."),
    "useful-workspace": LazyCommand(
        "pkmkit.cli.analysis_cmds", "useful_workspace_cmd",
        "Seed 004's procedure: a square of actuator values satisfying the criteria (the useful "
        "zone), its image (the useful workspace) and the square inscribed in it; with 3 "
        "actuators, cubes."),
    "design": LazyCommand(
        "pkmkit.cli.design_cmds", "design",
        "Sizing rules: the Orthoglide for a cube, the isotropic five-bar for a square, the "
        "linear Delta for a cube."),
    "optimize": LazyCommand(
        "pkmkit.cli.design_cmds", "optimize_cmd",
        "Optimise parameters of any machine for a prescribed region (one or several "
        "objectives)."),
    "view": LazyCommand(
        "pkmkit.cli.view_cmds", "view_cmd",
        "Write a 3-D view of MACHINE: one HTML page a browser opens without a network, a "
        "slider per actuator moving the machine through pkmkit's direct model, and on request "
        "its workspace, a tool path and a calibration's error vectors."),
    "path": LazyCommand(
        "pkmkit.cli.motion_cmds", "path_cmd",
        "Move along a tool path: duration, actuator strokes, speeds, accelerations, forces and "
        "powers, with a check of the actuator limits (exit status 3 when a limit is exceeded)."),
    "arm-sizing": LazyCommand(
        "pkmkit.cli.motion_cmds", "arm_sizing",
        "Size (or analyse) a solid or hollow circular arm: stress, buckling, bending, mass, "
        "stiffness."),
    "stiffness": LazyCommand(
        "pkmkit.cli.stiffness_cmds", "stiffness_cmd",
        "Stiffness of MACHINE at a pose: K and C at the tool point, eigen-stiffnesses, "
        "deflection."),
    "errors": LazyCommand(
        "pkmkit.cli.errors_cmds", "errors_cmd",
        "Geometric error analyses of MACHINE: its defect set (default), hyperstatic "
        "compatibility, sensitivity, tolerance analysis."),
    "identifiability": LazyCommand(
        "pkmkit.cli.errors_cmds", "identifiability_cmd",
        "Which defects KIND measurements at the poses can identify: rank, base parameters, "
        "combinations, gauges, observability indices."),
    "simulate-measurements": LazyCommand(
        "pkmkit.cli.calibration_cmds", "simulate_cmd",
        "Synthetic measurements of a machine with defects (for tests, studies and demos)."),
    "register": LazyCommand(
        "pkmkit.cli.calibration_cmds", "register_cmd",
        "Rigid registration of a measurement frame to the machine frame (≥ 3 points, optional "
        "direction vectors), with residuals."),
    "calibrate": LazyCommand(
        "pkmkit.cli.calibration_cmds", "calibrate_cmd",
        "Identify a machine's geometric defects from measurements, validate, report."),
    "compensate": LazyCommand(
        "pkmkit.cli.compensate_cmd", "compensate_cmd",
        "Corrected commands for the nominal controller from a calibrated machine."),
    "machined-part": LazyCommand(
        "pkmkit.cli.machining_cmds", "machined_part",
        "Seed 003's machined part: G-code → machining → CMM → tool centres (then calibrate)."),
    "export": LazyCommand(
        "pkmkit.cli.export_cmds", "export_cmd",
        "Write MACHINE for a controller, a firmware or a simulator (--to FORMAT --out PATH)."),
    "select-poses": LazyCommand(
        "pkmkit.cli.errors_cmds", "select_poses_cmd",
        "Choose N poses maximising an observability index; writes their actuator "
        "coordinates and reports the gain over random poses."),
}


class LazyGroup(click.Group):
    """A click group whose :data:`LAZY_COMMANDS` are imported on first use."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted({*super().list_commands(ctx), *LAZY_COMMANDS})

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        command = super().get_command(ctx, cmd_name)
        if command is not None or cmd_name not in LAZY_COMMANDS:
            return command
        entry = LAZY_COMMANDS[cmd_name]
        command = getattr(importlib.import_module(entry.module), entry.attribute)
        self.add_command(command, cmd_name)
        return command

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The command list without importing the lazy commands."""
        names = self.list_commands(ctx)
        if not names:
            return
        limit = formatter.width - 6 - max(len(name) for name in names)
        rows = []
        for name in names:
            loaded = self.commands.get(name)
            if loaded is not None:
                if not loaded.hidden:
                    rows.append((name, loaded.get_short_help_str(limit)))
            else:
                stand_in = click.Command(name, help=LAZY_COMMANDS[name].short_help)
                rows.append((name, stand_in.get_short_help_str(limit)))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)
