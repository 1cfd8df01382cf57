"""Seed 003's ball-bar protocol (§3.3.1, Fatronik's procedure on the Verne) as a ready plan, and its
iteration.

**Plan.** One end of the bar on a table point (the pivot), the other in a tool holder at the tool
centre; the NC programme sends the tool centre to **324 points on a hemisphere** whose radius is
the bar's nominal length, centred on the pivot, stops at each and reads the bar's length. This is
repeated for **3 table points** and **2 tool lengths**: 6 acquisition files, 6 × 324 = 1944
readings. The seed gives neither the points' pattern nor the table points, the bar or the tool
lengths; pkmkit uses an equal-area spiral on the hemisphere's cap above ``min_elevation`` (10°
by default: the bar must clear the table), three table points in a triangle under the machine's
default box, a 150 mm bar and tool lengths 0 and 100 mm (illustrative, like the Verne-type
machine's dimensions).

**Iteration.** The readings and the controller's current parameters go to the identification,
which updates the controller; "if the accuracy is not satisfactory, the ball-bar calibration is
repeated: in practice two or three iterations are needed" (seed 003). :func:`ballbar_iterations`
does exactly that: measure the plan with the current controller (its inverse model turns the
programme's points into actuator commands), identify, update, measure again.

The plan is a file ``simulate-measurements --measure ballbar --poses plan.csv`` takes: columns
``x, y, z`` (the programmed tool-centre point), ``px, py, pz`` (the table point), ``tool_length``,
``tool`` (T1, T2) and ``id`` (the acquisition file and point, e.g. ``P2-T1-017``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.calibration.controller import commanded_q
from pkmkit.calibration.models import tool_state
from pkmkit.exceptions import InputError
from pkmkit.model.measurement_set import MeasurementSet

#: Seed 003's protocol: points per hemisphere, table points, tool lengths.
SEED_POINTS, SEED_TABLE_POINTS, SEED_TOOLS = 324, 3, 2
#: pkmkit's choices where the seed is silent (module docstring): bar (m), tools (m), elevation.
BAR_LENGTH = 0.15
TOOL_LENGTHS = (0.0, 0.1)
MIN_ELEVATION = np.radians(10.0)
#: Uncertainty of a table point's position before identification (m, uniform ±).
PIVOT_UNCERTAINTY = 2e-4


@dataclass(frozen=True)
class BallbarPlan:
    """A ball-bar plan (machine frame, m): ``targets`` ``(N, 3)`` programmed tool-centre points,
    ``pivot`` ``(N, 3)`` their table points, ``tool_length`` ``(N,)``, ``tool`` ``(N,)`` labels,
    ``ids`` ``(N,)`` acquisition-and-point labels, ``bar_length``."""

    targets: np.ndarray
    pivot: np.ndarray
    tool_length: np.ndarray
    tool: tuple[str, ...]
    ids: tuple[str, ...]
    bar_length: float

    def __len__(self) -> int:
        return len(self.targets)


def hemisphere(points: int = SEED_POINTS, min_elevation: float = MIN_ELEVATION) -> np.ndarray:
    """``(points, 3)`` unit vectors spread evenly (equal-area golden-angle spiral) over the cap
    of the upper hemisphere above ``min_elevation`` (rad), from the rim up."""
    if points < 1:
        raise InputError(f"points must be ≥ 1, got {points}")
    if not 0 <= min_elevation < np.pi / 2:
        raise InputError("the minimum elevation must be in [0°, 90°)")
    k = np.arange(points) + 0.5
    z = np.sin(min_elevation) + (1 - np.sin(min_elevation)) * k / points
    azimuth = k * np.pi * (3 - np.sqrt(5))
    r = np.sqrt(1 - z**2)
    return np.column_stack([r * np.cos(azimuth), r * np.sin(azimuth), z])


def default_table_points(machine, bar_length: float = BAR_LENGTH) -> np.ndarray:
    """Three table points ``(3, 3)`` (m) in a triangle under the machine's default box: the
    hemispheres stay in the box (its bottom at the pivots' height)."""
    lo, hi = (np.asarray(v, dtype=float)[:3] for v in machine.default_box())
    centre = (lo + hi) / 2
    room = max(0.0, float(min(hi[0] - lo[0], hi[1] - lo[1])) / 2 - bar_length)
    spread = min(0.5 * room, 0.25 * bar_length) if room > 0 else 0.0
    angles = np.radians([90.0, 210.0, 330.0])
    pts = np.column_stack([centre[0] + spread * np.cos(angles), centre[1] + spread * np.sin(
        angles), np.full(3, lo[2])])
    return np.round(pts, 9)  # whole nanometres: no 1e-15 m of a cosine in a plan file


def ballbar_plan(machine, *, bar_length: float = BAR_LENGTH, table_points: Any = None,
                 tool_lengths: Any = TOOL_LENGTHS, points: int = SEED_POINTS,
                 min_elevation: float = MIN_ELEVATION) -> BallbarPlan:
    """The seed's plan (module docstring) for ``machine``: every table point with every tool,
    ``points`` hemisphere points each.

    Raises:
        InputError: a point the machine's controller cannot reach (which acquisition and how
            many), a bar length ≤ 0.
    """
    if not (np.isfinite(bar_length) and bar_length > 0):
        raise InputError(f"the bar length must be > 0, got {bar_length!r}")
    pivots = (default_table_points(machine, bar_length) if table_points is None
              else np.atleast_2d(np.asarray(table_points, dtype=float)))
    if pivots.shape[1] != 3 or not np.isfinite(pivots).all():
        raise InputError("table points must be finite (k, 3) coordinates")
    tools = np.asarray(tool_lengths, dtype=float).reshape(-1)
    dirs = hemisphere(points, min_elevation)
    targets, pivot, tl, tool, ids = [], [], [], [], []
    for i, p in enumerate(pivots):
        for j, length in enumerate(tools):
            tgt = p + bar_length * dirs
            q = commanded_q(machine, tgt, np.full(points, length))
            bad = ~np.isfinite(q).all(axis=1) | ~_within(machine, q)
            if bad.any():
                raise InputError(f"acquisition P{i + 1}-T{j + 1}: {int(bad.sum())} of {points} "
                                 f"hemisphere points (table point {np.round(p * 1e3, 3)} mm, "
                                 f"tool {length * 1e3:g} mm) are out of reach; move the table "
                                 "point or shorten the bar")
            targets.append(tgt)
            pivot.append(np.tile(p, (points, 1)))
            tl.append(np.full(points, length))
            tool += [f"T{j + 1}"] * points
            ids += [f"P{i + 1}-T{j + 1}-{k + 1:03d}" for k in range(points)]
    return BallbarPlan(targets=np.concatenate(targets), pivot=np.concatenate(pivot),
                       tool_length=np.concatenate(tl), tool=tuple(tool), ids=tuple(ids),
                       bar_length=float(bar_length))


def _within(machine, q: np.ndarray) -> np.ndarray:
    """``(N,)`` True where every actuator of ``q`` ``(N, n)`` is within its stroke."""
    model = machine.model
    lo, hi = np.asarray(model.q_min, dtype=float), np.asarray(model.q_max, dtype=float)
    if lo.shape[0] != q.shape[1]:  # a joint chain: the actuated joints' strokes
        act = np.flatnonzero(model.actuated)
        lo, hi = lo[act], hi[act]
    q = np.nan_to_num(q, nan=np.inf)
    return ((q >= lo) & (q <= hi)).all(axis=1)


def measure_plan(true_machine, controller, plan: BallbarPlan, rng: np.random.Generator, *,
                 sigma: float = 5e-7, true_pivots: np.ndarray | None = None,
                 source: str = "ball-bar plan") -> MeasurementSet:
    """Run the plan: ``controller``'s inverse model commands each point, ``true_machine`` goes
    where its geometry sends it, the bar reads the distance to the true table point (``true_
    pivots``: ``(N, 3)``; default the planned ones) with Gaussian noise σ (m)."""
    q = commanded_q(controller, plan.targets, plan.tool_length)
    point = tool_state(true_machine, q, plan.tool_length, jacobian=False).point
    pivots = plan.pivot if true_pivots is None else true_pivots
    length = np.linalg.norm(point - pivots, axis=1)
    length = length + sigma * rng.standard_normal(len(length))
    if not np.isfinite(length).all():
        raise InputError(f"{int((~np.isfinite(length)).sum())} plan points are out of the "
                         "true machine's reach")
    return MeasurementSet(kind="ballbar", values=length[:, None], q=q,
                          tool_length=plan.tool_length, tool=plan.tool, pivot=plan.pivot,
                          labels=plan.ids, source=source)


def true_table_points(plan: BallbarPlan, rng: np.random.Generator,
                      uncertainty: float = PIVOT_UNCERTAINTY) -> np.ndarray:
    """The table points where they really are ``(N, 3)``: each distinct planned point moved by
    a uniform ±``uncertainty`` (m) per coordinate (identified with the machine)."""
    unique, inverse = np.unique(plan.pivot, axis=0, return_inverse=True)
    moved = unique + rng.uniform(-uncertainty, uncertainty, unique.shape)
    return moved[np.asarray(inverse).reshape(-1)]


def ballbar_iterations(true_machine, nominal, plan: BallbarPlan, rng: np.random.Generator, *,
                       iterations: int = 3, sigma: float = 5e-7) -> list[dict[str, Any]]:
    """The seed's iteration (module docstring): ``iterations`` rounds of measure → identify →
    update the controller. Each round's bar-length RMS before and after its identification and
    the machined validation part's largest deviations along x and y with the updated controller
    (:func:`pkmkit.calibration.studies.machined_errors`), SI."""
    from pkmkit.calibration.identify import calibrate
    from pkmkit.calibration.studies import machined_errors

    pivots = true_table_points(plan, rng)
    controller = nominal
    out = []
    for k in range(iterations):
        data = measure_plan(true_machine, controller, plan, rng, sigma=sigma, true_pivots=pivots)
        result = calibrate(controller, data)
        controller = result.machine
        part = machined_errors(true_machine, nominal, controller)["compensated"]
        out.append({"iteration": k + 1, "identified": len(result.names),
                    "rms_before": result.before.rms, "rms_after": result.after.rms,
                    "along_x": part["along_x"], "along_y": part["along_y"],
                    "machine": controller})
    return out


PLAN_COLUMNS = ("x", "y", "z", "px", "py", "pz", "tool_length")


def format_plan(plan: BallbarPlan, *, units: str = "mm", comment: str = "") -> str:
    """The plan file's text (module docstring), lengths in ``units``."""
    from pkmkit.model.parameters import length_scale

    scale = length_scale(units)
    out = [f"# {line}" for line in comment.splitlines() if line.strip()]
    out += [f"# units: {units}", f"# bar length: {plan.bar_length / scale:.10g} {units}",
            ",".join((*PLAN_COLUMNS, "tool", "id"))]
    values = np.column_stack([plan.targets, plan.pivot, plan.tool_length]) / scale
    for row, tool, label in zip(values, plan.tool, plan.ids, strict=True):
        out.append(",".join(f"{v:.10g}" for v in row) + f",{tool},{label}")
    return "\n".join(out) + "\n"


def read_plan(path, *, units: str | None = None) -> BallbarPlan:
    """Read a plan file (module docstring); errors name the file line and column.

    Raises:
        InputError: a malformed file, or rows whose distance to their table point differs
            (a plan is one bar length), naming the line.
    """
    from pkmkit.io.measurements import read_csv_table

    table = read_csv_table(path, PLAN_COLUMNS, ("tool", "id"), units=units,
                           what=" (a ball-bar plan)")
    col = {c: table.numbers[c] * table.scale for c in PLAN_COLUMNS}
    targets = np.column_stack([col["x"], col["y"], col["z"]])
    pivot = np.column_stack([col["px"], col["py"], col["pz"]])
    radius = np.linalg.norm(targets - pivot, axis=1)
    bar = float(np.median(radius))
    off = np.flatnonzero(np.abs(radius - bar) > 1e-6 * max(bar, 1e-3))
    if off.size:
        i = int(off[0])
        raise InputError(f"{table.lines[i]}: column 'x': the point is "
                         f"{radius[i] / table.scale:.6g} {table.unit} from its table point, the "
                         f"plan's bar is {bar / table.scale:.6g} {table.unit}")
    n = len(targets)
    tool = tuple(table.texts.get("tool", [f"L{v:g}" for v in col["tool_length"]]))
    ids = tuple(table.texts.get("id", [f"row {k + 1}" for k in range(n)]))
    return BallbarPlan(targets=targets, pivot=pivot, tool_length=col["tool_length"], tool=tool,
                       ids=ids, bar_length=bar)
