import pytest

from pkmkit.exceptions import MachineFileError
from pkmkit.model.machine_file import read_machine_document

TOML = """# comment
[machine]
kind = "linear-delta"
units = "mm"

[parameters]
R = 700
angles = [0, 120, 240]

[[legs]]
base = [1, 2, 3]

[[legs]]
length = 4
"""


def test_toml_lines_are_located(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text(TOML)
    doc = read_machine_document(path)
    assert doc.data["parameters"]["R"] == 700
    assert doc.line_of(("machine", "kind")) == 3
    assert doc.line_of(("parameters", "angles")) == 8
    assert doc.line_of(("legs", 1, "length")) == 14
    assert doc.line_of(("legs", 0, "base", 2)) == 11  # falls back to the longest prefix
    assert doc.line_of(("nowhere",)) is None


def test_yaml_lines_are_located(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text("machine:\n  kind: five-bar\nparameters:\n  L: 0.5\n  A: [0, 0]\n")
    doc = read_machine_document(path)
    assert doc.data["parameters"]["A"] == [0, 0]
    assert doc.line_of(("parameters", "L")) == 4
    assert doc.line_of(("parameters", "A", 1)) == 5


@pytest.mark.parametrize(
    "name, text, line, message",
    [
        ("bad.toml", "[machine]\nkind = \n", 2, "TOML syntax error"),
        ("bad.yaml", "machine:\n  kind: [a\nparameters: {}\n", 3, "YAML syntax error"),
        ("list.yaml", "- a\n- b\n", 1, "mapping"),
        ("m.json", "{}", None, "unknown machine file type"),
    ],
)
def test_syntax_errors_report_the_line(tmp_path, name, text, line, message):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(MachineFileError, match=message) as info:
        read_machine_document(path)
    assert info.value.line == line
    if line is not None:
        assert f"{name}:{line}:" in str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(MachineFileError, match="cannot read file"):
        read_machine_document(tmp_path / "absent.toml")


@pytest.mark.parametrize("name", ["m.toml", "m.yaml"])
def test_a_number_beyond_pythons_digit_limit_names_its_line(tmp_path, name):
    """5000 digits (issue 18 §7 fuzz: tomllib's and PyYAML's int() raised ValueError)."""
    path = tmp_path / name
    value = "7" * 5000
    path.write_text(f"[machine]\nkind = 'linear-delta'\n\n[parameters]\nR = {value}\n"
                    if name.endswith("toml") else f"machine:\n  kind: linear-delta\n"
                    f"parameters:\n  R: {value}\n")
    with pytest.raises(MachineFileError, match="more than 4300 digits") as err:
        read_machine_document(path)
    assert err.value.line == (5 if name.endswith("toml") else 4)
