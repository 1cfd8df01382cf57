"""The view's page without Plotly's validation of every frame (export/view.py, session 35):
``view_html`` and ``view_fragment`` build the slider frames as the dictionaries Plotly's
validation makes; the oracle is the page of ``view_figure``'s figure, every trace and frame of
which goes through ``go.Scatter3d`` / ``go.Frame`` — the same bytes, for each family and option
(a calibration's vectors, a workspace surface, a tool path, a six-axis machine first shown off
home; a joint chain's frames are built by the same code from its skeleton)."""

from __future__ import annotations

import numpy as np
import plotly.graph_objects as go
import pytest
from _plotly_utils.utils import to_typed_array_spec

import pkmkit
from pkmkit.export import view

PROGRAM = "G21 G90\nG1 X0 Y0 Z0 F600\nG1 X40 Y0 Z0\nG1 X400 Y0 Z0\n"


def _case(name: str):
    if name == "calibrated":
        m = pkmkit.machine("linear-delta")
        return m, {"calibrated": m.with_params(R=0.7002, r=0.1499), "steps": 3,
                   "rigid_free": True}
    if name == "workspace-path":
        return pkmkit.machine("orthoglide"), {"workspace": True, "resolution": 5,
                                              "gcode": PROGRAM, "steps": 2}
    m = pkmkit.machine("gough-stewart")  # six axes, first shown off home
    q = np.array(m.home_q, dtype=float)
    q[0] += 0.01
    return m, {"q": q, "steps": 2}


@pytest.mark.parametrize("case", ["calibrated", "workspace-path", "six-axis-off-home"])
def test_the_page_and_fragment_are_the_validated_figures_byte_for_byte(case):
    machine, options = _case(case)
    fig, shown = view.view_figure(machine, **options)
    page, content = view.view_html(machine, **options)
    fragment, again = view.view_fragment(machine, **options)
    assert content == shown == again
    assert sum(content.steps.values()) == len(fig.frames) > 0
    assert page == view._page(fig, full_html=True)
    assert fragment == view._page(fig, full_html=False)


@pytest.mark.parametrize("value", [
    np.linspace(-1.5, 2.5, 7),
    np.arange(12.0).reshape(4, 3)[:, 1],          # a column: not contiguous
    np.arange(5),                                  # integers: to_dict() narrows them
    np.ones((2, 3)),
    [np.float64(3.25)],                            # the tool point's lists
])
def test_a_coordinate_is_written_as_plotlys_validation_and_to_dict_write_it(value):
    validated = go.Figure(go.Scatter3d(x=value)).to_dict()["data"][0]["x"]
    ours = view._coerced(value)
    if isinstance(ours, np.ndarray):
        ours = to_typed_array_spec(ours)
    assert type(ours) is type(validated)
    if isinstance(ours, dict):
        assert ours == validated
    else:
        assert ours == validated and all(type(v) is float for v in ours)


def test_a_frame_trace_is_the_validated_trace_whatever_the_traces_before_it():
    """Traces that differ in one style argument only (a name, a legend flag, a colour, a
    width: a machine file with more legs than colours has two legs of one colour) are each
    the trace ``go.Scatter3d`` validates, in any order and after any other."""
    from _plotly_utils.utils import convert_to_base64

    rng = np.random.default_rng(3)
    base = {"mode": "lines", "line": {"color": "#1f77b4", "width": 5}, "name": "leg 1",
            "legendgroup": "leg 1", "showlegend": True, "hoverinfo": "name"}
    styles = [base, {**base, "name": "leg 7"},
              {**base, "showlegend": False}, {**base, "line": {"color": "#ff7f0e", "width": 5}},
              {**base, "line": {"color": "#1f77b4", "width": 8}}]
    maker = view._FrameTraces()
    for k in [0, 1, 2, 0, 3, 4, 1, 2, 4, 3]:
        p = rng.standard_normal((4, 3))
        ours = [maker.Scatter3d(x=p[:, 0], y=p[:, 1], z=p[:, 2], **styles[k])]
        convert_to_base64(ours)
        fig = go.Figure(go.Scatter3d(x=p[:, 0], y=p[:, 1], z=p[:, 2], **styles[k]))
        assert ours[0] == fig.to_dict()["data"][0]
        assert list(ours[0]) == list(fig.to_dict()["data"][0])   # the keys' order too


def test_a_style_holding_an_array_is_validated_every_time():
    """Styles are told apart by their JSON text; one that has none (a colour per point, a NumPy
    width) is not kept, so two such traces never share a style however alike they print."""
    from _plotly_utils.utils import convert_to_base64

    maker = view._FrameTraces()
    x = np.zeros(1200)
    for k in range(3):
        colours = np.zeros(1200)
        colours[600] = k                       # the same repr, '...' in its middle
        for style in ({"marker": {"color": colours}}, {"line": {"width": np.float64(2 + k)}}):
            ours = [maker.Scatter3d(x=x, y=x, z=x, mode="markers", **style)]
            convert_to_base64(ours)
            assert ours[0] == go.Figure(go.Scatter3d(x=x, y=x, z=x, mode="markers",
                                                     **style)).to_dict()["data"][0]
