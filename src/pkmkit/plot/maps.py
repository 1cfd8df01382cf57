"""Figures of the analysis layer: index maps, workspace maps with the inscribed square/cube,
joint-space maps, velocity ellipses and actuator-coordinate maps (matplotlib, pyplot-free).

The analyses are in SI; a figure draws its positions (and linear actuator values) in the
length ``unit`` it is given (``"m"``, ``"mm"``, ``"in"``: a command's ``--units``), its axis
labels, titles and colour bars saying so; angular actuators are drawn in degrees.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from matplotlib.backend_bases import FigureCanvasBase
from matplotlib.colors import ListedColormap, LogNorm
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse, Rectangle
from matplotlib.ticker import MaxNLocator

from pkmkit.analysis.grids import Grid
from pkmkit.analysis.joint_space import JointSpaceMap, UsefulWorkspace
from pkmkit.analysis.workspace import InscribedBox, WorkspaceMap
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.model.parameters import length_scale
from pkmkit.plot.save import save_figure

#: Colours of the workspace classes: first failing criterion, then feasible.
_CLASSES = (
    ("unreachable", "#d9d9d9"),
    ("strokes", "#fdd0a2"),
    ("mode", "#bcbddc"),
    ("bounds", "#fcbba1"),
    ("condition", "#fc9272"),
    ("stiffness", "#9ecae1"),
    ("disconnected", "#c7e9c0"),
    ("workspace", "#41ab5d"),
    ("not evaluated", "#ffffff"),  # beyond a flood fill's rim (WorkspaceMap.evaluated)
)
_DISCONNECTED, _WORKSPACE, _NOT_EVALUATED = 6, 7, 8


def check_figure_path(path: str | Path) -> Path:
    """Validate a figure file name before any work: an existing folder and an extension
    matplotlib can write (.png, .svg, .pdf, ...).

    Raises:
        InputError: missing folder, no extension or an unsupported one.
    """
    path = Path(path)
    formats = FigureCanvasBase.get_supported_filetypes()
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in formats:
        what = f"extension .{suffix}" if suffix else "no extension"
        raise InputError(f"cannot write figure {str(path)!r}: {what}; use one of "
                         f"{', '.join('.' + k for k in sorted(formats))}")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise InputError(f"cannot write figure {str(path)!r}: folder {str(folder)!r} does not "
                         "exist")
    return path


def _save(fig: Figure, path: str | Path | None) -> Figure:
    if path is not None:
        check_figure_path(path)
        try:
            save_figure(fig, path, dpi=120, bbox_inches="tight")
        except OSError as exc:
            raise InputError(f"cannot write figure {str(path)!r}: "
                             f"{exc.strerror or exc}") from None
    return fig


def _extent(grid: Grid) -> list[float]:
    (ax0, ax1) = grid.axes
    h = 0.5 * grid.step
    return [ax0[0] - h, ax0[-1] + h, ax1[0] - h, ax1[-1] + h]


def _per_unit(unit: str) -> float:
    """SI value (m, or rad for ``"deg"``) of one ``unit``."""
    return float(np.radians(1.0)) if unit == "deg" else length_scale(unit)


def _shown(grid: Grid, unit: str) -> Grid:
    """``grid`` with its coordinates in ``unit`` instead of SI (what a figure draws)."""
    s = _per_unit(unit)
    return dataclasses.replace(
        grid, axes=tuple(np.asarray(a) / s for a in grid.axes),
        base=np.asarray(grid.base, dtype=float) / s, step=grid.step / s,
        upper=None if grid.upper is None else np.asarray(grid.upper) / s)


def _labels(ax, grid: Grid, unit: str) -> None:
    ax.set_xlabel(f"{grid.free_names[0]} [{unit}]")
    ax.set_ylabel(f"{grid.free_names[1]} [{unit}]")
    ax.set_aspect("equal")


#: A map's colour scale stops at the 95th percentile when the largest value exceeds it by more
#: than this factor (a singular curve would otherwise squeeze every other value into one colour).
TAIL_FACTOR = 10.0
#: ``scale="auto"`` switches to logarithmic levels above this ratio of largest to smallest value.
LOG_RATIO = 10.0


def color_levels(values: np.ndarray, levels: int = 12, scale: str = "auto"
                 ) -> tuple[np.ndarray, bool, bool]:
    """Contour levels for the finite values of ``values``: ``(levels, logarithmic, clipped)``.

    ``scale`` is ``"linear"``, ``"log"`` or ``"auto"`` (log when every value is positive and the
    largest exceeds the smallest by more than :data:`LOG_RATIO`). Linear levels are round
    numbers covering the values (``MaxNLocator``), logarithmic ones 1, 1.5, 2, 3, 5, 7 × 10^k.
    When the largest value exceeds the 95th percentile by more than :data:`TAIL_FACTOR` (a
    condition number near a singularity, up to 1e17), the levels stop at that percentile and
    ``clipped`` is True: larger values get the top colour.
    """
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    if finite.size == 0:
        raise ValueError("nothing to draw: the index is undefined everywhere on the slice")
    if scale not in ("auto", "linear", "log"):
        raise InputError(f"unknown colour scale {scale!r}; use auto, linear or log")
    low, high = float(finite.min()), float(finite.max())
    if scale == "log" and low <= 0:
        raise InputError("a logarithmic colour scale needs positive values")
    logarithmic = scale == "log" or (scale == "auto" and low > 0 and high > LOG_RATIO * low)
    top = high
    p95 = float(np.percentile(finite, 95))
    clipped = False
    if logarithmic and high > TAIL_FACTOR * p95 and p95 > low:
        top, clipped = p95, True
    elif not logarithmic and high - low > TAIL_FACTOR * (p95 - low) and p95 > low:
        top, clipped = p95, True
    if not top > low:
        return np.linspace(low - 0.5, low + 0.5, 3), False, False
    if logarithmic:
        return _log_levels(low, top, levels, clipped), True, clipped
    return MaxNLocator(levels + 1).tick_values(low, top), False, clipped


def _log_levels(low: float, top: float, count: int, clipped: bool) -> np.ndarray:
    """Readable logarithmic levels (1, 1.5, 2, 3, 5, 7 × 10^k) from ``low`` to ``top``."""
    first, last = int(np.floor(np.log10(low))), int(np.ceil(np.log10(top)))
    nice = np.array([m * 10.0**k for k in range(first, last + 1)
                     for m in (1.0, 1.5, 2.0, 3.0, 5.0, 7.0)])
    nice = nice[(nice > low * (1 + 1e-9)) & (nice < top * (1 - 1e-9))]
    while nice.size > count:
        nice = nice[1::2] if nice.size % 2 == 0 else nice[::2]
    return np.concatenate([[low], nice, [top]])


def plot_scalar_map(grid: Grid, values: np.ndarray, *, ax=None, title: str = "",
                    label: str = "", levels: int | np.ndarray = 12, unit: str = "m",
                    scale: str = "auto", path: str | Path | None = None) -> Figure:
    """Filled iso-contours of ``values`` (shape ``grid.shape``, 2 free axes; NaN = blank), the
    grid (m) drawn in ``unit``.

    ``scale``: colour levels, see :func:`color_levels` (ignored when ``levels`` is an array).
    Near a singularity (κ → ∞) the levels stop at the 95th percentile and the colour bar is
    extended: the map stays readable where the machine is usable.
    """
    if len(grid.free) != 2:
        raise ValueError("a map needs a grid with two free axes (a plane slice)")
    if ax is None:
        fig = Figure(figsize=(6.0, 5.0), layout="constrained")
        ax = fig.add_subplot()
    fig = ax.figure
    x, y = np.meshgrid(*_shown(grid, unit).axes, indexing="ij")
    data = np.ma.masked_invalid(values)
    if data.count() == 0:
        raise ValueError("nothing to draw: the index is undefined everywhere on the slice")
    norm = None
    extend = "neither"
    if np.ndim(levels) == 0:
        levels, logarithmic, clipped = color_levels(data.compressed(), int(levels), scale)
        if logarithmic:
            norm = LogNorm(vmin=levels[0], vmax=levels[-1])
        if clipped:  # larger values take the colour bar's extension
            extend = "max"
            label = f"{label} (top colour: above {levels[-1]:.3g})"
    filled = ax.contourf(x, y, data, levels=levels, cmap="viridis", norm=norm, extend=extend)
    lines = ax.contour(x, y, data, levels=filled.levels, colors="k", linewidths=0.4, norm=norm)
    ax.clabel(lines, fmt="%.3g", fontsize=6)
    bar = fig.colorbar(filled, ax=ax, label=label)
    if norm is not None:
        bar.set_ticks(filled.levels, labels=[f"{v:.3g}" for v in filled.levels])
        bar.minorticks_off()
    _labels(ax, grid, unit)
    ax.set_title(title, fontsize=9)
    return _save(fig, path)


def _draw_box(ax, box: InscribedBox | None, free: tuple[int, ...], unit: str = "m",
              **style) -> None:
    if box is None:
        return
    i, j = free[:2]
    s = _per_unit(unit)
    ax.add_patch(Rectangle((box.lower[i] / s, box.lower[j] / s), box.side / s, box.side / s,
                           fill=False, **{"edgecolor": "k", "linewidth": 1.6, **style}))


def classify(wmap: WorkspaceMap) -> np.ndarray:
    """Integer class per grid point: index into the workspace classes (first failing criterion,
    "disconnected", "workspace", or "not evaluated": beyond the rim of a flood fill from
    home)."""
    out = np.full(wmap.grid.shape, _DISCONNECTED)  # disconnected by default
    order = ("reachable", "strokes", "mode", "bounds", "condition", "stiffness")
    assigned = np.zeros(wmap.grid.shape, bool)
    for k, name in enumerate(order):
        if name not in wmap.masks:  # no stiffness criterion
            continue
        fail = ~wmap.masks[name] & ~assigned
        out[fail] = k
        assigned |= fail
    out[wmap.feasible] = _WORKSPACE
    if wmap.evaluated is not None:
        out[~wmap.evaluated] = _NOT_EVALUATED
    return out


def _plot_classes(ax, classes: np.ndarray, grid: Grid) -> None:
    cmap = ListedColormap([c for _, c in _CLASSES])
    ax.imshow(classes.T, origin="lower", extent=_extent(grid), cmap=cmap,
              vmin=-0.5, vmax=len(_CLASSES) - 0.5, interpolation="nearest")
    present = set(np.unique(classes).tolist())
    for k, (name, colour) in enumerate(_CLASSES):
        if k in present:
            ax.plot([], [], "s", color=colour, label=name)


def plot_workspace(wmap: WorkspaceMap, machine: Machine, *, title: str = "", unit: str = "m",
                   path: str | Path | None = None) -> Figure:
    """Workspace classes on a 2-D grid (or three slices through the inscribed cube of a 3-D
    grid), with the largest inscribed square/cube and the home pose, drawn in ``unit``."""
    grid = wmap.grid
    s = length_scale(unit)
    classes = classify(wmap)
    if len(grid.free) == 2:
        fig = Figure(figsize=(6.4, 5.6), layout="constrained")
        ax = fig.add_subplot()
        _plot_classes(ax, classes, _shown(grid, unit))
        _draw_box(ax, wmap.inscribed, grid.free, unit, label="inscribed square")
        home = np.asarray(machine.home_pose, dtype=float) / s
        ax.plot(home[grid.free[0]], home[grid.free[1]], "r*", ms=10, label="home")
        _labels(ax, grid, unit)
        ax.legend(fontsize=7, loc="upper right", framealpha=0.8)
        ax.set_title(title or _workspace_title(wmap, unit), fontsize=9)
        return _save(fig, path)
    fig = Figure(figsize=(15, 5.2), layout="constrained")
    center = wmap.inscribed.center if wmap.inscribed is not None else machine.home_pose
    index = grid.nearest_index(center) or tuple(n // 2 for n in grid.shape)
    for panel, (a, b) in enumerate(((0, 1), (0, 2), (1, 2))):
        ax = fig.add_subplot(1, 3, panel + 1)
        cut = [slice(None)] * 3
        other = ({0, 1, 2} - {a, b}).pop()
        cut[other] = index[other]
        sub = Grid(axes=(grid.axes[a], grid.axes[b]), free=(grid.free[a], grid.free[b]),
                   base=grid.base, step=grid.step, names=grid.names)
        _plot_classes(ax, classes[tuple(cut)], _shown(sub, unit))
        _draw_box(ax, wmap.inscribed, sub.free, unit, label="inscribed cube")
        _labels(ax, sub, unit)
        name = grid.names[grid.free[other]]
        ax.set_title(f"slice {name} = {grid.axes[other][index[other]] / s:.4g} {unit}",
                     fontsize=9)
        if panel == 0:
            ax.legend(fontsize=7, loc="upper right", framealpha=0.8)
    fig.suptitle(title or _workspace_title(wmap, unit), fontsize=10)
    return _save(fig, path)


def _workspace_title(wmap: WorkspaceMap, unit: str = "m") -> str:
    d = len(wmap.grid.free)
    what = "area" if d == 2 else "volume"
    s = length_scale(unit)
    text = f"{what} {wmap.measure / s**d:.4g} {unit}{'²' if d == 2 else '³'}"
    if wmap.inscribed is not None:
        text += f", inscribed side {wmap.inscribed.side / s:.4g} {unit}"
    return text


def plot_joint_space(jmap: JointSpaceMap, *, square: InscribedBox | None = None, ax=None,
                     title: str = "", unit: str = "m", path: str | Path | None = None
                     ) -> Figure:
    """Feasible actuator vectors (2 actuators, drawn in ``unit``: a length unit, or ``"deg"``
    for angular actuators) with a square of actuator values."""
    if ax is None:
        fig = Figure(figsize=(6.0, 5.4), layout="constrained")
        ax = fig.add_subplot()
    fig = ax.figure
    grid = jmap.grid
    classes = np.where(jmap.feasible, 2, np.where(jmap.masks["assembly"], 1, 0))
    cmap = ListedColormap(["#d9d9d9", "#fcbba1", "#41ab5d"])
    ax.imshow(classes.T, origin="lower", extent=_extent(_shown(grid, unit)), cmap=cmap,
              vmin=-0.5, vmax=2.5, interpolation="nearest")
    for k, name in enumerate(("no assembly", "criteria fail", "feasible")):
        ax.plot([], [], "s", color=cmap(k), label=name)
    _draw_box(ax, square if square is not None else jmap.inscribed, grid.free, unit,
              label="useful zone")
    _labels(ax, grid, unit)
    ax.legend(fontsize=7, loc="upper right", framealpha=0.8)
    ax.set_title(title, fontsize=9)
    return _save(fig, path)


def plot_useful_workspace(useful: UsefulWorkspace, machine: Machine, *, title: str = "",
                          unit: str = "m", path: str | Path | None = None) -> Figure:
    """Seed 004's pair of figures: joint space with the useful zone, and the useful workspace
    (its image) with the inscribed square and iso-contours of λ_min and λ_max, lengths drawn
    in ``unit``."""
    s = length_scale(unit)
    joint_unit = "deg" if np.asarray(machine.angular_actuators).any() else unit
    fig = Figure(figsize=(12.5, 5.4), layout="constrained")
    plot_joint_space(useful.joint, square=useful.joint_square, ax=fig.add_subplot(1, 2, 1),
                     unit=joint_unit, title=f"joint space: useful zone of side "
                     f"{useful.joint_square.side / _per_unit(joint_unit):.4g} {joint_unit}")
    ax = fig.add_subplot(1, 2, 2)
    ws = useful.workspace
    grid = ws.grid
    shown = _shown(grid, unit)
    ax.imshow(np.where(ws.feasible, 1.0, np.nan).T, origin="lower", extent=_extent(shown),
              cmap=ListedColormap(["#c7e9c0"]), interpolation="nearest")
    x, y = np.meshgrid(*shown.axes, indexing="ij")
    for k, colour in ((0, "tab:red"), (-1, "tab:blue")):
        values = np.where(ws.feasible, ws.factors[..., k], np.nan)
        if np.isfinite(values).any():
            lines = ax.contour(x, y, np.ma.masked_invalid(values), levels=8, colors=colour,
                               linewidths=0.7)
            ax.clabel(lines, fmt="%.2f", fontsize=6)
    ax.plot([], [], color="tab:red", label="λ_max iso-lines")
    ax.plot([], [], color="tab:blue", label="λ_min iso-lines")
    _draw_box(ax, useful.inscribed, grid.free, unit, label="inscribed square")
    home = np.asarray(machine.home_pose, dtype=float) / s
    ax.plot(home[0], home[1], "r*", ms=10, label="home")
    _labels(ax, grid, unit)
    ax.legend(fontsize=7, loc="upper right", framealpha=0.8)
    lo, hi = useful.factor_range
    side = useful.inscribed.side if useful.inscribed is not None else float("nan")
    ax.set_title(f"useful workspace: λ in [{lo:.2f}, {hi:.2f}], inscribed side "
                 f"{side / s:.4g} {unit}", fontsize=9)
    fig.suptitle(title or machine.name, fontsize=10)
    return _save(fig, path)


def plot_ellipses(machine: Machine, poses: np.ndarray, *, free: tuple[int, int] = (0, 1),
                  scale: float | None = None, ax=None, title: str = "",
                  path: str | Path | None = None) -> Figure:
    """Velocity ellipses {J q̇ : ‖q̇‖ ≤ 1} at sample poses, projected on the ``free`` plane."""
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    jac = machine.jacobian(poses)
    if ax is None:
        fig = Figure(figsize=(6.0, 5.4), layout="constrained")
        ax = fig.add_subplot()
    fig = ax.figure
    i, j = free
    span = np.ptp(poses[:, [i, j]], axis=0).max() if len(poses) > 1 else 0.1
    sv_max = np.nanmax(jac.singular_values)
    scale = scale or 0.35 * (span if span > 0 else 0.1) / sv_max
    for pose, jm in zip(poses, jac.J, strict=True):
        if not np.isfinite(jm).all():
            continue
        shape = (jm @ jm.T)[np.ix_([i, j], [i, j])]  # projection of the ellipsoid
        values, vectors = np.linalg.eigh(shape)
        angle = np.degrees(np.arctan2(vectors[1, 1], vectors[0, 1]))
        width, height = 2 * scale * np.sqrt(np.maximum(values[::-1], 0))
        ax.add_patch(Ellipse((pose[i], pose[j]), width, height, angle=angle, fill=False,
                             color="tab:blue"))
        ax.plot(pose[i], pose[j], "k.", ms=3)
    names = machine.pose_names
    ax.set_xlabel(f"{names[i]} [m]")
    ax.set_ylabel(f"{names[j]} [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.set_title(title or f"{machine.name}: velocity ellipses {{J q̇ : ‖q̇‖ ≤ 1}} "
                          f"(scale {scale:.3g} m per m/s)", fontsize=9)
    return _save(fig, path)


def plot_actuator_maps(machine: Machine, grid: Grid, *, title: str = "", unit: str = "m",
                       path: str | Path | None = None) -> Figure:
    """Actuator coordinates over a plane (one panel per actuator), as seed 000 Figs 3.9–3.11:
    positions and linear actuators in ``unit``, angular actuators in degrees."""
    q = machine.ik(grid.points).reshape((*grid.shape, machine.n_actuators))
    n = machine.n_actuators
    angular = np.asarray(machine.angular_actuators, dtype=bool)
    fig = Figure(figsize=(5.2 * n, 4.6), layout="constrained")
    for k in range(n):
        ax = fig.add_subplot(1, n, k + 1)
        shown, what = ((np.degrees(q[..., k]), "deg") if angular[k]
                       else (q[..., k] / length_scale(unit), unit))
        name = machine.actuator_names[k]
        digits = 4 if what == "m" else 2
        plot_scalar_map(grid, shown, ax=ax, label=f"{name} [{what}]", unit=unit,
                        title=f"{name}: {np.nanmin(shown):.{digits}f} … "
                              f"{np.nanmax(shown):.{digits}f} {what}")
    fig.suptitle(title or machine.name, fontsize=10)
    return _save(fig, path)
