"""Batched rigid-body maths: rotations as rotation vectors and matrices."""

from pkmkit.spatial.rotation import compose_rotvec, rotvec_to_matrix, skew

__all__ = ["compose_rotvec", "rotvec_to_matrix", "skew"]
