"""``pkmkit export``: a machine (built-in, machine file, calibrated machine file) in another
tool's terms — a LinuxCNC kinematics module, a Klipper delta configuration, a MuJoCo model, a
URDF tree and its loop closures."""

from __future__ import annotations

import re
from pathlib import Path

import click

from pkmkit.io.atomic import write_text_atomic as atomic_write_text

from .options import SET_OPTION, is_machine_file, parse_vector, resolve_machine

FORMATS = ("linuxcnc", "klipper", "mjcf", "urdf")


def register(cli: click.Group) -> None:
    """Add the export command to the ``pkmkit`` group."""
    cli.add_command(export_cmd)


@click.command("export")
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--to", "fmt", type=click.Choice(FORMATS), required=True,
              help="linuxcnc: a kinematics module (C source for halcompile); klipper: a delta "
                   "printer's [printer]/[stepper_*] values; mjcf: a MuJoCo model; urdf: "
                   "a URDF tree and its loop closures (NAME.closures.yaml beside it).")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="File to write (written whole or not at all).")
@click.option("--units", type=click.Choice(["mm", "in", "m"]), default="mm", show_default=True,
              help="Length unit of --set values, --endstops and of the LinuxCNC module "
                   "(its LINEAR_UNITS). Klipper files are in mm, MuJoCo models in m.")
@click.option("--endstops", "endstops_text", metavar="Q1,Q2,Q3", default=None,
              help="Klipper: actuator coordinates at which the endstops trigger, in --units "
                   "(default: the tops of the strokes).")
@click.option("--masses", "masses_file", type=click.Path(dir_okay=False), default=None,
              help="mjcf, urdf: a masses file (docs/motion.md; a joint-chain machine's "
                   "bodies: docs/export.md) instead of the illustrative masses.")
def export_cmd(machine_name, assignments, fmt, out_file, units, endstops_text, masses_file):
    """Write MACHINE for a controller, a firmware or a simulator (--to FORMAT --out PATH).

    linuxcnc: --out NAME.c, the module NAME (LinuxCNC loads it by that name).
    urdf: --out NAME.urdf, and the loop closures in NAME.closures.yaml beside it.

    MACHINE is a built-in id or a machine file, nominal or calibrated (`pkmkit calibrate --out`
    writes one: its defects go into the export). The written file is read back and checked
    against pkmkit's model before it is written. A machine the format cannot express is refused
    (exit status 1, nothing written) with what and why; docs/export.md lists which machine goes
    to which format.
    """
    m = resolve_machine(machine_name, assignments, units)
    if masses_file is not None and fmt not in ("mjcf", "urdf"):
        raise click.UsageError("--masses goes with --to mjcf or --to urdf")
    if endstops_text is not None and fmt != "klipper":
        raise click.UsageError("--endstops goes with --to klipper")
    source = machine_name if is_machine_file(machine_name) else ""
    if fmt == "linuxcnc":
        from pkmkit.export.linuxcnc import linuxcnc_source
        from pkmkit.export.linuxcnc_check import check_linuxcnc_source, check_sentence

        name = Path(out_file).stem
        if Path(out_file).suffix != ".c" or not re.fullmatch(r"[A-Za-z_]\w*", name):
            raise click.BadParameter("LinuxCNC loads a kinematics module by its file name: give "
                                     "NAME.c with NAME a C identifier (e.g. hexapodkins.c)",
                                     param_hint="--out")
        text = linuxcnc_source(m, units=units, name=name, source=source)
        check_linuxcnc_source(m, text, units)
        what = (f"LinuxCNC kinematics module {name} ({m.n_actuators} joints, {units}); "
                f"build: halcompile --install {out_file}")
        check = check_sentence(m)
    elif fmt == "klipper":
        from pkmkit.export.klipper import check_klipper_config, klipper_config

        endstops = (parse_vector(endstops_text, 3, "--endstops", units)
                    if endstops_text else None)
        text = klipper_config(m, endstops=endstops, source=source, units=units)
        check_klipper_config(m, text, endstops)
        what = "Klipper delta configuration ([printer], [stepper_a/b/c]; mm)"
        check = "Klipper's delta formulas move the carriages as pkmkit (≤ 1e-9 m)"
    elif fmt == "urdf":
        from pkmkit.export.chain_masses import read_masses
        from pkmkit.export.urdf_writer import check_urdf, write_urdf

        if Path(out_file).suffix != ".urdf":
            raise click.BadParameter("give NAME.urdf (the closures go to NAME.closures.yaml)",
                                     param_hint="--out")
        closures = str(Path(out_file).with_suffix(".closures.yaml"))
        export = write_urdf(m, masses_file and read_masses(masses_file, m),
                            name=Path(out_file).stem)
        _, reader = check_urdf(m, export)
        text = export.urdf
        atomic_write_text(closures, export.closures)
        masses_note = (f"; {export.masses_note}" if getattr(export, "masses_note", "")
                       else "" if export.inertial
                       else f"; no masses: pkmkit has none of {export.massless}")
        what = (f"URDF tree ({len(export.joints)} joints, {m.n_actuators} actuated; m, kg"
                f"{masses_note}) and {len(export.closure_frames)} loop closures "
                f"({export.closure_kind}) → {closures}")
        check = (f"read back with {'Pinocchio' if reader == 'pinocchio' else 'a URDF parser'},"
                 " its loops close at pkmkit's configurations (≤ 1e-9 m)")
    else:
        from pkmkit.export.chain_masses import read_masses
        from pkmkit.export.mjcf_writer import check_mjcf, write_mjcf

        export = write_mjcf(m, None if masses_file is None else read_masses(masses_file, m))
        worst = check_mjcf(m, export)
        text = export.xml
        what = "MuJoCo model (MJCF; m, kg" + (
            f"; {export.illustrative})" if export.illustrative else ")")
        check = ("not loaded (MuJoCo is not installed)" if worst is None else
                 "loaded in MuJoCo, its loops close at pkmkit's configurations (≤ 1e-9 m)")
    atomic_write_text(out_file, text)
    click.echo(f"{m.name}: {what}")
    click.echo(f"  check: {check}")
    click.echo(f"  → {out_file}")
