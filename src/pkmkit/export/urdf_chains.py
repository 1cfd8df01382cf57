"""A URDF spanning tree of a joint-chain machine (Tripteor X7, TriMule 600, crank–slider,
joint-chain machine files) and its loop closures, and the check that reads it back.

A joint-chain machine is already a set of serial chains of one-DOF joints (docs/joint-chains.md):
every element places a frame in the previous one (its invariant, the defects applied), and a
joint then turns about or slides along that frame's z by its variable. The tree written here:

- ``base``, pkmkit's base frame (SI units);
- every leg from the base, element by element: a joint element is a URDF ``revolute`` joint
  (``continuous`` when pkmkit gives no stroke) or ``prismatic`` joint **named as pkmkit's
  variable** (``psi1``, ``Q1`` …: its value *is* pkmkit's joint value, rad or m), its origin the
  element's frame (``xyz``/``rpy``), its axis z; a fixed element is a ``fixed`` joint. Each joint
  carries the link ``<name>_body``. An element shared by several legs (the TriMule's ψ1) is
  written once: the legs branch after it;
- the first leg ends on the link ``platform`` (pkmkit's platform frame); the head, if any,
  continues from it to the link ``tool`` (the tool frame) and ``tool_point`` (``tool_length``
  along the tool frame's z).

The **closures** (``NAME.closures.yaml``): every other leg's last link is welded to
``platform`` — the two frames coincide (type ``6D``: position and orientation, constrained
``[x, y, z, rx, ry, rz]``). In Pinocchio each pair is a
``RigidConstraintModel(ContactType.CONTACT_6D, …, ReferenceFrame.LOCAL)``. The YAML also holds the
actuated joints (``name_mot``), the tool length and an assembled configuration (pkmkit's home).

The URDF is kinematic — pkmkit has no mass model of joint-chain machines — unless a masses file
gives the bodies' masses (:mod:`pkmkit.export.chain_masses`): the links it names then carry
them (``inertial``), the others none.
A machine with defects closes its legs in least squares (docs/joint-chains.md): defects that
are compatible at first order (what a calibration identifies) leave a second-order misfit
(4·10⁻⁸ m for 2 mrad on the Tripteor), which the welds then carry. Refused
(:class:`~pkmkit.export.base.UnsupportedExportError`): a misfit beyond :data:`MISFIT`
(incompatible defects of a hyperstatic machine: a tree with exact closures would be another
machine), and an element shared by legs other than as a common first part.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.export.base import ExportCheckError, UnsupportedExportError
from pkmkit.export.urdf import (
    FORMAT,
    UNLIMITED,
    UrdfJoint,
    _attr,
    _inertial,
    _joint,
    _link,
    _rpy,
)
from pkmkit.export.urdf_check import (
    closure_pairs,
    link_placements,
    pinocchio_configuration,
    pinocchio_module,
    read_urdf,
)

#: Largest closure residual and tool-frame error a written export may have beyond pkmkit's own
#: closure misfit (m; rotations × the machine's characteristic length).
TOLERANCE = 1e-9
#: Largest closure misfit (m) of pkmkit's model a URDF with exact welds may stand for: defects
#: compatible at first order (calibrated ones) leave a second-order misfit, ~1e-8 m for 1 mrad;
#: an incompatible defect leaves ~ its own size.
MISFIT = 1e-7


@dataclass(frozen=True)
class ChainUrdfExport:
    """The texts of a joint-chain URDF export and their layout.

    Attributes:
        urdf: the URDF document.
        closures: the closures YAML.
        joints: the movable joints, each with its pkmkit variable index (``role``
            ``"actuator"`` or ``"passive"``).
        closure_frames: ``(link, "platform")`` pairs welded by the closures.
        inertial: whether links carry masses (a masses file's; pkmkit's dynamics model has
            none of joint chains).
        closure_kind: ``"6D"``; ``massless``: what pkmkit has no masses of.
        masses_note: where the masses come from ("" without).
    """

    urdf: str
    closures: str
    joints: tuple[UrdfJoint, ...]
    closure_frames: tuple[tuple[str, str], ...]
    inertial: bool = False
    closure_kind: str = "6D"
    massless: str = "joint chains"
    masses_note: str = ""


@dataclass(frozen=True)
class ChainNode:
    """One element of a joint-chain machine's spanning tree.

    Attributes:
        name: the element's name (the joint's: pkmkit's variable name for a joint element).
        parent: the link it hangs from (``base``, ``platform`` or another node's ``child``).
        child: the link it carries, ``<name>_body``.
        frame: ``(4, 4)`` the element's frame in the parent link (defects applied); the joint
            then turns about or slides along this frame's z by its variable.
        type: ``"F"`` (fixed), ``"R"`` (revolute) or ``"P"`` (prismatic).
        variable: pkmkit's variable index (-1 for a fixed element).
    """

    name: str
    parent: str
    child: str
    frame: np.ndarray
    type: str
    variable: int


@dataclass(frozen=True)
class ChainTree:
    """The spanning tree every joint-chain export writes (URDF here, MJCF in
    :mod:`pkmkit.export.mjcf_chains`).

    Attributes:
        legs: the legs' nodes from ``base``, leg by leg, an element shared by several legs
            (their common first part) once.
        head: the head's nodes from ``platform`` to the tool frame.
        ends: ``(L,)`` every leg's last link; the first carries ``platform`` (identity), the
            others are welded to it.
        tool: the link that is the tool frame (the head's last link, or ``platform``).
    """

    legs: tuple[ChainNode, ...]
    head: tuple[ChainNode, ...]
    ends: tuple[str, ...]
    tool: str


def _node(model, e: int, parent: str) -> ChainNode:
    spec = model.elements[e]
    return ChainNode(spec.name, parent, f"{spec.name}_body", np.asarray(model.frames[e]),
                     spec.type, int(model.element_variable[e]) if spec.type != "F" else -1)


def chain_tree(machine) -> ChainTree:
    """The spanning tree of a joint-chain machine's legs and head (:class:`ChainTree`).

    Raises:
        UnsupportedExportError: an element shared by legs other than as their common first
            part (not a tree).
    """
    model = machine.model
    placed: dict[int, str] = {}
    nodes, ends = [], []
    for leg_name, leg in zip(model.leg_names, model.legs, strict=True):
        parent, prefix = "base", True
        for e in leg:
            if e in placed:
                if not prefix:
                    raise UnsupportedExportError(
                        FORMAT, machine.id, f"element {model.elements[e].name!r} of {leg_name} "
                        "is shared with another leg after elements of its own: not a tree")
                parent = placed[e]
                continue
            prefix = False
            nodes.append(_node(model, e, parent))
            parent = placed[e] = nodes[-1].child
        ends.append(parent)
    head, parent = [], "platform"
    for e in model.head:
        head.append(_node(model, e, parent))
        parent = head[-1].child
    return ChainTree(legs=tuple(nodes), head=tuple(head), ends=tuple(ends), tool=parent)


def _element_joint(model, node: ChainNode) -> tuple[str, UrdfJoint | None]:
    """The URDF joint text of a tree node and its movable joint record (None for a fixed
    element)."""
    frame, parent, child = node.frame, node.parent, node.child
    xyz, rpy = frame[:3, 3], _rpy(frame[:3, :3])
    if node.type == "F":
        return _joint(node.name, "fixed", parent, child, xyz, rpy), None
    v = node.variable
    limits = (float(model.q_min[v]), float(model.q_max[v]))
    finite = bool(np.isfinite(limits).all())
    if node.type == "R":
        kind = "revolute" if finite else "continuous"
    else:
        kind = "prismatic"
        limits = tuple(float(np.sign(x) * UNLIMITED) if not np.isfinite(x) else x
                       for x in limits)
        finite = True
    text = _joint(node.name, kind, parent, child, xyz, rpy, axis=(0, 0, 1),
                  limits=limits if finite else None)
    role = "actuator" if model.actuated[v] else "passive"
    return text, UrdfJoint(node.name, kind, role, v)


def require_exact_closure(machine, fmt: str = FORMAT) -> None:
    """Refuse (for the format ``fmt``) a machine whose legs close at home only in least squares
    beyond :data:`MISFIT` (incompatible defects)."""
    res = machine.fk(machine.home_q, full_output=True, strokes="ignore")
    residual = float(np.max(res.closure_residual))
    if not residual <= MISFIT:
        raise UnsupportedExportError(
            fmt, machine.id, f"its legs close only in least squares at home (misfit "
            f"{residual:.3g} m > {MISFIT:g} m: incompatible defects of a hyperstatic machine); "
            f"a {fmt.upper()} model whose closures hold exactly would describe another machine "
            "— keep the compatible defects (pkmkit errors MACHINE --compatibility)")


def chain_urdf_export(machine, *, name: str = "machine", masses=None) -> ChainUrdfExport:
    """The URDF tree and closures YAML of a joint-chain machine (module docstring).

    Args:
        masses: the bodies' masses of a masses file
            (:class:`~pkmkit.export.chain_masses.ChainBodyMasses`; the links it names carry
            them, the others none), or None: a kinematic URDF.

    Raises:
        UnsupportedExportError: legs closing only in least squares, or an element shared by
            legs other than as their common first part.
    """
    require_exact_closure(machine)
    model = machine.model
    tree = chain_tree(machine)
    links, joints, movable = [_link("base")], [], []

    def inertial(body: str) -> str:
        if masses is None or body not in masses.bodies:
            return ""
        b = masses.bodies[body]
        return _inertial(b.mass, b.com, b.inertia)

    def add(nodes) -> None:
        for node in nodes:
            text, record = _element_joint(model, node)
            joints.append(text)
            links.append(_link(node.child, inertial(node.name)))
            if record is not None:
                movable.append(record)

    add(tree.legs)
    ends = tree.ends
    joints.append(_joint("platform_frame", "fixed", ends[0], "platform"))
    links.append(_link("platform", inertial("platform")))
    add(tree.head)
    parent = tree.tool
    joints.append(_joint("tool_frame", "fixed", parent, "tool"))
    joints.append(_joint("tool_point_frame", "fixed", "tool", "tool_point",
                         (0.0, 0.0, float(machine.tool_length))))
    links += [_link("tool"), _link("tool_point")]
    pairs = tuple((end, "platform") for end in ends[1:])
    values = joint_values(machine, machine.home_q)
    note = ("Kinematic: pkmkit has no masses of joint chains" if masses is None else
            masses.note([], short=True) + "; the links it does not name carry none")
    urdf = f"""<?xml version="1.0"?>
<robot name="{_attr(machine.id)}">
  <!-- pkmkit machine {_attr(machine.id)} ({_attr(machine.name)}): the spanning tree of its
       joint chains; every other leg's end is welded to the platform in the closures YAML
       beside this file. SI units (m, rad). Joints are named as pkmkit's joint variables and
       hold their values. {_attr(note)}. Limits
       {UNLIMITED:g} mean none. -->
{chr(10).join(links)}
{chr(10).join(joints)}
</robot>
"""
    home = "\n".join(f"  {k}: {v:.17g}" for k, v in values.items())
    closures = f"""# Loop closures of {name}.urdf: pkmkit machine {machine.id!r} ({machine.name}).
# The URDF is a spanning tree; each closure below welds a leg's last frame to the platform
# frame: the two frames coincide (type 6D: position and orientation). In Pinocchio, per pair:
#   RigidConstraintModel(ContactType.CONTACT_6D, model, f1.parentJoint, f1.placement,
#                        f2.parentJoint, f2.placement, ReferenceFrame.LOCAL)
# with f1, f2 = model.frames[model.getFrameId(name)]. SI units (m, rad).
closed_loop:
{chr(10).join(f"  - [{a}, {b}]" for a, b in pairs)}
type: [{", ".join("6D" for _ in pairs)}]
constrained: [{", ".join("[x, y, z, rx, ry, rz]" for _ in pairs)}]
# Actuated joints (pkmkit's actuators, in its order).
name_mot: [{", ".join(model.actuator_names)}]
joint_name: []
joint_type: []
# The tool point lies tool_length (m) along the tool frame's z (link tool_point).
tool_length: {float(machine.tool_length):.17g}
# An assembled configuration, pkmkit's home: joint name -> value (m or rad).
home:
{home}
"""
    return ChainUrdfExport(urdf=urdf, closures=closures, joints=tuple(movable),
                           closure_frames=pairs, inertial=masses is not None,
                           masses_note="" if masses is None else note)


def joint_values(machine, q) -> dict[str, float]:
    """Every joint variable's value (rad or m) at actuator values ``q (n,)``: the actuators
    and the passive joints of pkmkit's direct model, by variable name.

    Raises:
        ExportCheckError: pkmkit's direct model finds no assembly at ``q``.
    """
    return joint_assembly(machine, q)[0]


def joint_assembly(machine, q):
    """:func:`joint_values` and the direct model's full result at ``q`` (one solve)."""
    model = machine.model
    res = machine.fk(np.asarray(q, dtype=float), full_output=True, strokes="ignore")
    if not np.isfinite(res.passive).all():
        raise ExportCheckError(f"no assembly of {machine.id} at q = {np.asarray(q).tolist()}")
    out = dict(zip(res.passive_names, (float(v) for v in np.ravel(res.passive)), strict=True))
    out.update(zip(model.actuator_names, (float(v) for v in np.ravel(q)), strict=True))
    return {name: out[name] for name in model.variables}, res


def sample_configurations(machine, n: int = 12, seed: int = 0) -> np.ndarray:
    """``(n + 1, n_act)`` actuator vectors: home, then uniform draws within the strokes (home
    ± 0.05 where a stroke is unbounded) that pkmkit's direct model assembles."""
    rng = np.random.default_rng(seed)
    model = machine.model
    lo = np.asarray(model.q_min)[model.actuated]
    hi = np.asarray(model.q_max)[model.actuated]
    home = np.asarray(machine.home_q, dtype=float)
    lo = np.where(np.isfinite(lo), lo, home - 0.05)
    hi = np.where(np.isfinite(hi), hi, home + 0.05)
    draws = rng.uniform(lo, hi, (4 * n, home.size))
    res = machine.fk(draws, full_output=True, strokes="ignore")
    good = draws[np.isfinite(res.passive).all(axis=1) & (res.closure_residual <= MISFIT)]
    return np.vstack([home, good[:n]])


def _pinocchio_reader(export: ChainUrdfExport, pin):
    try:
        model = pin.buildModelFromXML(export.urdf)
    except (RuntimeError, ValueError) as exc:
        raise ExportCheckError(f"Pinocchio refuses the generated URDF: {exc}") from None
    data = model.createData()
    pairs = [(model.getFrameId(a), model.getFrameId(b)) for a, b in _pairs(export)]
    tool = model.getFrameId("tool")

    def evaluate(values: dict[str, float]) -> tuple[list[np.ndarray], np.ndarray]:
        pin.forwardKinematics(model, data, pinocchio_configuration(pin, model, values))
        pin.updateFramePlacements(model, data)
        gaps = [np.linalg.inv(data.oMf[a].homogeneous) @ data.oMf[b].homogeneous
                for a, b in pairs]
        return gaps, data.oMf[tool].homogeneous

    return evaluate


def _python_reader(export: ChainUrdfExport):
    joints = read_urdf(export.urdf)

    def evaluate(values: dict[str, float]) -> tuple[list[np.ndarray], np.ndarray]:
        placed = link_placements(joints, values)
        gaps = [np.linalg.inv(placed[a]) @ placed[b] for a, b in _pairs(export)]
        return gaps, placed["tool"]

    return evaluate


def _pairs(export: ChainUrdfExport) -> list[tuple[str, str]]:
    return closure_pairs(export.closures, "6D")


def frame_error(transform: np.ndarray, length: float) -> float:
    """Distance of a ``(4, 4)`` relative transform from the identity (m; its rotation angle
    × ``length``)."""
    cos = np.clip((np.trace(transform[:3, :3]) - 1.0) / 2.0, -1.0, 1.0)
    angle = float(np.arccos(cos)) if cos < 1 - 1e-12 else float(
        np.linalg.norm(transform[:3, :3] - transform[:3, :3].T) / np.sqrt(8))
    return max(float(np.linalg.norm(transform[:3, 3])), angle * length)


def check_chain_urdf_export(machine, export: ChainUrdfExport, *, use_pinocchio: bool | None = None
                            ) -> tuple[float, str]:
    """Read the tree back and put it in pkmkit's configurations (home and
    :func:`sample_configurations`, every joint at pkmkit's direct model): every closure's two
    frames must coincide and the tool frame sit where pkmkit puts it, to :data:`TOLERANCE`
    beyond pkmkit's own closure misfit r there (welds within 2r: the tree's platform is leg
    1's end, pkmkit's the least-squares one; the tool within 2r). Returns ``(largest error (m),
    reader)``.

    Raises:
        ExportCheckError: a closure or the tool frame off by more than that.
    """
    pin = pinocchio_module(use_pinocchio)
    evaluate = _pinocchio_reader(export, pin) if pin is not None else _python_reader(export)
    length = max(float(machine.model.characteristic_length), 1e-3)
    worst = 0.0
    for q in sample_configurations(machine):
        values, res = joint_assembly(machine, q)
        gaps, tool = evaluate(values)
        expected = expected_tool(res)
        errors = [frame_error(g, length) for g in gaps]
        errors.append(frame_error(np.linalg.inv(expected) @ tool, length))
        misfit = 2 * float(np.max(res.closure_residual))
        if not max(errors) <= misfit + TOLERANCE:
            raise ExportCheckError(
                f"the generated URDF does not close pkmkit's configurations (off by "
                f"{max(errors):.3g} m where pkmkit's own misfit allows {misfit:.3g} m): not "
                "written")
        worst = max(worst, *errors)
    return worst, "pinocchio" if pin is not None else "python"


def expected_tool(res) -> np.ndarray:
    """``(4, 4)`` the tool frame of pkmkit's direct-model result ``res`` (one configuration)."""
    from pkmkit.spatial.rotation import rotation_class

    frame = np.array(res.tool_frame, dtype=float).ravel()  # scipy: writeable buffers only
    out = np.eye(4)
    out[:3, :3] = rotation_class().from_rotvec(frame[3:]).as_matrix()
    out[:3, 3] = frame[:3]
    return out
