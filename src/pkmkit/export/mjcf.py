"""A MuJoCo model (MJCF) of a rod-leg machine of slides, struts and cranks, nominal or
calibrated.

Bodies, built at the machine's home configuration (so MuJoCo's reference configuration ``qpos0``
is an assembled one and every closure holds there):

- **slide actuator** k: a carriage body on a slide joint ``act{k}`` along the slide, its
  reference ``ref`` the home actuator coordinate (so ``qpos`` of ``act{k}`` *is* pkmkit's q_k),
  carrying one ball-jointed rod per rod of the actuator (a parallelogram's two rods, a
  Verne-type module's rods), uniform solid cylinders;
- **strut** actuator k: a cylinder tube on a ball joint ``ball{j}`` at the base joint and a piston
  tube on a slide joint ``act{k}`` along the strut inside it (``qpos`` = pkmkit's q_k), both
  uniform solid cylinders of the rod's radius; the actuator's "carriage" mass (the motor's
  translating inertia) is the slide joint's ``armature``;
- **crank** actuator k: an arm on a hinge joint ``act{k}`` (``qpos`` = pkmkit's crank angle)
  carrying its rods (:mod:`pkmkit.export.mjcf_cranks`: pkmkit has no mass model of cranks, so
  the model takes illustrative masses, or a masses file's with its carriage masses as the
  arms', and says which);
- the platform on a free joint, at pkmkit's home pose, joined to every rod tip by a ``connect``
  equality constraint (the loop closures; stiff: ``solref`` 2 time steps);
- a **planar** machine (the five-bars: x-y poses) stays in its plane: each rod on a hinge
  ``hinge{j}`` about z instead of a ball joint, the platform on a planar joint — slides
  ``platform_x``, ``platform_y`` (their ``ref`` the home pose, so their qpos is pkmkit's x, y)
  and a hinge ``platform_rz`` about z, which the parallelograms hold at 0 (the ``connect``
  constraints' z rows are then satisfied identically);
- a ``motor`` per actuator on ``act{k}`` (force in N, gear 1): pkmkit's actuator force.

Masses and inertias come from :mod:`pkmkit.dynamics.masses` (default: the illustrative values of
:func:`pkmkit.dynamics.defaults.default_masses`). The platform's inertia is the masses' (about
its centre of mass); when they give none (translational machines never need it) a uniform
sphere of the platform's mass and of the platform joints' radius is written, and the file says
so. Gravity is the masses'. Contacts are off (the model is a kinematic chain, not a scene).

Refused (:class:`~pkmkit.export.base.UnsupportedExportError`): joint chains (written by
:mod:`pkmkit.export.mjcf_chains`), a crank machine whose rods do not
close at home (a tilted crank axis), planar machines with struts, cranks or fewer than three rods,
and spatial platforms held by fewer than six rods (a translational machine of three single
rods: pkmkit assumes its platform cannot turn, MuJoCo would let it).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pkmkit.export.base import (
    ExportCheckError,
    UnsupportedExportError,
    machine_family,
    platform_points,
    sample_poses,
)
from pkmkit.export.mjcf_cranks import crank_body, crank_masses, masses_note, parent_turn
from pkmkit.model.rods import CRANK, SLIDE, STRUT

FORMAT = "mjcf"
#: Simulation time step written in the model (s); the closures' time constant is two steps.
TIMESTEP = 1e-4


@dataclass(frozen=True)
class MjcfLayout:
    """An MJCF text and the facts a user of the model needs to set states.

    Attributes:
        xml: the MJCF document.
        rod_direction: ``{rod j: (3,)}`` unit direction of rod j (base joint → platform joint)
            at home: a ball joint's identity orientation.
        actuator_joints: ``(n,)`` names of the actuated slide joints (``act{k}``).
        placeholder_inertia: True when the platform's inertia was made up (see module doc).
        illustrative: what the masses are when pkmkit's dynamics model gives none ("" when it
            does).
    """

    xml: str
    rod_direction: dict[int, np.ndarray] = field(default_factory=dict)
    actuator_joints: tuple[str, ...] = ()
    placeholder_inertia: bool = False
    illustrative: str = ""


def _f(v) -> str:
    return " ".join(f"{float(c):.17g}" for c in np.atleast_1d(v))


def _check(machine, held: bool) -> None:
    family = machine_family(machine)
    why = None
    if family == "chain":
        why = ("a joint-chain machine is written by pkmkit.export.mjcf_chains (or "
               "pkmkit.export.mjcf_writer.write_mjcf for any machine), not by the rod-leg "
               "writer")
    elif held and family == "planar" and machine.model.n_rods < 3:
        why = (f"a planar platform on {machine.model.n_rods} rods: pkmkit takes it as "
               "translating, MuJoCo would let it turn (three rods hold a platform in the plane; "
               "parallelograms give two per leg)")
    elif held and family == "planar" and (machine.model.leg_kind != SLIDE).any():
        why = "a planar machine with struts or cranks is not exported to MuJoCo yet; slides are"
    elif held and family != "planar" and machine.model.n_rods < 6:
        why = (f"the platform hangs on {machine.model.n_rods} rods: pkmkit takes it as "
               "translating, MuJoCo would let it turn (six rods hold a platform; parallelograms "
               "give two per leg)")
    if why:
        raise UnsupportedExportError(FORMAT, machine.id, why)
    strut_actuators = machine.model.leg_actuator[machine.model.leg_kind == STRUT]
    for k in np.unique(strut_actuators):
        if (machine.model.rod_actuator == k).sum() != 1:
            raise UnsupportedExportError(FORMAT, machine.id, f"strut actuator "
                                         f"{machine.model.actuator_names[k]!r} drives several "
                                         "rods")


def mjcf_layout(machine, masses=None, *, require_held_platform: bool = True) -> MjcfLayout:
    """The MJCF model of ``machine`` (see the module docstring) and its layout.

    Args:
        machine: a rod-leg machine of slides, struts and cranks (translational with
            parallelograms, planar, or full-pose), nominal or calibrated.
        masses: :class:`~pkmkit.dynamics.masses.MassProperties` (default: the kind's
            illustrative values).
        require_held_platform: refuse a platform held by fewer than six rods (default). Only
            analyses that set every state themselves (the test oracles of the dynamics) may
            pass False: MuJoCo's platform could then turn where pkmkit's cannot.

    Raises:
        UnsupportedExportError: a machine MuJoCo would hold differently (module docstring).
    """
    _check(machine, require_held_platform)
    model = machine.model
    strut = model.rod_kind == STRUT
    given = masses is not None
    masses = _masses(machine, masses)
    _, cylinder, piston_length = masses.strut_parts(model.n_rods)
    short = np.flatnonzero(strut & ((cylinder <= 0) | (piston_length <= 0)))
    if short.size:
        raise UnsupportedExportError(
            FORMAT, machine.id, f"strut rod {int(short[0]) + 1} has a cylinder or piston of no "
            "length: give cylinder_length and piston_length in the masses")
    q0 = np.asarray(machine.home_q, dtype=float)
    p0, rot0, tips = platform_points(machine, machine.home_pose)  # tips: joint centres (m, 3)
    directions: dict[int, np.ndarray] = {}
    bodies, connects = [], []
    # a planar machine on hinges and a planar joint (the oracles of the dynamics, which set
    # every state themselves, keep the spatial joints)
    planar = require_held_platform and machine_family(machine) == "planar"
    rod_joint = ('<joint name="hinge{j}" type="hinge" axis="0 0 1"/>' if planar
                 else '<joint name="ball{j}" type="ball"/>')
    for k in range(model.n_actuators):
        leg = int(np.flatnonzero(model.leg_actuator == k)[0])
        body = {STRUT: _strut_body, CRANK: crank_body}.get(int(model.leg_kind[leg]), _slide_body)
        bodies.append(body(machine, k, q0, tips, masses, rod_joint, directions, connects))
    inertia = np.asarray(masses.platform_inertia, dtype=float)
    placeholder = not inertia.any()
    if placeholder:
        radius = float(np.linalg.norm(model.rod_platform, axis=1).max()) or 0.1
        inertia = np.eye(3) * 0.4 * max(masses.platform_mass, 1e-6) * radius**2
    full = inertia[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
    quat = _quaternion(rot0)
    equality = "\n".join(
        f'    <connect body1="{b}" body2="platform" anchor="{_f(t)}" solref="{2 * TIMESTEP:g} 1" '
        f'solimp="0.9999 0.9999 0.001"/>' for b, t in connects)
    actuators = "\n".join(f'    <motor name="{model.actuator_names[k]}" joint="act{k}" gear="1"/>'
                          for k in range(model.n_actuators))
    note = (" (placeholder: a sphere of the platform's mass; pkmkit's masses give none)"
            if placeholder else "")
    cranks = bool((model.leg_kind == CRANK).any())
    crank_note = f"\n       Masses: {masses_note(given)}." if cranks else ""
    platform_joint = "planar joint (platform_x, _y, _rz)" if planar else "free joint"
    xml = f"""<mujoco model="{_attr(machine.name)}">
  <!-- pkmkit machine {_attr(machine.id)}: joints act{{k}} hold pkmkit's actuator coordinates
       (m, or rad for a crank), the platform's {platform_joint} its pose at the platform
       reference point; SI units.{crank_note} -->
  <compiler angle="radian"/>
  <option gravity="{_f(masses.gravity)}" timestep="{TIMESTEP:g}" tolerance="1e-12"
          iterations="200" jacobian="dense">
    <flag contact="disable"/>
  </option>
  <worldbody>
{chr(10).join(bodies)}
    <body name="platform" pos="{_f(p0)}" quat="{_f(quat)}">{_platform_joints(planar, p0)}
      <!-- platform inertia{note} -->
      <inertial pos="{_f(masses.platform_com)}" mass="{max(masses.platform_mass, 1e-6):.17g}"
                fullinertia="{_f(full)}"/>
    </body>
  </worldbody>
  <equality>
{equality}
  </equality>
  <actuator>
{actuators}
  </actuator>
</mujoco>
"""
    return MjcfLayout(xml=xml, rod_direction=directions,
                      actuator_joints=tuple(f"act{k}" for k in range(model.n_actuators)),
                      placeholder_inertia=placeholder,
                      illustrative=(masses_note(given) if cranks and given else
                                    "illustrative masses: pkmkit has no mass model of crank "
                                    "actuators" if cranks else ""))


def _strut_body(machine, k: int, q0: np.ndarray, tips: np.ndarray, masses, rod_joint: str,
                directions: dict, connects: list) -> str:
    """The MJCF bodies of strut k at home (cylinder on a ball joint, piston on the slide
    ``act{k}``); records its rod's home direction and ``connect`` anchor (``rod_joint``
    unused: a strut's base joint is a ball joint)."""
    model = machine.model
    leg = int(np.flatnonzero(model.leg_actuator == k)[0])
    (j,) = np.flatnonzero(model.rod_actuator == k)
    piston, cyl_len, pis_len = masses.strut_parts(model.n_rods)
    base = model.rod_base[j]
    tip = tips[j] - base
    s0 = float(np.linalg.norm(tip))
    e0 = tip / s0
    directions[int(j)] = e0
    radius = max(float(masses.rod_radius[j]), 1e-4)
    connects.append((f"piston{j}", tip))
    return (f'    <!-- actuator {model.actuator_names[k]}: strut ({model.leg_names[leg]}) -->\n'
            f'    <body name="cyl{j}" pos="{_f(base)}"><joint name="ball{j}" type="ball"/>'
            f'<geom type="cylinder" fromto="0 0 0 {_f(cyl_len[j] * e0)}" '
            f'size="{radius:.17g}" mass="{masses.rod_mass[j]:.17g}"/>'
            f'<body name="piston{j}"><joint name="act{k}" type="slide" axis="{_f(e0)}" '
            f'ref="{q0[k]:.17g}" armature="{masses.carriage_mass[k]:.17g}"/>'
            f'<geom type="cylinder" fromto="{_f((s0 - pis_len[j]) * e0)} {_f(tip)}" '
            f'size="{radius:.17g}" mass="{piston[j]:.17g}"/></body></body>')


def _slide_body(machine, k: int, q0: np.ndarray, tips: np.ndarray, masses, rod_joint: str,
                directions: dict, connects: list) -> str:
    """The MJCF body of slide k at home (carriage on the slide ``act{k}``, its rods on
    ``rod_joint``s); records each rod's home direction and ``connect`` anchor."""
    model = machine.model
    leg = int(np.flatnonzero(model.leg_actuator == k)[0])
    u = model.leg_axis[leg]
    carriage = model.leg_base[leg] + q0[k] * u
    children = []
    for j in np.flatnonzero(model.rod_actuator == k):
        joint_pt = model.rod_base[j] + q0[k] * model.rod_axis[j]
        tip = tips[j] - joint_pt
        directions[int(j)] = tip / np.linalg.norm(tip)
        children.append(
            f'<body name="rod{j}" pos="{_f(joint_pt - carriage)}">'
            f'{rod_joint.format(j=j)}<geom type="cylinder" fromto="0 0 0 '
            f'{_f(tip)}" size="{max(float(masses.rod_radius[j]), 1e-4):.17g}" '
            f'mass="{masses.rod_mass[j]:.17g}"/></body>')
        connects.append((f"rod{j}", tip))
    return (f'    <!-- actuator {model.actuator_names[k]}: slide ({model.leg_names[leg]}) -->\n'
            f'    <body name="carriage{k}" pos="{_f(carriage)}"><joint name="act{k}" '
            f'type="slide" axis="{_f(u)}" ref="{q0[k]:.17g}"/><geom type="box" '
            f'size="0.02 0.02 0.02" mass="{masses.carriage_mass[k]:.17g}"/>'
            + "".join(children) + "</body>")


def _masses(machine, masses):
    """The masses the model takes (module docstring), checked; a machine with cranks takes the
    illustrative ones of :mod:`pkmkit.export.mjcf_cranks` unless masses are given (their
    carriage masses are then the arms')."""
    model = machine.model
    if (model.leg_kind == CRANK).any():
        from pkmkit.export.urdf import require_closed_rods
        from pkmkit.solve.rod_closure import rod_base_points

        q0 = np.asarray(machine.home_q, dtype=float)
        bases = rod_base_points(model, q0[:, None])[:, :, 0].T
        require_closed_rods(machine, q0, bases, platform_points(machine, machine.home_pose)[2],
                            FORMAT)
        masses = crank_masses(machine) if masses is None else masses
    elif masses is None:
        from pkmkit.dynamics.defaults import default_masses

        strut = model.rod_kind == STRUT
        masses = default_masses(machine, tubes_at_home=bool((model.rod_length[strut] <= 0)
                                                            .any()))
    masses.check(machine)
    return masses


def _platform_joints(planar: bool, p0: np.ndarray) -> str:
    """A free joint, or for a planar machine the planar joint: slides ``platform_x``,
    ``platform_y`` (their qpos pkmkit's x, y) and a hinge ``platform_rz`` about z (0 at
    home)."""
    if not planar:
        return '<freejoint name="platform"/>'
    return (f'<joint name="platform_x" type="slide" axis="1 0 0" ref="{p0[0]:.17g}"/>'
            f'<joint name="platform_y" type="slide" axis="0 1 0" ref="{p0[1]:.17g}"/>'
            '<joint name="platform_rz" type="hinge" axis="0 0 1"/>')


def mjcf_model(machine, masses=None) -> str:
    """The MJCF text of ``machine`` (see :func:`mjcf_layout`)."""
    return mjcf_layout(machine, masses).xml


def _attr(text: str) -> str:
    return (str(text).replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")
            .replace(">", "&gt;").replace("--", "- -"))


def _quaternion(rot: np.ndarray) -> np.ndarray:
    """MuJoCo's (w, x, y, z) of a rotation matrix."""
    from pkmkit.spatial.rotation import rotation_class

    x, y, z, w = rotation_class().from_matrix(rot).as_quat()
    return np.array([w, x, y, z])


def set_configuration(model, data, machine, layout: MjcfLayout, x: np.ndarray,
                      q: np.ndarray) -> None:
    """Put a loaded model in pkmkit's configuration: actuated joints at ``q (n,)``, every rod's
    ball joint turned onto its rod (the least rotation from its home direction), the platform at
    the pose ``x`` (``(dims,)``: position, and rotation vector for a full pose)."""
    from pkmkit.solve.rod_closure import rod_base_points
    from pkmkit.spatial.rotation import rotation_class

    rod = machine.model
    rotation = rotation_class()
    planar = _has_joint(model, "platform_rz")  # the planar layout (hinges, planar joint)
    p, rot, _ = platform_points(machine, x)
    for k in range(rod.n_actuators):
        data.qpos[model.jnt_qposadr[model.joint(f"act{k}").id]] = q[k]
    base = rod_base_points(rod, np.asarray(q, dtype=float)[:, None])[:, :, 0].T  # (m, 3)
    for j, e0 in layout.rod_direction.items():
        d = p + rot @ rod.rod_platform[j] - base[j]
        e = parent_turn(machine, j, np.asarray(q, dtype=float)).T @ (d / np.linalg.norm(d))
        axis = np.cross(e0, e)
        sin = float(np.linalg.norm(axis))
        turn = (rotation.from_rotvec(axis / sin * np.arctan2(sin, float(e0 @ e))) if sin > 1e-15
                else rotation.identity())
        if planar:  # a hinge about z: the turn's z component: the turn's z component
            data.qpos[model.jnt_qposadr[model.joint(f"hinge{j}").id]] = turn.as_rotvec()[2]
            continue
        qx, qy, qz, qw = turn.as_quat()
        adr = model.jnt_qposadr[model.joint(f"ball{j}").id]
        data.qpos[adr:adr + 4] = [qw, qx, qy, qz]
    if planar:
        for axis, value in zip("xy", p[:2], strict=True):
            data.qpos[model.jnt_qposadr[model.joint(f"platform_{axis}").id]] = value
        data.qpos[model.jnt_qposadr[model.joint("platform_rz").id]] = 0.0
        return
    free = model.jnt_qposadr[model.body("platform").jntadr[0]]
    data.qpos[free:free + 3] = p
    data.qpos[free + 3:free + 7] = _quaternion(rot)


def check_mjcf_model(machine, xml: str) -> float | None:
    """Load a written model in MuJoCo (when installed) and check it against pkmkit: at home and
    at pkmkit's sample configurations (:func:`~pkmkit.export.base.sample_poses`, with their
    inverse model), put in MuJoCo's joints, every closure holds. Returns the largest violation
    (m), or None without MuJoCo.

    Raises:
        ExportCheckError: MuJoCo refuses the model, or a violation beyond 1e-9 m.
    """
    loaded = load_mjcf(xml)
    if loaded is None:
        return None
    mujoco, model, data = loaded
    layout = mjcf_layout(machine, require_held_platform=False)
    poses, q = sample_poses(machine)
    worst = 0.0
    for x, qk in zip([machine.home_pose, *poses], [machine.home_q, *q], strict=True):
        set_configuration(model, data, machine, layout, x, qk)
        mujoco.mj_forward(model, data)
        if data.nefc:
            worst = max(worst, float(np.abs(data.efc_pos[: data.nefc]).max()))
    if not worst <= 1e-9:
        raise ExportCheckError(f"the generated MuJoCo model does not close pkmkit's "
                               f"configurations (off by {worst:.3g} m): not written")
    return worst


def load_mjcf(xml: str):
    """``(mujoco module, MjModel, MjData)`` of an MJCF text, or None when MuJoCo is not
    installed.

    Raises:
        ExportCheckError: MuJoCo refuses the model (its message on one line).
    """
    try:
        import mujoco
    except ImportError:
        return None
    try:
        model = mujoco.MjModel.from_xml_string(xml)
    except ValueError as exc:
        detail = "; ".join(line.strip() for line in str(exc).splitlines() if line.strip())
        raise ExportCheckError(f"MuJoCo refuses the generated model: {detail}") from None
    return mujoco, model, mujoco.MjData(model)


def _has_joint(model, name: str) -> bool:
    try:
        model.joint(name)
    except KeyError:
        return False
    return True
