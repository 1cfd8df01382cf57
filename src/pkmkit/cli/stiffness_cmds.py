"""``pkmkit stiffness``: Cartesian stiffness, compliance and deflection of any machine.

Values on the command line follow :mod:`pkmkit.boundary.coordinates` (lengths in ``--units``,
angles in degrees); the elastic data are always SI (N/m, N·m/rad, Pa), section dimensions in
``--units``. Text output shows stiffnesses in N/µm (translation) and N·m/µrad (rotation);
``--json`` gives every matrix in SI.
"""

from __future__ import annotations

import sys
from typing import Any, NamedTuple

import click
import numpy as np

from pkmkit.boundary.coordinates import (
    actuator_scales,
    parse_actuators,
    parse_numbers,
    pose_columns,
    pose_from_cli,
    pose_units,
    pose_widths,
)
from pkmkit.boundary.kinematics import inverse_options
from pkmkit.exceptions import InputError
from pkmkit.model.parameters import length_scale
from pkmkit.spatial.rotation import resolve_convention
from pkmkit.stiffness.results import linear_range_problem

from .batch import batch_options, run_batch, status_names
from .limits import check_wrench
from .options import (
    ANGLES_OPTION,
    JSON_OPTION,
    SET_OPTION,
    TOOL_LENGTH_OPTION,
    UNITS_OPTION,
    emit_json,
    fmt,
    resolve_machine,
)
from .stroke_flags import BatchFlags, add_to_payload, finish_single, single_check

#: N/m in one N/µm; N·m/rad in one N·m/µrad.
PER_MICRO = 1e6


def register(cli: click.Group) -> None:
    """Add the stiffness command to the ``pkmkit`` group."""
    cli.add_command(stiffness_cmd)


def split_settings(assignments) -> tuple[list[str], dict[str, str]]:
    """``--set`` assignments: machine parameters, and the elastic settings by name."""
    from pkmkit.stiffness.data import SET_KEYS

    machine_sets, elastic = [], {}
    for text in assignments:
        key, sep, value = text.partition("=")
        if sep and key.strip() in SET_KEYS:
            elastic[key.strip()] = value
        else:
            machine_sets.append(text)
    return machine_sets, elastic


def machine_and_data(machine_name: str, assignments, units: str):
    """The machine named on the command line and its elastic data, ``--set`` split between the
    two (elastic keys: :data:`pkmkit.stiffness.data.SET_KEYS`): ``(machine, StiffnessData)``."""
    from pkmkit.stiffness import with_settings
    from pkmkit.stiffness.file_data import machine_data

    machine_sets, elastic = split_settings(assignments)
    m = resolve_machine(machine_name, machine_sets, units)
    data = with_settings(machine_data(machine_name, m), elastic, m.n_actuators,
                         length_scale(units))
    return m, data


def parse_wrench(text: str | None, machine) -> tuple[np.ndarray | None, str]:
    """``--wrench FX,FY,FZ[,MX,MY,MZ]`` (N, N·m) for ``machine``'s twist width, and a note
    when moments are dropped (a translating platform)."""
    from pkmkit.stiffness import twist_names

    return _wrench(text, len(twist_names(machine)))


def _wrench(text: str | None, d: int) -> tuple[np.ndarray | None, str]:
    if text is None:
        return None, ""
    values = check_wrench(parse_numbers(text, "--wrench", (d, 6) if d < 6 else (6,)))
    note = ""
    if values.size == 6 and d < 6:
        if np.any(values[3:]):
            note = ("moments carried by the parallelograms, rigid in rotation in this model: "
                    "they cause no deflection here")
        values = values[:d]
    return values, note


@click.command("stiffness")
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--pose", help="Pose (see `pkmkit ik --help`); joint-chain machines: tool point "
                             "and axis, or give --q.")
@click.option("--q", "q_text", help="Actuator coordinates (joint-chain machines, instead of "
                                    "--pose).")
@click.option("--wrench", "wrench_text", metavar="FX,FY,FZ,MX,MY,MZ",
              help="Load at the reference point: forces in N, moments in N·m (a translating "
                   "platform: its force components, e.g. FX,FY,FZ). Prints the deflection.")
@click.option("--reference", "reference_text", metavar="DX,DY,DZ",
              help="Move the reference point by this offset (in --units) in the platform frame "
                   "(full-pose machines) or the tool frame (joint-chain machines).")
@click.option("--gravity", is_flag=True,
              help="Also the deflection of the reference point under the weight of the moving "
                   "parts (illustrative masses, docs/stiffness.md): joint chains, rod machines "
                   "on slides or struts.")
@batch_options
@ANGLES_OPTION
@TOOL_LENGTH_OPTION
@UNITS_OPTION
@JSON_OPTION
def stiffness_cmd(machine_name, assignments, pose, q_text, wrench_text, reference_text, gravity,
                  input_, output, chunk_rows, convention, tool_length, units, as_json):
    """Stiffness of MACHINE at a pose: K and C at the tool point, eigen-stiffnesses, deflection.

    Virtual-joint model (docs/stiffness.md): actuator drives as springs (--set
    actuator_stiffness=K or K1,...,Kn in N/m or N·m/rad), rods with an axial spring (--set
    rod_section=circle:D | tube:D,d | rect:B,H in --units, rod_material=E,G in Pa), joint-chain
    links as beams (link_section=..., link_material=...); passive joints ideal. The machine's
    assumed values are listed in the output.

    Batch input columns: the pose (as for `pkmkit ik`). Output columns: the pose, kt1..kt3
    (translational eigen-stiffnesses, N/µm, ascending), kr1..kr3 (rotational, N·m/µrad; 6-D
    twists), rigid (rigid directions), the deflection under --wrench (dx.. in µm, rx.. in
    µrad; rod machines on slides or struts also the loaded equilibrium dx_loaded.. and the
    geometric-stiffness share geometric_share), K11..Kdd (SI) and status (not-converged: no
    loaded equilibrium).
    """
    from pkmkit.stiffness import stiffness, twist_names

    m, data = machine_and_data(machine_name, assignments, units)
    convention = resolve_convention(convention)
    names = twist_names(m)
    d = len(names)
    wrench, wrench_note = _wrench(wrench_text, d)
    scale = length_scale(units)
    reference = None
    if reference_text is not None:
        reference = parse_numbers(reference_text, "--reference", (3,)) * scale
    tl = None if tool_length is None else tool_length * scale
    face = _FACES.get(m.family, _RODS)
    if input_ is not None or output is not None:
        if gravity:
            raise click.UsageError("--gravity takes one configuration (--pose or --q)")
        if input_ is None or output is None:
            raise click.UsageError("--input and --output go together")
        if pose is not None or q_text is not None:
            raise click.UsageError("--pose/--q and --input are exclusive")
        _batch(m, data, input_, output, chunk_rows, units, convention, wrench, reference, tl)
        return
    q = None
    x = None
    if face.takes_q and q_text is not None:
        if pose is not None:
            raise click.UsageError("--pose and --q are exclusive")
        q = parse_actuators(q_text, m, units)
    elif pose is None:
        raise click.UsageError("give --pose" + (" or --q" if face.takes_q else "")
                               + " (or --input TABLE --output TABLE)")
    else:
        x = pose_from_cli(parse_numbers(pose, "--pose", pose_widths(m)), m, units,
                          convention)[0]
    if q is None and not face.takes_q and q_text is not None:
        raise InputError("--q is for joint-chain machines; give --pose")
    tool = inverse_options(m, tool_length=tl)
    kwargs: dict[str, Any] = {"wrench": wrench, "data": data, "reference": reference, **tool}
    if face.takes_q:
        result = stiffness(m, x, q=q, **kwargs)
        if q is None:
            q = np.asarray(m.ik(x, strokes="ignore", **tool))
        stroke_q = q
    else:
        result = stiffness(m, x, **kwargs)
        stroke_q = np.asarray(m.ik(x, strokes="ignore"))
    # the one stroke check of every command: a configuration beyond a stroke is reported and
    # exits with status 3 (a stiffness there is that of a machine that cannot be there)
    check = single_check(m, stroke_q, units)
    payload = _payload(m, result, data, units, x, q, wrench)
    weight = None
    if gravity:
        weight = (_gravity(m, q, data, tl) if face.takes_q
                  else _rod_gravity(m, x, data, reference))
    if weight is not None:
        payload["gravity_deflection"], payload["masses"] = weight
    loaded = None
    if wrench is not None and not face.takes_q:
        loaded = _loaded(m, x, wrench, data, reference)
        loaded = loaded if isinstance(loaded, str) else loaded.single()
        payload.update(_loaded_payload(loaded))
    elif wrench is not None:
        payload.update(_loaded_payload("joint-chain machines: the linear deflection only"))
    add_to_payload(payload, check, units, set_status=False)
    too_far = ("" if wrench is None else
               linear_range_problem(result.deflection, m.length_scale, units))
    if not too_far and loaded is not None and not isinstance(loaded, str) and loaded.status:
        too_far = ("no loaded equilibrium found from the linear deflection (Newton on the "
                   "exact rod geometry did not converge): the load is beyond the "
                   "small-displacement range or the pose is near a singularity")
    if too_far:
        payload["beyond_linear_range"] = too_far
    if as_json:
        emit_json(payload)
    else:
        _print(m, result, data, units, x, q, wrench, wrench_note, names)
        if loaded is not None:
            _print_loaded(loaded, len(names))
        if weight is not None:
            defl = weight[0] * PER_MICRO
            turn = f", rotation {fmt(defl[3:], 5)} µrad" if defl.size == 6 else ""
            click.echo(f"  deflection under its own weight: {fmt(defl[:3], 5)} µm{turn} "
                       f"({weight[1]})")
    if too_far:
        click.echo(f"doubtful: {too_far}", err=True)
        if check is None or not check.out_of_stroke[0]:
            sys.exit(3)
    finish_single(check, units)


def _gravity(m, q, data, tool_length) -> tuple[np.ndarray, str]:
    """The tool point's deflection ``(6,)`` (m, rad) under the moving parts' weight and the
    masses' note (:mod:`pkmkit.stiffness.chain_gravity`); a singular configuration raises."""
    from pkmkit.exceptions import SingularConfigurationError
    from pkmkit.stiffness.chain_gravity import chain_gravity_deflection, illustrative_masses

    masses = illustrative_masses(m)
    defl, status = chain_gravity_deflection(m, q, masses, data=data, tool_length=tool_length)
    if status[0] != 0:
        raise SingularConfigurationError("no weight deflection at this configuration (singular "
                                         "or a mechanism)")
    return defl[0], masses.note


def _loaded(m, x, wrench, data, reference):
    """The loaded equilibrium beside the linear deflection
    (:func:`pkmkit.stiffness.equilibrium.loaded_equilibrium`), or why there is none (text)."""
    from pkmkit.stiffness.equilibrium import loaded_equilibrium

    try:  # a batch (of one pose): a row without equilibrium is flagged, not raised
        return loaded_equilibrium(m, np.atleast_2d(x), np.atleast_2d(wrench), data=data,
                                  reference=reference)
    except InputError as exc:  # cranks: no model of their exact geometry under load
        return str(exc)


def _loaded_payload(loaded) -> dict[str, Any]:
    if isinstance(loaded, str):
        return {"deflection_loaded": None, "loaded_note": loaded}
    ok = loaded.status == 0
    return {"deflection_loaded": loaded.loaded if ok else None,
            "deflection_difference": loaded.difference if ok else None,
            "geometric_stiffness_share": float(loaded.share) if ok else None,
            "loaded_status": "ok" if ok else "not-converged"}


def _print_loaded(loaded, d) -> None:
    if isinstance(loaded, str):
        click.echo(f"  loaded equilibrium: none ({loaded})")
        return
    if loaded.status != 0:
        click.echo("  loaded equilibrium: not found (Newton on the exact geometry did not "
                   "converge from the linear deflection)")
        return
    for label, values in (("loaded equilibrium", loaded.loaded),
                          ("difference (geometric stiffness)", loaded.difference)):
        defl = np.asarray(values) * PER_MICRO
        text = f"{fmt(defl[:min(d, 3)], 5)} µm"
        if d == 6:
            text += f", rotation {fmt(defl[3:], 5)} µrad"
        click.echo(f"  {label}: {text}")
    click.echo(f"  geometric-stiffness share: {loaded.share:.3g} of the loaded deflection")


def _rod_gravity(m, x, data, reference) -> tuple[np.ndarray, str]:
    """A rod machine's deflection under its own weight at pose ``x``: ``(d,)`` for a translating
    platform (:mod:`pkmkit.stiffness.loads`), ``(6,)`` at the reference point for a turning one
    (:mod:`pkmkit.stiffness.platform_gravity`), and the masses' note."""
    from pkmkit.exceptions import SingularConfigurationError

    if m.orientation_fixed:
        from pkmkit.dynamics.defaults import default_masses
        from pkmkit.stiffness.loads import load_deflection

        masses = default_masses(m)
        defl = load_deflection(m, np.atleast_2d(x), masses, data=data).gravity
        what = ""
    else:
        from pkmkit.stiffness.platform_gravity import platform_gravity_deflection, platform_masses

        masses = platform_masses(m)
        defl, _ = platform_gravity_deflection(m, np.atleast_2d(x), masses, data=data,
                                              point=reference)
        what = " at its frame origin"
    if not np.isfinite(defl).all():
        raise SingularConfigurationError("no weight deflection at this configuration")
    rods = masses.rod_mass + masses.strut_parts(m.model.n_rods)[0]
    slides = bool((m.model.rod_kind == 0).any())
    note = (f"illustrative masses of pkmkit.dynamics.defaults, no source gives them: platform "
            f"{masses.platform_mass:g} kg{what}"
            + (f", carriages {float(np.max(masses.carriage_mass)):g} kg" if slides else "")
            + f", rods or struts up to {float(np.max(rods)):.3g} kg")
    return defl[0], note


def _payload(m, r, data, units, x, q, wrench) -> dict[str, Any]:
    out: dict[str, Any] = {"machine": m.id, "units": units}
    if x is not None:
        out["pose"] = np.asarray(x, dtype=float)
    if q is not None:
        out["q"] = np.asarray(q) / actuator_scales(m, units)
    out.update({
        "coordinates": list(r.coordinates), "reference": r.reference,
        "stiffness": r.stiffness, "compliance": r.compliance, "eigenvalues": r.eigenvalues,
        "directions": r.directions, "translational_eigenvalues": r.translational,
        "rigid_directions": int(r.rigid),
        "si_units": {"stiffness": "N/m, N/rad, N·m/rad", "compliance": "m/N, rad/N, rad/(N·m)",
                     "pose": "m, rad (rotation vector)", "deflection": "m, rad"},
        "elastic_data": {"actuator_stiffness": data.actuator_stiffness,
                         "rod_section": data.rod_section.label if data.rod_section else None,
                         "link_section": data.link_section.label if data.link_section else None,
                         "notes": list(data.notes), "assumed": data.assumed},
    })
    if r.rotational is not None:
        out["rotational_eigenvalues"] = r.rotational
    if wrench is not None:
        out["wrench"] = wrench
        out["deflection"] = r.deflection
    return out


def _micro(values: np.ndarray) -> str:
    return fmt(np.asarray(values) / PER_MICRO, 5)


def _print(m, r, data, units, x, q, wrench, note, names) -> None:
    d = len(names)
    where = (f"pose {fmt(np.asarray(x)[:3] / length_scale(units))} {units}" if x is not None
             else f"q {fmt(np.asarray(q) / actuator_scales(m, units))}")
    click.echo(f"{m.name}: stiffness at {r.reference}, {where}")
    click.echo(f"  elastic data: {'; '.join(data.notes)}")
    if r.rigid:
        click.echo(f"  rigid in {r.rigid} direction(s): the model holds them with rigid rods, "
                   "links or constraints (give sections with --set to make them compliant)")
    else:
        label = "N/µm" if d < 6 else "SI: N/m | N/rad ; N | N·m/rad"
        click.echo(f"  K ({label}) =")
        mat = r.stiffness / PER_MICRO if d < 6 else r.stiffness.copy()
        mat = np.where(np.abs(mat) < 1e-12 * np.abs(mat).max(), 0.0, mat)  # rounding noise
        for row in mat:
            click.echo("    " + "  ".join(f"{v:11.4g}" for v in row))
    kt = np.asarray(r.translational)
    if kt.size > 1 and abs(kt[1] - kt[0]) <= 1e-9 * abs(kt[1]):
        where = ("equal in every direction" if abs(kt[-1] - kt[0]) <= 1e-9 * abs(kt[-1])
                 else "smallest in every direction of a plane")
    else:
        where = f"smallest along {fmt(_weakest(r), 4)}"
    click.echo(f"  translational stiffness (pure force): {_micro(kt)} N/µm; {where}")
    if r.rotational is not None:
        click.echo(f"  rotational stiffness (pure moment): {_micro(r.rotational)} N·m/µrad")
    if wrench is not None:
        defl = np.asarray(r.deflection) * PER_MICRO
        text = f"{fmt(defl[:min(d, 3)], 5)} µm"
        if d == 6:
            text += f", rotation {fmt(defl[3:], 5)} µrad"
        click.echo(f"  deflection under {fmt(wrench)} (N, N·m): {text}")
        if note:
            click.echo(f"  note: {note}")


def _weakest(r) -> np.ndarray:
    """Direction of the smallest translational stiffness (unit, sign: largest component > 0)."""
    c = np.asarray(r.compliance)[:3, :3]
    c = c[: len(r.translational), : len(r.translational)]
    _, v = np.linalg.eigh(c)
    u = v[:, -1]
    return u if u[np.argmax(np.abs(u))] > 0 else -u


def _batch(m, data, input_, output, chunk_rows, units, convention, wrench, reference, tl):
    from pkmkit.io.table import Labels
    from pkmkit.stiffness import stiffness, twist_names

    names = twist_names(m)
    d = len(names)
    columns = pose_columns(m)
    face = _FACES.get(m.family, _RODS)
    tool = inverse_options(m, tool_length=tl)
    flags = BatchFlags(m, units)

    def compute(values, chunk):
        x = pose_from_cli(values, m, units, convention)
        kwargs: dict[str, Any] = {"wrench": wrench, "data": data, "reference": reference}
        r = stiffness(m, x, **kwargs, **tool)
        status = np.asarray(r.status)
        if not face.inverse_flags_strokes:  # the one stroke check
            inverse = m.ik(x, full_output=True, strokes="ignore")
            status = flags(np.asarray(inverse.q), status, chunk)
        out: dict[str, Any] = {name: values[:, j] for j, name in enumerate(columns)}
        for j in range(r.translational.shape[1]):
            out[f"kt{j + 1}"] = r.translational[:, j] / PER_MICRO
        if r.rotational is not None:
            for j in range(3):
                out[f"kr{j + 1}"] = r.rotational[:, j] / PER_MICRO
        out["rigid"] = r.rigid
        if wrench is not None:
            for j, name in enumerate(names):
                out[name] = r.deflection[:, j] * PER_MICRO
            loaded = None if face.takes_q else _loaded(m, x, wrench, data, reference)
            if loaded is not None and not isinstance(loaded, str):
                for j, name in enumerate(names):
                    out[f"{name}_loaded"] = loaded.loaded[:, j] * PER_MICRO
                out["geometric_share"] = loaded.share
                late = (status == 0) & (loaded.status != 0)
                status = np.where(late, loaded.status, status)
        flat = r.stiffness.reshape(len(x), d * d)
        for i in range(d):
            for j in range(d):
                out[f"K{i + 1}{j + 1}"] = flat[:, i * d + j]
        out["status"] = Labels(status, status_names())
        return out, status

    run_batch(input_, output, columns, compute, chunk_rows=chunk_rows, units=units,
              column_units=pose_units(m, units))


class _Face(NamedTuple):
    """What ``stiffness`` does differently for a family: whether a configuration may be given
    by its actuator values (``--q``), and whether the stiffness's own inverse already flags
    the rows beyond the strokes in a batch."""

    takes_q: bool
    inverse_flags_strokes: bool


_RODS = _Face(takes_q=False, inverse_flags_strokes=False)
#: The one family dispatch table of ``pkmkit stiffness`` (rod legs by default).
_FACES = {"chain": _Face(takes_q=True, inverse_flags_strokes=True)}
