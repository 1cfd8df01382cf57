"""A MuJoCo model (MJCF) of a joint-chain machine (Tripteor X7, TriMule 600, crank–slider,
joint-chain machine files), nominal or calibrated, and the check that loads it back.

The bodies are the spanning tree the URDF export writes (:func:`pkmkit.export.urdf_chains.
chain_tree`): every leg from the world, element by element, a body per element placed by the
element's frame (defects applied) with a ``hinge`` (R) or ``slide`` (P) joint along its z
**named as pkmkit's joint variable**; an element shared by several legs (the TriMule's ψ1) is
one body and the legs branch after it. The model is built at pkmkit's home configuration: each
joint's ``ref`` is its home value, so **qpos of a joint is pkmkit's joint value** (rad or m) and
MuJoCo's reference configuration ``qpos0`` is assembled. The body ``platform`` (pkmkit's platform
frame) sits on the first leg's last body; the head's bodies continue from it to the tool frame,
which carries the sites ``tool`` (the tool frame) and ``tool_point`` (``tool_length`` along its
z). Finite strokes are joint ranges (``limited``).

**Loops**: every other leg's last body is welded to ``platform`` by a ``weld`` equality
constraint (``relpose`` identity: the two frames coincide in position and orientation, the 6D
welds of the URDF closures; stiff: time constant two steps, as the rod-leg export).

**Actuators**: a ``motor`` per actuated joint (gear 1): force (N) on a slide, torque (N·m) on a
hinge.

**Masses** (pkmkit's dynamics model has none of joint chains, :mod:`pkmkit.dynamics.masses`
refuses them): a masses file's, body by body (:mod:`pkmkit.export.chain_masses`: mass, centre
of mass and inertia of the bodies it names, placeholders elsewhere, the file says which), or
else the *illustrative* lumped masses of pkmkit's gravity-deflection model
(:func:`pkmkit.stiffness.chain_gravity.illustrative_masses`: a 50 kg platform with half of every
leg's tube at the platform frame origin, an 80 kg head at the spindle nose, the tool frame's
origin) as small spheres; every other body is a :data:`LINK_MASS` kg sphere of
:data:`LINK_RADIUS` m at its frame origin (a placeholder: MuJoCo needs a mass on every moving
body). The file says so. No source gives these masses: simulate the kinematics, the weights only
as illustrations. Contacts are off.

A calibrated machine closes its legs in least squares; compatible defects leave a second-order
misfit the welds carry (as in the URDF export); a misfit beyond
:data:`~pkmkit.export.urdf_chains.MISFIT` is refused.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from pkmkit.export.base import ExportCheckError, UnsupportedExportError
from pkmkit.export.mjcf import TIMESTEP, _attr, _f, _quaternion, load_mjcf
from pkmkit.export.urdf_chains import (
    TOLERANCE,
    ChainNode,
    chain_tree,
    expected_tool,
    frame_error,
    joint_assembly,
    joint_values,
    require_exact_closure,
    sample_configurations,
)

FORMAT = "mjcf"
#: Placeholder mass (kg) and sphere radius (m) of every body the lumped masses leave out.
LINK_MASS = 0.01
LINK_RADIUS = 0.02


@dataclass(frozen=True)
class ChainMjcf:
    """An MJCF text of a joint-chain machine and its layout.

    Attributes:
        xml: the MJCF document.
        joints: every joint's name (pkmkit's variables, in its order).
        actuator_joints: the actuated joints, in pkmkit's actuator order.
        welds: ``(leg end body, "platform")`` pairs of the weld constraints.
        masses_note: where the masses come from.
        illustrative: what the masses are (the command's words).
    """

    xml: str
    joints: tuple[str, ...]
    actuator_joints: tuple[str, ...]
    welds: tuple[tuple[str, str], ...]
    masses_note: str
    illustrative: str = ("illustrative lumped masses: pkmkit has no dynamics masses of joint "
                         "chains")


def _home_placement(node: ChainNode, value: float) -> np.ndarray:
    """``(4, 4)`` the node's body frame in its parent at the joint value ``value``."""
    motion = np.eye(4)
    if node.type == "R":
        c, s = np.cos(value), np.sin(value)
        motion[:2, :2] = [[c, -s], [s, c]]
    elif node.type == "P":
        motion[2, 3] = value
    return node.frame @ motion


def _sphere(mass: float, radius: float, pos=(0.0, 0.0, 0.0)) -> str:
    inertia = 0.4 * mass * radius**2
    return (f'<inertial pos="{_f(pos)}" mass="{mass:.17g}" '
            f'diaginertia="{inertia:.17g} {inertia:.17g} {inertia:.17g}"/>')


def _inertial(body) -> str:
    """A :class:`~pkmkit.export.chain_masses.BodyMass` as MJCF (full inertia about its
    centre of mass, body frame)."""
    full = body.inertia[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
    return (f'<inertial pos="{_f(body.com)}" mass="{body.mass:.17g}" '
            f'fullinertia="{_f(full)}"/>')


def _file_bodies(machine, tree, masses) -> str:
    """The nested bodies with the masses of a masses file (:mod:`pkmkit.export.chain_masses`),
    the tool sites on the tool body."""
    children: dict[str, list[ChainNode]] = {}
    for node in (*tree.legs, *tree.head):
        children.setdefault(node.parent, []).append(node)
    home = joint_values(machine, machine.home_q)
    tool_sites = (f'<site name="tool"/><site name="tool_point" '
                  f'pos="0 0 {float(machine.tool_length):.17g}"/>')

    def inside(link: str, depth: int) -> str:
        pad = "  " * depth
        parts = []
        if link == tree.ends[0]:
            parts.append(f'{pad}<body name="platform">{_inertial(masses.body("platform"))}'
                         + (tool_sites if tree.tool == "platform" else "") + "\n"
                         + inside("platform", depth + 1) + f"{pad}</body>\n")
        for node in children.get(link, []):
            body = _inertial(masses.body(node.name)) + (
                tool_sites if node.child == tree.tool else "")
            parts.append(f"{pad}{_body_open(machine, node, home)}{body}\n"
                         + inside(node.child, depth + 1) + f"{pad}</body>\n")
        return "".join(parts)

    return inside("base", 2)


def _body_open(machine, node: ChainNode, home_values: dict[str, float]) -> str:
    model = machine.model
    v = node.variable
    home = home_values[node.name] if v >= 0 else 0.0
    placed = _home_placement(node, home)
    text = (f'<body name="{_attr(node.child)}" pos="{_f(placed[:3, 3])}" '
            f'quat="{_f(_quaternion(placed[:3, :3]))}">')
    if v >= 0:
        kind = "hinge" if node.type == "R" else "slide"
        lo, hi = float(model.q_min[v]), float(model.q_max[v])
        limits = (f' limited="true" range="{lo:.17g} {hi:.17g}"'
                  if np.isfinite([lo, hi]).all() else ' limited="false"')
        text += (f'<joint name="{_attr(node.name)}" type="{kind}" axis="0 0 1" '
                 f'ref="{home:.17g}"{limits}/>')
    return text


def _bodies(machine, tree, masses) -> str:
    """The nested bodies of the tree, the platform and the head (MJCF text)."""
    children: dict[str, list[ChainNode]] = {}
    for node in (*tree.legs, *tree.head):
        children.setdefault(node.parent, []).append(node)
    lumped = masses.platform + 0.5 * float(np.sum(masses.legs))
    home = joint_values(machine, machine.home_q)  # pkmkit's home, assembled
    tool_sites = (f'<site name="tool"/><site name="tool_point" '
                  f'pos="0 0 {float(machine.tool_length):.17g}"/>')

    def inside(link: str, depth: int) -> str:
        pad = "  " * depth
        parts = []
        if link == tree.ends[0]:
            parts.append(f'{pad}<body name="platform">'
                         f'<!-- platform and half of every leg: {lumped:.6g} kg -->'
                         + (_sphere(lumped, 0.1) if tree.tool != "platform"
                            else _sphere(lumped + masses.head, 0.1))
                         + (tool_sites if tree.tool == "platform" else "") + "\n"
                         + inside("platform", depth + 1) + f"{pad}</body>\n")
        for node in children.get(link, []):
            if node.child == tree.tool:
                body = (f'<!-- head: {masses.head:.6g} kg at the spindle nose -->'
                        + _sphere(masses.head, 0.1) + tool_sites)
            else:
                body = _sphere(LINK_MASS, LINK_RADIUS)
            parts.append(f"{pad}{_body_open(machine, node, home)}{body}\n"
                         + inside(node.child, depth + 1) + f"{pad}</body>\n")
        return "".join(parts)

    return inside("base", 2)


def chain_mjcf(machine, masses=None) -> ChainMjcf:
    """The MJCF model of a joint-chain machine (module docstring).

    Args:
        machine: a joint-chain machine, nominal or calibrated.
        masses: the bodies' masses of a masses file
            (:class:`~pkmkit.export.chain_masses.ChainBodyMasses`), or None: the illustrative
            lumped masses of the gravity-deflection model (pkmkit's dynamics model has no
            masses of joint chains).

    Raises:
        UnsupportedExportError: rod-leg masses given, legs closing only in least squares beyond
            :data:`~pkmkit.export.urdf_chains.MISFIT`, or legs that are not a tree.
    """
    require_exact_closure(machine, FORMAT)
    from pkmkit.export.chain_masses import ChainBodyMasses
    from pkmkit.stiffness.chain_gravity import illustrative_masses

    if masses is not None and not isinstance(masses, ChainBodyMasses):
        raise UnsupportedExportError(FORMAT, machine.id, "rod-leg masses (carriages, rods) "
                                     "were given; a joint-chain machine takes its bodies' "
                                     "masses (pkmkit.export.chain_masses)")
    lumped = illustrative_masses(machine)
    tree = chain_tree(machine)
    model = machine.model
    welds = tuple((end, "platform") for end in tree.ends[1:])
    equality = "\n".join(
        f'    <weld body1="{_attr(a)}" body2="{b}" relpose="0 0 0 1 0 0 0" '
        f'solref="{2 * TIMESTEP:g} 1" solimp="0.9999 0.9999 0.001"/>' for a, b in welds)
    actuators = "\n".join(f'    <motor name="{_attr(n)}" joint="{_attr(n)}" gear="1"/>'
                          for n in model.actuator_names)
    note = (f"{lumped.note}; every other body a {LINK_MASS:g} kg sphere of {LINK_RADIUS:g} m "
            "(placeholder). pkmkit has no dynamics masses of joint chains")
    bodies, gravity = _bodies(machine, tree, lumped), lumped.gravity
    if masses is not None:
        names = ["platform", *(n.name for n in (*tree.legs, *tree.head))]
        note = masses.note(names)
        bodies, gravity = _file_bodies(machine, tree, masses), masses.gravity
    xml = f"""<mujoco model="{_attr(machine.name)}">
  <!-- pkmkit machine {_attr(machine.id)}: the spanning tree of its joint chains, every other
       leg welded to the platform (equality). Joints are named as pkmkit's joint variables and
       their qpos is pkmkit's value (rad or m); built at pkmkit's home. SI units.
       Masses: {_attr(note)}. -->
  <compiler angle="radian"/>
  <option gravity="{_f(gravity)}" timestep="{TIMESTEP:g}" tolerance="1e-12"
          iterations="200" jacobian="dense">
    <flag contact="disable"/>
  </option>
  <worldbody>
{bodies}  </worldbody>
  <equality>
{equality}
  </equality>
  <actuator>
{actuators}
  </actuator>
</mujoco>
"""
    out = ChainMjcf(xml=xml, joints=tuple(model.variables),
                    actuator_joints=tuple(model.actuator_names), welds=welds, masses_note=note)
    return out if masses is None else replace(out, illustrative=masses.note(names, short=True))


def set_joint_values(model, data, values: dict[str, float]) -> None:
    """Put every joint of a loaded chain model at ``values`` (pkmkit's variables by name)."""
    for name, value in values.items():
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = value


def body_transform(data, body: str) -> np.ndarray:
    """``(4, 4)`` a body's frame in the world of a forwarded ``data``."""
    out = np.eye(4)
    out[:3, :3] = data.body(body).xmat.reshape(3, 3)
    out[:3, 3] = data.body(body).xpos
    return out


def tool_transform(data) -> np.ndarray:
    """``(4, 4)`` the tool frame (site ``tool``) in the world of a forwarded ``data``."""
    out = np.eye(4)
    out[:3, :3] = data.site("tool").xmat.reshape(3, 3)
    out[:3, 3] = data.site("tool").xpos
    return out


def check_chain_mjcf(machine, export: ChainMjcf) -> float | None:
    """Load a written model in MuJoCo (when installed) and put it in pkmkit's configurations
    (home and :func:`~pkmkit.export.urdf_chains.sample_configurations`, every joint at pkmkit's
    direct model): every weld's two frames must coincide and the tool frame sit where pkmkit
    puts it, to :data:`~pkmkit.export.urdf_chains.TOLERANCE` beyond pkmkit's own closure misfit
    r (2r, as the URDF check); MuJoCo's own weld residuals as well. Returns the largest error
    (m), or None without MuJoCo.

    Raises:
        ExportCheckError: MuJoCo refuses the model, or an error beyond that.
    """
    loaded = load_mjcf(export.xml)
    if loaded is None:
        return None
    mujoco, model, data = loaded
    length = max(float(machine.model.characteristic_length), 1e-3)
    worst = 0.0
    for q in sample_configurations(machine):
        values, res = joint_assembly(machine, q)
        set_joint_values(model, data, values)
        mujoco.mj_forward(model, data)
        platform = body_transform(data, "platform")
        errors = [frame_error(np.linalg.inv(body_transform(data, a)) @ platform, length)
                  for a, _ in export.welds]
        errors.append(frame_error(np.linalg.inv(expected_tool(res)) @ tool_transform(data),
                                  length))
        welds = data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
        if welds.any():  # (a joint limit a sample passes is a stop, not a closure)
            errors.append(float(np.abs(data.efc_pos[: data.nefc][welds]).max()))
        misfit = 2 * float(np.max(res.closure_residual))
        if not max(errors) <= misfit + TOLERANCE:
            raise ExportCheckError(
                f"the generated MuJoCo model does not close pkmkit's configurations (off by "
                f"{max(errors):.3g} m where pkmkit's own misfit allows {misfit:.3g} m): not "
                "written")
        worst = max(worst, *errors)
    return worst

