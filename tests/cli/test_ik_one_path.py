"""``pkmkit ik`` is one code path for every family (issue 19 §4): a single pose and the same
pose in a batch give the same actuators as the library, and an option the machine's inverse
does not take is refused (it used to be ignored without a word)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.boundary.coordinates import actuator_scales, pose_columns, pose_to_cli

MACHINES = ("linear-delta", "five-bar", "gough-stewart", "tripteor-x7")


@pytest.mark.parametrize("name", MACHINES)
def test_single_and_batch_give_the_library_actuators(run, as_json, tmp_path, name):
    m = pkmkit.machine(name)
    cli_pose = pose_to_cli(m.home_pose, m, "mm", "xyz")[0]
    text = ",".join(f"{v:.12g}" for v in cli_pose)
    expected = m.ik(m.home_pose, strokes="ignore") / actuator_scales(m, "mm")
    single = as_json(run("ik", name, f"--pose={text}", "--units", "mm", "--json"))
    assert np.allclose(single["q"], expected, atol=1e-6)
    table = tmp_path / "poses.csv"
    table.write_text(",".join(pose_columns(m)) + "\n" + text + "\n")
    out = tmp_path / "q.csv"
    result = run("ik", name, "--units", "mm", "--input", table, "--output", out)
    assert result.exit_code == 0, result.output
    header, row = out.read_text().splitlines()[-2:]
    values = dict(zip(header.split(","), row.split(","), strict=True))
    assert np.allclose([float(values[a]) for a in m.actuator_names], expected, atol=1e-6)
    assert values["status"] == "ok"


@pytest.mark.parametrize(("args", "message"), [
    (["gough-stewart", "--pose", "0,0,0.8,0,0,0", "--method", "numeric"], "takes no method"),
    (["tripteor-x7", "--pose", "0,0,1.8,0,0,1", "--branches", "1,1,1"], "takes no branches"),
    (["orthoglide", "--pose", "0,0,0", "--tool-length", "0.1"], "takes no tool length"),
])
def test_an_option_the_inverse_does_not_take_is_refused(run, args, message):
    result = run("ik", *args)
    assert result.exit_code == 1
    assert message in result.output
