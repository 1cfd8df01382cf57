"""A 3-D view a person can open: one self-contained HTML page (Plotly, bundled; no network).

The page shows the machine drawn from its geometry (:func:`pkmkit.machines.skeleton.skeleton`,
the same for every family) and, on request, its workspace as a surface, a tool path with the
points its actuators cannot follow coloured, and a calibration's error vectors. One slider per
actuator moves the machine through pkmkit's own direct model: each slider's positions are
precomputed (the actuator across its stroke, the others at home), so the page needs no Python.

Lengths are drawn in millimetres.
"""

from __future__ import annotations

import base64
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pkmkit.exceptions import (
    ConvergenceError,
    InputError,
    NoAssemblyError,
    SingularConfigurationError,
)
from pkmkit.machines.skeleton import Skeleton, skeleton
from pkmkit.machines.strokes import stroke_excess, stroke_limits

#: Positions of each actuator's slider (its stroke, ends included).
SLIDER_STEPS = 21
_MM = 1000.0
_LEG_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b")
_KIND_STYLE = {"guide": ("#9a9a9a", 9), "platform": ("#222222", 5), "head": ("#555555", 8),
               "tool": ("#dc143c", 6)}


@dataclass
class ViewContent:
    """What a view shows, for the command's summary: slider positions per actuator that the
    direct model assembled (``steps``) and refused (``skipped``), the workspace's feasible grid
    points, the path's points and those out of reach or stroke, the error vectors drawn."""

    machine: str
    steps: dict[str, int] = field(default_factory=dict)
    skipped: dict[str, int] = field(default_factory=dict)
    workspace_points: int | None = None
    path_points: int | None = None
    path_refused: int | None = None
    path_first_refused: int | None = None
    error_vectors: int | None = None
    error_max: float | None = None
    error_max_with_rigid: float | None = None


def _line_style(line) -> tuple[str, int]:
    if line.kind == "leg":
        return _LEG_COLOURS[max(line.leg, 0) % len(_LEG_COLOURS)], 5
    return _KIND_STYLE[line.kind]


def _machine_traces(sk: Skeleton, go) -> list[Any]:
    """One trace per skeleton line, then the joints, then the tool point (a fixed count and
    order for every configuration of one machine: the sliders' frames replace their data)."""
    traces, named = [], set()
    for line in sk.lines:
        colour, width = _line_style(line)
        legend = {"guide": "slides and cranks"}.get(line.kind, line.name)
        show = legend not in named
        named.add(legend)
        p = line.points * _MM
        traces.append(go.Scatter3d(x=p[:, 0], y=p[:, 1], z=p[:, 2], mode="lines",
                                   line={"color": colour, "width": width}, name=legend,
                                   legendgroup=legend, showlegend=show, hoverinfo="name"))
    j = sk.joints * _MM
    traces.append(go.Scatter3d(x=j[:, 0], y=j[:, 1], z=j[:, 2], mode="markers",
                               marker={"size": 3, "color": "black"}, name="joints",
                               hoverinfo="skip"))
    t = sk.tool * _MM
    traces.append(go.Scatter3d(x=[t[0]], y=[t[1]], z=[t[2]], mode="markers",
                               marker={"size": 6, "color": "#dc143c", "symbol": "diamond"},
                               name="tool point",
                               hovertemplate="tool point<br>%{x:.3f}, %{y:.3f}, %{z:.3f} mm"))
    return traces


def _slider_values(machine, k: int, steps: int) -> np.ndarray:
    """``steps`` values of actuator ``k`` over its stroke (±10 % of home, ±0.2 rad for an
    angle, where the stroke is unlimited)."""
    lo, hi = stroke_limits(machine)
    home = float(machine.home_q[k])
    a, b = float(lo[k]), float(hi[k])
    if not (np.isfinite(a) and np.isfinite(b)):
        half = 0.2 if machine.angular_actuators[k] else 0.1 * max(abs(home), 1e-3)
        a, b = home - half, home + half
    return np.linspace(a, b, steps)


def _actuator_label(machine, k: int, value: float) -> str:
    if machine.angular_actuators[k]:
        return f"{np.degrees(value):.1f}°"
    return f"{value * _MM:.1f}"


def _workspace_trace(machine, resolution: int, go) -> tuple[Any, int]:
    from pkmkit.analysis.grids import make_grid, pose_frame
    from pkmkit.analysis.workspace import compute_workspace

    frame = pose_frame(machine)
    free = list(range(frame.positions))
    grid = make_grid(frame.lower[free], frame.upper[free], free=free, base=frame.base,
                     names=frame.names, resolution=resolution)
    wmap = compute_workspace(machine, grid)
    feasible = np.asarray(wmap.feasible, dtype=float).reshape(-1)
    points = grid.points[:, :3] * _MM if len(free) == 3 else np.column_stack(
        [grid.points[:, :2] * _MM, np.zeros(grid.size)])
    count = int(feasible.sum())
    if len(free) == 3:
        # a layer of infeasible points around the box closes the surface where the workspace
        # reaches the study box's faces
        shape = tuple(grid.shape)
        volume = np.pad(feasible.reshape(shape), 1)
        points = _padded_points(points.reshape(*shape, 3)).reshape(-1, 3)
        feasible = volume.reshape(-1)
        trace = go.Isosurface(x=points[:, 0], y=points[:, 1], z=points[:, 2], value=feasible,
                              isomin=0.5, isomax=1.0, surface_count=1, opacity=0.25,
                              colorscale=[[0, "#4c9be8"], [1, "#4c9be8"]], showscale=False,
                              caps={"x": {"show": False}, "y": {"show": False},
                                    "z": {"show": False}},
                              name="workspace (in the study box)", showlegend=True,
                              hoverinfo="skip")
    else:
        inside = points[feasible > 0.5]
        trace = go.Scatter3d(x=inside[:, 0], y=inside[:, 1], z=inside[:, 2], mode="markers",
                             marker={"size": 2, "color": "#4c9be8", "opacity": 0.35},
                             name="workspace", hoverinfo="skip")
    return trace, count


def _padded_points(points: np.ndarray) -> np.ndarray:
    """A regular grid of points ``(a, b, c, 3)`` extended by one step on every side."""
    for axis in range(3):
        first = np.take(points, [0], axis=axis)
        second = np.take(points, [1], axis=axis)
        last = np.take(points, [-1], axis=axis)
        before = np.take(points, [-2], axis=axis)
        points = np.concatenate([2 * first - second, points, 2 * last - before], axis=axis)
    return points


def _poses_at(machine, points: np.ndarray) -> np.ndarray:
    """Poses with the tool at ``points (N, 3)`` (m) and the home orientation held."""
    poses = np.tile(np.asarray(machine.home_pose, dtype=float), (len(points), 1))
    d = min(machine.dims if machine.dims <= 3 else 3, 3)
    poses[:, :d] = points[:, :d]
    return poses


def _path_traces(machine, gcode: str | Path, origin, spacing: float, go
                 ) -> tuple[list[Any], int, int, int | None]:
    from pkmkit.motion.gcode import read_gcode

    path = read_gcode(gcode, origin=np.asarray(origin, dtype=float))
    points = path.sample(spacing)
    poses = _poses_at(machine, points)
    q = np.atleast_2d(machine.ik(poses, strokes="ignore"))
    reach = np.isfinite(q).all(axis=1)
    refused = ~reach
    if reach.any():
        refused[reach] = stroke_excess(machine, q[reach]).out_of_stroke
    p = points * _MM
    traces = [go.Scatter3d(x=p[:, 0], y=p[:, 1], z=p[:, 2], mode="lines",
                           line={"color": "#2b8a3e", "width": 4}, name="tool path",
                           hoverinfo="skip")]
    if refused.any():
        bad = p[refused]
        traces.append(go.Scatter3d(x=bad[:, 0], y=bad[:, 1], z=bad[:, 2], mode="markers",
                                   marker={"size": 4, "color": "#e03131"},
                                   name="out of reach or stroke",
                                   hovertemplate="%{x:.3f}, %{y:.3f}, %{z:.3f} mm"))
    first = int(np.flatnonzero(refused)[0]) if refused.any() else None
    return traces, len(points), int(refused.sum()), first


def _error_traces(nominal, calibrated, resolution: int, go, rigid_free: bool = False
                  ) -> tuple[list[Any], int, float, float | None]:
    """Where the calibrated machine's tool goes when the nominal model's actuator values are
    commanded: the error the calibration corrects, as vectors on a grid of the workspace.
    With ``rigid_free`` (measurements that cannot see a rigid motion of the whole machine: a
    part's placement, ball-bar pivots, an identified frame) the best rigid motion of the
    vectors is removed first, as the set-up removes it (its size is a gauge, not an error):
    the vectors, their count, their largest length and (``rigid_free``) the largest before
    the removal."""
    from pkmkit.analysis.grids import make_grid, pose_frame

    frame = pose_frame(nominal)
    free = list(range(frame.positions))
    lo, hi = frame.lower[free], frame.upper[free]
    centre, half = 0.5 * (lo + hi), 0.25 * (hi - lo)  # the middle half of the study box
    grid = make_grid(centre - half, centre + half, free=free, base=frame.base,
                     names=frame.names, resolution=resolution)
    poses = grid.points
    q = np.atleast_2d(nominal.ik(poses, strokes="ignore"))
    ok = np.isfinite(q).all(axis=1)
    reached = np.full((len(poses), 3), np.nan)
    if ok.any():
        x = np.atleast_2d(calibrated.fk(q[ok], strokes="ignore"))
        reached[ok] = _three(x)
    start = _three(poses)
    error = reached - start
    good = np.isfinite(error).all(axis=1)
    if not good.any():
        raise InputError("the calibrated machine reaches none of the nominal grid's poses")
    raw = None
    if rigid_free and good.sum() >= 3:
        from pkmkit.calibration.uncertainty import without_rigid_motion

        raw = float(np.linalg.norm(error[good], axis=1).max())
        error[good] = without_rigid_motion(start[good], error[good][:, :, None])[:, :, 0]
    length = np.linalg.norm(error[good], axis=1)
    worst = float(length.max())
    span = float(np.max(hi - lo))
    gain = 0.05 * span / worst if worst > 0 else 1.0
    a = start[good] * _MM
    b = (start[good] + gain * error[good]) * _MM
    segments = np.full((3 * len(a), 3), np.nan)
    segments[0::3], segments[1::3] = a, b
    trace = go.Scatter3d(x=segments[:, 0], y=segments[:, 1], z=segments[:, 2], mode="lines",
                         line={"color": "#ae3ec9", "width": 3},
                         name=f"calibration: tool error ×{gain:.3g} (max {worst * 1e6:.1f} µm)",
                         hoverinfo="skip")
    return [trace], int(good.sum()), worst, raw


def _three(poses: np.ndarray) -> np.ndarray:
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    if poses.shape[1] >= 3:
        return poses[:, :3]
    return np.column_stack([poses, np.zeros((len(poses), 3 - poses.shape[1]))])


def view_figure(machine, *, q: Any = None, workspace: bool = False, gcode: str | Path | None = None,
                origin=(0.0, 0.0, 0.0), calibrated=None, steps: int = SLIDER_STEPS,
                resolution: int = 15, path_spacing: float = 0.002,
                rigid_free: bool = False) -> tuple[Any, ViewContent]:
    """The Plotly figure of the view and what it shows.

    Args:
        machine: any pkmkit machine.
        q: ``(n,)`` actuator values (m, rad) of the configuration shown first (default home).
        workspace: add the workspace (feasible set of the machine's default criteria over its
            study box, ``resolution`` points along the longest side) as a surface.
        gcode: a G-code program (file or text): its tool path, held at the home orientation,
            with the points out of reach or stroke marked. ``origin``: work offset (m).
        calibrated: the calibrated machine (same family as ``machine``): draw its tool error
            over the middle of the workspace as vectors.
        rigid_free: with ``calibrated``, remove the vectors' best rigid motion (measurements
            whose set-up absorbs one: :func:`_error_traces`).
        steps: slider positions per actuator.

    Every trace and frame goes through Plotly's validation (``go.Scatter3d``, ``go.Frame``):
    the figure is the one :func:`view_html` and :func:`view_fragment` write, which build the
    slider frames without it (:class:`_FrameTraces`; the same page, byte for byte).

    Raises:
        InputError: no assembly at ``q``, or the options cannot be drawn.
    """
    import plotly.graph_objects as go

    def frame(sk: Skeleton, name: str, moving: list[int]) -> Any:
        return go.Frame(name=name, data=_machine_traces(sk, go), traces=moving)

    traces, frames, layout, meta, content = _view_parts(
        machine, frame, q=q, workspace=workspace, gcode=gcode, origin=origin,
        calibrated=calibrated, steps=steps, resolution=resolution, path_spacing=path_spacing,
        rigid_free=rigid_free)
    fig = go.Figure(data=traces, frames=frames)
    fig.update_layout(**layout)
    fig.layout.meta = meta
    return fig, content


def _view_parts(machine, make_frame, *, q, workspace, gcode, origin, calibrated, steps,
                resolution, path_spacing, rigid_free
                ) -> tuple[list[Any], list[Any], dict[str, Any], dict[str, Any], ViewContent]:
    """The validated traces of the first configuration and the options, one frame per slider
    position (``make_frame(skeleton, name, moving)``), the layout, its ``meta`` and the
    content: :func:`view_figure`'s parts, shared with :func:`_view_dict`."""
    import plotly.graph_objects as go

    if steps < 2 or steps > 201:
        raise InputError(f"steps: between 2 and 201 slider positions per actuator, got {steps}")
    first = skeleton(machine, q)
    content = ViewContent(machine=machine.id)
    traces = _machine_traces(first, go)
    moving = list(range(len(traces)))
    extras = []
    if workspace:
        trace, content.workspace_points = _workspace_trace(machine, resolution, go)
        extras.append(trace)
    if gcode is not None:
        path_traces, content.path_points, content.path_refused, content.path_first_refused = (
            _path_traces(machine, gcode, origin, path_spacing, go))
        extras.extend(path_traces)
    if calibrated is not None:
        (error_traces, content.error_vectors, content.error_max,
         content.error_max_with_rigid) = _error_traces(machine, calibrated,
                                                       max(5, resolution // 2), go, rigid_free)
        extras.extend(error_traces)
    frames, sliders = [], []
    names = list(machine.actuator_names)
    for k, name in enumerate(names):
        slider_steps = []
        for j, value in enumerate(_slider_values(machine, k, steps)):
            qk = np.array(first.q, dtype=float)
            qk[k] = value
            try:
                sk = skeleton(machine, qk)
            except (NoAssemblyError, SingularConfigurationError, ConvergenceError):
                continue  # no assembly there: the slider skips this position
            if len(sk.lines) != len(first.lines):
                continue
            frame_name = f"{name}:{j}"
            frames.append(make_frame(sk, frame_name, moving))
            slider_steps.append({"label": _actuator_label(machine, k, value), "method": "animate",
                                 "args": [[frame_name], {"mode": "immediate",
                                                         "frame": {"duration": 0, "redraw": True},
                                                         "transition": {"duration": 0}}]})
        content.steps[name] = len(slider_steps)
        content.skipped[name] = steps - len(slider_steps)
        if slider_steps:
            unit = "deg" if machine.angular_actuators[k] else "mm"
            home = int(np.argmin([abs(v - first.q[k]) for v in
                                  _slider_values(machine, k, steps)]))
            active = min(home, len(slider_steps) - 1)
            sliders.append({"active": active, "steps": slider_steps, "len": 0.9, "x": 0.05,
                            "y": -0.02 - 0.12 * len(sliders), "pad": {"t": 30},
                            "currentvalue": {"prefix": f"{name} [{unit}] = "}})
    lower, upper = first.bounds()
    size = float(np.max(upper - lower)) * _MM or 1.0
    layout = {
        "title": f"{machine.name}: {len(names)} actuators; one slider each (the others at home)",
        "scene": {"xaxis_title": "x [mm]", "yaxis_title": "y [mm]", "zaxis_title": "z [mm]",
                  "aspectmode": "data"},
        "sliders": sliders, "height": 640 + 90 * len(sliders),
        "margin": {"l": 0, "r": 0, "t": 50}, "legend": {"itemsizing": "constant"},
        "uirevision": "pkmkit"}
    return traces + extras, frames, layout, {"pkmkit_machine": machine.id, "size_mm": size}, content


class _FrameTraces:
    """Stands in for ``plotly.graph_objects`` in :func:`_machine_traces` for the slider
    frames: a ``Scatter3d`` is the dictionary Plotly's validation makes of it, without running
    the validation again for every frame.

    The first trace of each style (every argument but the coordinates) is validated by
    ``go.Scatter3d`` and kept; a later trace of that style is a copy of it with its own
    coordinates, coerced as Plotly's data-array validator coerces them (an array to a
    C-ordered copy of its dtype, a list to Python scalars). A frame is the dictionary
    ``go.Frame(name=, data=, traces=)`` makes. Plotly validated each frame's traces at ≈ 0.3 ms
    a trace (the calibration report's view: 13 traces × 33 frames, ≈ 0.5 s of CPU a report);
    the page written is the same, byte for byte (tests/export/test_view_page.py)."""

    _COORDS = ("x", "y", "z")

    def __init__(self):
        import plotly.graph_objects as go

        self._go = go
        self._styles: dict[str, dict[str, Any]] = {}

    def Scatter3d(self, **kwargs: Any) -> dict[str, Any]:  # Plotly's name
        style = {k: v for k, v in kwargs.items() if k not in self._COORDS}
        try:  # a style holding an array or a NumPy scalar is validated every time
            key = json.dumps(style, sort_keys=True)
        except TypeError:
            return self._go.Scatter3d(**kwargs).to_plotly_json()
        kept = self._styles.get(key)
        if kept is None:
            kept = self._styles[key] = self._go.Scatter3d(**kwargs).to_plotly_json()
            return dict(kept)
        trace = dict(kept)
        for axis in self._COORDS:
            if axis in kwargs:
                trace[axis] = _coerced(kwargs[axis])
        return trace

    def frame(self, sk: Skeleton, name: str, moving: list[int]) -> dict[str, Any]:
        return {"data": _machine_traces(sk, self), "name": name, "traces": list(moving)}


def _coerced(value: Any) -> Any:
    """A coordinate array as Plotly's data-array validator keeps it and ``to_dict()`` writes
    it: a float64 vector as its typed-array form (base64 of its bytes), another array as a
    C-ordered copy (``to_dict()``'s conversion applies), a list as Python scalars."""
    if isinstance(value, np.ndarray):
        if value.dtype == np.float64 and value.ndim == 1:
            data = np.ascontiguousarray(value).tobytes()
            return {"dtype": "f8", "bdata": base64.b64encode(data).decode("ascii")}
        return np.array(value, order="C", copy=True)
    return np.asarray(value).tolist()


def _view_dict(machine, **options: Any) -> tuple[dict[str, Any], ViewContent]:
    """:func:`view_figure`'s figure as the dictionary its ``to_dict()`` gives, its frames
    built by :class:`_FrameTraces` (the first configuration, the options' traces and the
    layout are validated by Plotly as in :func:`view_figure`)."""
    import plotly.graph_objects as go
    from _plotly_utils.utils import convert_to_base64

    maker = _FrameTraces()
    options = {"q": None, "workspace": False, "gcode": None, "origin": (0.0, 0.0, 0.0),
               "calibrated": None, "steps": SLIDER_STEPS, "resolution": 15,
               "path_spacing": 0.002, "rigid_free": False, **options}
    traces, frames, layout, meta, content = _view_parts(machine, maker.frame, **options)
    fig = go.Figure(data=traces)
    fig.update_layout(**layout)
    fig.layout.meta = meta
    figure = fig.to_dict()
    if frames:
        convert_to_base64(frames)
        figure["frames"] = frames
    return figure, content


#: Run by the page once drawn: a position named in the address (``view.html#q1:5``, an
#: actuator's name and its slider position) is shown at once, and the page records the tool
#: point it shows (``data-tool`` on the body, mm) after every move, for scripts and tests.
_PAGE_SCRIPT = """
var gd = document.getElementById('{plot_id}');
function pkmkitReport(name) {
  var tool = gd.data.filter(function (t) { return t.name === 'tool point'; })[0];
  document.body.setAttribute('data-tool', JSON.stringify([tool.x[0], tool.y[0], tool.z[0]]));
  document.body.setAttribute('data-frame', name || '');
}
var pkmkitStart = decodeURIComponent(window.location.hash.slice(1));
var pkmkitFrame = pkmkitStart;
gd.on('plotly_sliderchange', function (e) { pkmkitFrame = e.step.args[0][0]; });
gd.on('plotly_animated', function () { pkmkitReport(pkmkitFrame); });
if (pkmkitStart) {
  Plotly.animate(gd, [pkmkitStart], {mode: 'immediate', frame: {duration: 0, redraw: true},
                                     transition: {duration: 0}})
    .then(function () { pkmkitReport(pkmkitStart); });
} else {
  pkmkitReport('');
}
"""


def view_fragment(machine, **options: Any) -> tuple[str, ViewContent]:
    """The view as an HTML fragment (a ``<div>`` with the Plotly library and the page script
    inlined) to embed in another self-contained page, such as a calibration's
    ``report.html``; ``options`` as :func:`view_figure`."""
    figure, content = _view_dict(machine, **options)
    return _page(figure, full_html=False), content


def view_html(machine, **options: Any) -> tuple[str, ViewContent]:
    """The view as one self-contained HTML page (the Plotly library inlined) and what it
    shows; ``options`` as :func:`view_figure`."""
    figure, content = _view_dict(machine, **options)
    return _page(figure, full_html=True), content


def _page(figure: Any, *, full_html: bool) -> str:
    """The HTML of a figure (a ``go.Figure``, or the dictionary of :func:`_view_dict`, whose
    parts Plotly validated already): the Plotly library inlined, the page script run."""
    import plotly.io as pio

    return pio.to_html(figure, include_plotlyjs=True, full_html=full_html, div_id="pkmkit-view",
                       config={"displaylogo": False, "responsive": True},
                       post_script=_PAGE_SCRIPT, auto_play=False,
                       validate=not isinstance(figure, dict))
