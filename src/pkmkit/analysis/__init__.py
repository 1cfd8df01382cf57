"""Algorithms over any machine: kinetostatic indices and workspace analysis."""

from pkmkit.analysis.grids import MAX_GRID_POINTS, Grid, make_grid
from pkmkit.analysis.indices import (
    SCALAR_INDICES,
    Indices,
    global_conditioning_index,
    homogenize,
    indices,
    scalar_index,
)
from pkmkit.analysis.joint_space import (
    JointSpaceMap,
    joint_box_factor_range,
    joint_grid,
    joint_space_map,
    region_factor_range,
    useful_workspace,
)
from pkmkit.analysis.workspace import (
    Criteria,
    InscribedBox,
    RegionCheck,
    WorkspaceMap,
    check_region,
    compute_workspace,
    feasible_interval,
    largest_inscribed_box,
)

__all__ = [
    "MAX_GRID_POINTS",
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
    "joint_box_factor_range",
    "joint_grid",
    "joint_space_map",
    "largest_inscribed_box",
    "make_grid",
    "region_factor_range",
    "scalar_index",
    "useful_workspace",
]
