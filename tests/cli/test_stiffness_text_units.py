"""The stiffness lines of ``pkmkit stiffness`` and ``pkmkit analyze`` in N/µm, N·m/µrad, µm
and µrad, against the compliance matrix the command gives in SI (issue 18 §9, plausible
bugs: the rotation half of a deflection printed as its translation, the rotational stiffness
without its 10⁻⁶ and the translational one multiplied by 10⁶ passed every test).

Independent values, from the SI compliance C (6×6) of ``stiffness --json``: the deflection
under a wrench w is C w; the stiffness under a pure force is 1/eig(C[:3, :3]) and under a
pure moment 1/eig(C[3:, 3:]).
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

POSE = "0.02,-0.01,0.8,3,-2,5"  # a tilted hexapod pose: every component couples
WRENCH = "100,-40,250,6,-3,10"


def _vector(line: str, after: str) -> np.ndarray:
    m = re.search(re.escape(after) + r"\s*\[([^\]]*)\]", line)
    assert m, (after, line)
    return np.array([float(v) for v in m.group(1).split(",")])


@pytest.fixture(scope="module")
def compliance():
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    res = CliRunner().invoke(cli, ["stiffness", "gough-stewart", "--pose", POSE, "--wrench",
                                   WRENCH, "--json"], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    c = np.array(json.loads(res.stdout)["compliance"])
    assert c.shape == (6, 6)
    return c


def _expected(c):
    w = np.array([float(v) for v in WRENCH.split(",")])
    deflection = c @ w
    kt = np.sort(1 / np.linalg.eigvalsh(c[:3, :3]))
    kr = np.sort(1 / np.linalg.eigvalsh(c[3:, 3:]))
    return deflection, kt, kr


def _check(text: str, c) -> None:
    deflection, kt, kr = _expected(c)
    lines = text.splitlines()
    force = next(x for x in lines if "translational stiffness (pure force)" in x)
    moment = next(x for x in lines if "rotational stiffness (pure moment)" in x)
    under = next(x for x in lines if x.strip().startswith("deflection under"))
    assert "N/µm" in force and "N·m/µrad" in moment
    np.testing.assert_allclose(np.sort(_vector(force, "(pure force):")), kt * 1e-6, rtol=2e-4)
    np.testing.assert_allclose(np.sort(_vector(moment, "(pure moment):")), kr * 1e-6, rtol=2e-4)
    assert not np.allclose(deflection[:3], deflection[3:], rtol=0.01)  # a swap shows
    np.testing.assert_allclose(_vector(under, "(N, N·m):"), deflection[:3] * 1e6, rtol=2e-4,
                               atol=1e-4 * np.abs(deflection[:3]).max() * 1e6)
    np.testing.assert_allclose(_vector(under, "rotation"), deflection[3:] * 1e6, rtol=2e-4,
                               atol=1e-4 * np.abs(deflection[3:]).max() * 1e6)


def test_stiffness_command_text(run, compliance):
    res = run("stiffness", "gough-stewart", "--pose", POSE, "--wrench", WRENCH)
    assert res.exit_code == 0, res.output
    _check(res.output, compliance)


def test_analyze_command_stiffness_lines(run, compliance):
    res = run("analyze", "gough-stewart", "--pose", POSE, "--wrench", WRENCH)
    assert res.exit_code == 0, res.output
    _check(res.output, compliance)
