import numpy as np
import pytest

import pkmkit
from pkmkit.plot.drawing import draw_machine, machine_geometry


def test_geometry_rods_have_their_length(preset):
    pose = preset.home_pose
    geo = machine_geometry(preset, pose, preset.ik(pose))
    lengths = np.linalg.norm(geo["platform"] - geo["carriage"], axis=1)
    np.testing.assert_allclose(lengths, preset.model.rod_length, atol=1e-12)


@pytest.mark.ci
def test_png_written(tmp_path):
    for ident in ("linear-delta", "five-bar"):
        m = pkmkit.machine(ident)
        path = tmp_path / f"{ident}.png"
        fig = draw_machine(m, path=path)
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert fig.axes
