"""Algorithms over any machine: kinetostatic indices and workspace analysis."""

from pkmkit.analysis.grids import Grid, make_grid
from pkmkit.analysis.indices import (
    SCALAR_INDICES,
    Indices,
    global_conditioning_index,
    homogenize,
    indices,
    scalar_index,
)
from pkmkit.analysis.workspace import (
    Criteria,
    InscribedBox,
    JointSpaceMap,
    RegionCheck,
    WorkspaceMap,
    check_region,
    compute_workspace,
    feasible_interval,
    joint_grid,
    joint_space_map,
    largest_inscribed_box,
    useful_workspace,
)

__all__ = [
    "SCALAR_INDICES",
    "Criteria",
    "Grid",
    "Indices",
    "InscribedBox",
    "JointSpaceMap",
    "RegionCheck",
    "WorkspaceMap",
    "check_region",
    "compute_workspace",
    "feasible_interval",
    "global_conditioning_index",
    "homogenize",
    "indices",
    "joint_grid",
    "joint_space_map",
    "largest_inscribed_box",
    "make_grid",
    "scalar_index",
    "useful_workspace",
]
