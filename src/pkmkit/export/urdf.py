"""A URDF spanning tree of a rod-leg machine and its loop closures (a YAML file beside it).

URDF holds trees only; a parallel machine is a tree plus loop closures. The tree written here:

- ``base``, the fixed frame of pkmkit's machine (pkmkit's base frame, SI units);
- **slide** actuator k: a carriage link on a ``prismatic`` joint named as pkmkit's actuator
  (``q1``, ``rho1`` …; its value *is* pkmkit's q_k, m), the joint frame at the carriage point
  of q = 0; **crank** actuator k: an arm link on a ``revolute`` joint (``continuous`` when
  pkmkit gives no stroke) about the crank axis through its pivot, value pkmkit's crank angle
  (rad); **strut**: the rod itself carries the actuator (below);
- every rod j: a **universal joint** at its base-side joint centre, written as two
  ``continuous`` revolute joints ``rod{j}_ux`` (about the frame's x) and ``rod{j}_uy`` (about
  the next y) joined by a massless link ``rod{j}_cross``; the joint frame's z axis is the rod's
  direction at pkmkit's home configuration, so the two angles are 0 at home. (A rod's spin about
  its own axis moves nothing in pkmkit's model; a universal joint leaves it out.) A slide's or
  crank's rod is the link ``rod{j}``, its tip (the platform-side joint centre) the frame
  ``rod{j}_tip`` at (0, 0, ℓ_j); a strut is a ``cylinder{j}`` link on the universal joint and a
  ``piston{j}`` link on a ``prismatic`` joint named as the actuator along the rod, its frame at
  the rod's tip when the strut is ℓ0_j + q long;
- the **platform**: hung from rod 1's tip by a **spherical joint** written as three
  ``continuous`` revolute joints ``rod1_sx``, ``rod1_sy``, ``rod1_sz`` (x, then y, then z:
  intrinsic XYZ angles, 0 at home), its frame pkmkit's platform reference point (the pose);
  frames ``platform_b{j}`` at the other rods' platform joint centres.

The **closures** (``NAME.closures.yaml``): for every rod j ≥ 2 the ball joint between
``rod{j}_tip`` and ``platform_b{j}`` is cut — the two frames' origins coincide (type ``3D``: 3
constraints along x, y, z; their relative rotation is free). The keys ``closed_loop``, ``type``,
``name_mot``, ``joint_name``, ``joint_type`` are those closed-loop tools on Pinocchio read (e.g.
``example-parallel-robots``' loader; each pair becomes a
``pinocchio.RigidConstraintModel(ContactType.CONTACT_3D, …, ReferenceFrame.LOCAL)``); pkmkit
adds ``constrained`` and an assembled ``home`` configuration (every joint's value at pkmkit's
home).

Masses and inertias come from :mod:`pkmkit.dynamics.masses` (default: the illustrative values of
:func:`pkmkit.dynamics.defaults.default_masses`): carriages as 40 mm cubes of their mass (as the
MJCF export), rods, cylinders and pistons as uniform solid cylinders (without their inertia
about their own axis: :func:`_tube`), the platform with the masses' centre of mass and inertia
(a point mass when they give none). A strut's "carriage"
mass (the motor's translating inertia) has no URDF field: it is the YAML's ``armature``.
Machines with cranks have no mass model in pkmkit: their URDF is kinematic (no ``inertial``).
Joint limits are pkmkit's strokes; an unlimited stroke, and the effort and velocity URDF
requires but pkmkit does not give, are written as :data:`UNLIMITED`.

Joint-chain machines are written by :mod:`pkmkit.export.urdf_chains`
(:func:`pkmkit.export.urdf_writer.write_urdf` picks the writer).

Refused (:class:`~pkmkit.export.base.UnsupportedExportError`): joint chains, planar machines,
a strut actuator driving several rods, masses given for a machine with cranks, and a
translational machine whose rods do not close at its home (a calibration that tilts a crank's
axis: pkmkit keeps such a platform translating on its legs' midlines, its parallelogram rods
would not).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.export.base import UnsupportedExportError, machine_family, platform_points
from pkmkit.model.rods import CRANK, SLIDE, STRUT

FORMAT = "urdf"
#: What stands for "no limit" in the URDF's ``<limit>`` (URDF has no infinity).
UNLIMITED = 1e300
#: Side of the cube a carriage's mass is written as (m), as in the MJCF export.
CARRIAGE_SIDE = 0.04


@dataclass(frozen=True)
class UrdfJoint:
    """One movable joint of the tree: ``name``, URDF ``type``, ``role`` (``"actuator"``,
    ``"ux"``, ``"uy"``, ``"sx"``, ``"sy"``, ``"sz"``) and the rod (0-based) or actuator it
    belongs to."""

    name: str
    type: str
    role: str
    index: int


@dataclass(frozen=True)
class UrdfExport:
    """The two files of a URDF export and what setting a configuration needs.

    Attributes:
        urdf: the URDF document (the spanning tree).
        closures: the YAML document (the loop closures).
        joints: the movable joints, in tree order.
        closure_frames: ``((frame on the rod, frame on the platform), …)`` one per cut joint.
        frame0: ``(m, 3, 3)`` the orientation (world) of each rod's universal-joint frame at
            zero angles; ``parent_spin``: per rod, the actuator turning its parent (crank) or -1.
        ball_offset: ``(3, 3)`` rod 1's frame to the spherical joint's zero frame.
        inertial: the URDF has inertias (False for cranks: pkmkit has no mass model of them).
        closure_kind: ``"3D"`` (cut ball joints); ``massless``: what pkmkit has no masses of.
    """

    urdf: str
    closures: str
    joints: tuple[UrdfJoint, ...]
    closure_frames: tuple[tuple[str, str], ...]
    frame0: np.ndarray
    parent_spin: np.ndarray
    ball_offset: np.ndarray
    inertial: bool
    closure_kind: str = "3D"
    massless: str = "cranks"


def _f(v) -> str:
    return " ".join(f"{float(c):.17g}" for c in np.atleast_1d(v))


def _rpy(rot: np.ndarray) -> np.ndarray:
    """URDF's roll, pitch, yaw (``R = Rz(yaw) Ry(pitch) Rx(roll)``) of a rotation matrix."""
    import warnings

    from pkmkit.spatial.rotation import rotation_class

    with warnings.catch_warnings():  # a pitch of ±90° (a rod along x) is exact all the same
        warnings.simplefilter("ignore", UserWarning)
        return rotation_class().from_matrix(rot).as_euler("xyz")


def z_frame(e: np.ndarray) -> np.ndarray:
    """A rotation ``(3, 3)`` whose z axis is the unit vector ``e (3,)`` (its x axis across e,
    built from the world axis least aligned with e)."""
    helper = np.eye(3)[int(np.argmin(np.abs(e)))]
    x = np.cross(helper, e)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(e, x), e])


def _check(machine) -> None:
    family = machine_family(machine)
    why = None
    if family == "chain":
        why = ("a joint-chain machine is written by pkmkit.export.urdf_chains (or "
               "pkmkit.export.urdf_writer.write_urdf for any machine), not by the rod-leg writer")
    elif family == "planar":
        why = ("a planar machine is written by pkmkit.export.urdf_planar (or "
               "pkmkit.export.urdf_writer.write_urdf for any machine), not by the spatial writer")
    if why:
        raise UnsupportedExportError(FORMAT, machine.id, why)
    model = machine.model
    for k in np.unique(model.leg_actuator[model.leg_kind == STRUT]):
        if (model.rod_actuator == k).sum() != 1:
            raise UnsupportedExportError(FORMAT, machine.id, f"strut actuator "
                                         f"{model.actuator_names[k]!r} drives several rods")


def _inertial(mass: float, com, inertia: np.ndarray) -> str:
    i = np.asarray(inertia, dtype=float)
    return (f'<inertial><origin xyz="{_f(com)}" rpy="0 0 0"/><mass value="{mass:.17g}"/>'
            f'<inertia ixx="{i[0, 0]:.17g}" ixy="{i[0, 1]:.17g}" ixz="{i[0, 2]:.17g}" '
            f'iyy="{i[1, 1]:.17g}" iyz="{i[1, 2]:.17g}" izz="{i[2, 2]:.17g}"/></inertial>')


def _tube(mass: float, radius: float, start: float, length: float) -> str:
    """A uniform solid cylinder along z from ``start`` over ``length`` (m), its inertia about
    its own axis left out (0): a rod between ball joints spins idly, so that inertia never loads
    the machine; in the tree the universal joint drives the spin, and 0 keeps the dynamics the
    ball-jointed rod's (pkmkit's)."""
    across = mass * (3 * radius**2 + length**2) / 12
    inertia = np.diag([across, across, 0.0])
    return _inertial(mass, [0.0, 0.0, start + 0.5 * length], inertia)


def _link(name: str, inertial: str = "") -> str:
    return f'  <link name="{name}">{inertial}</link>' if inertial else f'  <link name="{name}"/>'


def _joint(name: str, kind: str, parent: str, child: str, xyz=(0, 0, 0), rpy=(0, 0, 0),
           axis=None, limits=None) -> str:
    text = (f'  <joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{_f(xyz)}" rpy="{_f(rpy)}"/>')
    if axis is not None:
        text += f'<axis xyz="{_f(axis)}"/>'
    if limits is not None:
        lo, hi = (float(v) if np.isfinite(v) else np.sign(v) * UNLIMITED for v in limits)
        text += (f'<limit lower="{lo:.17g}" upper="{hi:.17g}" effort="{UNLIMITED:g}" '
                 f'velocity="{UNLIMITED:g}"/>')
    return text + "</joint>"


def _masses(machine, masses):
    model = machine.model
    if (model.leg_kind == CRANK).any():
        if masses is not None:
            raise UnsupportedExportError(
                FORMAT, machine.id, "masses were given, but pkmkit has no mass model of crank "
                "actuators (the arms' inertia): export this machine without masses (a "
                "kinematic URDF)")
        return None
    if masses is None:
        from pkmkit.dynamics.defaults import default_masses

        strut = model.rod_kind == STRUT
        masses = default_masses(machine, tubes_at_home=bool((model.rod_length[strut] <= 0)
                                                            .any()))
    masses.check(machine)
    return masses


def urdf_export(machine, masses=None, *, name: str = "machine") -> UrdfExport:
    """The URDF tree and closures YAML of ``machine`` (see the module docstring).

    Args:
        machine: a spatial rod-leg machine (slides, struts, cranks), nominal or calibrated.
        masses: :class:`~pkmkit.dynamics.masses.MassProperties` (default: the kind's
            illustrative values; ignored for cranks, which pkmkit has no mass model of).
        name: the URDF file's stem (the YAML names it).

    Raises:
        UnsupportedExportError: a machine this writer cannot express (module docstring).
    """
    _check(machine)
    model = machine.model
    masses = _masses(machine, masses)
    q0 = np.asarray(machine.home_q, dtype=float)
    _, rot0, tips = platform_points(machine, machine.home_pose)
    from pkmkit.solve.rod_closure import rod_base_points
    from pkmkit.spatial.rotation import axis_rotation

    bases = rod_base_points(model, q0[:, None])[:, :, 0].T  # (m, 3) at home
    require_closed_rods(machine, q0, bases, tips)
    links, joints, movable = [_link("base")], [], []
    frame0 = np.zeros((model.n_rods, 3, 3))
    spin = -np.ones(model.n_rods, dtype=int)
    parent_of: dict[int, tuple[str, np.ndarray]] = {}  # rod → (parent link, its origin at q=0)
    for k in range(model.n_actuators):
        legs = np.flatnonzero(model.leg_actuator == k)
        leg = int(legs[0])
        act, kind = model.actuator_names[k], int(model.leg_kind[leg])
        limits = (model.q_min[k], model.q_max[k])
        rods = np.flatnonzero(model.rod_actuator == k)
        if kind == STRUT:
            continue
        if kind == SLIDE:
            link, origin = f"carriage{k + 1}", model.leg_base[leg]
            mass = "" if masses is None else _inertial(
                float(masses.carriage_mass[k]), (0, 0, 0),
                np.eye(3) * masses.carriage_mass[k] * CARRIAGE_SIDE**2 / 6)
            joints.append(_joint(act, "prismatic", "base", link, origin, axis=model.leg_axis[leg],
                                 limits=limits))
        else:
            link, origin = f"crank{k + 1}", model.leg_pivot[leg]
            mass = ""
            finite = bool(np.isfinite(limits).all())
            joints.append(_joint(act, "revolute" if finite else "continuous", "base", link,
                                 origin, axis=model.leg_axis[leg],
                                 limits=limits if finite else None))
            spin[rods] = k
        links.append(_link(link, mass))
        movable.append(UrdfJoint(act, "prismatic" if kind == SLIDE else "revolute", "actuator",
                                 k))
        for j in rods:
            parent_of[int(j)] = (link, origin)
    for j in range(model.n_rods):
        e0 = tips[j] - bases[j]
        e0 = e0 / np.linalg.norm(e0)
        if spin[j] >= 0:
            k = spin[j]
            turn = axis_rotation(model.rod_axis[j][None], np.array([q0[k]]))[0]
        else:
            turn = np.eye(3)
        frame0[j] = z_frame(e0)  # world orientation of the U frame at zero angles, at home
        local = turn.T @ frame0[j]  # in the parent link's frame (a crank turned back to q = 0)
        r = j + 1
        kind = int(model.rod_kind[j])
        if kind == STRUT:
            parent, origin = "base", model.rod_base[j]
        else:
            parent, link_origin = parent_of[j]
            origin = model.rod_base[j] - link_origin
        body = f"cylinder{r}" if kind == STRUT else f"rod{r}"
        joints.append(_joint(f"rod{r}_ux", "continuous", parent, f"rod{r}_cross", origin,
                             _rpy(local), axis=(1, 0, 0)))
        joints.append(_joint(f"rod{r}_uy", "continuous", f"rod{r}_cross", body, axis=(0, 1, 0)))
        links.append(_link(f"rod{r}_cross"))
        movable += [UrdfJoint(f"rod{r}_ux", "continuous", "ux", j),
                    UrdfJoint(f"rod{r}_uy", "continuous", "uy", j)]
        radius = 0.0 if masses is None else max(float(masses.rod_radius[j]), 0.0)
        if kind == STRUT:
            k = int(model.rod_actuator[j])
            piston, cyl_len, pis_len = masses.strut_parts(model.n_rods)
            links.append(_link(body, _tube(float(masses.rod_mass[j]), radius, 0.0,
                                           float(cyl_len[j]))))
            links.append(_link(f"piston{r}", _tube(float(piston[j]), radius,
                                                   -float(pis_len[j]), float(pis_len[j]))))
            joints.append(_joint(model.actuator_names[k], "prismatic", body, f"piston{r}",
                                 (0, 0, model.rod_length[j]), axis=(0, 0, 1),
                                 limits=(model.q_min[k], model.q_max[k])))
            movable.append(UrdfJoint(model.actuator_names[k], "prismatic", "actuator", k))
            joints.append(_joint(f"rod{r}_tip_frame", "fixed", f"piston{r}", f"rod{r}_tip"))
        else:
            length = float(model.rod_length[j])
            links.append(_link(body, "" if masses is None else
                               _tube(float(masses.rod_mass[j]), radius, 0.0, length)))
            joints.append(_joint(f"rod{r}_tip_frame", "fixed", body, f"rod{r}_tip",
                                 (0, 0, length)))
        links.append(_link(f"rod{r}_tip"))
    offset = frame0[0].T @ rot0  # rod 1's frame at home to the platform's orientation
    balls = [("sx", (1, 0, 0), "rod1_tip", "rod1_ball_x"), ("sy", (0, 1, 0), "rod1_ball_x",
             "rod1_ball_y"), ("sz", (0, 0, 1), "rod1_ball_y", "rod1_ball")]
    for i, (role, axis, parent, child) in enumerate(balls):
        joints.append(_joint(f"rod1_{role}", "continuous", parent, child,
                             rpy=_rpy(offset) if i == 0 else (0, 0, 0), axis=axis))
        links.append(_link(child))
        movable.append(UrdfJoint(f"rod1_{role}", "continuous", role, 0))
    platform = ""
    if masses is not None:
        platform = _inertial(float(masses.platform_mass), masses.platform_com,
                             masses.platform_inertia)
    links.append(_link("platform", platform))
    joints.append(_joint("platform_mount", "fixed", "rod1_ball", "platform",
                         -model.rod_platform[0]))
    pairs = []
    for j in range(1, model.n_rods):
        links.append(_link(f"platform_b{j + 1}"))
        joints.append(_joint(f"platform_b{j + 1}_frame", "fixed", "platform",
                             f"platform_b{j + 1}", model.rod_platform[j]))
        pairs.append((f"rod{j + 1}_tip", f"platform_b{j + 1}"))
    layout = UrdfExport(urdf="", closures="", joints=tuple(movable), closure_frames=tuple(pairs),
                        frame0=frame0, parent_spin=spin, ball_offset=offset,
                        inertial=masses is not None)
    values = configuration(machine, layout, machine.home_pose, q0)
    urdf = _urdf_text(machine, links, joints, masses is not None)
    yaml = _closures_text(machine, layout, values, name, masses)
    return UrdfExport(urdf=urdf, closures=yaml, joints=layout.joints, closure_frames=tuple(pairs),
                      frame0=frame0, parent_spin=spin, ball_offset=offset,
                      inertial=masses is not None)


def require_closed_rods(machine, q0: np.ndarray, bases: np.ndarray, tips: np.ndarray,
                        fmt: str = FORMAT) -> None:
    """Refuse a machine whose rods do not close at its own home configuration: a translational
    machine is modelled by its legs' midlines, and defects that tilt a crank's axis make its
    parallelogram's two rods miss their lengths (pkmkit keeps the platform translating; a
    tree of those rods would not be pkmkit's machine)."""
    model = machine.model
    length = model.rod_length + np.where(model.rod_kind == STRUT, q0[model.rod_actuator], 0.0)
    miss = np.abs(np.linalg.norm(tips - bases, axis=1) - length)
    j = int(np.argmax(miss))
    if miss[j] > 1e-12 * max(1.0, float(length.max())):
        raise UnsupportedExportError(
            fmt, machine.id, f"rod {j + 1} misses its length by {miss[j]:.3g} m at home: "
            "pkmkit models this translational machine by its legs' midlines, and its defects "
            "(e.g. a tilted crank axis) leave a parallelogram's rods unable to close with the "
            "platform translating; a model of its rods would describe another machine")


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _attr(text: str) -> str:
    return (str(text).replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")
            .replace(">", "&gt;").replace("--", "- -"))


def _urdf_text(machine, links, joints, inertial: bool) -> str:
    note = ("" if inertial else "\n     No inertias: pkmkit has no mass model of crank "
            "actuators (a kinematic model).")
    return f"""<?xml version="1.0"?>
<robot name="{_attr(machine.id)}">
  <!-- pkmkit machine {_attr(machine.id)} ({_attr(machine.name)}): the spanning tree of its
       loops; the cut ball joints are in the closures YAML beside this file. SI units (m, rad,
       kg). Joints named as pkmkit's actuators hold its actuator coordinates; rod{{j}}_ux/_uy
       are universal joints, rod1_sx/_sy/_sz the spherical joint carrying the platform.
       Limits {UNLIMITED:g} mean none (pkmkit gives no such limit).{note} -->
{chr(10).join(links)}
{chr(10).join(joints)}
</robot>
"""


def _closures_text(machine, layout: UrdfExport, values: dict, name: str, masses,
                   note: str = "") -> str:
    model = machine.model
    pairs = "\n".join(f"  - [{a}, {b}]" for a, b in layout.closure_frames)
    actuators = model.actuator_names
    strut = model.leg_kind[model.leg_actuator.argsort()] == STRUT
    armature = ""
    if masses is not None and strut.any():
        armature = ("# Motor translating inertia (kg) of each strut actuator, pkmkit's "
                    "'carriage' mass: URDF has no field for it (a joint armature).\narmature: {"
                    + ", ".join(f"{model.actuator_names[k]}: {masses.carriage_mass[k]:.17g}"
                                for k in range(model.n_actuators)
                                if (model.leg_kind[model.leg_actuator == k] == STRUT).any())
                    + "}\n")
    home = "\n".join(f"  {k}: {v:.17g}" for k, v in values.items())
    return f"""# Loop closures of {name}.urdf: pkmkit machine {machine.id!r} ({machine.name}).
# The URDF is a spanning tree; each closure below is a cut ball joint between a rod's tip and
# the platform: the two frames' origins coincide (type 3D: 3 constraints, along x, y, z of the
# first frame; the relative rotation is free). In Pinocchio, for each pair:
#   RigidConstraintModel(ContactType.CONTACT_3D, model, f1.parentJoint, f1.placement,
#                        f2.parentJoint, f2.placement, ReferenceFrame.LOCAL)
# with f1, f2 = model.frames[model.getFrameId(name)]. SI units (m, rad, kg).{note}
closed_loop:
{pairs}
type: [{", ".join("3D" for _ in layout.closure_frames)}]
constrained: [{", ".join("[x, y, z]" for _ in layout.closure_frames)}]
# Actuated joints (pkmkit's actuators, in its order).
name_mot: [{", ".join(actuators)}]
# No joint to convert: the universal and spherical joints are written as revolute chains.
joint_name: []
joint_type: []
{armature}# An assembled configuration, pkmkit's home: joint name -> value (m or rad).
home:
{home}
"""


def configuration(machine, layout: UrdfExport, x, q) -> dict[str, float]:
    """Every movable joint's value (m or rad) of the tree at pkmkit's configuration: the pose
    ``x (dims,)`` and actuator values ``q (n,)`` (SI) — the actuators at q, each universal
    joint turning its rod onto the line from its base-side joint to its platform joint, the
    spherical joint turning the platform to its orientation. The closures then hold."""
    from pkmkit.solve.rod_closure import rod_base_points
    from pkmkit.spatial.rotation import axis_rotation, rotation_class

    model = machine.model
    q = np.asarray(q, dtype=float).reshape(-1)
    _, rot, tips = platform_points(machine, np.asarray(x, dtype=float).reshape(-1))
    bases = rod_base_points(model, q[:, None])[:, :, 0].T
    out: dict[str, float] = {}
    rods = np.zeros((model.n_rods, 3, 3))
    for joint in layout.joints:
        if joint.role == "actuator":
            out[joint.name] = float(q[joint.index])
        elif joint.role == "ux":
            j = joint.index
            k = layout.parent_spin[j]
            turn = (axis_rotation(model.rod_axis[j][None], np.array([q[k] - machine.home_q[k]]))[0]
                    if k >= 0 else np.eye(3))
            zero = turn @ layout.frame0[j]
            v = zero.T @ _unit(tips[j] - bases[j])
            a, b = np.arctan2(-v[1], v[2]), np.arcsin(np.clip(v[0], -1.0, 1.0))
            out[f"rod{j + 1}_ux"], out[f"rod{j + 1}_uy"] = float(a), float(b)
            rx = axis_rotation(np.array([[1.0, 0, 0]]), np.array([a]))[0]
            ry = axis_rotation(np.array([[0, 1.0, 0]]), np.array([b]))[0]
            rods[j] = zero @ rx @ ry
        elif joint.role == "rz":  # a planar rod's hinge about z (pkmkit.export.urdf_planar)
            j = joint.index
            v = layout.frame0[j].T @ _unit(tips[j] - bases[j])
            a = float(np.arctan2(v[1], v[0]))
            out[joint.name] = a
            rods[j] = layout.frame0[j] @ axis_rotation(np.array([[0, 0, 1.0]]), np.array([a]))[0]
    relative = (rods[0] @ layout.ball_offset).T @ rot
    if any(joint.role == "pz" for joint in layout.joints):  # the planar platform's hinge
        out["rod1_pz"] = float(np.arctan2(relative[1, 0], relative[0, 0]))
        return out
    angles = rotation_class().from_matrix(relative).as_euler("XYZ")
    for role, value in zip(("sx", "sy", "sz"), angles, strict=True):
        out[f"rod1_{role}"] = float(value)
    return out
