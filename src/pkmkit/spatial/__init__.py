"""Batched rigid-body maths: rotations and named angle conventions, 6-DOF poses, twists and
small-displacement torsors with their adjoints.

Conventions (stated once): a 6-DOF pose row is ``(x, y, z, rx, ry, rz)`` = position (m) + rotation
vector (rad); a twist or small-displacement torsor is ``(v, ω)``, linear part first; rotation
increments act on the left (fixed frame) unless said otherwise.
"""

from pkmkit.spatial.poses import (
    POSE_NAMES,
    compose_poses,
    from_transform,
    invert_poses,
    pose_difference,
    pose_from_angles,
    pose_from_parts,
    pose_matrices,
    pose_parts,
    pose_to_angles,
    to_transform,
)
from pkmkit.spatial.rotation import (
    CONVENTION_ALIASES,
    DEFAULT_CONVENTION,
    angles_from_rotation,
    angles_from_rotvec,
    as_rotation_matrices,
    axis_rotation,
    compose_rotvec,
    describe_convention,
    matrix_to_rotvec,
    resolve_convention,
    rotation_from_angles,
    rotvec_from_angles,
    rotvec_to_matrix,
    skew,
)
from pkmkit.spatial.twists import (
    adjoint,
    adjoint_inverse,
    hat,
    move_reduction_point,
    point_displacement,
    se3_exp,
    se3_log,
)

__all__ = [
    "CONVENTION_ALIASES",
    "DEFAULT_CONVENTION",
    "POSE_NAMES",
    "adjoint",
    "adjoint_inverse",
    "angles_from_rotation",
    "angles_from_rotvec",
    "as_rotation_matrices",
    "axis_rotation",
    "compose_poses",
    "compose_rotvec",
    "describe_convention",
    "from_transform",
    "hat",
    "invert_poses",
    "matrix_to_rotvec",
    "move_reduction_point",
    "point_displacement",
    "pose_difference",
    "pose_from_angles",
    "pose_from_parts",
    "pose_matrices",
    "pose_parts",
    "pose_to_angles",
    "resolve_convention",
    "rotation_from_angles",
    "rotvec_from_angles",
    "rotvec_to_matrix",
    "se3_exp",
    "se3_log",
    "skew",
    "to_transform",
]
