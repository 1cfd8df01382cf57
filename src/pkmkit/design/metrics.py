"""Design metrics: numbers that describe how good a machine is for a prescribed region.

Every metric is computed from one batched evaluation of the region (a grid of poses through the
inverse model and the velocity model), never pose by pose. The prescribed region is an
axis-aligned square (planar machines) or cube, given by its side and centre.

- ``violation``: 0 when every pose of the region satisfies the criteria; otherwise the fraction of
  unreachable poses plus the largest relative excess of a transmission-factor bound or of κ (a
  continuous measure for constraint handling);
- ``stroke``: largest actuator range needed over the region, m;
- ``compactness``: region side / stroke;
- ``lambda_min``, ``lambda_max``: extreme velocity transmission factors over the region;
- ``worst_condition``: largest condition number over the region;
- ``gci``: global conditioning index (mean 1/κ) over the region;
- ``footprint``: area of the convex hull, in the x-y plane, of the carriage joints over the
  region, m²;
- ``inscribed_side``: side of the largest square/cube satisfying the criteria in the machine's
  default box (a workspace computation: slower);
- ``min_stiffness``: smallest translational stiffness over the region, N/m (N/µm at the
  command line) — the least, over the region's poses, of the smallest eigenvalue of
  ``(C_tt)⁻¹`` (:mod:`pkmkit.stiffness.indices`), with the criteria's elastic data
  (``Criteria.stiffness_data``, default the machine's); NaN when a pose has no stiffness.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.workspace import Criteria, compute_workspace, evaluate_poses
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.model.rods import SLIDE
from pkmkit.stiffness.indices import stiffness_figures

METRICS = ("violation", "stroke", "compactness", "lambda_min", "lambda_max", "worst_condition",
           "gci", "footprint", "inscribed_side", "min_stiffness")
#: Metrics computed only when asked (slower): not part of the inert-variable check otherwise.
ON_REQUEST = ("inscribed_side", "min_stiffness")
#: Quantity of each metric (``"length"`` m, ``"area"`` m², ``"stiffness"`` N/m, ``"number"``
#: dimensionless).
METRIC_QUANTITIES = {name: "number" for name in METRICS} | {
    "stroke": "length", "footprint": "area", "inscribed_side": "length",
    "min_stiffness": "stiffness"}


@dataclass(frozen=True)
class Region:
    """A prescribed square/cube: ``side`` (m) and ``center`` (``(dims,)`` m, None: home)."""

    side: float
    center: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.side) and self.side > 0):
            raise InputError(f"the prescribed region's side must be > 0, got {self.side}")
        if self.center is not None:
            center = np.asarray(self.center, dtype=float).reshape(-1)
            if not np.isfinite(center).all():
                raise InputError(f"the prescribed region's centre must be finite, got "
                                 f"{list(self.center)}")

    def check(self, machine: Machine) -> None:
        """Raise :class:`InputError` unless the centre has ``machine.dims`` coordinates."""
        if self.center is not None and len(np.reshape(self.center, -1)) != machine.dims:
            raise InputError(f"the prescribed region's centre needs {machine.dims} coordinates "
                             f"({', '.join(machine.pose_names)}) for {machine.id!r}, got "
                             f"{len(np.reshape(self.center, -1))}")

    def points(self, machine: Machine, samples: int) -> np.ndarray:
        """Grid of ``samples`` points per edge over the region, ``(M, dims)``."""
        self.check(machine)
        center = machine.home_pose if self.center is None else np.asarray(self.center, float)
        free = tuple(range(machine.dims))
        return make_grid(center - self.side / 2, center + self.side / 2, free=free,
                         base=center, names=machine.pose_names, resolution=samples).points


def evaluate_metrics(machine: Machine, region: Region, criteria: Criteria,
                     names: tuple[str, ...] = METRICS, samples: int = 11) -> dict[str, float]:
    """The requested metrics (see the module docstring) of ``machine`` for ``region``."""
    unknown = [n for n in names if n not in METRICS]
    if unknown:
        raise InputError(f"unknown metric(s) {', '.join(unknown)}; valid: {', '.join(METRICS)}")
    points = region.points(machine, samples)
    loose = Criteria(bounds=criteria.bounds, kappa_max=criteria.kappa_max, strokes=False,
                     connected=False, tol=criteria.tol)
    ev = evaluate_poses(machine, points, loose)
    reach = ev.masks["reachable"] & ev.masks["mode"]
    out: dict[str, float] = {}
    sv = ev.factors[reach]
    q = ev.q[reach]
    if "violation" in names:
        excess = 0.0
        if sv.size:
            excess = _excess(sv, ev.condition[reach], criteria)
        out["violation"] = float(1.0 - reach.mean()) + max(excess, 0.0)
    nan = float("nan")
    if "stroke" in names or "compactness" in names:
        stroke = float(np.max(q.max(axis=0) - q.min(axis=0))) if q.size else nan
        out["stroke"] = stroke
        out["compactness"] = region.side / stroke if stroke > 0 else nan
    if "lambda_min" in names:
        out["lambda_min"] = float(sv[:, -1].min()) if sv.size else nan
    if "lambda_max" in names:
        out["lambda_max"] = float(sv[:, 0].max()) if sv.size else nan
    if "worst_condition" in names:
        out["worst_condition"] = float(np.max(ev.condition[reach])) if sv.size else nan
    if "gci" in names:
        out["gci"] = float(np.mean(1.0 / ev.condition[reach])) if sv.size else nan
    if "footprint" in names:
        out["footprint"] = _footprint(machine, q)
    if "min_stiffness" in names:
        smallest = stiffness_figures(machine, points[reach],
                                     data=criteria.stiffness_data).smallest if reach.any() else []
        out["min_stiffness"] = (float(np.min(smallest)) if len(smallest)
                                and np.isfinite(smallest).all() else nan)
    if "inscribed_side" in names:
        lower, upper = machine.default_box()
        grid = make_grid(lower, upper, free=tuple(range(machine.dims)), base=machine.home_pose,
                         names=machine.pose_names, resolution=31 if machine.dims == 3 else 81)
        box = compute_workspace(machine, grid, criteria).inscribed
        out["inscribed_side"] = box.side if box is not None else 0.0
    return {k: out[k] for k in names}


def _excess(sv: np.ndarray, condition: np.ndarray, criteria: Criteria) -> float:
    """Largest relative excess of a transmission-factor bound or of κ_max (inf on a
    singularity)."""
    excess = 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        if criteria.bounds is not None:
            lo, hi = criteria.bounds
            excess = max(excess, float(np.max(lo / sv[:, -1] - 1.0)),
                         float(np.max(sv[:, 0] / hi - 1.0)))
        if criteria.kappa_max is not None:
            excess = max(excess, float(np.max(condition / criteria.kappa_max - 1.0)))
    return excess


def _footprint(machine: Machine, q: np.ndarray) -> float:
    if q.size == 0:
        return float("nan")
    model = machine.model
    slide = (model.leg_kind == SLIDE)[None, :, None]
    joints = model.leg_base[None] + np.where(slide, q[:, :, None] * model.leg_axis[None], 0.0)
    xy = joints[:, :, :2].reshape(-1, 2)
    from scipy.spatial import ConvexHull, QhullError  # at first use (≈ 0.2 s with scipy.sparse)

    try:
        return float(ConvexHull(xy).volume)  # the "volume" of a 2-D hull is its area
    except QhullError:
        return 0.0


def metric_values(machine: Machine | None, region: Region, criteria: Criteria,
                  names: tuple[str, ...], samples: int = 11) -> dict[str, Any]:
    """Metrics of a candidate, or NaN everywhere (and violation = inf) when the candidate could
    not be built (``machine`` None)."""
    if machine is None:
        values = dict.fromkeys(names, float("nan"))
        if "violation" in values:
            values["violation"] = float("inf")
        return values
    return evaluate_metrics(machine, region, criteria, names, samples)
