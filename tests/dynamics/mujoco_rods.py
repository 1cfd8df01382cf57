"""Any translational rod-leg machine — slide legs and actuated struts — in MuJoCo, used only as an
independent test oracle for pkmkit's inverse dynamics.

The model is pkmkit's MJCF export (:func:`pkmkit.export.mjcf.mjcf_layout`: carriages on slide
joints, ball-jointed rods, struts as cylinder + piston, the platform on a free joint closed by
``connect`` equalities); the dynamics are MuJoCo's own.

:meth:`MujocoRodMachine.hard_constraint_forces` solves M q̈ + c = Sᵀτ + J_cᵀλ for the actuator
forces τ with every joint acceleration given by the motion (closures enforced exactly).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from pkmkit.export.mjcf import mjcf_layout
from pkmkit.model.rods import STRUT

mujoco = __import__("pytest").importorskip("mujoco")


def _rotation_between(a: np.ndarray, b: np.ndarray) -> Rotation:
    axis = np.cross(a, b)
    s = np.linalg.norm(axis)
    if s < 1e-15:
        return Rotation.identity()
    return Rotation.from_rotvec(axis / s * np.arctan2(s, float(np.dot(a, b))))


class MujocoRodMachine:
    def __init__(self, machine, masses):
        self.machine = machine
        layout = mjcf_layout(machine, masses, require_held_platform=False)
        self.rod_dir0 = layout.rod_direction
        self.model = mujoco.MjModel.from_xml_string(layout.xml)
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
