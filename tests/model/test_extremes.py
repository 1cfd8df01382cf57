"""Numbers and files at the extremes, each class hit by a Hypothesis strategy: numbers that
overflow or underflow, YAML duplicate keys, pathological nesting, binary files, and requests
too large for memory. Every case must give a typed error naming the line (or the option) —
never a traceback, a hang or a silent infinity."""

import string

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pkmkit
from pkmkit.exceptions import InputError, MachineFileError, PkmError
from pkmkit.model.machine_file import read_machine_document
from pkmkit.model.text_files import MAX_NESTING, number_problem, toml_nesting

SETTINGS = settings(max_examples=25, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])

overflowing = st.builds(lambda m, e: f"{m}e{e}", st.integers(1, 9), st.integers(309, 100_000))
underflowing = st.builds(lambda m, e: f"{m}e-{e}", st.integers(1, 9), st.integers(325, 100_000))
long_integers = st.integers(310, 2000).map(lambda n: "9" * n)
bad_numbers = st.one_of(overflowing, underflowing, long_integers)
binary = st.binary(min_size=0, max_size=200).map(lambda b: b + b"\x00" + b)


@given(bad_numbers)
def test_number_problem_flags_every_overflow_and_underflow(token):
    problem = number_problem(f"key = [{token}, 1.0]")
    assert problem is not None and ("overflows" in problem or "underflows" in problem)


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_number_problem_accepts_every_double(value):
    assert number_problem(f"x = {value!r}") is None


# ------------------------------------------------------------------------------- masses files


@SETTINGS
@given(bad_numbers, st.sampled_from(["carriage", "rod", "rod_radius", "rod_diameter"]))
def test_masses_file_numbers_name_the_line(tmp_path, token, key):
    from pkmkit.dynamics.masses import load_masses

    path = tmp_path / "m.toml"
    path.write_text(f"# masses\n[masses]\nplatform = 10\n{key} = [1, {token}]\n")
    with pytest.raises(InputError, match=rf"m\.toml:4: {key}: .*(overflows|underflows)"):
        load_masses(path, pkmkit.machine("linear-delta-table-iv1"))


# -------------------------------------------------------------------------------- G-code


@SETTINGS
@given(bad_numbers, st.sampled_from("XYZF"), st.integers(0, 5))
def test_gcode_numbers_name_the_line(tmp_path, token, letter, blank_lines):
    from pkmkit.motion.gcode import read_gcode

    line = 3 + blank_lines
    program = "G21 G90\nG1 X1 F600\n" + "\n" * blank_lines + f"G1 {letter}{token}\n"
    if token.startswith("1e") or "e" in token:
        # G-code numbers have no exponent: the reader refuses the word, still at that line
        with pytest.raises(InputError, match=rf":{line}: "):
            read_gcode(program)
        return
    with pytest.raises(InputError, match=rf":{line}: {letter} word: .*overflows"):
        read_gcode(program)


# --------------------------------------------------------------------------- binary files


@SETTINGS
@given(binary, st.sampled_from(["machine.toml", "machine.yaml", "masses.toml", "prog.nc",
                                "poses.csv", "wrench.csv"]))
def test_binary_files_are_not_text(tmp_path, data, name):
    path = tmp_path / name
    path.write_bytes(data)
    m = pkmkit.machine("linear-delta-table-iv1")
    with pytest.raises(PkmError, match="not a text file"):
        if name.startswith("machine"):
            read_machine_document(path)
        elif name == "masses.toml":
            from pkmkit.dynamics.masses import load_masses
            load_masses(path, m)
        elif name == "prog.nc":
            from pkmkit.motion.gcode import read_gcode
            read_gcode(path)
        elif name == "poses.csv":
            from pkmkit.io.table import read_table
            read_table(path, ["x", "y", "z"])
        else:
            from pkmkit.dynamics.wrench import load_wrench_series
            load_wrench_series(path)


# ------------------------------------------------------------------------ YAML and nesting


keys = st.text(alphabet=string.ascii_lowercase, min_size=1, max_size=8)


@SETTINGS
@given(keys, st.integers(0, 3), st.lists(keys, max_size=3, unique=True))
def test_yaml_duplicate_keys_name_the_second_line(tmp_path, key, depth, others):
    indent = "  " * depth
    head = "".join("  " * k + f"level{k}:\n" for k in range(depth))
    body = [f"{indent}{key}: 1"] + [f"{indent}{o}_x: 2" for o in others] + [f"{indent}{key}: 3"]
    path = tmp_path / "m.yaml"
    path.write_text(head + "\n".join(body) + "\n")
    second = depth + len(body)
    with pytest.raises(MachineFileError, match=rf"m\.yaml:{second}: key '{key}' given twice"):
        read_machine_document(path)


@SETTINGS
@given(st.integers(MAX_NESTING + 1, 5000), st.sampled_from(["toml", "yaml"]),
       st.sampled_from(["array", "table"]))
def test_pathological_nesting_is_refused_with_its_line(tmp_path, depth, fmt, kind):
    opening = "[" if kind == "array" else ("{a = " if fmt == "toml" else "{a: ")
    closing = "]" if kind == "array" else "}"
    separator = " = " if fmt == "toml" else ": "
    text = f"# deep\nx{separator}" + opening * depth + "1" + closing * depth + "\n"
    path = tmp_path / f"m.{fmt}"
    path.write_text(text)
    with pytest.raises(MachineFileError, match=rf"m\.{fmt}:2: .*nested"):
        read_machine_document(path)


def test_toml_nesting_ignores_strings_and_comments():
    text = 'a = "[[[[[["\nb = \'{{{{\'\n# [[[[[[[[\nc = """\n[[[[\n"""\nd = [[1], [2]]\n'
    assert toml_nesting(text) == (2, 7)


# ------------------------------------------------------------------- sizes beyond memory


@given(st.integers(2_000_001, 10**12))
def test_raster_too_many_passes_is_refused_with_the_estimate(passes):
    from pkmkit.motion import raster

    with pytest.raises(InputError, match=r"passes make .* segments \(about .* GiB\)"):
        raster([0, 0, 0.2], 0.1, 0.1, passes)


@pytest.mark.parametrize("passes, strategy", [(600_000, "one-way"), (1e300, "zigzag")])
def test_raster_passes_have_one_limit_the_memory_estimate(passes, strategy):
    """One check and one message for too many passes, whatever the strategy (one-way passes
    make 4 segments each, so fewer of them reach the limit) or the magnitude."""
    from pkmkit.motion import raster

    with pytest.raises(InputError, match=r"passes make .* segments \(about .* GiB\), above"):
        raster([0, 0, 0.2], 0.1, 0.1, passes, strategy=strategy)


@given(st.integers(10_000, 10**6))
def test_grid_too_large_is_refused_with_its_size(resolution):
    from pkmkit.analysis.grids import make_grid

    with pytest.raises(InputError, match=r"the grid would have .* points"):
        make_grid([0, 0, 0], [1, 1, 1], free=(0, 1, 2), base=np.zeros(3), names="xyz",
                  resolution=resolution)


def test_gcode_with_too_many_moves_is_refused(monkeypatch):
    import pkmkit.motion.gcode as gcode

    monkeypatch.setattr(gcode, "MAX_SEGMENTS", 50)
    program = "G21 G91 F600\n" + "G1 X1\n" * 60
    with pytest.raises(InputError, match=r":52: more than 50 moves \(about .* GiB"):
        gcode.read_gcode(program)


@SETTINGS
@given(st.floats(1e-300, 1e-8), st.floats(1e8, 1e300))
def test_time_laws_that_overflow_are_refused(jerk, accel):
    """Magnitudes whose time law would overflow are refused before any computation, as unit
    mistakes naming the argument (accelerations above 1e7 m/s², jerks below 1e-9 m/s³)."""
    from pkmkit.motion import circle, plan

    unit_mistake = (r"^(accel|the S-curve's jerk limit) = .* is "
                    r"(beyond 1e\+07|below 1e-9 \(SI units\)); check the units")
    with pytest.raises(InputError, match=unit_mistake):
        plan(circle([0, 0, 0.2], 0.15), feed=0.1, accel=accel, jerk=jerk, period=0.01,
             max_samples=100_000)


@SETTINGS
@given(st.floats(1e-9, 1e11), st.floats(1e-9, 1e7))
def test_time_laws_at_the_accepted_extremes_are_finite_or_refused(jerk, accel):
    """Within the accepted magnitudes a time law is finite, or refused for its size."""
    from pkmkit.motion import circle, plan

    try:
        traj = plan(circle([0, 0, 0.2], 0.15), feed=0.1, accel=accel, jerk=jerk, period=0.01,
                    max_samples=100_000)
    except InputError as exc:
        assert "not finite" in str(exc) or "samples" in str(exc)
    else:
        assert np.isfinite(traj.x).all() and np.isfinite(traj.t).all()


# -------------------------------------------------------------------------- command line


@SETTINGS
@given(st.one_of(overflowing, underflowing), st.sampled_from(
    ["--feed", "--accel", "--jerk", "--period", "--speed-limit", "--force-limit"]))
def test_path_options_at_the_extremes_name_the_option(token, option):
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    args = {"--feed": "0.1", "--accel": "1", "--jerk": "10"}
    args[option] = token
    flat = [a for kv in args.items() for a in kv]
    result = CliRunner().invoke(cli, ["path", "linear-delta-table-iv1", "--circle",
                                      "0,0,0.2,0.15", *flat])
    assert result.exit_code == 1, result.output
    assert option in result.output and "Traceback" not in result.output


def test_read_text_strips_exactly_the_byte_order_mark(tmp_path):
    """A UTF-8 BOM (3 bytes) is dropped and nothing else; kept on request."""
    from pkmkit.model.text_files import read_text

    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf[machine]\nname = \"\xc3\xa9\"\n")
    assert read_text(path, ValueError) == '[machine]\nname = "é"\n'
    assert read_text(path, ValueError, strip_bom=False) == '\ufeff[machine]\nname = "é"\n'
