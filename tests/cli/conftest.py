"""Shared helpers of the command-line tests: ``run`` invokes ``pkmkit`` in-process and
``as_json`` checks the exit status and parses the JSON it printed."""

import json

import pytest
from click.testing import CliRunner

from pkmkit.cli.main import cli


@pytest.fixture
def run():
    runner = CliRunner()

    def invoke(*args, **kwargs):
        return runner.invoke(cli, [str(a) for a in args], catch_exceptions=False, **kwargs)

    return invoke


def parse_json(result):
    """The JSON printed by a successful command."""
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


@pytest.fixture
def as_json():
    return parse_json


def table_lines(text: str, units: str = "m") -> list[str]:
    """The lines of a CSV table written by a command, after its ``# units:`` line (checked)."""
    first, *lines = text.splitlines()
    assert first == f"# units: {units}", first
    return lines
