"""Bottom layer: array validation and batched small-matrix linear algebra."""

from pkmkit.numerics.arrays import as_batch, finite_rows, require_finite, restore_shape
from pkmkit.numerics.linalg import batched_det, condition_number, singular_values

__all__ = [
    "as_batch",
    "batched_det",
    "condition_number",
    "finite_rows",
    "require_finite",
    "restore_shape",
    "singular_values",
]
