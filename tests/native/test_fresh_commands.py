"""Fresh processes of the commands whose compiled kernels have C twins (issue 22 §5): a
``pkmkit jacobian MACHINE --input`` of translational rod-leg machines (3-DOF and planar) and
``pkmkit workspace gough-stewart|verne`` never import Numba (checked in ``sys.modules``, never
by timing), and a workspace without ``--output`` never imports matplotlib."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import pkmkit
from pkmkit.numerics import jit
from tests.conftest import random_poses

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = [pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "rod_velocity3"),
                                 reason="pkmkit.native.kernels was not built"),
              pytest.mark.ci]  # a workspace study per process: seconds each


def _modules_after_cli(args: list[str]) -> list[bool]:
    """Whether Numba, the C extension and matplotlib are loaded after ``pkmkit ARGS`` in a
    fresh interpreter."""
    code = ("import sys\nfrom pkmkit.cli.main import cli\n"
            f"try:\n    cli({args!r}, standalone_mode=False)\n"
            "except SystemExit:\n    pass\n"
            "print(*[m in sys.modules for m in ('numba', 'pkmkit.native.kernels', "
            "'matplotlib')])\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    return [word == "True" for word in out[-3:]]


@pytest.mark.parametrize("name", ["orthoglide", "linear-delta", "five-bar-biglide"])
def test_a_rod_leg_jacobian_table_imports_no_numba(tmp_path, name):
    m = pkmkit.machine(name)
    x = random_poses(m, jit.MIN_ROWS + 10, seed=1)  # large enough for the compiled kernel
    path = tmp_path / "poses.csv"
    np.savetxt(path, x, delimiter=",", header=",".join("xyz"[: m.dims]), comments="",
               fmt="%.9g")
    numba, native, _ = _modules_after_cli(["jacobian", name, "--input", str(path), "--output",
                                           str(tmp_path / "j.csv")])
    assert (numba, native) == (False, True)
    assert (tmp_path / "j.csv").exists()


@pytest.mark.parametrize("name", ["gough-stewart", "verne", "orthoglide"])
def test_a_workspace_imports_neither_numba_nor_matplotlib(name):
    assert _modules_after_cli(["workspace", name]) == [False, True, False]
