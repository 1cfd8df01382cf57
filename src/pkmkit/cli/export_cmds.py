"""``pkmkit export``: a machine (built-in, machine file, calibrated machine file) in another
tool's terms — a LinuxCNC kinematics module, a Klipper delta configuration, a MuJoCo model."""

from __future__ import annotations

import click
import numpy as np

from pkmkit.io.measurements import atomic_write_text
from pkmkit.model.parameters import length_scale

from .options import SET_OPTION, is_machine_file, parse_vector, resolve_machine

FORMATS = ("linuxcnc", "klipper", "mjcf")


def register(cli: click.Group) -> None:
    """Add the export command to the ``pkmkit`` group."""
    cli.add_command(export_cmd)


@click.command("export")
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--to", "fmt", type=click.Choice(FORMATS), required=True,
              help="linuxcnc: a kinematics module (C source for halcompile); klipper: a delta "
                   "printer's [printer]/[stepper_*] values; mjcf: a MuJoCo model.")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="File to write (written whole or not at all).")
@click.option("--units", type=click.Choice(["mm", "in", "m"]), default="mm", show_default=True,
              help="Length unit of --set values, --endstops and of the LinuxCNC module "
                   "(its LINEAR_UNITS). Klipper files are in mm, MuJoCo models in m.")
@click.option("--name", "module", default=None,
              help="LinuxCNC module name (default: the machine id + 'kins').")
@click.option("--endstops", "endstops_text", metavar="Q1,Q2,Q3", default=None,
              help="Klipper: actuator coordinates at which the endstops trigger, in --units "
                   "(default: the tops of the strokes).")
def export_cmd(machine_name, assignments, fmt, out_file, units, module, endstops_text):
    """Write MACHINE for a controller, a firmware or a simulator (--to FORMAT --out PATH).

    MACHINE is a built-in id or a machine file, nominal or calibrated (`pkmkit calibrate --out`
    writes one: its defects go into the export). A machine the format cannot express is refused
    (exit status 1, nothing written) with what and why; docs/export.md lists which machine goes
    to which format.
    """
    m = resolve_machine(machine_name, assignments, units)
    source = machine_name if is_machine_file(machine_name) else ""
    if fmt == "linuxcnc":
        from pkmkit.export.linuxcnc import linuxcnc_source, module_name

        name = module or module_name(m.id)
        text = linuxcnc_source(m, units=units, name=name, source=source)
        what = (f"LinuxCNC kinematics module {name} ({m.n_actuators} joints, {units}); "
                f"build: halcompile --install {out_file}")
    elif fmt == "klipper":
        from pkmkit.export.klipper import klipper_config

        endstops = (parse_vector(endstops_text, 3, "--endstops", units)
                    if endstops_text else None)
        text = klipper_config(m, endstops=endstops, source=source)
        what = "Klipper delta configuration ([printer], [stepper_a/b/c]; mm)"
    else:
        from pkmkit.export.mjcf import mjcf_model

        text = mjcf_model(m)
        what = "MuJoCo model (MJCF; m, kg)"
    atomic_write_text(out_file, text)
    scale = length_scale(units)
    click.echo(f"{m.name}: {what}")
    click.echo(f"  home pose {np.round(np.asarray(m.home_pose)[:3] / scale, 6).tolist()} "
               f"{units} -> {out_file}")
