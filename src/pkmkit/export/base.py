"""What every exporter shares: the refusal error and the rod geometry a format writes out.

An export writes a machine in another tool's terms (a controller's kinematics module, a firmware
configuration, a simulator's model). A machine the format cannot express is refused with
:class:`UnsupportedExportError` naming the format, the machine and the reason; an exporter never
writes a file that would load but describe another machine.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.exceptions import (  # noqa: F401  (re-exported: their first home)
    ExportCheckError,
    UnsupportedExportError,
)
from pkmkit.model.rods import CRANK, STRUT, RodModel


@dataclass(frozen=True)
class RodGeometry:
    """One rod per actuator, as a controller closes it: ``|p + R b_j − a_j(q)| = ρ_j(q)``.

    ``a_j(q) = base_j + q u_j`` for a slide (``ρ_j = length_j``), ``a_j = base_j`` and
    ``ρ_j = length_j + q`` for a strut; for a crank turning by q (rad) about the axis ``u_j``
    through ``pivot_j``, ``a_j(q) = pivot_j + h_j u_j + r_j (cos q e1_j + sin q e2_j)`` with the
    arm ``base_j − pivot_j`` split along the axis (``h_j``) and across it (``r_j e1_j``),
    ``e2_j = u_j × e1_j`` (:mod:`pkmkit.machines.closed_form`). For a translational machine the
    rods are its equivalent legs (a parallelogram's midline, exact while the platform only
    translates) and R = I; for a full-pose machine they are its real rods. Defects of a
    calibrated machine are already in these numbers (:mod:`pkmkit.model.rod_defects` applies
    them exactly).

    Attributes:
        names: ``(n,)`` leg names (pkmkit's).
        actuators: ``(n,)`` actuator names, rod j driven by actuator j.
        kind: ``(n,)`` :data:`~pkmkit.model.rods.SLIDE`, :data:`~pkmkit.model.rods.STRUT` or
            :data:`~pkmkit.model.rods.CRANK`.
        base: ``(n, 3)`` base-side joint centre at q = 0, m.
        platform: ``(n, 3)`` platform joint centre in the platform frame, m.
        axis: ``(n, 3)`` unit slide direction or crank axis (zero for struts).
        pivot: ``(n, 3)`` a point of a crank's axis (zero for other kinds), m.
        length: ``(n,)`` rod length (strut: length at q = 0), m.
        branch: ``(n,)`` working branch of the inverse model (±1; slides only).
        q_min, q_max: ``(n,)`` actuator strokes, m (±inf when unlimited).
        full_pose: the platform also turns (pose x, y, z + orientation).
        joint: ``(n,)`` the actuator driving each rod (default: rod j by actuator j; the
            Verne-type module: two rods per slide).
    """

    names: tuple[str, ...]
    actuators: tuple[str, ...]
    kind: np.ndarray
    base: np.ndarray
    platform: np.ndarray
    axis: np.ndarray
    length: np.ndarray
    branch: np.ndarray
    q_min: np.ndarray
    q_max: np.ndarray
    full_pose: bool
    pivot: np.ndarray | None = None
    joint: np.ndarray | None = None

    def crank_frames(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(e1 (n, 3), e2 (n, 3), r (n,), h (n,))`` of the cranks (zeros for other rods)."""
        pivot = np.zeros_like(self.base) if self.pivot is None else self.pivot
        crank = self.kind == CRANK
        arm = self.base - pivot
        along = np.einsum("jd,jd->j", arm, self.axis)
        across = arm - along[:, None] * self.axis
        radius = np.where(crank, np.linalg.norm(across, axis=1), 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            e1 = np.where(crank[:, None], across / np.where(radius > 0, radius, 1.0)[:, None],
                          0.0)
        e2 = np.cross(self.axis, e1)
        return e1, e2, radius, np.where(crank, along, 0.0)

    @property
    def n(self) -> int:
        """Number of rods (= actuators)."""
        return len(self.names)


def machine_family(machine) -> str:
    """The layout the machine declares to the export formats (``machine.export_layout``,
    :mod:`pkmkit.machines.export_layouts`): ``"translational"``, ``"planar"``, ``"full-pose"``
    or ``"chain"``."""
    return machine.export_layout


def rod_geometry(machine, fmt: str, *, cranks: bool = False, planar: bool = False,
                 position_controlled: bool = False) -> RodGeometry:
    """The one-rod-per-actuator geometry of a rod-leg machine of slides and struts (and cranks
    when the format takes them).

    Raises:
        UnsupportedExportError: a joint-chain machine, a planar one (unless ``planar``: its
            geometry is then 3-D with z = 0), crank actuators (unless ``cranks``), or a
            full-pose machine that is not six rods on six actuators (or, with
            ``position_controlled``, six rods on the three actuators of a machine whose
            orientation follows its position: the Verne-type module).
    """
    family = machine_family(machine)
    if family == "chain":
        raise UnsupportedExportError(
            fmt, machine.id, "a joint-chain machine (serial R/P chains closed on the platform) "
            "has no closed-form rod model; only rod-leg machines are exported to this format")
    if family == "planar" and not planar:
        raise UnsupportedExportError(
            fmt, machine.id, "a planar machine (2 actuators, x-y only) is not exported to this "
            "format yet")
    m: RodModel = machine.model
    if (m.leg_kind == CRANK).any() and not cranks:
        raise UnsupportedExportError(
            fmt, machine.id, "crank (rotary) actuators are not exported to this format yet; "
            "slides and struts are")
    if family == "full-pose":
        verne = position_controlled and machine.position_controlled and m.n_actuators == 3
        if m.n_rods != 6 or (m.n_actuators != 6 and not verne):
            raise UnsupportedExportError(
                fmt, machine.id, f"a full-pose machine with {m.n_actuators} actuators and "
                f"{m.n_rods} rods: only six rods on six actuators (hexapods) are exported; with "
                "fewer actuators the orientation follows the position and the inverse model is "
                "iterative")
        order = np.argsort(m.rod_actuator, kind="stable")
        base, platform, length = m.rod_base[order], m.rod_platform[order], m.rod_length[order]
        axis, kind = m.rod_axis[order], m.rod_kind[order]
        pivot = m.rod_pivot[order]
        legs = m.rod_leg[order]
        branch = m.leg_branch[legs]
        names = tuple(m.leg_names[i] for i in legs)
        joint = np.asarray(m.rod_actuator)[order]
    else:
        base, platform, length = m.leg_base, m.leg_platform, m.leg_length
        axis, kind, branch = m.leg_axis, m.leg_kind, m.leg_branch
        pivot = m.leg_pivot
        names = m.leg_names
        joint = np.arange(len(names))
    return RodGeometry(
        names=tuple(names), actuators=tuple(m.actuator_names[int(k)] for k in joint),
        kind=np.array(kind, dtype=int),
        base=np.array(base, dtype=float), platform=np.array(platform, dtype=float),
        axis=np.where((np.asarray(kind) != STRUT)[:, None], axis, 0.0),
        length=np.array(length, dtype=float), branch=np.array(branch, dtype=int),
        q_min=np.array(m.q_min, dtype=float)[joint], q_max=np.array(m.q_max, dtype=float)[joint],
        full_pose=family == "full-pose", joint=np.array(joint, dtype=int),
        pivot=np.where((np.asarray(kind) == CRANK)[:, None], pivot, 0.0))


def platform_points(machine, x) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(p (3,), rot (3, 3), points (m, 3))`` of a rod-leg machine's pose ``x (dims,)`` (SI):
    the platform reference point, its orientation (identity for a translational machine) and
    its rods' platform joint centres, m, base frame (z = 0 for a planar machine)."""
    from pkmkit.spatial.rotation import rotvec_to_matrix

    model = machine.model
    x = np.asarray(x, dtype=float).reshape(-1)
    p = model.pad(x[None])[0][:3]
    rot = rotvec_to_matrix(x[None, 3:6])[0] if model.full_pose else np.eye(3)
    return p, rot, p + model.rod_platform @ rot.T


def sample_poses(machine, n: int = 24, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Home, the machine's named poses and ``n`` random poses near home that pkmkit's inverse
    model reaches in the working mode: ``(poses (k, dims), q (k, n_act))``, where an export's
    self-check compares the written model with pkmkit's. (A position-controlled machine, the
    Verne-type module, is sampled at positions and given the orientation its rods impose.)"""
    rng = np.random.default_rng(seed)
    width = 3 if machine.position_controlled else machine.dims
    named = [np.asarray(p, dtype=float) for p in machine.reference_poses().values()]
    named = np.array([p[:width] for p in named if len(p) >= width])
    lo, hi = machine.default_box()
    centre, half = 0.5 * (lo + hi), 0.25 * (hi - lo)
    x = centre + rng.uniform(-1, 1, (n, len(centre))) * half
    if width == 6:
        from pkmkit.spatial.rotation import compose_rotvec

        turn = rng.uniform(-1, 1, (n, 3)) * np.radians(5)
        x = np.concatenate([x, compose_rotvec(turn, np.broadcast_to(machine.home_pose[3:],
                                                                    (n, 3)))], axis=1)
    poses = np.concatenate([named, x]) if len(named) else x
    with np.errstate(invalid="ignore"):
        res = machine.ik(poses, full_output=True)
    keep = (np.asarray(res.status) == 0) & (np.asarray(res.mode) == machine.working_mode)
    full = np.asarray(res.pose) if width != machine.dims else poses
    return full[keep], np.asarray(res.q)[keep]
