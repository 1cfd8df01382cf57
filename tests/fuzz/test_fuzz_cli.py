"""Fuzzing of the command line: every command with random and hostile option values. A run
ends with exit status 0 (done), 1 (a one-line error), 2 (usage error) or 3 (some rows or limits
flagged) — never with a traceback — and within the time limit."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import event, given
from hypothesis import strategies as st

from pkmkit.cli.main import cli

from .conftest import bounded

MACHINES = ["orthoglide", "linear-delta", "five-bar", "linear-delta-table-iv1",
            str(Path(__file__).resolve().parents[2] / "docs" / "examples" / "strut-tripod.toml"),
            "nope", "", "missing.toml"]
NUMBER_TEXT = st.one_of(
    st.sampled_from(["0", "-1", "1e999", "nan", "inf", "-inf", "1e-300", "0.5", "2", "", " ",
                     "a", "1,2", "0,0,0", "0.1,0.2", "0.1,0.05,0.2", "1:2", "0,0,0.2,0.1",
                     "1,0,0,0.1,0.01,2", "-0.1,-0.1,0.2,0.2,0.1,3", "0.5,2", "3,0.5", "z=0",
                     "x=0.1", "q=0", "R=0.5", "L=-1", "angles=0,120", "r=0", "R=0.45:1.0",
                     "max:gci", "min:stroke", "0.3@0,0,0.2", "stroke<=1", "1,2,3,4,5,6,7",
                     "zigzag", "-0", "1e10", "9" * 30, "actuator_stiffness=0",
                     "actuator_stiffness=1e8,2e8,nan", "rod_section=circle:0.01",
                     "rod_section=tube:1,2", "rod_material=1,-1"]),
    st.text(max_size=12),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)
COMMANDS = {
    "ik": ["--pose", "--branches", "--method", "--set", "--units"],
    "fk": ["--q", "--mode", "--method", "--set", "--all", "--x"],
    "jacobian": ["--pose", "--tol", "--set"],
    "analyze": ["--pose", "--isotropy-tol", "--set"],
    "map": ["--index", "--slice", "--range", "--resolution", "--scale", "--set"],
    "workspace": ["--bounds", "--kappa-max", "--box", "--slice", "--cube", "--center",
                  "--resolution", "--no-strokes"],
    "useful-workspace": ["--bounds", "--kappa-max", "--resolution", "--anywhere"],
    "path": ["--line", "--circle", "--helix", "--raster", "--feed", "--accel", "--jerk",
             "--profile", "--period", "--rapid-feed", "--wrench", "--speed-limit",
             "--force-limit", "--origin"],
    "arm-sizing": ["--force", "--length", "--section", "--inner", "--diameter",
                   "--diameter-range", "--min-stiffness"],
    "show": ["--set", "--units"],
    "stiffness": ["--pose", "--wrench", "--set", "--units", "--reference"],
    "design orthoglide": ["--cube", "--bounds", "--max-leg"],
    "design five-bar": ["--square", "--bounds", "--design"],
    "optimize": ["--vary", "--objective", "--region", "--constraint", "--bounds"],
    "export": ["--to", "--set", "--units", "--endstops", "--masses"],
}
FLAGS = {"--all", "--no-strokes", "--anywhere"}
CHOICES = {"--index": ["condition", "lambda_min", "actuators", "bogus"],
           "--scale": ["auto", "log", "x"], "--method": ["closed", "numeric", "de", "x"],
           "--profile": ["scurve", "trapezoid", "x"], "--section": ["solid", "hollow", "x"],
           "--design": ["isotropic", "biglide", "x"], "--units": ["m", "mm", "in", "x"],
           "--mode": ["working", "other", "nacelle-above", "-1", "2"],
           "--to": ["linuxcnc", "klipper", "mjcf", "x"]}
NO_MACHINE = {"arm-sizing", "design orthoglide", "design five-bar"}
#: keep the expensive commands cheap: small grids, few generations
FIXED = {"map": ["--resolution", "15"], "workspace": ["--resolution", "9"],
         "useful-workspace": ["--resolution", "9"],
         "optimize": ["--generations", "1", "--population", "4", "--samples", "3",
                      "--no-progress"]}


#: A valid command line per command (machine, options), which the fuzzer then mutates.
BASE = {
    "ik": ("linear-delta", ["--pose", "0.1,0.05,0.2"]),
    "fk": ("orthoglide", ["--q", "0.31,0.3,0.32"]),
    "jacobian": ("five-bar", ["--pose", "1.05,0.05"]),
    "analyze": ("linear-delta", ["--pose", "0,0,0.2"]),
    "map": ("five-bar", ["--index", "condition"]),
    "workspace": ("orthoglide", []),
    "useful-workspace": ("five-bar", []),
    "path": ("linear-delta-table-iv1", ["--circle", "0,0,0.2,0.1", "--feed", "0.1", "--accel",
                                        "1"]),
    "arm-sizing": (None, ["--length", "1"]),
    "show": ("orthoglide", []),
    "stiffness": ("orthoglide", ["--pose", "0,0,0"]),
    "design orthoglide": (None, ["--cube", "0.2", "--bounds", "0.5,2"]),
    "design five-bar": (None, ["--square", "0.2", "--bounds", "0.34,3"]),
    "optimize": ("linear-delta", ["--vary", "R=0.45:1.0", "--objective", "max:compactness",
                                  "--region", "0.3@0,0,0.2"]),
    "export": ("linear-delta", ["--to", "klipper"]),
}


@st.composite
def command_lines(draw):
    name = draw(st.sampled_from(sorted(COMMANDS)))
    machine, base = BASE[name]
    options = dict(zip(base[::2], base[1::2], strict=True))
    if name not in NO_MACHINE and draw(st.integers(0, 4)) == 0:
        machine = draw(st.sampled_from(MACHINES))
    flags = []
    for option in draw(st.lists(st.sampled_from(COMMANDS[name]), max_size=3, unique=True)):
        if option in FLAGS:
            flags.append(option)
        elif option in CHOICES:
            options[option] = draw(st.sampled_from(CHOICES[option]))
        else:
            options[option] = draw(NUMBER_TEXT)
    args = name.split() + ([machine] if machine is not None else [])
    for option, value in options.items():
        args += [option, value]
    args += flags
    fixed = FIXED.get(name, [])
    for k, item in enumerate(fixed):  # cheap settings unless the fuzzer set them
        if item.startswith("--") and item not in options and item not in args:
            args += [item] if item in ("--no-progress",) else [item, fixed[k + 1]]
    if draw(st.booleans()):
        args.append("--json")
    return args


@pytest.mark.ci
@given(command_lines())
def test_cli_commands(args):
    runner = CliRunner()
    with tempfile.TemporaryDirectory() as tmp:
        if args[0] in ("map", "optimize", "export"):
            name = {"map": "m.png", "optimize": "o", "export": "fuzzkins.c"}[args[0]]
            args = [*args, "--out", str(Path(tmp) / name)]
        with bounded(60.0):
            result = runner.invoke(cli, args, catch_exceptions=True)
    event(f"exit {result.exit_code}")
    assert result.exit_code in (0, 1, 2, 3), (args, result.output)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    assert "Traceback" not in result.output
    if result.exit_code == 1:
        assert result.output.strip().splitlines()[-1].startswith("Error:"), result.output
