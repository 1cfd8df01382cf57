"""Fuzzing of the commands that read files — calibrate (every measurement type, --validate,
--frame), register, compensate (targets, calibrated machine files, G-code), errors --tolerance,
machined-part reconstruct and simulate, simulate-measurements / identifiability / select-poses
from pose files, stiffness and show on joint-chain and six-axis machine files, export — with
hostile files and option values (``file_cases.py``). Each run ends ``ok`` (exit 0, or 3 with
nothing a machine would act on written) or with a typed one-line error and no output left;
never a traceback, a hang or a partial file.

Each example runs a command in-process (0.2–2 s) after a corpus of valid files is written
(≈ 4 s), so the test runs only under the many-example profiles (``HYPOTHESIS_PROFILE=fuzz`` or
``explore``: 100 examples; ``.ci/run`` runs it), and is skipped by the ordinary suite.
``tools/fuzz_cli.py`` runs the same cases as subprocesses for the published counts
(docs/reliability.md)."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import event, given, settings
from hypothesis import strategies as st

from pkmkit.cli.main import cli

from .conftest import bounded
from .file_cases import classify, corpus, draw_case

#: Whether the profile asks for many examples (fuzz, explore: 400 per property).
MANY = settings.default.max_examples >= 400


@pytest.mark.skipif(not MANY, reason="heavy: runs under HYPOTHESIS_PROFILE=fuzz (.ci/run)")
@settings(max_examples=100)
@given(st.randoms(use_true_random=False))
def test_commands_reading_hostile_files(rng):
    case = draw_case(rng, corpus())
    work = Path(tempfile.mkdtemp(prefix="pkmkit-fuzz-run-"))
    try:
        out = work / "out"
        out.mkdir()
        file = work / ("input" + Path(case.template.target).suffix)
        if case.data is None:
            shutil.copyfile(corpus() / case.template.target, file)
        else:
            file.write_bytes(case.data)
        argv = case.argv(corpus(), out, file)
        with bounded(60.0):
            result = CliRunner().invoke(cli, argv, catch_exceptions=True)
        if result.exception is not None and not isinstance(result.exception, SystemExit):
            raise result.exception
        kind = classify(result.exit_code, result.output, out, case.template)
        event(f"{case.template.name}: {kind}")
        assert kind in ("ok", "typed"), (kind, argv, result.output[-2000:])
    finally:
        shutil.rmtree(work, ignore_errors=True)
