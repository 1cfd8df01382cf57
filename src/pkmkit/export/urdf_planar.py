"""A URDF spanning tree of a planar rod-leg machine (the five-bars: x-y poses, slides and
parallelograms in the plane) and its loop closures: the tree never leaves the plane.

The tree (pkmkit's base frame, SI units):

- **slide** actuator k: a carriage link ``carriage{k}`` on a ``prismatic`` joint named as
  pkmkit's actuator (``rho1`` …; its value *is* pkmkit's q_k, m), as the spatial writer
  (:mod:`pkmkit.export.urdf`);
- every rod j: a ``continuous`` revolute joint ``rod{j}_rz`` about z at its carriage-side joint
  centre, its frame's x axis along the rod at pkmkit's home (so the angle is 0 at home), the
  rod link ``rod{j}`` along x and its tip frame ``rod{j}_tip`` at (ℓ_j, 0, 0);
- the **platform** hung from rod 1's tip by a ``continuous`` revolute joint ``rod1_pz`` about z
  (0 at home: the platform frame is then world-aligned, as pkmkit's translating platform) and a
  fixed joint to ``platform``, pkmkit's platform reference point; frames ``platform_b{j}`` at the
  other rods' platform joint centres.

The **closures** (``NAME.closures.yaml``, the spatial writer's keys): for every rod j ≥ 2 the
revolute joint between ``rod{j}_tip`` and ``platform_b{j}`` is cut, type ``3D`` (the frames'
origins coincide; in Pinocchio a ``RigidConstraintModel(ContactType.CONTACT_3D, …)``; Pinocchio
has no 2-D contact). The tree moves in the plane only, so each closure's z row holds
identically: the YAML lists ``constrained: [x, y]`` and says so. The parallelograms' closures
are redundant in rotation (each leg alone keeps the platform from turning), as in pkmkit.

Masses from :mod:`pkmkit.dynamics.masses` (default: the illustrative ones), as the spatial
writer: carriages as 40 mm cubes, rods as uniform solid cylinders along x without their inertia
about their own axis, the platform with the masses' centre of mass and inertia.

Refused (:class:`~pkmkit.export.base.UnsupportedExportError`): struts and cranks (a planar
machine of slides is what pkmkit has), fewer than three rods (two single rods leave the
platform free to turn, pkmkit takes it as translating).
"""

from __future__ import annotations

import numpy as np

from pkmkit.export.base import UnsupportedExportError, platform_points
from pkmkit.export.urdf import (
    CARRIAGE_SIDE,
    FORMAT,
    UrdfExport,
    UrdfJoint,
    _attr,
    _closures_text,
    _inertial,
    _joint,
    _link,
    _masses,
    _rpy,
    configuration,
)
from pkmkit.model.rods import SLIDE

PLANAR_NOTE = ("\n# Planar machine: the tree moves in the x-y plane only, so each closure's z row "
               "holds\n# identically; the constrained directions are x and y.")


def _check(machine) -> None:
    model = machine.model
    why = None
    if (model.leg_kind != SLIDE).any():
        why = "a planar machine with struts or cranks is not exported to URDF; slides are"
    elif model.n_rods < 3:
        why = (f"a planar platform on {model.n_rods} rods: pkmkit takes it as translating, the "
               "tree would let it turn (three rods hold a platform in the plane; parallelograms "
               "give two per leg)")
    if why:
        raise UnsupportedExportError(FORMAT, machine.id, why)


def _rod_tube(mass: float, radius: float, length: float) -> str:
    """A uniform solid cylinder along x from 0 to ``length`` (m), its inertia about its own
    axis left out (0), as the spatial writer's rods."""
    across = mass * (3 * radius**2 + length**2) / 12
    return _inertial(mass, [0.5 * length, 0.0, 0.0], np.diag([0.0, across, across]))


def _rz(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _carriages(machine, masses, links, joints, movable) -> dict[int, tuple[str, np.ndarray]]:
    """The carriages on their prismatic joints; returns rod → (carriage link, its origin)."""
    model = machine.model
    parent_of = {}
    for k in range(model.n_actuators):
        leg = int(np.flatnonzero(model.leg_actuator == k)[0])
        link, origin = f"carriage{k + 1}", model.leg_base[leg]
        cube = "" if masses is None else _inertial(
            float(masses.carriage_mass[k]), (0, 0, 0),
            np.eye(3) * masses.carriage_mass[k] * CARRIAGE_SIDE**2 / 6)
        joints.append(_joint(model.actuator_names[k], "prismatic", "base", link, origin,
                             axis=model.leg_axis[leg], limits=(model.q_min[k], model.q_max[k])))
        links.append(_link(link, cube))
        movable.append(UrdfJoint(model.actuator_names[k], "prismatic", "actuator", k))
        for j in np.flatnonzero(model.rod_actuator == k):
            parent_of[int(j)] = (link, origin)
    return parent_of


def planar_urdf_export(machine, masses=None, *, name: str = "machine") -> UrdfExport:
    """The URDF tree and closures YAML of a planar machine (module docstring).

    Raises:
        UnsupportedExportError: struts, cranks or fewer than three rods.
    """
    _check(machine)
    model = machine.model
    masses = _masses(machine, masses)
    from pkmkit.solve.rod_closure import rod_base_points

    q0 = np.asarray(machine.home_q, dtype=float)
    _, _, tips = platform_points(machine, machine.home_pose)
    bases = rod_base_points(model, q0[:, None])[:, :, 0].T
    links, joints, movable = [_link("base")], [], []
    parent_of = _carriages(machine, masses, links, joints, movable)
    frame0 = np.zeros((model.n_rods, 3, 3))
    for j in range(model.n_rods):
        d = tips[j] - bases[j]
        frame0[j] = _rz(float(np.arctan2(d[1], d[0])))
        parent, origin = parent_of[j]
        r, length = j + 1, float(model.rod_length[j])
        joints.append(_joint(f"rod{r}_rz", "continuous", parent, f"rod{r}",
                             model.rod_base[j] - origin, _rpy(frame0[j]), axis=(0, 0, 1)))
        links.append(_link(f"rod{r}", "" if masses is None else _rod_tube(
            float(masses.rod_mass[j]), float(masses.rod_radius[j]), length)))
        joints.append(_joint(f"rod{r}_tip_frame", "fixed", f"rod{r}", f"rod{r}_tip",
                             (length, 0, 0)))
        links.append(_link(f"rod{r}_tip"))
        movable.append(UrdfJoint(f"rod{r}_rz", "continuous", "rz", j))
    offset = frame0[0].T  # rod 1's frame at home to the platform's (world-aligned)
    joints.append(_joint("rod1_pz", "continuous", "rod1_tip", "rod1_pivot", rpy=_rpy(offset),
                         axis=(0, 0, 1)))
    links.append(_link("rod1_pivot"))
    movable.append(UrdfJoint("rod1_pz", "continuous", "pz", 0))
    pairs = _platform(machine, masses, links, joints)
    layout = UrdfExport(urdf="", closures="", joints=tuple(movable), closure_frames=pairs,
                        frame0=frame0, parent_spin=-np.ones(model.n_rods, dtype=int),
                        ball_offset=offset, inertial=masses is not None)
    values = configuration(machine, layout, machine.home_pose, q0)
    return UrdfExport(urdf=_text(machine, links, joints),
                      closures=_planar_closures(machine, layout, values, name, masses),
                      joints=layout.joints, closure_frames=pairs, frame0=frame0,
                      parent_spin=layout.parent_spin, ball_offset=offset,
                      inertial=masses is not None)


def _planar_closures(machine, layout: UrdfExport, values: dict, name: str, masses) -> str:
    """The spatial writer's closures YAML, said of cut revolute joints in the plane:
    ``constrained: [x, y]`` per pair."""
    pairs = layout.closure_frames
    text = _closures_text(machine, layout, values, name, masses, PLANAR_NOTE)
    return (text.replace("each closure below is a cut ball joint",
                         "each closure below is a cut revolute joint (about z)")
            .replace("constrained: [" + ", ".join("[x, y, z]" for _ in pairs),
                     "constrained: [" + ", ".join("[x, y]" for _ in pairs)))


def _platform(machine, masses, links, joints) -> tuple[tuple[str, str], ...]:
    """The platform link on rod 1's pivot and its frames at the other rods' joints; returns the
    closure pairs."""
    model = machine.model
    platform = "" if masses is None else _inertial(float(masses.platform_mass),
                                                   masses.platform_com, masses.platform_inertia)
    links.append(_link("platform", platform))
    joints.append(_joint("platform_mount", "fixed", "rod1_pivot", "platform",
                         -model.rod_platform[0]))
    pairs = []
    for j in range(1, model.n_rods):
        links.append(_link(f"platform_b{j + 1}"))
        joints.append(_joint(f"platform_b{j + 1}_frame", "fixed", "platform",
                             f"platform_b{j + 1}", model.rod_platform[j]))
        pairs.append((f"rod{j + 1}_tip", f"platform_b{j + 1}"))
    return tuple(pairs)


def _text(machine, links, joints) -> str:
    return f"""<?xml version="1.0"?>
<robot name="{_attr(machine.id)}">
  <!-- pkmkit machine {_attr(machine.id)} ({_attr(machine.name)}), planar: the spanning tree of
       its loops in the x-y plane; the cut joints are in the closures YAML beside this file. SI
       units (m, rad, kg). Joints named as pkmkit's actuators hold its actuator coordinates;
       rod{{j}}_rz turn the rods about z (0 at home), rod1_pz turns the platform about z on rod
       1's tip (0 at home). -->
{chr(10).join(links)}
{chr(10).join(joints)}
</robot>
"""
