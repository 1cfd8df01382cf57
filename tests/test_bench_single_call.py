"""``python bench/single_call.py --json FILE`` writes its report (issue 22 §1's figures).

The report holds NumPy integers (the iteration counts of the joint-chain rows are
``numpy.int64``), which ``json.dumps`` refuses: the command crashed after minutes of timing,
at the very end. The bench now passes the report through ``json_ready``; these tests build a
real report row (few calls) and a synthetic one, and read the JSON back."""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench" / "single_call.py"


@pytest.fixture(scope="module")
def single_call():
    spec = importlib.util.spec_from_file_location("bench_single_call", BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # puts bench/ on sys.path for its `load` import
    yield module
    sys.modules.pop("load", None)


def test_a_joint_chain_report_row_is_written_and_read_back(single_call):
    row = single_call.chain_rows("tripteor-x7", 40)
    with pytest.raises(TypeError, match="int64"):  # what --json did before
        json.dumps(row)
    back = json.loads(json.dumps(single_call.json_ready(row)))
    assert back.keys() == row.keys()
    for key, value in row.items():
        expected = list(value) if isinstance(value, tuple) else value
        assert back[key] == pytest.approx(expected, nan_ok=True), key


def test_numpy_values_become_python_numbers(single_call):
    report = {"a": {"n": np.int64(7), "x": np.float64(0.25), "flag": np.bool_(True),
                    "pair": (np.int32(2), 3.5), "rows": np.arange(3), "nan": math.nan,
                    "none": None, 4: "four"}}
    ready = single_call.json_ready(report)
    assert json.loads(json.dumps(ready)) == {
        "a": {"n": 7, "x": 0.25, "flag": True, "pair": [2, 3.5], "rows": [0, 1, 2],
              "nan": pytest.approx(math.nan, nan_ok=True), "none": None, "4": "four"}}
    assert type(ready["a"]["n"]) is int and type(ready["a"]["flag"]) is bool


def test_an_unknown_value_is_a_type_error(single_call):
    with pytest.raises(TypeError, match="object is not a report value"):
        single_call.json_ready({"a": object()})
