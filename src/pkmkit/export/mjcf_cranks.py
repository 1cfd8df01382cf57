"""The crank (rotary) actuators of a rod-leg machine in its MuJoCo model (the Delta robot):
arm bodies on hinge joints, and the illustrative masses the model takes (pkmkit's dynamics model
has no mass model of crank actuators, :func:`pkmkit.dynamics.defaults.default_masses` refuses
them).

- **crank** actuator k: an arm body ``arm{k}`` on a hinge joint ``act{k}`` about the crank axis
  through its pivot, its ``ref`` the home crank angle (so ``qpos`` of ``act{k}`` *is* pkmkit's
  q_k, rad), carrying the leg's ball-jointed rods at their joint centres (the elbow);
- **illustrative masses** (no source gives them; the file says so): every rod and every arm a
  solid Ø :data:`DIAMETER` m aluminium cylinder (:data:`DENSITY` kg/m³), an arm from the pivot
  to the middle of its rods' joints, the platform :data:`PLATFORM_KG` kg (the generic values of
  :mod:`pkmkit.dynamics.defaults`).
"""

from __future__ import annotations

import numpy as np

#: Illustrative section and density of the arms and rods (m, kg/m³), platform mass (kg).
DIAMETER = 0.020
DENSITY = 2700.0
PLATFORM_KG = 5.0


def _f(v) -> str:
    return " ".join(f"{float(c):.17g}" for c in np.atleast_1d(v))


def arm_length(machine, k: int) -> float:
    """Length (m) of crank k's arm: from the pivot to the middle of its rods' joint centres,
    across the axis."""
    model = machine.model
    leg = int(np.flatnonzero(model.leg_actuator == k)[0])
    rods = np.flatnonzero(model.rod_actuator == k)
    arm = model.rod_base[rods].mean(axis=0) - model.leg_pivot[leg]
    u = model.leg_axis[leg]
    return float(np.linalg.norm(arm - (arm @ u) * u))


def crank_masses(machine):
    """The illustrative :class:`~pkmkit.dynamics.masses.MassProperties` of a machine with
    cranks: its ``carriage_mass`` holds the arms' masses (module docstring)."""
    from pkmkit.dynamics.masses import mass_properties, rod_section_mass

    rod, radius, _ = rod_section_mass(machine, DIAMETER, DENSITY)
    area = np.pi / 4 * DIAMETER**2
    arms = np.array([DENSITY * area * arm_length(machine, k)
                     for k in range(machine.n_actuators)])
    return mass_properties(machine, carriage=arms, rod=rod, rod_radius=radius,
                           platform=PLATFORM_KG)


def masses_note(given: bool = False) -> str:
    """What the file says of the crank machine's masses: the illustrative ones, or a masses
    file's (``given``: its carriage masses are the arms', as Ø :data:`DIAMETER` uniform
    cylinders from the pivot to the elbow)."""
    if given:
        return (f"masses of the masses file; the arms (pkmkit has no mass model of crank "
                f"actuators): its carriage masses, uniform Ø {DIAMETER * 1e3:g} mm cylinders "
                "from the pivot to the elbow (assumed)")
    return (f"illustrative masses (no source gives them; pkmkit has no mass model of crank "
            f"actuators): arms and rods solid Ø {DIAMETER * 1e3:g} mm aluminium cylinders "
            f"({DENSITY:g} kg/m³), platform {PLATFORM_KG:g} kg")


def crank_body(machine, k: int, q0: np.ndarray, tips: np.ndarray, masses, rod_joint: str,
               directions: dict, connects: list) -> str:
    """The MJCF body of crank k at home (arm on its hinge, its rods on ball joints); records
    each rod's home direction in ``directions`` and its ``connect`` anchor in ``connects``."""
    from pkmkit.solve.rod_closure import rod_base_points

    model = machine.model
    leg = int(np.flatnonzero(model.leg_actuator == k)[0])
    pivot, u = model.leg_pivot[leg], model.leg_axis[leg]
    joints = rod_base_points(model, q0[:, None])[:, :, 0].T  # (m, 3) rod joint centres, home
    rods = np.flatnonzero(model.rod_actuator == k)
    elbow = joints[rods].mean(axis=0) - pivot
    elbow_across = elbow - (elbow @ u) * u
    children = []
    for j in rods:
        tip = tips[j] - joints[j]
        directions[int(j)] = tip / np.linalg.norm(tip)
        children.append(
            f'<body name="rod{j}" pos="{_f(joints[j] - pivot)}">{rod_joint.format(j=j)}'
            f'<geom type="cylinder" fromto="0 0 0 {_f(tip)}" '
            f'size="{max(float(masses.rod_radius[j]), 1e-4):.17g}" '
            f'mass="{masses.rod_mass[j]:.17g}"/></body>')
        connects.append((f"rod{j}", tip))
    return (f'    <!-- actuator {model.actuator_names[k]}: crank ({model.leg_names[leg]}) -->\n'
            f'    <body name="arm{k}" pos="{_f(pivot)}"><joint name="act{k}" type="hinge" '
            f'axis="{_f(u)}" ref="{q0[k]:.17g}"/><geom type="cylinder" fromto="0 0 0 '
            f'{_f(elbow_across)}" size="{DIAMETER / 2:.17g}" '
            f'mass="{masses.carriage_mass[k]:.17g}"/>' + "".join(children) + "</body>")


def parent_turn(machine, j: int, q: np.ndarray) -> np.ndarray:
    """``(3, 3)`` how far rod j's parent body has turned from home at actuator values
    ``q (n,)``: its crank's rotation by q_k − q_k(home), the identity for other rods."""
    from pkmkit.model.rods import CRANK
    from pkmkit.spatial.rotation import axis_rotation

    model = machine.model
    k = int(model.rod_actuator[j])
    leg = int(np.flatnonzero(model.leg_actuator == k)[0])
    if model.leg_kind[leg] != CRANK:
        return np.eye(3)
    return axis_rotation(model.leg_axis[leg][None],
                         np.array([q[k] - machine.home_q[k]]))[0]
