"""A LinuxCNC kinematics module (C source) for a machine, nominal or calibrated: rod-leg
machines here, joint-chain machines in :mod:`pkmkit.export.linuxcnc_chains`.

The generated file implements LinuxCNC's kinematics API (``kinematics.h``):
``kinematicsInverse`` (closed form, rod by rod), ``kinematicsForward`` (a bounded Newton
iteration from the previous position, as ``genhexkins`` does, retried from home), ``kinematicsType``
(``KINEMATICS_BOTH``) and ``kinematicsHome``, with the ``rtapi_app_main`` / ``hal_init`` glue of a
realtime module. Build it with ``halcompile --install NAME.c`` (the line is in its header).

**Model.** One rod per actuator (:class:`~pkmkit.export.base.RodGeometry`; the Verne-type
module: six rods on three slides, its inverse model a Newton iteration for the rotation and
the joints, the position given):
``|p + R b_j − a_j(q_j)| = ρ_j(q_j)`` with ``a_j = base_j + q_j u_j``, ``ρ_j = length_j`` for a
slide, ``a_j = base_j``, ``ρ_j = length_j + q_j`` for a strut, the arm tip of a crank turned by
q_j (a rotary joint, in degrees for LinuxCNC) — pkmkit's own equations, with
its parameter names and its calibrated defects already applied to the numbers. A translational
machine (linear Delta, Orthoglide, Delta robot) has R = I and world coordinates X Y Z (a planar
one, the five-bars, X Y); a hexapod has
X Y Z A B C with ``R = Rz(C) Ry(B) Rx(A)`` (A, B, C in degrees about the fixed x, y, z axes:
pkmkit's ``--angles xyz``, LinuxCNC's and ``genhexkins``' roll–pitch–yaw), the position being
pkmkit's platform reference point.

**Refusals** (the functions' return values; 0 = success, LinuxCNC stops on anything else):
``-1`` a rod cannot close (pose out of reach, the same test as pkmkit's inverse model), ``-2``
a singular configuration, ``-3`` a configuration in the other assembly mode (the sign of det A
differs from the working mode's, which contains home: reaching it would cross a parallel
singularity), ``-4`` a non-finite or absurd input, ``-5`` the direct model did not converge
(no assembly within reach of the start, or beyond the iteration limit).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from pkmkit.export.base import RodGeometry, UnsupportedExportError, machine_family, rod_geometry
from pkmkit.export.linuxcnc_chain_c import MODULE_GLUE_C
from pkmkit.export.linuxcnc_chains import chain_linuxcnc_source
from pkmkit.export.linuxcnc_rod_c import ROD_MODEL_C
from pkmkit.model.parameters import length_scale
from pkmkit.model.rods import CRANK, STRUT

FORMAT = "linuxcnc"
#: C names of the rod kinds (pkmkit.model.rods SLIDE, STRUT, CRANK).
KIND_NAMES = {0: "PKM_SLIDE", 1: "PKM_STRUT", 2: "PKM_CRANK"}
#: Iteration limit of the generated direct model (per start; two starts at most).
FK_MAX_ITER = 40
#: Relative rod-length tolerance of the generated direct model (× the machine's size).
FK_TOL = 1e-13
#: Relative tolerance on ℓ² within which a negative radicand is rounding at the workspace
#: boundary (pkmkit's :data:`~pkmkit.machines.closed_form.BOUNDARY_TOL`).
BOUNDARY_TOL = 1e-12
#: Input coordinates beyond this many metres are refused (pkmkit's ``MAX_COORDINATE``).
MAX_COORDINATE = 1e9

#: Return codes of the generated functions, by name.
REFUSALS = {"unreachable": -1, "singular": -2, "other-mode": -3, "invalid-input": -4,
            "not-converged": -5}


def module_name(machine_id: str) -> str:
    """A C identifier for the module: the machine id's stem, ``-`` and ``.`` as ``_``, with
    ``kins`` appended (LinuxCNC's custom: ``lineardeltakins``, ``genhexkins``)."""
    stem = re.sub(r"\.(toml|ya?ml)$", "", str(machine_id).replace("\\", "/").split("/")[-1])
    name = re.sub(r"[^A-Za-z0-9_]", "_", stem).strip("_").lower() or "pkm"
    if name[0].isdigit():
        name = "pkm_" + name
    return name + "kins"


def _num(v: float) -> str:
    """The shortest text that reads back as the same double (a C literal)."""
    text = repr(float(v))
    return text if any(c in text for c in ".eEn") else text + ".0"


def _parameters_comment(machine, units: str, scale: float) -> str:
    """The machine's named pkmkit parameters (built-in kinds), as a comment block."""
    kind = machine.kind
    if kind is None or not machine.params:
        return (" * Geometry: given rod by rod (a machine file's legs, or a calibrated machine "
                "whose\n * defects replaced the named parameters).\n")
    rows = []
    for spec in kind.parameters:
        value = np.asarray(machine.params[spec.name], dtype=float)
        factor = {"length": 1.0 / scale, "angle": 180.0 / np.pi}.get(spec.quantity, 1.0)
        unit = {"length": " " + units, "angle": " deg"}.get(spec.quantity, "")
        text = ", ".join(f"{v:.12g}" for v in np.ravel(value * factor))
        rows.append(f" *   {spec.name} = {text}{unit}")
    return (f" * pkmkit parameters (kind {kind.kind!r}), from which the rods below are built:\n"
            + "\n".join(rows) + "\n")


def _array(values: np.ndarray) -> str:
    return "{" + ", ".join(_num(v) for v in np.ravel(values)) + "}"


def _rows(values: np.ndarray, names: Sequence[str]) -> str:
    return "\n".join(f"    {_array(row)},  /* {name} */" for row, name in zip(values, names,
                                                                                 strict=True))


def linuxcnc_source(machine, *, units: str = "mm", name: str | None = None,
                    source: str = "") -> str:
    """The C source of a LinuxCNC kinematics module for ``machine``.

    Args:
        machine: a rod-leg machine of slides, struts or cranks: a translational one (3
            actuators, X Y Z), a planar one (2 actuators, X Y) or a hexapod of six rods on six
            actuators (X Y Z A B C).
        units: LinuxCNC's length unit (``LINEAR_UNITS``: ``"mm"``, ``"in"`` or ``"m"``) for the
            world coordinates, the joints and the numbers in the file; angles in degrees.
        name: module name (default :func:`module_name` of the machine id).
        source: where the machine came from (a file path), written in the header.

    Returns:
        The source text (``NAME.c``).

    Raises:
        UnsupportedExportError: a machine this module cannot express (joint chains, full-pose
            machines other than six rods on six actuators).
    """
    name = name or module_name(machine.id)
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise UnsupportedExportError(FORMAT, machine.id,
                                     f"module name {name!r} is not a C identifier")
    scale = length_scale(units)
    if machine_family(machine) == "chain":
        return chain_linuxcnc_source(machine, name, units, scale, source)
    geo = rod_geometry(machine, FORMAT, cranks=True, planar=True, position_controlled=True)
    return _render(machine, geo, name, units, scale, source)


def _home_world(machine, geo: RodGeometry) -> np.ndarray:
    """Home pose as LinuxCNC world coordinates (SI lengths; A, B, C in degrees)."""
    home = np.array(machine.home_pose, dtype=float)  # scipy's from_rotvec: writeable only
    if not geo.full_pose:
        return np.concatenate([home, np.zeros(6 - len(home))])
    from pkmkit.spatial.rotation import angles_from_rotation, rotation_class

    abc = angles_from_rotation(rotation_class().from_rotvec(home[3:]), "xyz", degrees=True)
    return np.concatenate([home[:3], abc])


def _render(machine, geo: RodGeometry, name: str, units: str, scale: float, source: str) -> str:
    """The module's text: the header comment, the defines, the tables, then the fixed C of the
    rod models (:data:`~pkmkit.export.linuxcnc_rod_c.ROD_MODEL_C`)."""
    first = np.array([np.flatnonzero(geo.joint == j)[0] for j in range(machine.n_actuators)])
    crank = geo.kind[first] == CRANK
    joint_scale = np.where(crank, np.pi / 180.0, scale)  # LinuxCNC: rotary joints in degrees
    home_q = np.asarray(machine.home_q, dtype=float) / joint_scale
    limits = _joint_limits(geo, home_q, joint_scale, units)
    return (_rod_header(machine, geo, name, units, scale, source, limits)
            + _rod_defines(machine, geo) + _rod_tables(machine, geo, units, scale, home_q)
            + "static int comp_id;\n\n" + ROD_MODEL_C + MODULE_GLUE_C.replace("@NAME@", name))


def _joint_limits(geo: RodGeometry, home_q: np.ndarray, joint_scale: np.ndarray,
                  units: str) -> list[str]:
    """The INI lines of the joints (strokes and home, in LinuxCNC's units), as comment rows."""
    crank = geo.kind == CRANK
    limits = []
    for j in range(len(home_q)):
        r = int(np.flatnonzero(geo.joint == j)[0])  # a rod of joint j
        lo, hi = geo.q_min[r] / joint_scale[j], geo.q_max[r] / joint_scale[j]
        unit = "deg" if crank[r] else units
        if np.isfinite(lo) and np.isfinite(hi):
            limits.append(f" *   [JOINT_{j}] MIN_LIMIT = {lo:.9g}  MAX_LIMIT = {hi:.9g}  "
                          f"HOME = {home_q[j]:.9g}   ({geo.actuators[r]}, {geo.names[r]}; "
                          f"{unit})")
        else:
            limits.append(f" *   [JOINT_{j}] HOME = {home_q[j]:.9g}   ({geo.actuators[r]}, "
                          f"{geo.names[r]}; {unit}; pkmkit gives no stroke)")
    return limits


def _crank_arrays(geo: RodGeometry, scale: float) -> str:
    """The cranks' tables (empty without cranks)."""
    crank = geo.kind == CRANK
    crank_arrays = ""
    if crank.any():
        e1, e2, radius, offset = geo.crank_frames()
        crank_arrays = f"""/* cranks: a_j(q) = pivot_j + offset_j axis_j
                   + radius_j (cos q e1_j + sin q e2_j), q in degrees;
   pivot: a point of the crank axis (legs[j].pivot), e1: the arm's direction at q = 0
   across the axis, e2 = axis x e1, radius and offset: the arm across and along the axis
   (derived from legs[j].base, legs[j].pivot, legs[j].axis); zeros for other rods */
static const double crank_pivot[N_RODS][3] = {{
{_rows(geo.pivot / scale, geo.names)}
}};
static const double crank_e1[N_RODS][3] = {{
{_rows(e1, geo.names)}
}};
static const double crank_e2[N_RODS][3] = {{
{_rows(e2, geo.names)}
}};
static const double crank_radius[N_RODS] = {_array(radius / scale)};
static const double crank_offset[N_RODS] = {_array(offset / scale)};
"""
    return crank_arrays


def _rod_header(machine, geo: RodGeometry, name: str, units: str, scale: float, source: str,
                limits: list[str]) -> str:
    """The header comment: build line, INI lines, the model, pkmkit's parameters."""
    from pkmkit import __version__

    n = geo.n
    planar = machine.dims == 2
    verne = machine.n_actuators < n
    coords = "XYZABC" if geo.full_pose and not verne else ("XY" if planar else "XYZ")
    kind_text = ("six rods on three slides, the orientation R following the position:\n"
                 " * world X Y Z" if verne else
                 "full-pose (hexapod): world X Y Z A B C, R = Rz(C) Ry(B) Rx(A), A B C in "
                 "degrees about the fixed x, y, z axes" if geo.full_pose else
                 "planar: world X Y, z = 0, the platform does not turn (R = I)" if planar else
                 "translational: world X Y Z, the platform does not turn (R = I)")
    mode_name = machine.mode_label(machine.working_mode)
    inverse_text = ("Newton on the rod lengths for R and the joints, the position given, from "
                    "the last\n * solution (kinematicsHome resets it), then home; every rod on "
                    "its working branch.\n *" if verne else "closed form per rod.")
    return f"""/* {name}.c -- LinuxCNC kinematics of "{machine.name}"
 * (pkmkit machine {machine.id!r})
 *
 * Generated by pkmkit {__version__} (`pkmkit export {machine.id} --to linuxcnc`); do not edit:
 * regenerate from the machine file{f' ({source})' if source else ''}.
 * Build and install:   halcompile --install {name}.c
 * INI:   [KINS] KINEMATICS = {name}   JOINTS = {machine.n_actuators}
 *        [TRAJ] COORDINATES = {coords}   LINEAR_UNITS = {units}   ANGULAR_UNITS = degree
{chr(10).join(limits)}
 *
 * Model ({kind_text}): rod j joins a_j(q_j) to the platform joint p + R b_j,
 *     | p + R b_j - a_j(q_j) | = rho_j(q_j)
 * slide: a_j = base_j + q_j axis_j, rho_j = length_j;  strut: a_j = base_j, rho_j = length_j + q_j;
 * crank: the arm tip a_j turns by q_j (degrees) about axis_j, rho_j = length_j.
 * Joint j is pkmkit's actuator j; lengths in {units}. The numbers are pkmkit's rod end points and
 * lengths (legs[j].base, legs[j].platform, legs[j].length, legs[j].axis) with any calibrated
 * defects of the machine file already applied.
 * Inverse: {inverse_text} Forward: Newton iteration from the previous position (at most
 * {FK_MAX_ITER} steps, each bounded), retried from home (and started there when the previous
 * position is LinuxCNC's unset all-zero one); the result must lie in the working assembly mode
 * ("{mode_name}", sign of det A = {machine.working_mode:+d}).
 * Return codes: 0 ok, -1 out of reach, -2 singular, -3 other assembly mode, -4 invalid input,
 * -5 direct model not converged.
{_parameters_comment(machine, units, scale)} */
"""


def _rod_defines(machine, geo: RodGeometry) -> str:
    """The includes and the defines (sizes, kinds, return codes)."""
    n = geo.n
    planar = machine.dims == 2
    crank = geo.kind == CRANK
    return f"""
#include "rtapi_math.h"
#include "rtapi_app.h"
#include "hal.h"
#include "kinematics.h"

#define N_RODS {n}
#define N_JOINTS {machine.n_actuators}
#define POSITION_CONTROLLED {1 if machine.n_actuators < n else 0}
#define FULL_POSE {1 if geo.full_pose else 0}
#define PLANAR {1 if planar else 0}
#define PKM_SLIDE 0
#define PKM_STRUT 1
#define PKM_CRANK 2
#define HAS_CRANKS {1 if crank.any() else 0}
#define PKM_UNREACHABLE (-1)
#define PKM_SINGULAR (-2)
#define PKM_OTHER_MODE (-3)
#define PKM_INVALID (-4)
#define PKM_NOT_CONVERGED (-5)
#define FK_MAX_ITER {FK_MAX_ITER}
#define DEG (3.14159265358979323846 / 180.0)

"""


def _rod_tables(machine, geo: RodGeometry, units: str, scale: float, home_q: np.ndarray) -> str:
    """The numbers: rods, cranks, home, working mode, tolerances (pkmkit's names)."""
    base, platform = geo.base / scale, geo.platform / scale
    length = geo.length / scale
    home_world = _home_world(machine, geo)
    home_world[:3] /= scale
    size = 1.0 + float(max(np.abs(base).max(), np.abs(platform).max(), np.abs(length).max()))
    rho_home = np.where(geo.kind == STRUT, length + home_q[geo.joint], length)  # at home
    kinds = ", ".join(KIND_NAMES[int(k)] for k in geo.kind)
    crank_arrays = _crank_arrays(geo, scale)
    return f"""/* ---- parameters (pkmkit names; {units}) ---- */
static const int rod_kind[N_RODS] = {{{kinds}}};
/* base-side joint centre at q = 0 (legs[j].base) */
static const double rod_base[N_RODS][3] = {{
{_rows(base, geo.names)}
}};
/* platform joint centre in the platform frame (legs[j].platform) */
static const double rod_platform[N_RODS][3] = {{
{_rows(platform, geo.names)}
}};
/* unit slide direction or crank axis (legs[j].axis; 0 for struts) */
static const double rod_axis[N_RODS][3] = {{
{_rows(geo.axis, geo.names)}
}};
/* rod length (strut: length at q = 0) (legs[j].length) */
static const double rod_length[N_RODS] = {_array(length)};
/* working branch of each slide's or crank's inverse model: q = s + branch * sqrt(...) */
static const double rod_branch[N_RODS] = {_array(geo.branch)};
{crank_arrays}
/* home: world X Y Z A B C and joints (pkmkit's home configuration) */
static const double home_world[6] = {_array(home_world)};
static const double home_joints[N_JOINTS] = {_array(home_q)};
/* the joint driving each rod (pkmkit's actuator) */
static const int rod_joint[N_RODS] = {{{", ".join(str(int(k)) for k in geo.joint)}}};
/* sign of det A in the working assembly mode */
static const int working_mode = {machine.working_mode:d};
/* tolerances: rod-length convergence, boundary rounding (relative to length^2), input bound */
static const double fk_tol = {_num(FK_TOL * size)};
#if !POSITION_CONTROLLED
static const double boundary_tol = {_num(BOUNDARY_TOL)};
#endif
static const double max_coordinate = {_num(MAX_COORDINATE / scale)};
static const double max_step = {_num(0.25 * float(np.min(rho_home)))};
#if POSITION_CONTROLLED
/* a rod's joint off its working branch's closed form by more than this: another branch */
static const double branch_tol = {_num(1e-7 / scale)};
#endif

"""
