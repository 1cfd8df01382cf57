"""Every numeric option of every command, given an absurd value (issue 18 §5): 1e300, ±inf,
NaN and -1e300 (a trillion for a count) must give a one-line error naming the option, never a
run with exit 0, a traceback or a hang (``path
--force-limit 1e300`` and ``--speed-limit``, ``--accel-limit``, ``--max-deflection``,
``workspace --kappa-max 1e300``, ``--min-stiffness``, ``analyze --isotropy-tol 1e300``,
``machined-part simulate --sigma 1e300``, ``reconstruct --ball-end 1e300``, ``arm-sizing
--inner`` and ``--region``, ``design orthoglide --max-leg``, ``optimize`` and
``useful-workspace --kappa-max 1e300``, ``compensate --step``/``--tolerance``/
``--max-correction 1e300`` and ``errors --sensitivity --rtol`` anything were accepted with exit
0; ``machined-part program --levels 10**12`` hung, ``simulate --sections`` and ``ballbar-plan
--points 10**12`` raised ``MemoryError``).

The options are found by walking the command tree (every option of type float or int): a
command added later without a base line here fails :func:`test_every_numeric_option_is_swept`.
"""

from __future__ import annotations

from pathlib import Path

import click
import pytest

from pkmkit.cli.main import cli

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"

#: A valid command line per command (files made by the ``files`` fixture: ``{d}``).
BASE = {
    "analyze": ["analyze", "orthoglide"],
    "arm-sizing": ["arm-sizing", "--length", "1", "--force", "100", "--section", "hollow"],
    "calibrate": ["calibrate", "linear-delta", "--measure", "height", "--measurements",
                  "{d}/h.csv"],
    "compensate": ["compensate", "linear-delta", "--calibrated", "{d}/h.truth.toml",
                   "--targets", "{d}/targets.csv", "--out", "table.csv"],
    "design five-bar": ["design", "five-bar", "--square", "0.2", "--bounds", "0.3333333,3"],
    "design linear-delta": ["design", "linear-delta", "--cube", "0.5", "--bounds", "0.4,2.5"],
    "design orthoglide": ["design", "orthoglide", "--cube", "0.2", "--bounds", "0.5,2"],
    "errors": ["errors", "linear-delta", "--sensitivity", "--points", "5"],
    "fk": ["fk", "orthoglide", "--q", "0.31,0.31,0.31"],
    "identifiability": ["identifiability", "orthoglide", "--measure", "point", "--poses",
                        "20"],
    "ik": ["ik", "orthoglide", "--pose", "0,0,0"],
    "jacobian": ["jacobian", "orthoglide", "--pose", "0,0,0"],
    "machined-part ballbar-plan": ["machined-part", "ballbar-plan", "verne", "--out",
                                   "plan.csv"],
    "machined-part program": ["machined-part", "program", "verne", "--out", "p.nc"],
    "machined-part reconstruct": ["machined-part", "reconstruct", "{d}/cmm.csv", "--gcode",
                                  str(EXAMPLES / "pocket.nc"), "--out", "rec.csv"],
    "machined-part simulate": ["machined-part", "simulate", "verne", "--gcode",
                               str(EXAMPLES / "pocket.nc"), "--out", "cmm.csv"],
    "map": ["map", "orthoglide", "--index", "condition", "--slice", "z=0", "--out", "m.png"],
    "optimize": ["optimize", "linear-delta", "--vary", "R=0.45:1.0", "--objective",
                 "max:gci", "--region", "0.5@0,0,0.25", "--bounds", "0.4,2.5",
                 "--generations", "1", "--population", "4", "--out", "opt", "--no-progress"],
    "path": ["path", "orthoglide", "--line", "0,0,0:0.05,0,0", "--feed", "0.05", "--accel",
             "1"],
    "register": ["register", "--measured", str(EXAMPLES / "lts-points.csv"), "--nominal",
                 str(EXAMPLES / "bcs-points.csv")],
    "select-poses": ["select-poses", "orthoglide", "--measure", "point", "--n", "20", "--out",
                     "sel.csv"],
    "simulate-measurements": ["simulate-measurements", "orthoglide", "--measure", "point",
                              "--poses", "5", "--out", "s.csv"],
    "stiffness": ["stiffness", "orthoglide", "--pose", "0,0,0"],
    "useful-workspace": ["useful-workspace", "orthoglide", "--bounds", "0.5,2"],
    "view": ["view", "orthoglide", "--out", "v.html"],
    "workspace": ["workspace", "orthoglide", "--resolution", "9"],
}

#: Options whose value is not a physical magnitude: any integer is a valid random seed, and a
#: chunk size larger than the batch is one chunk.
NOT_MAGNITUDES = {"--seed", "--chunk-rows"}

#: Options that need a companion to mean anything (given with it here).
COMPANIONS = {
    ("arm-sizing", "--machine-stiffness"): ["--machine", "orthoglide", "--region", "0.1"],
    ("arm-sizing", "--region"): ["--machine", "orthoglide", "--machine-stiffness", "1"],
    ("workspace", "--max-deflection"): ["--wrench", "100,0,0"],
    ("register", "--direction-weight"): [],
}


def _numeric_options():
    def walk(cmd, path):
        if isinstance(cmd, click.Group):
            ctx = click.Context(cmd)
            for name in cmd.list_commands(ctx):
                yield from walk(cmd.get_command(ctx, name), [*path, name])
            return
        for p in cmd.params:
            if (isinstance(p, click.Option) and p.opts[0] not in NOT_MAGNITUDES
                    and isinstance(p.type, (click.types.FloatParamType,
                                            click.types.IntParamType))):
                yield " ".join(path), p.opts[0], isinstance(p.type, click.types.FloatParamType)

    return sorted(walk(cli, []))


OPTIONS = _numeric_options()


def test_every_numeric_option_is_swept():
    missing = sorted({cmd for cmd, _, _ in OPTIONS} - set(BASE))
    assert not missing, f"add a valid command line to BASE for {missing}"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from click.testing import CliRunner

    d = tmp_path_factory.mktemp("sweep")
    runner = CliRunner()
    for args in (["simulate-measurements", "linear-delta", "--measure", "height", "--poses",
                  "30", "--defects", "random", "--units", "mm", "--out", d / "h.csv"],
                 ["machined-part", "simulate", "verne", "--gcode", EXAMPLES / "pocket.nc",
                  "--out", d / "cmm.csv"]):
        res = runner.invoke(cli, [str(a) for a in args], catch_exceptions=False)
        assert res.exit_code == 0, res.output
    (d / "targets.csv").write_text("x,y,z\n0,0,-0.4\n0.05,0,-0.4\n")
    return d


@pytest.mark.parametrize("command, option, is_float", OPTIONS,
                         ids=[f"{c}{o}" for c, o, _ in OPTIONS])
def test_absurd_values_of_every_numeric_option_are_refused(run, files, tmp_path,
                                                           monkeypatch, command, option,
                                                           is_float):
    monkeypatch.chdir(tmp_path)
    base = [a.format(d=files) for a in BASE[command]]
    extra = COMPANIONS.get((command, option), [])
    values = ("1e300", "-1e300", "inf", "nan") if is_float else ("1000000000000",)
    for value in values:
        result = run(*base, *extra, option, value)
        assert result.exit_code in (1, 2), (value, result.output)
        last = result.output.strip().splitlines()[-1]
        assert last.startswith("Error:"), (value, result.output)
        # the option, or its words ("--buckling-safety": "the buckling safety = 1e+300 …")
        words = option.lstrip("-")
        assert any(w in last for w in (option, words, words.replace("-", " "))), (value, last)


#: Options of several numbers (a region, a centre, a box, a point): one coordinate absurd. The
#: refusal names the option as written (``--region``), not only a word of it: ``optimize
#: --region 1e300`` ran and reported "no evaluated design satisfies", ``--region 0.5@0,0,1e300``
#: said "box bounds for z", ``errors --region 0,1e300,…`` "only 0 of 256 points … reachable",
#: ``design linear-delta --center 1e300,0,0`` spoke of arms of 1e6 m, ``-1e6`` in z was sized,
#: ``path --circle``/``--helix``/``--raster`` named "the radius"/"the pitch"/"the rectangle",
#: ``path``/``machined-part`` ``--origin`` a G-code line, ``arm-sizing --diameter-range
#: 0.01,1e300`` called the range empty.
TUPLES = [
    (["errors", "linear-delta", "--sensitivity", "--points", "5"], "--region",
     "-0.1,0.1,-0.1,0.1,-0.5,{v}"),
    (["errors", "linear-delta", "--sensitivity", "--points", "5"], "--region",
     "{v},0.1,-0.1,0.1,-0.5,-0.3"),
    (BASE["identifiability"], "--region", "-0.1,0.1,-0.1,0.1,-0.1,{v}"),
    (BASE["identifiability"], "--pivot", "0,0,{v}"),
    (BASE["select-poses"], "--region", "-0.1,0.1,-0.1,0.1,-0.1,{v}"),
    ([a for a in BASE["optimize"] if a not in ("--region", "0.5@0,0,0.25")], "--region",
     "{v}@0,0,0.25"),
    ([a for a in BASE["optimize"] if a not in ("--region", "0.5@0,0,0.25")], "--region",
     "0.5@0,0,{v}"),
    (BASE["design linear-delta"], "--center", "{v},0,0"),
    (BASE["design linear-delta"], "--center", "0,0,{v}"),
    ([a for a in BASE["design orthoglide"] if a not in ("--bounds", "0.5,2")], "--bounds",
     "0.5,{v}"),
    (BASE["workspace"], "--box", "-0.1,0.1,-0.1,0.1,-0.1,{v}"),
    ([*BASE["workspace"], "--cube", "0.05"], "--center", "0,0,{v}"),
    (BASE["map"], "--range", "-0.1,0.1,-0.1,{v}"),
    (BASE["analyze"], "--wrench", "0,0,{v}"),
    (BASE["jacobian"][:2], "--pose", "0,0,{v}"),
    (BASE["stiffness"], "--wrench", "0,0,{v},0,0,0"),
    (BASE["path"][:2] + BASE["path"][4:], "--line", "0,0,0:0.05,0,{v}"),
    (BASE["path"][:2] + BASE["path"][4:], "--circle", "0,0,0,{v}"),
    (BASE["path"][:2] + BASE["path"][4:], "--helix", "0,0,0,0.05,{v},1"),
    (BASE["path"][:2] + BASE["path"][4:], "--raster", "0,0,0,0.05,{v},3"),
    (BASE["path"][:2] + BASE["path"][4:] + ["--gcode", str(EXAMPLES / "pocket.nc")],
     "--origin", "0,0,{v}"),
    (BASE["machined-part simulate"], "--origin", "0,0,{v}"),
    (BASE["machined-part simulate"], "--placement", "0,0,0,{v}"),
    (BASE["machined-part ballbar-plan"], "--tool-lengths", "0,{v}"),
    (BASE["simulate-measurements"], "--tool-lengths", "0,{v}"),
    (BASE["arm-sizing"], "--diameter-range", "0.01,{v}"),
]


@pytest.mark.parametrize("base, option, template", TUPLES,
                         ids=[f"{b[0]}{o}={t}" for b, o, t in TUPLES])
def test_absurd_coordinates_of_tuple_options_are_refused_naming_the_option(
        run, tmp_path, monkeypatch, base, option, template):
    monkeypatch.chdir(tmp_path)
    for value in ("1e300", "-1e300", "inf", "nan"):
        result = run(*base, option, template.format(v=value))
        assert result.exit_code in (1, 2), (value, result.output)
        last = result.output.strip().splitlines()[-1]
        assert last.startswith("Error:") and option in last, (value, result.output)


@pytest.mark.parametrize("args, option, range_text", [
    ([*TUPLES[5][0], "--units", "mm", "--region", "1e300@0,0,250"], "--region side",
     "[1e-06, 1e+06] mm"),
    ([*TUPLES[6][0], "--region", "0.5@0,0,1e300"], "--region centre Z", "[-1000, 1000] m"),
    ([*TUPLES[0][0], "--region", "-0.1,1e300,-0.1,0.1,-0.5,-0.3"], "--region x MAX",
     "[-1000, 1000] m"),
    ([*TUPLES[0][0], "--units", "mm", "--region", "-100,100,-100,100,-500,-2e6"],
     "--region z MAX", "[-1e+06, 1e+06] mm"),
    ([*BASE["design linear-delta"], "--center", "0,0,-1e6"], "--center Z", "[-1000, 1000] m"),
    ([*BASE["design linear-delta"], "--units", "mm", "--center", "1e300,0,0"], "--center X",
     "[-1e+06, 1e+06] mm"),
])
def test_region_and_centre_refusals_name_the_coordinate_and_its_plausible_range(
        run, tmp_path, monkeypatch, args, option, range_text):
    """``optimize --region``, ``errors --region`` and ``design --center``: one line naming the
    option and coordinate, the value and the plausible range in the command's unit (a
    centre 1000 km below the slides was sized before)."""
    monkeypatch.chdir(tmp_path)
    result = run(*args)
    assert result.exit_code == 1, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1, result.output
    assert lines[0].startswith(f"Error: {option} "), lines[0]
    assert f"plausible range {range_text}" in lines[0], lines[0]


def test_region_with_min_not_below_max_names_the_option(run):
    result = run(*TUPLES[0][0], "--region", "0.1,0,-0.1,0.1,-0.5,-0.3")
    assert result.exit_code == 1
    assert result.output.strip().splitlines()[-1] == \
        "Error: --region x: MIN 0.1 is not below MAX 0"


@pytest.mark.parametrize("args, line", [
    (["ik", "linear-delta", "--pose", "1e12,0,0"],
     "Error: --pose x 1e+12 m is outside the plausible range [-1000, 1000] m"),
    (["ik", "linear-delta", "--units", "mm", "--pose", "0,0,-2e6"],
     "Error: --pose z -2e+06 mm is outside the plausible range [-1e+06, 1e+06] mm"),
    (["analyze", "orthoglide", "--pose", "0,1e5,0"],
     "Error: --pose y 100000 m is outside the plausible range [-1000, 1000] m"),
    (["ik", "gough-stewart", "--pose", "0,0,0.9,0,800,0"],
     "Error: --pose B 800 deg is outside the plausible range [-720, 720] deg"),
    (["ik", "tripteor-x7", "--pose", "0,0,0,0,0,1e9"],
     "Error: --pose k 1e+09 is outside the plausible range [-1000, 1000]"),
    (["jacobian", "tripteor-x7", "--pose", "0,0,0,0,-1e300,1"],
     "Error: --pose j -1e+300 is outside the plausible range [-1000, 1000]"),
    (["fk", "linear-delta", "--q", "1e12,1,1"],
     "Error: --q q1 1e+12 m is outside the plausible range [-1000, 1000] m"),
    (["fk", "delta", "--q", "0,1e6,0"],
     "Error: --q q2 1e+06 deg is outside the plausible range [-720, 720] deg"),
])
def test_pose_and_actuator_refusals_name_the_option_and_column(run, args, line):
    """``--pose`` and ``--q``: one line naming the option and the column, in the command's
    unit, with the plausible range of a position (±1 km), an angle (±720°) or a tool-axis
    component (before: "pose [...] has a coordinate beyond 1e+09 m", in metres whatever
    ``--units``, without the option, and a crank at 10⁶° ran into the stroke test)."""
    result = run(*args)
    assert result.exit_code == 1, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1, result.output
    assert lines[0].startswith(line), lines[0]
