"""A LinuxCNC kinematics module (C source) for a joint-chain machine (Tripteor X7, TriMule 600,
crank–slider, joint-chain machine files), nominal or calibrated with compatible defects.

The module carries pkmkit's chains element by element (:meth:`chain_tables`: each element's
frame D_e with the defects applied, its joint type and variable) and solves **the same
closure pkmkit solves** (:mod:`pkmkit.solve.chains`): every leg's end frame
``T = D_1 M_1(q_1) D_2 M_2(q_2) …`` welded to the platform pose (residual ``(p_leg − p_X,
L v / c)``, the Gibbs vector of ``R_leg R_Xᵀ`` scaled by the characteristic length L), the
head from the platform to the tool frame, the tool point ``tool_length`` along its z axis.

- **Forward** (``kinematicsForward``): the actuators given, Gauss–Newton on the legs' closure
  for the platform pose and the passive joints, from the last configuration the module solved
  (LinuxCNC calls it along the motion), retried from home unless it was home; then the head.
- **Inverse** (``kinematicsInverse``): the tool point and axis given, Gauss–Newton on the
  closure plus the tool rows ``(p_tool − p, L (a_tool − a))`` for the platform and every joint,
  from the last configuration, retried from home (the inverse model pkmkit solves from home);
  a two-branch head (the TriMule's (Q4, Q5) and (Q4 ± π, −Q5)) solved again flipped and the
  branch whose turn is nearest the start's taken, pkmkit's rule
  (:mod:`pkmkit.machines.head_branches`).
- Each step is bounded (:data:`MAX_STEP` × L, :data:`MAX_TURN` rad), at most
  :data:`CHAIN_MAX_ITER` steps per start.
- **World**: X Y Z the tool point, A B the tool axis ``a = Ry(B) Rx(A) (0, 0, 1)`` in degrees
  (C is not used: a spindle's turn about its axis is not a degree of freedom of these machines);
  joints in degrees (revolute) or the length unit (prismatic), pkmkit's actuator order.
- **Refusals**: ``-1`` out of reach (a least-squares residual beyond pkmkit's 1e-9 m: the legs
  do not close, or the target is not reached), ``-2`` singular, ``-4`` invalid input, ``-5`` not
  converged, ``-6`` a joint (actuated or passive) beyond its stroke.
"""

from __future__ import annotations

import numpy as np

from pkmkit.export.base import UnsupportedExportError
from pkmkit.export.linuxcnc_chain_c import CHAIN_INTERFACE_C, CHAIN_MODEL_C, MODULE_GLUE_C
from pkmkit.machines.head_branches import FLIP_MARGIN

FORMAT = "linuxcnc"
#: Iteration limit of the generated solvers, per start (pkmkit's engine: 60).
CHAIN_MAX_ITER = 60
#: A closure is exact below this residual (m; pkmkit's ``residual_tol``).
RESIDUAL_TOL = 1e-9
#: Step bounds: a translation or a prismatic joint by at most MAX_STEP × L, a rotation by
#: MAX_TURN rad.
MAX_STEP, MAX_TURN = 0.1, 0.25
#: Input coordinates beyond this many metres are refused (pkmkit's ``MAX_COORDINATE``).
MAX_COORDINATE = 1e9


def _num(v: float) -> str:
    text = repr(float(v))
    return text if any(c in text for c in ".eEn") else text + ".0"


def _ints(values) -> str:
    values = [int(v) for v in values] or [0]
    return "{" + ", ".join(str(v) for v in values) + "}"


def _doubles(values) -> str:
    return "{" + ", ".join(_num(v) for v in np.ravel(values)) + "}"


def _stroke(values: np.ndarray, joint_scale: np.ndarray) -> str:
    """Strokes in the module's units; ±1e300 stands for unlimited."""
    return _doubles(np.where(np.isfinite(values), values / joint_scale,
                             np.sign(values) * 1e300))


def _element_rows(t, scale: float) -> tuple[str, str]:
    """The element frames: rotations and positions, one row per element with its name."""
    rot, pos = [], []
    for name, kind, r, p in zip(t.element_names, t.element_types, t.rotations, t.positions,
                                strict=True):
        rows = ", ".join(_doubles(row) for row in r)
        rot.append(f"    {{{rows}}},  /* {name} ({kind}) */")
        pos.append(f"    {_doubles(p / scale)},  /* {name} */")
    return "\n".join(rot), "\n".join(pos)


def _sizes(t, inverse: list[int]) -> str:
    """The defines: sizes of the tables and of the solvers' arrays."""
    return f"""#define N_ELEMENTS {len(t.element_names)}
#define N_VARIABLES {len(t.variables)}
#define N_ACTUATORS {len(t.actuated)}
#define N_PASSIVE {len(t.passive)}
#define N_INVERSE {len(inverse)}
#define N_LEGS {len(t.legs)}
#define N_HEAD {len(t.head)}
#define MAX_CHAIN {max([len(leg) for leg in t.legs] + [len(t.head), 1])}
#define MAX_ROWS {6 * len(t.legs) + 6}
#define MAX_UNKNOWNS {6 + len(inverse)}
#define CHAIN_MAX_ITER {CHAIN_MAX_ITER}
#define DAMPING 1e-12
"""


def _tables(t, scale: float) -> str:
    """The machine's numbers as C tables (pkmkit's names in comments)."""
    joint_scale = np.where(t.revolute, 1.0, scale)
    code = {"R": "JOINT_R", "P": "JOINT_P", "F": "JOINT_F"}
    leg_first = np.concatenate([[0], np.cumsum([len(leg) for leg in t.legs])])
    inverse = sorted({int(t.element_variable[e]) for leg in t.legs for e in leg}
                     | {int(t.element_variable[e]) for e in t.head} - {-1})
    inverse = [v for v in inverse if v >= 0]
    size = max(float(np.abs(t.positions).sum()) / scale, 1.0)
    rot, pos = _element_rows(t, scale)
    names = ", ".join(t.variables)
    from pkmkit.spatial.rotation import rotvec_to_matrix

    home_rot = rotvec_to_matrix(t.home_platform[None, 3:])[0]
    flip = t.head_flip or (-1, -1)
    return _sizes(t, inverse) + f"""
/* ---- parameters: pkmkit's element frames D_e (model.frames, defects applied) ---- */
/* rotation of each element's frame in the previous frame (rows) */
static const double element_rotation[N_ELEMENTS][3][3] = {{
{rot}
}};
/* origin of each element's frame in the previous frame */
static const double element_position[N_ELEMENTS][3] = {{
{pos}
}};
static const int element_type[N_ELEMENTS] = {{{", ".join(code[k] for k in t.element_types)}}};
/* the joint variable of each element (index in: {names}; -1: a fixed frame) */
static const int element_variable[N_ELEMENTS] = {_ints(t.element_variable)};
/* the legs {", ".join(t.leg_names)}: elements leg_element[leg_first[l] .. leg_first[l + 1] - 1] */
static const int leg_first[N_LEGS + 1] = {_ints(leg_first)};
static const int leg_element[] = {_ints([e for leg in t.legs for e in leg])};
/* the head, from the platform frame to the tool frame */
static const int head_element[] = {_ints(t.head)};
/* the actuators (joint j of LinuxCNC is pkmkit's actuator j), the passive joints the direct
   model solves, the variables the inverse model solves */
static const int actuated_variable[] = {_ints(t.actuated)};
static const int passive_variable[] = {_ints(t.passive)};
static const int inverse_variable[] = {_ints(inverse)};
static const int variable_revolute[N_VARIABLES] = {_ints(t.revolute)};
/* strokes (rad or length unit; +-1e300: unlimited) and which ones pkmkit checks */
static const double variable_min[N_VARIABLES] = {_stroke(t.q_min, joint_scale)};
static const double variable_max[N_VARIABLES] = {_stroke(t.q_max, joint_scale)};
static const int variable_checked[N_VARIABLES] = {_ints(t.checked)};
/* a two-branch head (-1: none): its turn and tilt variables; the inverse model takes the
   branch whose turn is nearest the start's (pkmkit's rule) */
static const int head_flip_turn = {flip[0]}, head_flip_tilt = {flip[1]};
static const double flip_margin = {_num(FLIP_MARGIN)};
/* home: every joint, the platform position and rotation (pkmkit's home configuration) */
static const double home_values[N_VARIABLES] = {_doubles(t.home_values / joint_scale)};
static const double home_platform_position[3] = {_doubles(t.home_platform[:3] / scale)};
static const double home_platform_rotation[3][3] = {{{", ".join(_doubles(r) for r in home_rot)}}};
/* the closures' characteristic length L and the tool length */
static const double closure_length = {_num(t.closure_length / scale)};
static const double tool_length = {_num(t.tool_length / scale)};
/* tolerances: exact closure, pkmkit's residual_tol (1e-9 m), a stopped step, step bounds,
   input bound */
static const double exact_tol = {_num(1e-15 * size)};
static const double residual_tol = {_num(RESIDUAL_TOL / scale)};
static const double step_tol = 1e-12;
static const double max_step = {_num(MAX_STEP * t.closure_length / scale)};
static const double max_turn = {_num(MAX_TURN)};
static const double max_coordinate = {_num(MAX_COORDINATE / scale)};
"""


def _header(machine, t, name: str, units: str, scale: float, source: str) -> str:
    from pkmkit import __version__

    limits = []
    for j, v in enumerate(t.actuated):
        unit, factor = ("deg", np.pi / 180.0) if t.revolute[v] else (units, scale)
        lo, hi, home = t.q_min[v] / factor, t.q_max[v] / factor, t.home_values[v] / factor
        stroke = (f"MIN_LIMIT = {lo:.9g}  MAX_LIMIT = {hi:.9g}  " if np.isfinite([lo, hi]).all()
                  else "")
        limits.append(f" *   [JOINT_{j}] {stroke}HOME = {home:.9g}   ({t.variables[v]}; {unit})")
    legs = "; ".join(f"{n}: {' '.join(t.element_names[e] for e in leg)}"
                     for n, leg in zip(t.leg_names, t.legs, strict=True))
    head = (" ".join(t.element_names[e] for e in t.head)
            or "(none: the tool frame is the platform's)")
    flip_note = ("" if t.head_flip is None else
                 f"\n * Head branches: ({t.variables[t.head_flip[0]]}, "
                 f"{t.variables[t.head_flip[1]]}) and ({t.variables[t.head_flip[0]]} +- 180 deg, "
                 f"-{t.variables[t.head_flip[1]]}) give the same tool axis:\n * the inverse "
                 f"takes the one whose {t.variables[t.head_flip[0]]} is nearest the start's "
                 "(pkmkit's rule).")
    return f"""/* {name}.c -- LinuxCNC kinematics of "{machine.name}"
 * (pkmkit machine {machine.id!r}, joint chains)
 *
 * Generated by pkmkit {__version__} (`pkmkit export {machine.id} --to linuxcnc`); do not edit:
 * regenerate from the machine file{f' ({source})' if source else ''}.
 * Build and install:   halcompile --install {name}.c
 * INI:   [KINS] KINEMATICS = {name}   JOINTS = {len(t.actuated)}
 *        [TRAJ] COORDINATES = XYZAB   LINEAR_UNITS = {units}   ANGULAR_UNITS = degree
{chr(10).join(limits)}
 *
 * Model (pkmkit's joint chains, its closure): each chain is the product of its elements'
 * frames and joint motions, T = D_1 M_1(q_1) D_2 M_2(q_2) ... (D_e: element_rotation,
 * element_position, calibrated defects applied; M: a turn about / a slide along z).
 * Legs ({legs}) close on the platform pose X: r = (p_leg - p_X, L v / c),
 * v = vee(M - M^T) / 2, c = (1 + tr M) / 4, M = R_leg R_X^T (L = closure_length).
 * Head: {head}; the tool point lies tool_length along the tool frame's z, the tool axis is z.
 * World: X Y Z the tool point ({units}); A B the tool axis a = Ry(B) Rx(A) (0, 0, 1), degrees
 * (C unused). Joints: pkmkit's actuators in order, degrees (revolute) or {units} (prismatic).
 * Forward: Gauss-Newton on the legs' closure (platform pose, passive joints), inverse:
 * Gauss-Newton on the closure and the tool rows (platform pose, every joint); both start from
 * the last configuration solved (kinematicsHome resets it to home), then from home; at most
 * {CHAIN_MAX_ITER} steps per start, each bounded.{flip_note}
 * Return codes: 0 ok, -1 out of reach (least-squares residual > 1e-9 m), -2 singular,
 * -4 invalid input, -5 not converged, -6 a joint beyond its stroke.
 */
"""


def chain_linuxcnc_source(machine, name: str, units: str, scale: float, source: str) -> str:
    """The C source of a joint-chain machine's LinuxCNC module (module docstring).

    Raises:
        UnsupportedExportError: legs that close only in least squares at home (incompatible
            defects): no configuration of the module would be exact.
    """
    t = machine.chain_tables()
    if not t.home_misfit <= RESIDUAL_TOL:
        raise UnsupportedExportError(
            FORMAT, machine.id, f"its legs close only in least squares at home (misfit "
            f"{t.home_misfit:.3g} m > {RESIDUAL_TOL:g} m: incompatible defects of a "
            "hyperstatic machine); keep the compatible defects (pkmkit errors MACHINE "
            "--compatibility)")
    body = f"""
#include "rtapi_math.h"
#include "rtapi_app.h"
#include "hal.h"
#include "kinematics.h"

#define JOINT_R 0
#define JOINT_P 1
#define JOINT_F 2
#define PKM_UNREACHABLE (-1)
#define PKM_SINGULAR (-2)
#define PKM_INVALID (-4)
#define PKM_NOT_CONVERGED (-5)
#define PKM_OUT_OF_STROKE (-6)
#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

{_tables(t, scale)}
static int comp_id;
"""
    return (_header(machine, t, name, units, scale, source) + body + CHAIN_MODEL_C
            + CHAIN_INTERFACE_C + MODULE_GLUE_C.replace("@NAME@", name))
