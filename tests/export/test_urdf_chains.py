"""URDF export of joint-chain machines (export/urdf_chains.py): the tree read back by Pinocchio
(and the pure-Python reader) closes every 6D weld and carries the tool frame where pkmkit's
direct model puts it; Pinocchio's closure Jacobian has pkmkit's mobility and degree of
hyperstatism; planted errors are caught; incompatible defects are refused."""

from __future__ import annotations

import re

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

import pkmkit
from pkmkit.cli.main import cli
from pkmkit.export.base import ExportCheckError, UnsupportedExportError
from pkmkit.export.urdf_chains import (
    chain_urdf_export,
    check_chain_urdf_export,
    joint_values,
    sample_configurations,
)
from pkmkit.export.urdf_check import pinocchio_configuration
from pkmkit.export.urdf_writer import check_urdf, write_urdf
from pkmkit.geometric_errors.compatibility import compatibility

CHAINS = ["tripteor-x7", "trimule-600", "crank-slider"]


def _pinocchio_q(pin, model, values):
    return pinocchio_configuration(pin, model, values)


@pytest.mark.parametrize("ident", CHAINS)
def test_both_readers_close_the_welds_and_place_the_tool(ident):
    m = pkmkit.machine(ident)
    export = write_urdf(m, name=ident)
    worst, _ = check_urdf(m, export)
    assert worst < 1e-12
    worst_python, python = check_chain_urdf_export(m, export, use_pinocchio=False)
    assert python == "python" and worst_python < 1e-12
    # one URDF joint per pkmkit joint variable, named as it, actuators marked
    assert [j.name for j in export.joints] == list(m.model.variables)
    assert [j.role == "actuator" for j in export.joints] == list(m.model.actuated)
    assert len(export.closure_frames) == len(m.model.legs) - 1


@pytest.mark.parametrize("ident", CHAINS)
def test_pinocchio_sees_pkmkit_mobility_and_hyperstatism(ident):
    """The welds' Jacobian in Pinocchio (frame Jacobians of each pair, world-aligned):
    nv − rank = pkmkit's actuators (mobility), rows − rank = the degree of hyperstatism of
    pkmkit's compatibility analysis (Tripteor and TriMule 2, crank–slider 3)."""
    pin = pytest.importorskip("pinocchio")
    m = pkmkit.machine(ident)
    export = chain_urdf_export(m, name=ident)
    model = pin.buildModelFromXML(export.urdf)
    data = model.createData()
    q = _pinocchio_q(pin, model, joint_values(m, sample_configurations(m, 2)[1]))
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    rows = []
    for a, b in export.closure_frames:
        ja, jb = (pin.getFrameJacobian(model, data, model.getFrameId(n),
                                       pin.LOCAL_WORLD_ALIGNED) for n in (a, b))
        rows.append(ja - jb)
    jac = np.vstack(rows)
    rank = np.linalg.matrix_rank(jac, tol=1e-9 * np.abs(jac).max())
    assert model.nv - rank == m.n_actuators
    assert jac.shape[0] - rank == compatibility(m).hyperstatism


def test_the_tool_frame_is_pkmkit_direct_model_at_random_configurations():
    pin = pytest.importorskip("pinocchio")
    m = pkmkit.machine("tripteor-x7")
    export = chain_urdf_export(m)
    model = pin.buildModelFromXML(export.urdf)
    data = model.createData()
    point = model.getFrameId("tool_point")
    qs = sample_configurations(m, 8, seed=3)
    for q in qs:
        pin.framesForwardKinematics(model, data, _pinocchio_q(pin, model, joint_values(m, q)))
        np.testing.assert_allclose(data.oMf[point].translation, m.fk(q)[:3], atol=1e-12)
        # the tool axis: z of the tool frame
        np.testing.assert_allclose(data.oMf[point].rotation[:, 2], m.fk(q)[3:], atol=1e-12)
    assert np.ptp(qs, axis=0).min() > 0        # every actuator moved over the sample


def test_planted_errors_are_caught():
    m = pkmkit.machine("tripteor-x7")
    export = chain_urdf_export(m)
    # an element's origin 1 µm off: leg 3's θ3 joint
    moved = re.sub(r'(<joint name="theta3" type="\w+">.*?<origin xyz=")([-0-9.e]+)',
                   lambda g: g.group(1) + repr(float(g.group(2)) + 1e-6), export.urdf, count=1)
    assert moved != export.urdf
    for reader in (None, False):
        with pytest.raises(ExportCheckError, match="does not close"):
            check_chain_urdf_export(m, type(export)(**{**export.__dict__, "urdf": moved}),
                                    use_pinocchio=reader)
    # the YAML: 6D welds, pkmkit's actuators and tool, the home configuration
    data = yaml.safe_load(export.closures)
    assert data["type"] == ["6D", "6D"] and data["name_mot"] == list(m.actuator_names)
    assert data["tool_length"] == pytest.approx(m.tool_length)
    home = data["home"]
    assert home == pytest.approx(joint_values(m, m.home_q))


def test_compatible_defects_are_exported_exactly_incompatible_ones_refused():
    m = pkmkit.machine("tripteor-x7")
    bent = m.with_defects({"dJ21": 2e-3, "db21": 1e-4, "dK12": 1e-3})   # compatible
    export = chain_urdf_export(bent)
    misfit = float(np.max(bent.fk(bent.home_q, full_output=True).closure_residual))
    assert 1e-9 < misfit < 1e-7              # compatible at first order: a 2nd-order misfit
    worst, _ = check_chain_urdf_export(bent, export)
    assert worst <= 2 * misfit + 1e-9
    assert export.urdf != chain_urdf_export(m).urdf
    with pytest.raises(UnsupportedExportError, match="least squares"):
        chain_urdf_export(m.with_defects({"dK21": 1e-3}))          # forced to zero


def test_a_leg_sharing_its_first_joint_branches_the_tree():
    """The TriMule's ψ1 is shared by legs 1, 3 and 4: one joint, the legs branching after."""
    export = chain_urdf_export(pkmkit.machine("trimule-600"))
    assert export.urdf.count('<joint name="psi1"') == 1
    assert len(re.findall(r'<parent link="psi1_body"/>', export.urdf)) == 3


def test_command_line(tmp_path):
    runner = CliRunner()
    out = tmp_path / "tripteor.urdf"
    done = runner.invoke(cli, ["export", "tripteor-x7", "--to", "urdf", "--out", str(out)])
    assert done.exit_code == 0, done.output
    assert "2 loop closures (6D)" in done.output
    assert "Pinocchio" in done.output or "URDF parser" in done.output
    assert out.exists() and (tmp_path / "tripteor.closures.yaml").exists()
    masses = tmp_path / "m.toml"
    masses.write_text("[masses]\nplatform = 1.0\n")
    done = runner.invoke(cli, ["export", "tripteor-x7", "--to", "urdf", "--masses", str(masses),
                               "--out", str(tmp_path / "t2.urdf")])
    assert done.exit_code == 1 and not (tmp_path / "t2.urdf").exists()
    assert "[bodies.NAME]" in done.output and "joint-chain" in done.output
    assert done.exception is None or isinstance(done.exception, SystemExit)  # no traceback
