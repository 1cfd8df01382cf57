"""The batch readers and writers never import pandas: pyarrow's ``pa.array``, ``pa.table`` and
``ChunkedArray.to_numpy`` consult its pandas shim, which imports pandas when it is installed
(0.3 to 0.9 s per run). The check runs the command line in a fresh process whose import system
records every attempt to import pandas (installed or not)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
feather = pytest.importorskip("pyarrow.feather")

SPY = r"""
import importlib.abc, sys
tried = []

class Spy(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] == "pandas":
            tried.append(name)
        return None

sys.meta_path.insert(0, Spy())
from pkmkit.cli.main import main
sys.argv = ["pkmkit", "ik", "linear-delta", "--input", sys.argv[1], "--output", sys.argv[2]]
try:
    main()
except SystemExit as exc:
    print("exit", exc.code)
print("pandas attempts:", len(tried))
"""


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("tables")
    x = np.linspace(-0.01, 0.01, 50)
    z = np.full(50, 0.8)
    z[7] = np.nan  # one flagged row
    columns = [pa.array(x), pa.array(np.zeros(50)), pa.array(z)]
    y = columns[1].to_pylist()
    y[11] = None  # an empty cell
    columns[1] = pa.array(y, pa.float64())
    table = pa.Table.from_arrays(columns, names=["x", "y", "z"])
    paths = {"parquet": folder / "in.parquet", "arrow": folder / "in.arrow",
             "csv": folder / "in.csv"}
    pq.write_table(table, paths["parquet"], row_group_size=16)
    feather.write_feather(table, paths["arrow"])
    paths["csv"].write_text("x,y,z\n" + "".join(f"{a!r},0,{b!r}\n" for a, b in zip(x, z,
                                                                                    strict=True)))
    return paths


# Parquet to Parquet in the ordinary run, the other pairs marked ci (.ci/run): 0.37 s each
_CI = [pytest.mark.ci]


@pytest.mark.parametrize("source", ["parquet", pytest.param("arrow", marks=_CI),
                                    pytest.param("csv", marks=_CI)])
@pytest.mark.parametrize("target", ["parquet", pytest.param("csv", marks=_CI)])
def test_batch_reading_and_writing_do_not_import_pandas(inputs, tmp_path, source, target):
    out = tmp_path / f"out.{target}"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(__file__).parents[2] / "src"),
                                                        os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-c", SPY, str(inputs[source]), str(out)],
                          capture_output=True, text=True, env=env, timeout=300)
    assert "pandas attempts: 0" in done.stdout, done.stdout + done.stderr
    assert "exit 3" in done.stdout  # the flagged rows are still flagged
    assert out.exists()


def test_buffers_give_the_values_pa_array_gives(tmp_path):
    """The writer's arrays built from buffers equal pyarrow's own conversion (floats, ints,
    bools, strings, labels) and the reader's copy of a chunked column keeps every value."""
    from pkmkit.io.table_sources import _fill
    from pkmkit.io.table_writer import Labels, _to_arrow

    rng = np.random.default_rng(3)
    cases = [rng.standard_normal(9), np.arange(9, dtype=np.int64), rng.random(9) > 0.5,
             np.array(["ok", "unreachable", "é", "", "x"] * 2)[:9]]
    for values in cases:
        assert _to_arrow(values).equals(pa.array(values if values.dtype.kind != "U"
                                                 else [str(v) for v in values]))
    labels = _to_arrow(Labels(codes=np.array([1, 0, 1]), names=["a", "b"]))
    assert labels.to_pylist() == ["b", "a", "b"]
    column = pa.chunked_array([pa.array([1.0, 2.0, 3.0]).slice(1), pa.array([4.0, 5.0])])
    out = np.empty(4)
    _fill(out, column)
    assert out.tolist() == [2.0, 3.0, 4.0, 5.0]
