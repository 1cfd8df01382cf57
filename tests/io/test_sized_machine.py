"""Sized machine files (the design commands' output) against values worked out by hand."""

import tomllib

import numpy as np

import pkmkit
from pkmkit.io.sized_machine import box_corners, load_text, sized_machine_text


def test_sized_machine_file_in_mm_and_degrees():
    """The linear Delta written in mm: lengths 1000× the SI values, slide angles in degrees
    (the shortest decimals: 120, 240), and the text read back is the same machine."""
    m = pkmkit.machine("linear-delta")
    text = sized_machine_text(m, "mm")
    params = tomllib.loads(text)["parameters"]
    assert params["R"] == 700.0 and params["L"] == 1300.0 and params["q_max"] == [2000.0] * 3
    assert params["angles"] == [0.0, 120.0, 240.0]
    back = load_text(text, "sized.toml")
    for spec in m.kind.parameters:
        np.testing.assert_allclose(back.params[spec.name], m.params[spec.name], rtol=1e-15)


def test_box_corners():
    np.testing.assert_allclose(box_corners([1.0, 2.0], 2.0),
                               [[0.0, 1.0], [0.0, 3.0], [2.0, 1.0], [2.0, 3.0]])
    corners = box_corners([0.0, 0.0, 1.0], 0.2)
    assert corners.shape == (8, 3)
    np.testing.assert_allclose(np.sort(np.unique(corners[:, 2])), [0.9, 1.1])
