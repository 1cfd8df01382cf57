"""Orientation analysis of full-pose machines: the orientation workspace at a point and the
coupled (parasitic) orientation of machines with fewer than six actuators.

**Tilt-and-torsion angles** (Bonev & Ryu): the platform orientation is
``R = Rz(φ) Ry(θ) Rz(σ − φ)``, θ ∈ [0, π) the *tilt* of the platform's z axis away from the
base's, φ its *azimuth* (the direction of the tilt), σ the *torsion* about the platform's own
axis. Unlike Euler angles they have no singularity at θ = 0, which is where machine tools work.

- :func:`orientation_workspace` — at a fixed platform position and torsion, the feasible set of
  (azimuth, tilt) directions: reachable, within strokes, away from singularities, optionally
  within bounds of the conditioning. Its boundary gives the largest tilt in every direction.
- :func:`coupled_orientation` — a machine with fewer than six actuators (the Verne-type module)
  takes the orientation its rods impose at each position: its tilt, torsion and rotation vector
  over a grid of positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.machines.strokes import signed_excess
from pkmkit.spatial.euler import matrix_from_angles
from pkmkit.spatial.rotation import rotation_class, rotvec_to_matrix
from pkmkit.status import Status

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation


def tilt_torsion_rotation(azimuth: Any, tilt: Any, torsion: Any = 0.0) -> Rotation:
    """Rotations ``Rz(φ) Ry(θ) Rz(σ − φ)`` of tilt-and-torsion angles (radians, broadcast)."""
    phi, theta, sigma = np.broadcast_arrays(np.asarray(azimuth, float), np.asarray(tilt, float),
                                            np.asarray(torsion, float))
    angles = np.stack([phi.ravel(), theta.ravel(), (sigma - phi).ravel()], axis=1)
    return rotation_class().from_euler("ZYZ", angles)


def tilt_torsion_angles(rotation: Rotation) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(azimuth, tilt, torsion)`` of rotations (radians): the tilt from the platform z axis
    ``R e_z``, the azimuth of its horizontal projection, the torsion the rest (at zero tilt the
    azimuth is 0 and the torsion the rotation about z)."""
    return _tilt_torsion_of_matrices(rotation.as_matrix().reshape(-1, 3, 3))


def _tilt_torsion_of_matrices(mat: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`tilt_torsion_angles` of rotation matrices ``(N, 3, 3)``, in NumPy alone (the
    one-pose ``pkmkit ik verne`` must not import SciPy's rotations)."""
    z = mat[:, :, 2]
    tilt = np.arccos(np.clip(z[:, 2], -1.0, 1.0))
    azimuth = np.where(np.hypot(z[:, 0], z[:, 1]) > 1e-15, np.arctan2(z[:, 1], z[:, 0]), 0.0)
    # Rz(φ) Ry(θ) Rz(−φ) undone: the remaining rotation is about z
    undo = matrix_from_angles(np.stack([azimuth, tilt, -azimuth], axis=1), "ZYZ")
    rest = np.swapaxes(undo, 1, 2) @ mat
    torsion = np.arctan2(rest[:, 1, 0], rest[:, 0, 0])
    return azimuth, tilt, torsion


@dataclass(frozen=True)
class OrientationWorkspace:
    """Feasible orientations at a point on an (azimuth, tilt) grid.

    Attributes:
        position: ``(3,)`` platform position (m).
        torsion: torsion σ (rad).
        azimuth: ``(na,)`` azimuths (rad); tilt: ``(nt,)`` tilts (rad).
        feasible: ``(na, nt)`` bool.
        masks: ``{"reachable", "strokes", "regular"}`` each ``(na, nt)``.
        condition: ``(na, nt)`` condition number of the homogenised J (NaN where unreachable).
        max_tilt: ``(na,)`` the largest tilt reached from θ = 0 without leaving the feasible set,
            per azimuth (rad; the grid's resolution: ``tilt[1] − tilt[0]``).
    """

    position: np.ndarray
    torsion: float
    azimuth: np.ndarray
    tilt: np.ndarray
    feasible: np.ndarray
    masks: dict[str, np.ndarray]
    condition: np.ndarray
    max_tilt: np.ndarray

    @property
    def resolution(self) -> float:
        """Tilt step of the grid (rad): ``max_tilt`` holds to within it."""
        return float(self.tilt[1] - self.tilt[0]) if len(self.tilt) > 1 else float("nan")


def orientation_workspace(machine, position: Any, *, max_tilt: float = np.radians(45.0),
                          torsion: float = 0.0, azimuths: int = 72, tilts: int = 91,
                          kappa_max: float | None = None) -> OrientationWorkspace:
    """Feasible orientations of a full-pose machine at ``position`` (see the module docstring).

    Args:
        machine: a six-actuator full-pose machine.
        position: ``(3,)`` platform position, m.
        max_tilt: largest tilt explored (rad).
        torsion: torsion σ (rad).
        azimuths, tilts: grid resolution.
        kappa_max: also require the homogenised condition number ≤ this.

    Raises:
        InputError: a machine that does not control its orientation, bad arguments.
    """
    if not machine.six_dof:
        raise InputError("an orientation workspace needs a machine that controls its platform's "
                         "orientation (six actuators); for a Verne-type module use "
                         "coupled_orientation")
    p = np.asarray(position, dtype=float).reshape(-1)
    if p.shape != (3,) or not np.isfinite(p).all():
        raise InputError(f"position must be 3 finite numbers, got {position!r}")
    if not (0 < max_tilt < np.pi) or azimuths < 4 or tilts < 2:
        raise InputError("max_tilt must be in (0, π), azimuths ≥ 4 and tilts ≥ 2")
    az = np.linspace(-np.pi, np.pi, azimuths, endpoint=False)
    ti = np.linspace(0.0, max_tilt, tilts)
    grid_az, grid_ti = np.meshgrid(az, ti, indexing="ij")
    rot = tilt_torsion_rotation(grid_az, grid_ti, torsion)
    poses = np.concatenate([np.tile(p, (grid_az.size, 1)), rot.as_rotvec()], axis=1)
    inv = machine.ik(poses, full_output=True)
    reachable = inv.status == Status.OK
    with np.errstate(invalid="ignore"):
        strokes = reachable & ~(signed_excess(inv.q, machine.model.q_min, machine.model.q_max)
                                != 0).any(axis=1)
    jac = machine.jacobian(poses, q=inv.q)
    regular = reachable & (jac.singularity == 0) & (np.sign(jac.det_A) == machine.working_mode)
    feasible = strokes & regular
    if kappa_max is not None:
        with np.errstate(invalid="ignore"):
            feasible &= jac.condition <= kappa_max
    shape = grid_az.shape
    feasible = feasible.reshape(shape)
    # largest tilt reached continuously from the untilted platform, per azimuth
    blocked = ~feasible
    first_bad = np.where(blocked.any(axis=1), blocked.argmax(axis=1), len(ti))
    max_reach = np.where(first_bad > 0, ti[np.maximum(first_bad - 1, 0)], np.nan)
    return OrientationWorkspace(
        position=p, torsion=float(torsion), azimuth=az, tilt=ti, feasible=feasible,
        masks={"reachable": reachable.reshape(shape), "strokes": strokes.reshape(shape),
               "regular": regular.reshape(shape)},
        condition=jac.condition.reshape(shape), max_tilt=max_reach)


@dataclass(frozen=True)
class CoupledOrientation:
    """The orientation a machine with fewer than six actuators takes at each position.

    Attributes:
        positions: ``(M, 3)`` positions (m).
        rotation: ``(M, 3)`` rotation vectors (rad); NaN where unreachable.
        tilt, azimuth, torsion: ``(M,)`` tilt-and-torsion angles (rad).
        angle: ``(M,)`` total rotation angle |φ| (rad).
        q: ``(M, n)`` actuator coordinates.
        status: ``(M,)`` status codes.
    """

    positions: np.ndarray
    rotation: np.ndarray
    tilt: np.ndarray
    azimuth: np.ndarray
    torsion: np.ndarray
    angle: np.ndarray
    q: np.ndarray
    status: np.ndarray


def coupled_orientation(machine, positions: Any) -> CoupledOrientation:
    """Parasitic orientation over positions ``(M, 3)`` of a position-controlled full-pose
    machine (the Verne-type module): the rods impose the rotation at each position.

    Raises:
        InputError: a machine that controls its orientation (six actuators), bad positions.
    """
    if not machine.position_controlled:
        raise InputError("the coupled orientation is that of a machine with fewer than six "
                         "actuators, whose rods impose the platform's orientation")
    pts = np.atleast_2d(np.asarray(positions, dtype=float))
    if pts.shape[1] != 3:
        raise InputError(f"positions must be (M, 3), got {pts.shape}")
    inv = machine.ik(pts, full_output=True)
    rotvec = np.array(inv.pose[:, 3:])  # the result's own (the record's fields are read-only)
    ok = np.isfinite(rotvec).all(axis=1)
    tilt = np.full(len(pts), np.nan)
    azimuth = np.full(len(pts), np.nan)
    torsion = np.full(len(pts), np.nan)
    if ok.any():
        a, t, s = _tilt_torsion_of_matrices(rotvec_to_matrix(rotvec[ok]))
        azimuth[ok], tilt[ok], torsion[ok] = a, t, s
    return CoupledOrientation(positions=pts, rotation=rotvec, tilt=tilt, azimuth=azimuth,
                              torsion=torsion, angle=np.linalg.norm(rotvec, axis=1),
                              q=inv.q, status=inv.status)
