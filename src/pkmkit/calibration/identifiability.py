"""Identifiability of a machine's defects from measurements — the functions of
:mod:`pkmkit.errors.identifiability` and :mod:`pkmkit.errors.pose_selection` under the
calibration namespace (one implementation)."""

from pkmkit.errors.identifiability import (
    INDICES,
    Combination,
    IdentifiabilityResult,
    IdentificationJacobian,
    analyse_jacobian,
    characteristic_length,
    combined_parameters,
    compatible_parameters,
    identifiability,
    identification_jacobian,
    indices_from_singular_values,
    observability,
)
from pkmkit.errors.pose_selection import PoseSelection, select_poses

__all__ = [
    "INDICES",
    "Combination",
    "IdentifiabilityResult",
    "IdentificationJacobian",
    "PoseSelection",
    "analyse_jacobian",
    "characteristic_length",
    "combined_parameters",
    "compatible_parameters",
    "identifiability",
    "identification_jacobian",
    "indices_from_singular_values",
    "observability",
    "select_poses",
]
