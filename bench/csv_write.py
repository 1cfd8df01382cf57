"""Benchmark: writing a batch command's CSV table, the C formatter against pyarrow, in one
process (issue 22 §5, session 35).

The tables are those ``pkmkit ik --input`` writes for ``--rows`` rows: the hexapod's (x, y, z,
A, B, C rounded to 6 decimals as a table's inputs are, six actuator coordinates of full
precision, a ``status`` text column) and the linear Delta's (x, y, z, q1..q3, ``mode``,
``status``). For each, median of ``--repeat`` runs, wall and CPU time (user + system of the
process, both cores):

- ``c``: :class:`pkmkit.io.table.TableWriter` with the C formatter
  (``pkmkit.native.kernels.csv_rows``, pieces over the cores), the command's writer;
- ``pyarrow``: the same writer with ``PKMKIT_NATIVE=0`` (pyarrow's ``write_csv`` in slices
  over the cores: the writer before session 35), and ``xpa`` = pyarrow / c;
- ``floor``: pyarrow's own ``write_csv`` of the same Arrow table in one call (its default
  options, what a user's pyarrow script pays), and ``xfloor`` = floor / c.

Then the number formatting alone, one thread, per value: ``csv_rows`` on one float64 column
against pyarrow's ``pyarrow.compute.cast`` to text of the same column.

Every run's file is compared byte for byte with the pyarrow writer's (the bench stops if they
differ).

Usage::

    python bench/csv_write.py [--rows 1000000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pcsv

from pkmkit.io.table import Labels, TableWriter
from pkmkit.numerics.jit import native_kernels

STATUS = ["ok", "unreachable", "invalid-input", "out-of-stroke"]


def tables(rows: int) -> dict[str, dict]:
    rng = np.random.default_rng(0)
    pose = np.round(rng.uniform(-1, 1, (rows, 6)) * [0.05, 0.05, 0.05, 10, 10, 10]
                    + [0, 0, 0.8, 0, 0, 0], 6)
    q = 1.0 + rng.uniform(-0.1, 0.1, (rows, 6))
    status = Labels(rng.choice(4, rows, p=[0.9, 0.04, 0.01, 0.05]).astype(np.int32), STATUS)
    hexapod = {**{c: pose[:, j] for j, c in enumerate("xyzABC")},
               **{f"q{j + 1}": q[:, j] for j in range(6)}, "status": status}
    x = np.round(rng.uniform(-0.1, 0.1, (rows, 3)) + np.array([0.0, 0.0, -0.9]), 6)
    delta = {**{c: x[:, j] for j, c in enumerate("xyz")},
             **{f"q{j + 1}": q[:, j] for j in range(3)},
             "mode": Labels(rng.integers(1, 3, rows).astype(np.int32), ["", "up", "down"]),
             "status": status}
    return {"gough-stewart": hexapod, "linear-delta": delta}


def timed(func, repeat: int) -> tuple[float, float]:
    walls, cpus = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        func()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return statistics.median(walls), statistics.median(cpus)


def write(path: Path, columns: dict, native: bool) -> None:
    if native:
        os.environ.pop("PKMKIT_NATIVE", None)
    else:
        os.environ["PKMKIT_NATIVE"] = "0"
    try:
        with TableWriter(path) as writer:
            writer.write(columns)
    finally:
        os.environ.pop("PKMKIT_NATIVE", None)


def arrow_table(columns: dict) -> pa.Table:
    arrays = {}
    for name, values in columns.items():
        if isinstance(values, Labels):
            arrays[name] = pa.DictionaryArray.from_arrays(pa.array(values.codes),
                                                          pa.array(values.names))
        else:
            arrays[name] = pa.array(values)
    return pa.table(arrays)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    kernels = native_kernels()
    if kernels is None or not hasattr(kernels, "csv_rows"):
        raise SystemExit("the C extension (with csv_text.c) is not built")
    print(f"pyarrow {pa.__version__}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.2f}; {args.rows} rows, median of {args.repeat}")
    print(f"{'table':<15} {'c s':>7} {'c cpu':>7} {'pyarrow s':>9} {'pa cpu':>7} {'xpa':>5} "
          f"{'xpa cpu':>7} {'floor s':>7} {'fl cpu':>7} {'xfloor':>6} {'xfl cpu':>7}")
    with tempfile.TemporaryDirectory() as folder:
        for name, columns in tables(args.rows).items():
            c_path, pa_path, floor_path = (Path(folder) / f"{name}-{k}.csv" for k in "cpf")
            table = arrow_table(columns)
            c = timed(lambda p=c_path, t=columns: write(p, t, True), args.repeat)
            py = timed(lambda p=pa_path, t=columns: write(p, t, False), args.repeat)
            floor = timed(lambda p=floor_path, t=table: pcsv.write_csv(t, str(p)), args.repeat)
            if c_path.read_bytes() != pa_path.read_bytes():
                raise SystemExit(f"{name}: the C formatter's file differs from pyarrow's")
            print(f"{name:<15} {c[0]:7.3f} {c[1]:7.3f} {py[0]:9.3f} {py[1]:7.3f} "
                  f"{py[0] / c[0]:5.2f} {py[1] / c[1]:7.2f} {floor[0]:7.3f} {floor[1]:7.3f} "
                  f"{floor[0] / c[0]:6.2f} {floor[1] / c[1]:7.2f}")
    rng = np.random.default_rng(1)
    for label, x in (("17 digits", rng.uniform(-0.3, 0.3, args.rows)),
                     ("6 decimals", np.round(rng.uniform(-0.3, 0.3, args.rows), 6))):
        ours = timed(lambda x=x: kernels.csv_rows((x,), 0, len(x)), args.repeat)[1]
        theirs = timed(lambda x=x: pc.cast(pa.array(x), pa.string()), args.repeat)[1]
        print(f"one float64 column, {label:<10}: csv_rows {1e9 * ours / len(x):6.1f} ns, "
              f"pyarrow cast {1e9 * theirs / len(x):6.1f} ns per value, x{theirs / ours:.2f}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
