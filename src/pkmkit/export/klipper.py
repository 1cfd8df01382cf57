"""A Klipper delta-printer configuration (``[printer]`` and ``[stepper_a/b/c]``) for a linear Delta.

Klipper's delta model (``klippy/kinematics/delta.py``): three vertical towers at the angles
``angle_i`` on one circle of radius ``delta_radius`` about the origin, tower i at
``t_i = delta_radius (cos angle_i, sin angle_i)``; its carriage height is

    h_i = z + sqrt(arm_length_i² − (x − t_ix)² − (y − t_iy)²)

and homing sets the carriage at the endstop to ``position_endstop_i + sqrt(arm_length_i² −
delta_radius²)``.

pkmkit's equivalent legs (one rod per slide, a parallelogram's midline) say the same when the
slides are vertical (``u_i = +z``), the carriages are above the platform (branch +1) and the
points ``c_i = base_i − platform_i`` lie on one circle about the z axis: then
``t_i = (c_ix, c_iy)``, ``arm_length_i = ℓ_i``, ``h_i = q_i + c_iz`` and, the endstop of tower i
triggering at the actuator coordinate ``e_i``, ``position_endstop_i = e_i + c_iz −
sqrt(ℓ_i² − R²)``. A calibrated machine's arm lengths, tower angles and actuator offsets (``dL``,
``dq``, tangential base moves) fit that model exactly; radial moves of one tower, tilted slides or
an off-centre tower circle do not, and are refused: Klipper cannot hold them.
"""

from __future__ import annotations

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.export.base import (
    ExportCheckError,
    UnsupportedExportError,
    machine_family,
    rod_geometry,
    sample_poses,
)
from pkmkit.model.parameters import length_scale
from pkmkit.model.rods import SLIDE

FORMAT = "klipper"
#: Largest deviation (m) from Klipper's model accepted as rounding (tower radii, centre,
#: slide tilt × reach): beyond it the export is refused.
MODEL_TOL = 1e-9
STEPPERS = ("stepper_a", "stepper_b", "stepper_c")
#: Largest length (m) written to a configuration (radius, arms, endstops): no delta printer is
#: 100 m tall, and a value beyond is a unit slip (its 12 printed digits in mm would also no
#: longer hold :data:`MODEL_TOL`).
MAX_LENGTH = 100.0
#: Slack (m) of the test "an endstop lies within its actuator's stroke".
STROKE_TOL = 1e-9


def klipper_values(machine, endstops: np.ndarray | None = None, *, units: str = "mm") -> dict:
    """Klipper's delta parameters of a linear Delta (SI: m, angles in degrees).

    Args:
        machine: a translational machine of three slides (a linear Delta).
        endstops: ``(3,)`` actuator coordinates (m) at which the homing endstops trigger
            (default: the tops of the strokes, ``q_max``); each within its actuator's stroke.
        units: length unit of the numbers in error messages.

    Returns:
        ``{"delta_radius": R, "angle": (3,), "arm_length": (3,), "position_endstop": (3,)}``.

    Raises:
        UnsupportedExportError: a machine Klipper's delta model cannot express (names what),
            lengths beyond :data:`MAX_LENGTH`.
        InputError: endstops that are not 3 finite numbers or lie outside their strokes.
    """
    if machine_family(machine) != "translational":
        raise UnsupportedExportError(FORMAT, machine.id, "Klipper's delta kinematics is a "
                                     "translational machine of three vertical slides")
    geo = rod_geometry(machine, FORMAT)
    if geo.n != 3 or not (geo.kind == SLIDE).all():
        raise UnsupportedExportError(FORMAT, machine.id, "Klipper's delta needs three slides")
    reach = float(geo.length.max())
    tilt = np.linalg.norm(geo.axis - np.array([0.0, 0.0, 1.0]), axis=1)
    if (tilt * reach > MODEL_TOL).any():
        j = int(np.argmax(tilt))
        raise UnsupportedExportError(
            FORMAT, machine.id, f"the slide of {geo.names[j]} is not vertical (+z): axis "
            f"{np.round(geo.axis[j], 12).tolist()}; Klipper's towers are vertical")
    if (geo.branch != 1).any():
        raise UnsupportedExportError(FORMAT, machine.id, "Klipper's carriages ride above the "
                                     "effector (working branch +1 on every slide)")
    centre = geo.base - geo.platform
    radii = np.hypot(centre[:, 0], centre[:, 1])
    if np.ptp(radii) > MODEL_TOL:
        raise UnsupportedExportError(
            FORMAT, machine.id, "the towers (carriage joints less the effector offsets) are at "
            f"{', '.join(f'{1e3 * r:.6f}' for r in radii)} mm from the z axis; Klipper has one "
            "delta_radius about the origin (a calibration that moved one tower radially, or "
            "off-centred them, cannot be written without changing the machine)")
    radius = float(radii.mean())
    if not (geo.length > radius).all():
        raise UnsupportedExportError(FORMAT, machine.id, "Klipper needs arm_length > "
                                     "delta_radius")
    scale = length_scale(units)
    for what, values in (("delta_radius", [radius]), ("arm_length", geo.length)):
        _refuse_beyond(machine, what, np.asarray(values), units)
    if endstops is None:
        endstops = geo.q_max
        if not np.isfinite(endstops).all():
            raise UnsupportedExportError(
                FORMAT, machine.id, "the machine gives no stroke tops to put the endstops at; "
                "give the actuator coordinates of the endstops (--endstops)")
    endstops = np.asarray(endstops, dtype=float).reshape(-1)
    if endstops.shape != (3,) or not np.isfinite(endstops).all():
        raise InputError(f"the endstops must be 3 finite actuator coordinates, got "
                         f"{(endstops / scale).tolist()} {units}")
    outside = np.flatnonzero(~((endstops >= geo.q_min - STROKE_TOL)
                               & (endstops <= geo.q_max + STROKE_TOL)))
    if outside.size:
        j = int(outside[0])
        raise InputError(
            f"the endstop of {geo.actuators[j]} at {endstops[j] / scale:.6g} {units} lies "
            f"outside its stroke [{geo.q_min[j] / scale:.6g}, {geo.q_max[j] / scale:.6g}] "
            f"{units}: a carriage cannot trigger it (check the units)")
    _refuse_beyond(machine, "endstop", endstops, units)
    angle = np.degrees(np.arctan2(centre[:, 1], centre[:, 0]))
    position = endstops + centre[:, 2] - np.sqrt(geo.length**2 - radius**2)
    _refuse_beyond(machine, "position_endstop", position, units)
    return {"delta_radius": radius, "angle": angle, "arm_length": geo.length.copy(),
            "position_endstop": position, "endstops": endstops, "steppers": geo.actuators}


def _refuse_beyond(machine, what: str, values_m: np.ndarray, units: str) -> None:
    """An :class:`UnsupportedExportError` if a length ``values_m`` (m) is beyond
    :data:`MAX_LENGTH` (named ``what``, in ``units``)."""
    big = np.flatnonzero(~(np.abs(values_m) <= MAX_LENGTH))
    if big.size:
        scale = length_scale(units)
        raise UnsupportedExportError(
            FORMAT, machine.id, f"{what} {values_m[big[0]] / scale:.6g} {units} is beyond "
            f"{MAX_LENGTH / scale:g} {units}: no delta printer is that large (check the units "
            "of the machine, --set and --endstops)")


def klipper_config(machine, *, endstops: np.ndarray | None = None, source: str = "",
                   units: str = "mm") -> str:
    """The Klipper configuration text (mm, degrees) of a linear Delta; see the module docstring.

    The file holds the kinematic values only: ``[include]`` it after the printer's own
    configuration (pins, currents, ``max_velocity``, ``max_accel``), whose ``[printer]`` and
    ``[stepper_*]`` sections Klipper merges with these.

    ``units`` is the length unit of error messages (the file is in mm whatever it is).

    Raises:
        UnsupportedExportError, InputError: see :func:`klipper_values`.
    """
    from pkmkit import __version__

    v = klipper_values(machine, endstops, units=units)
    mm = 1.0 / length_scale("mm")
    lines = [
        f"# Klipper delta kinematics of \"{machine.name}\" (pkmkit machine {machine.id!r})",
        f"# Generated by pkmkit {__version__}"
        + (f" from {source}" if source else "") + "; regenerate rather than edit.",
        "# [include] this file after the printer's own configuration (pins, max_velocity,",
        "# max_accel ...): Klipper merges the sections. Lengths in mm, angles in degrees.",
        "# Tower i is pkmkit's actuator i; its endstop triggers at the actuator coordinate",
        "# " + ", ".join(f"{n} = {e * mm:.9g} mm" for n, e in zip(v["steppers"], v["endstops"],
                                                                   strict=True)) + ".",
        "",
        "[printer]",
        "kinematics: delta",
        f"delta_radius: {v['delta_radius'] * mm:.12g}",
    ]
    for k, section in enumerate(STEPPERS):
        lines += ["", f"[{section}]",
                  f"# pkmkit actuator {v['steppers'][k]}",
                  f"angle: {v['angle'][k]:.12g}",
                  f"arm_length: {v['arm_length'][k] * mm:.12g}",
                  f"position_endstop: {v['position_endstop'][k] * mm:.12g}"]
    return "\n".join(lines) + "\n"


def check_klipper_config(machine, text: str, endstops: np.ndarray | None = None) -> float:
    """Read a written configuration back and move Klipper's carriages (its delta formulas) to
    pkmkit's sample poses (:func:`~pkmkit.export.base.sample_poses`): the largest difference
    (m) between Klipper's carriage travel from the endstop and pkmkit's ``q − endstop``.

    Raises:
        ExportCheckError: beyond 1e-9 m.
    """
    import configparser

    cfg = configparser.ConfigParser()
    cfg.read_string(text)
    mm = length_scale("mm")
    x, q = sample_poses(machine)
    x = x / mm
    ends = klipper_values(machine, endstops)["endstops"]
    radius = cfg.getfloat("printer", "delta_radius")
    worst = 0.0
    for k, name in enumerate(STEPPERS):
        angle = np.radians(cfg.getfloat(name, "angle"))
        arm = cfg.getfloat(name, "arm_length")
        tower = radius * np.array([np.cos(angle), np.sin(angle)])
        height = x[:, 2] + np.sqrt(arm**2 - ((x[:, :2] - tower) ** 2).sum(axis=1))
        travel = height - cfg.getfloat(name, "position_endstop") - np.sqrt(arm**2 - radius**2)
        worst = max(worst, float(np.abs(travel * mm - (q[:, k] - ends[k])).max()))
    if not worst <= 1e-9:
        raise ExportCheckError(f"the Klipper configuration moves the carriages {worst:.3g} m "
                               "away from pkmkit's: not written")
    return worst
