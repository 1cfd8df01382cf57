"""A linear Delta in MuJoCo (closed loops by `connect` equality constraints), used only as an
independent test oracle for pkmkit's inverse dynamics."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

mujoco = __import__("pytest").importorskip("mujoco")


def _rotation_between(a: np.ndarray, b: np.ndarray) -> Rotation:
    axis = np.cross(a, b)
    s = np.linalg.norm(axis)
    angle = np.arctan2(s, float(np.dot(a, b)))
    if s < 1e-15:
        return Rotation.identity()
    return Rotation.from_rotvec(axis / s * angle)


class MujocoDelta:
    """The pkmkit rod model of a machine with slide legs, built in MuJoCo at its home
    configuration (carriages on slide joints with motors, rods on ball joints, a free platform
    connected to each rod tip)."""

    def __init__(self, machine, masses):
        self.machine = machine
        model = machine.model
        q0, p0 = machine.home_q, model.pad(machine.home_pose[None])[0]
        self.q0, self.p0 = q0, p0
        g = masses.gravity
        body = []
        rod_tip0 = []
        self.rod_dir0 = []
        for k in range(model.n_legs):
            base = model.leg_base[k]
            u = model.leg_axis[k]
            carriage = base + q0[k] * u
            rods = []
            for j in np.flatnonzero(model.rod_leg == k):
                joint_pt = model.rod_base[j] + q0[k] * model.rod_axis[j]
                tip = p0 + model.rod_platform[j] - joint_pt
                rod_tip0.append((j, tip))
                self.rod_dir0.append(tip / np.linalg.norm(tip))
                rel = joint_pt - carriage
                rods.append(
                    f'<body name="rod{j}" pos="{rel[0]:.17g} {rel[1]:.17g} {rel[2]:.17g}">'
                    f'<joint name="ball{j}" type="ball"/>'
                    f'<geom type="cylinder" fromto="0 0 0 {tip[0]:.17g} {tip[1]:.17g} '
                    f'{tip[2]:.17g}" size="{max(masses.rod_radius[j], 1e-4):.17g}" '
                    f'mass="{masses.rod_mass[j]:.17g}"/></body>')
            body.append(
                f'<body name="carriage{k}" pos="{carriage[0]:.17g} {carriage[1]:.17g} '
                f'{carriage[2]:.17g}">'
                f'<joint name="slide{k}" type="slide" axis="{u[0]:.17g} {u[1]:.17g} {u[2]:.17g}" '
                f'ref="{q0[k]:.17g}"/>'
                f'<geom type="box" size="0.02 0.02 0.02" mass="{masses.carriage_mass[k]:.17g}"/>'
                + "".join(rods) + "</body>")
        equality = "".join(
            f'<connect body1="rod{j}" body2="platform" anchor="{t[0]:.17g} {t[1]:.17g} '
            f'{t[2]:.17g}" solimp="0.9999999 0.9999999 0.0001" solref="0.0002 1"/>'
            for j, t in rod_tip0)
        actuators = "".join(f'<motor joint="slide{k}" gear="1"/>' for k in range(model.n_legs))
        xml = f"""
<mujoco>
  <option gravity="{g[0]:.17g} {g[1]:.17g} {g[2]:.17g}" timestep="0.0001" tolerance="1e-14"
          iterations="500" cone="elliptic" jacobian="dense"/>
  <worldbody>
    {''.join(body)}
    <body name="platform" pos="{p0[0]:.17g} {p0[1]:.17g} {p0[2]:.17g}">
      <freejoint/>
      <inertial pos="0 0 0" mass="{masses.platform_mass:.17g}" diaginertia="0.05 0.05 0.05"/>
    </body>
  </worldbody>
  <equality>{equality}</equality>
  <actuator>{actuators}</actuator>
</mujoco>"""
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)

    def set_state(self, x, xd, q, qd) -> None:
        """MuJoCo state of the machine's configuration (x, q) and velocities (ẋ, q̇)."""
        _machine, model = self.machine, self.machine.model
        m, d = self.model, self.data
        p = model.pad(x[None])[0]
        v = model.pad(xd[None])[0]
        for k in range(model.n_legs):
            d.qpos[m.jnt_qposadr[m.joint(f"slide{k}").id]] = q[k]
            d.qvel[m.jnt_dofadr[m.joint(f"slide{k}").id]] = qd[k]
        for idx, j in enumerate(range(model.n_rods)):
            k = model.rod_actuator[j]
            a = model.rod_base[j] + q[k] * model.rod_axis[j]
            dvec = p + model.rod_platform[j] - a
            length = np.linalg.norm(dvec)
            rot = _rotation_between(self.rod_dir0[idx], dvec / length)
            quat = rot.as_quat()  # x, y, z, w
            adr = m.jnt_qposadr[m.joint(f"ball{j}").id]
            d.qpos[adr:adr + 4] = [quat[3], quat[0], quat[1], quat[2]]
            omega = np.cross(dvec / length, v - qd[k] * model.rod_axis[j]) / length
            dof = m.jnt_dofadr[m.joint(f"ball{j}").id]
            d.qvel[dof:dof + 3] = rot.as_matrix().T @ omega  # ball joints: local frame
        free = m.body("platform").jntadr[0]
        adr, dof = m.jnt_qposadr[free], m.jnt_dofadr[free]
        d.qpos[adr:adr + 3] = p
        d.qpos[adr + 3:adr + 7] = [1, 0, 0, 0]
        d.qvel[dof:dof + 3] = v
        d.qvel[dof + 3:dof + 6] = 0

    def slide_accelerations(self, forces) -> np.ndarray:
        """Carriage accelerations under actuator forces (forward dynamics)."""
        self.data.ctrl[:] = forces
        mujoco.mj_forward(self.model, self.data)
        m = self.model
        return np.array([self.data.qacc[m.jnt_dofadr[m.joint(f"slide{k}").id]]
                         for k in range(self.machine.n_actuators)])

    def forces_for(self, qdd) -> np.ndarray:
        """Actuator forces giving the carriage accelerations ``qdd`` (the map is affine)."""
        n = self.machine.n_actuators
        base = self.slide_accelerations(np.zeros(n))
        columns = [self.slide_accelerations(np.eye(n)[i] * 100.0) - base for i in range(n)]
        return np.linalg.solve(np.array(columns).T / 100.0, qdd - base)

    def constraint_violation(self) -> float:
        mujoco.mj_forward(self.model, self.data)
        return float(np.abs(self.data.efc_pos[: self.data.nefc]).max()) if self.data.nefc else 0

    def hard_constraint_forces(self, x, xd, xdd, q, qd, qdd) -> tuple[np.ndarray, float]:
        """Actuator forces from MuJoCo's mass matrix, bias forces (gravity, Coriolis) and
        constraint Jacobian with *hard* loop closures: solve M q̈ + c = Sᵀτ + J_cᵀλ for (τ, λ),
        the accelerations of every joint given by the motion. Returns (τ, relative residual)."""
        model = self.machine.model
        m, d = self.model, self.data
        self.set_state(x, xd, q, qd)
        mujoco.mj_forward(m, d)
        p = model.pad(x[None])[0]
        a_p = model.pad(xdd[None])[0]
        qacc = np.zeros(m.nv)
        for k in range(model.n_legs):
            qacc[m.jnt_dofadr[m.joint(f"slide{k}").id]] = qdd[k]
        for idx, j in enumerate(range(model.n_rods)):
            k = model.rod_actuator[j]
            a = model.rod_base[j] + q[k] * model.rod_axis[j]
            dvec = p + model.rod_platform[j] - a
            length = np.linalg.norm(dvec)
            alpha = np.cross(dvec / length, a_p - qdd[k] * model.rod_axis[j]) / length
            rot = _rotation_between(self.rod_dir0[idx], dvec / length)
            dof = m.jnt_dofadr[m.joint(f"ball{j}").id]
            qacc[dof:dof + 3] = rot.as_matrix().T @ alpha
        free = m.body("platform").jntadr[0]
        dof = m.jnt_dofadr[free]
        qacc[dof:dof + 3] = a_p
        mass = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, mass)
        rhs = mass @ qacc + d.qfrc_bias
        select = np.zeros((m.nv, self.machine.n_actuators))
        for k in range(model.n_legs):
            select[m.jnt_dofadr[m.joint(f"slide{k}").id], k] = 1.0
        jc = d.efc_J[: d.nefc * m.nv].reshape(d.nefc, m.nv)
        system = np.hstack([select, jc.T])
        z, *_ = np.linalg.lstsq(system, rhs, rcond=None)
        residual = np.linalg.norm(system @ z - rhs) / max(np.linalg.norm(rhs), 1e-300)
        return z[: self.machine.n_actuators], float(residual)
