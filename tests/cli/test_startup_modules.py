"""Which modules a fresh ``pkmkit --help`` and a fresh one-pose ``pkmkit ik`` import (issue 22
§5: each ≤ 0.3 s) — checked in ``sys.modules`` of a fresh interpreter, never by timing.

``pkmkit --help`` imports click, the standard library and the nine pkmkit modules listed
below: no NumPy (≈ 0.1 s), no machine library (≈ 0.1–0.2 s). A one-pose ``ik`` of each family
imports only click and NumPy besides pkmkit, and only the pkmkit sub-packages listed. An import
added at the top of a module on these paths (or a command moved back into ``cli/main.py``)
fails here with the module's name. Figures: ``python bench/cli_startup.py`` (docs/benchmarks.md,
"Session 35: start-up").
"""

import json
import subprocess
import sys
import textwrap

import pytest

#: Every pkmkit module a fresh ``pkmkit --help`` imports.
HELP_MODULES = {"pkmkit", "pkmkit.aliases", "pkmkit.exceptions", "pkmkit.progress",
                "pkmkit.status", "pkmkit.cli", "pkmkit.cli.lazy", "pkmkit.cli.main",
                "pkmkit.cli.notes"}

#: The pkmkit sub-packages a one-pose ``ik`` may import (no analysis, design, calibration,
#: dynamics, stiffness, plot, … layer; ``io`` for its JSON and atomic writes).
IK_SUBPACKAGES = {"boundary", "cli", "io", "machines", "model", "native", "numerics", "solve",
                  "spatial"}

#: pkmkit's own top-level modules (not layers).
TOP_MODULES = {"aliases", "exceptions", "parallel", "progress", "status"}

ONE_POSE_IK = {
    "rod legs": ["ik", "linear-delta", "--pose", "0.25,0.25,0"],
    "full pose": ["ik", "gough-stewart", "--pose", "0.08,-0.04,0.84,10,0,5"],
    "joint chain": ["ik", "tripteor-x7", "--pose",
                    "-0.1,-0.5,1.8,-0.00490948,0.00700943,0.999963"],
}


def _fresh_modules(args: list[str] | None) -> set[str]:
    """``sys.modules`` of a fresh interpreter after ``pkmkit ARGS`` as the console script runs
    it (``main()``: warning notes, progress display), or after ``pass`` when ``args`` is None."""
    run = "" if args is None else f"""
        sys.argv = ["pkmkit", *{args!r}]
        from pkmkit.cli.main import main
        try:
            main()
        except SystemExit as exc:
            assert exc.code in (None, 0, 3), exc.code  # 3: flagged (out of stroke)
    """
    script = "import json, sys\n" + textwrap.dedent(run) + textwrap.dedent("""
        print()
        print(json.dumps(sorted(sys.modules)))
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True).stdout
    return set(json.loads(out.splitlines()[-1]))


@pytest.fixture(scope="module")
def baseline() -> set[str]:
    """What any interpreter here holds (``site``, the environment's ``.pth`` hooks)."""
    return _fresh_modules(None)


def _third_party(modules: set[str], baseline: set[str]) -> set[str]:
    """Top-level packages outside the standard library, over the baseline."""
    tops = {name.split(".")[0] for name in modules - baseline}
    return {top for top in tops if top not in sys.stdlib_module_names and not top.startswith("_")}


def test_help_imports_click_and_nine_pkmkit_modules(baseline):
    modules = _fresh_modules(["--help"])
    assert _third_party(modules, baseline) == {"click", "pkmkit"}
    assert {m for m in modules if m.split(".")[0] == "pkmkit"} == HELP_MODULES
    assert "numpy" not in modules


@pytest.mark.parametrize("family", ONE_POSE_IK)
def test_one_pose_ik_imports_click_numpy_and_the_kinematics_layers(family, baseline):
    modules = _fresh_modules(ONE_POSE_IK[family])
    assert _third_party(modules, baseline) <= {"click", "numpy", "pkmkit"}
    layers = {m.split(".")[1] for m in modules if m.startswith("pkmkit.")} - TOP_MODULES
    assert layers <= IK_SUBPACKAGES, sorted(layers - IK_SUBPACKAGES)


def test_the_package_s_names_load_the_machine_library_on_first_use():
    """``import pkmkit`` loads no machine library; its names still answer, and
    ``pkmkit.machines`` stays the function after the sub-package is imported by name."""
    script = textwrap.dedent("""
        import json, sys
        import pkmkit
        before = ["numpy" in sys.modules, "pkmkit.machines" in sys.modules]
        import pkmkit.machines.registry  # binds the sub-package to pkmkit.machines, then
        from pkmkit.machines import registry  # the property keeps the function there
        listed = pkmkit.machines()
        m = pkmkit.machine("linear-delta")
        from pkmkit import Machine, Singularity, load, machines
        checks = [machines is registry.machines, isinstance(m, Machine),
                  pkmkit.load is registry.load, Singularity.PARALLEL.label == "parallel",
                  all(n in dir(pkmkit) for n in ("machine", "machines", "Machine", "load")),
                  "linear-delta" in listed]
        try:
            pkmkit.no_such_name
        except AttributeError:
            checks.append(True)
        print(json.dumps([before, checks]))
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True).stdout
    before, checks = json.loads(out.splitlines()[-1])
    assert before == [False, False]
    assert checks == [True] * 7
