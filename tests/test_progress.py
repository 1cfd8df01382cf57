"""Progress bars only where a person watches (issue 18 §8): estimates on long work, nothing
in scripts, pipes and tests, and results unchanged by the chunking that feeds the bar."""

from __future__ import annotations

import io
import subprocess
import sys

import numpy as np

from pkmkit.progress import progress_display, tracked, wanted


def test_without_a_display_scope_the_items_come_back_untouched():
    items = [1, 2, 3]
    assert tracked(items, total=3, label="x") is items


def test_a_display_scope_draws_a_bar_with_the_time_left():
    stream = io.StringIO()
    with progress_display(True, delay=0.0, stream=stream):
        assert list(tracked(range(4), total=4, label="orthoglide: 4 poses")) == [0, 1, 2, 3]
    text = stream.getvalue()
    assert "orthoglide: 4 poses" in text and "/4" in text and "left]" in text


def test_a_disabled_scope_and_a_pipe_show_nothing(monkeypatch):
    stream = io.StringIO()                       # not a terminal
    monkeypatch.delenv("PKMKIT_PROGRESS", raising=False)
    assert not wanted(stream)
    with progress_display(stream=stream):
        list(tracked(range(3), total=3))
    assert stream.getvalue() == ""
    monkeypatch.setenv("PKMKIT_PROGRESS", "1")
    assert wanted(stream)
    monkeypatch.setenv("PKMKIT_PROGRESS", "0")
    assert not wanted(stream)


def test_the_workspace_grid_reports_its_chunks_and_keeps_its_result():
    """The bar counts the grid's chunks; the evaluation is the same as in one piece."""
    import pkmkit
    from pkmkit.analysis.criteria import Criteria, _evaluate_chunk, _evaluate_range
    from pkmkit.analysis.grids import make_grid

    machine = pkmkit.machine("orthoglide")
    h = machine.home_pose
    grid = make_grid(h - 0.3, h + 0.3, free=(0, 1, 2), base=h, names=machine.pose_names,
                     resolution=60)                 # 216,000 poses: 4 chunks
    stream = io.StringIO()
    with progress_display(True, delay=0.0, stream=stream):
        chunked = _evaluate_range(0, grid.size, machine, grid, Criteria())
    whole = _evaluate_chunk(machine, grid.points_between(0, grid.size), Criteria())
    assert f"{grid.size:,} poses" in stream.getvalue()
    np.testing.assert_array_equal(chunked.q, whole.q)
    for key in whole.masks:
        np.testing.assert_array_equal(chunked.masks[key], whole.masks[key])


def test_the_command_line_turns_warnings_into_one_line_notes():
    code = ("import warnings, sys; from pkmkit.cli.notes import install_warning_notes;"
            "install_warning_notes();"
            "warnings.warn('leg 2 is near\\n its stroke end', RuntimeWarning);"
            "warnings.warn('leg 2 is near\\n its stroke end', RuntimeWarning)")
    done = subprocess.run([sys.executable, "-W", "always", "-c", code], capture_output=True,
                          text=True, check=True)
    assert done.stderr == "note: leg 2 is near its stroke end (RuntimeWarning)\n"
