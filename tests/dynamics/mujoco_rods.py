"""Any translational rod-leg machine — slide legs and actuated struts — in MuJoCo, used only as an
independent test oracle for pkmkit's inverse dynamics.

Bodies, built at the machine's home configuration:

- slide leg k: a carriage on a slide joint (motor) carrying one ball-jointed rod per rod of the
  leg (uniform solid cylinders);
- strut leg: a cylinder tube on a ball joint at the base, and a piston tube on a slide joint
  (motor) along the strut inside it, both uniform solid cylinders of the rod's radius; the
  carriage mass of a strut (the motor's translating inertia) is the slide joint's armature;
- the platform on a free joint, joined to every rod tip by a ``connect`` equality.

:meth:`MujocoRodMachine.hard_constraint_forces` solves M q̈ + c = Sᵀτ + J_cᵀλ for the actuator
forces τ with every joint acceleration given by the motion (closures enforced exactly).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from pkmkit.model.rods import STRUT

mujoco = __import__("pytest").importorskip("mujoco")


def _rotation_between(a: np.ndarray, b: np.ndarray) -> Rotation:
    axis = np.cross(a, b)
    s = np.linalg.norm(axis)
    if s < 1e-15:
        return Rotation.identity()
    return Rotation.from_rotvec(axis / s * np.arctan2(s, float(np.dot(a, b))))


def _f(v) -> str:
    return " ".join(f"{float(c):.17g}" for c in np.atleast_1d(v))


class MujocoRodMachine:
    def __init__(self, machine, masses):
        self.machine = machine
        model = machine.model
        q0, p0 = machine.home_q, model.pad(machine.home_pose[None])[0]
        piston, cyl_len, pis_len = masses.strut_parts(model.n_rods)
        self.rod_dir0 = {}
        bodies, connects = [], []
        for k in range(model.n_legs):
            rods = np.flatnonzero(model.rod_leg == k)
            if model.leg_kind[k] == STRUT:
                (j,) = rods
                base = model.rod_base[j]
                tip = p0 + model.rod_platform[j] - base
                s0 = np.linalg.norm(tip)
                e0 = tip / s0
                self.rod_dir0[j] = e0
                radius = max(masses.rod_radius[j], 1e-4)
                bodies.append(
                    f'<body name="cyl{j}" pos="{_f(base)}"><joint name="ball{j}" type="ball"/>'
                    f'<geom type="cylinder" fromto="0 0 0 {_f(cyl_len[j] * e0)}" '
                    f'size="{radius:.17g}" mass="{masses.rod_mass[j]:.17g}"/>'
                    f'<body name="piston{j}"><joint name="act{k}" type="slide" axis="{_f(e0)}" '
                    f'ref="{q0[k]:.17g}" armature="{masses.carriage_mass[k]:.17g}"/>'
                    f'<geom type="cylinder" fromto="{_f((s0 - pis_len[j]) * e0)} {_f(tip)}" '
                    f'size="{radius:.17g}" mass="{piston[j]:.17g}"/></body></body>')
                connects.append((f"piston{j}", tip))
                continue
            u = model.leg_axis[k]
            carriage = model.leg_base[k] + q0[k] * u
            children = []
            for j in rods:
                joint_pt = model.rod_base[j] + q0[k] * model.rod_axis[j]
                tip = p0 + model.rod_platform[j] - joint_pt
                self.rod_dir0[j] = tip / np.linalg.norm(tip)
                children.append(
                    f'<body name="rod{j}" pos="{_f(joint_pt - carriage)}">'
                    f'<joint name="ball{j}" type="ball"/><geom type="cylinder" fromto="0 0 0 '
                    f'{_f(tip)}" size="{max(masses.rod_radius[j], 1e-4):.17g}" '
                    f'mass="{masses.rod_mass[j]:.17g}"/></body>')
                connects.append((f"rod{j}", tip))
            bodies.append(
                f'<body name="carriage{k}" pos="{_f(carriage)}"><joint name="act{k}" '
                f'type="slide" axis="{_f(u)}" ref="{q0[k]:.17g}"/><geom type="box" '
                f'size="0.02 0.02 0.02" mass="{masses.carriage_mass[k]:.17g}"/>'
                + "".join(children) + "</body>")
        equality = "".join(f'<connect body1="{b}" body2="platform" anchor="{_f(t)}"/>'
                           for b, t in connects)
        actuators = "".join(f'<motor joint="act{k}" gear="1"/>' for k in range(model.n_legs))
        xml = f"""
<mujoco>
  <option gravity="{_f(masses.gravity)}" timestep="0.0001" jacobian="dense">
    <flag contact="disable"/>
  </option>
  <worldbody>
    {''.join(bodies)}
    <body name="platform" pos="{_f(p0)}"><freejoint/>
      <inertial pos="0 0 0" mass="{masses.platform_mass:.17g}" diaginertia="0.05 0.05 0.05"/>
    </body>
  </worldbody>
  <equality>{equality}</equality>
  <actuator>{actuators}</actuator>
</mujoco>"""
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)

    def _dof(self, name: str) -> int:
        return int(self.model.jnt_dofadr[self.model.joint(name).id])

    def _qpos(self, name: str) -> int:
        return int(self.model.jnt_qposadr[self.model.joint(name).id])

    def _state(self, x, xd, xdd, q, qd, qdd) -> np.ndarray:
        """Set MuJoCo's qpos and qvel for (x, q, ẋ, q̇); return the joint accelerations q̈."""
        model, m, d = self.machine.model, self.model, self.data
        p, v, a = (model.pad(np.asarray(w)[None])[0] for w in (x, xd, xdd))
        qacc = np.zeros(m.nv)
        for k in range(model.n_legs):
            d.qpos[self._qpos(f"act{k}")] = q[k]
            d.qvel[self._dof(f"act{k}")] = qd[k]
            qacc[self._dof(f"act{k}")] = qdd[k]
        for j in range(model.n_rods):
            k = model.rod_actuator[j]
            if model.rod_kind[j] == STRUT:
                dvec = p + model.rod_platform[j] - model.rod_base[j]
                length = np.linalg.norm(dvec)
                e = dvec / length
                omega = np.cross(e, v) / length
                alpha = (np.cross(e, a) - 2 * qd[k] * omega) / length
            else:
                joint_pt = model.rod_base[j] + q[k] * model.rod_axis[j]
                dvec = p + model.rod_platform[j] - joint_pt
                length = np.linalg.norm(dvec)
                e = dvec / length
                omega = np.cross(e, v - qd[k] * model.rod_axis[j]) / length
                alpha = np.cross(e, a - qdd[k] * model.rod_axis[j]) / length
            rot = _rotation_between(self.rod_dir0[j], e)
            quat = rot.as_quat()  # x, y, z, w
            adr = self._qpos(f"ball{j}")
            d.qpos[adr:adr + 4] = [quat[3], quat[0], quat[1], quat[2]]
            dof = self._dof(f"ball{j}")
            d.qvel[dof:dof + 3] = rot.as_matrix().T @ omega  # ball joints: local frame
            qacc[dof:dof + 3] = rot.as_matrix().T @ alpha
        free = m.body("platform").jntadr[0]
        adr, dof = m.jnt_qposadr[free], m.jnt_dofadr[free]
        d.qpos[adr:adr + 3] = p
        d.qpos[adr + 3:adr + 7] = [1, 0, 0, 0]
        d.qvel[dof:dof + 3] = v
        d.qvel[dof + 3:dof + 6] = 0
        qacc[dof:dof + 3] = a
        return qacc

    def hard_constraint_forces(self, x, xd, xdd, q, qd, qdd) -> tuple[np.ndarray, float, float]:
        """Actuator forces with exact closures: (τ, relative residual, closure violation m)."""
        m, d = self.model, self.data
        n = self.machine.n_actuators
        qacc = self._state(x, xd, xdd, q, qd, qdd)
        mujoco.mj_forward(m, d)
        violation = float(np.abs(d.efc_pos[: d.nefc]).max()) if d.nefc else 0.0
        mass = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, mass)
        rhs = mass @ qacc + d.qfrc_bias
        select = np.zeros((m.nv, n))
        for k in range(n):
            select[self._dof(f"act{k}"), k] = 1.0
        jc = d.efc_J[: d.nefc * m.nv].reshape(d.nefc, m.nv)
        system = np.hstack([select, jc.T])
        z, *_ = np.linalg.lstsq(system, rhs, rcond=None)
        residual = np.linalg.norm(system @ z - rhs) / max(np.linalg.norm(rhs), 1e-300)
        return z[:n], float(residual), violation
