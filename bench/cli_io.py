"""Benchmark: the command line end to end — batch tables and start-up.

Batch (``pkmkit ik|fk|jacobian --input T --output T``, a fresh process each time, timed from
outside, median of ``--repeat`` runs) on ``--rows`` rows, against baselines measured in the same
run on the same tables:

- ``xlib``: pyarrow's own read of the input table plus write of the command's output table (the
  least any tool reading and writing those tables with that library pays), with pyarrow's
  default write options; for Parquet also ``plain s``, the same write with the command's
  encoding (numbers plain, texts dictionary-encoded: ``pkmkit.io.table_writer``), and
  ``xplain`` against it;
- ``xold``: the former implementation (csv module, per-row ``float()`` and ``.17g`` formatting,
  per-row status labels) on the first ``--old-rows`` rows, scaled to ``--rows``.

``cpu s``, ``lib cpu`` and ``solve cpu`` are the same in CPU time (user + system): on a loaded
machine they estimate the wall time of a quiet one.

``solve s`` is the engine call the command makes (``Machine.ik(full_output=True)``,
``Machine.fk(full_output=True)``, ``Machine.jacobian``) timed in this process on the same rows;
``rest`` = total − solve is what the command line adds (start-up, reading, writing, statuses),
compared with the library's read + write in ``rest/lib``.

Start-up: ``pkmkit --help`` and a one-pose ``pkmkit ik`` against ``python -c pass`` and
``python -c "import numpy"`` (the floor any NumPy program pays); then the CPU time of a fresh
process's first batch call (5,000 poses or Verne positions; 200 configurations for the
direct models, the joint-chain closures included) over
``import pkmkit``, by default (the C kernels of ``pkmkit.native`` where built), with the Numba
kernels (``PKMKIT_NATIVE=0``) and with the compiled kernels forced (``PKMKIT_COMPILED=1``);
``--first-calls-only`` prints that table alone. ``m.ik(X)`` against ``m.ik(X,
full_output=True)`` (statuses, modes, shortfalls, strokes) is timed in the bench's process.

Memory: with ``--big-rows N`` (e.g. 10⁷), the peak resident memory of ``pkmkit ik`` on an
N-row CSV → Parquet run, beside that of the ``--rows`` run (bounded by the chunk size, it should
not grow with N).

``--load`` runs everything again beside a competing busy process.

``--phases``: where a fresh ``pkmkit ik linear-delta`` process spends its CPU time, Parquet to
Parquet (and CSV to CSV) on the ``--rows`` table, median of ``--repeat`` processes: the imports
before the command runs (pkmkit, click, NumPy), the conversion of the read batches to float64
arrays, the inverse model with statuses and modes, the output table built and written, and the
rest of the command (pyarrow's imports, opening the file and reading its batches, the columns);
with ``--six-axis`` those machines' tables instead, their angle conversion and stroke flags
timed too (session 34).

``--six-axis gough-stewart,verne``: ``pkmkit ik`` of those machines on their own ``--rows``
tables (the hexapod's full poses x,y,z,A,B,C in m and degrees, the Verne module's positions
x,y,z, drawn about home), CSV and Parquet, against pyarrow's read + write of the same file
(``xlib``) and the engine call ``m.ik(X, full_output=True)`` on the SI rows (``solve``), in
the same run; then nothing else (issue 22 §5, session 33).

Usage::

    python bench/cli_io.py [--rows 1000000] [--repeat 5] [--big-rows 10000000] [--load]
                           [--commands ik] [--formats parquet] [--old-rows 0]
                           [--first-calls-only | --no-first-calls]
                           [--six-axis gough-stewart,verne]
"""

from __future__ import annotations

import argparse
import csv
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pcsv
import pyarrow.parquet as pq

import pkmkit

PKMKIT = [sys.executable, "-m", "pkmkit.cli.main"]


def _pkmkit_command() -> list[str]:
    exe = shutil.which("pkmkit")
    return [exe] if exe else PKMKIT


def wall(cmd: list[str], repeat: int) -> float:
    """Median wall time (s) of ``cmd`` run ``repeat`` times (exit status 0 or 3 accepted)."""
    return run_times(cmd, repeat)[0]


def run_times(cmd: list[str], repeat: int, env: dict | None = None) -> tuple[float, float]:
    """Median wall time and median CPU time (user + system, s) of ``cmd`` over ``repeat`` runs.
    On a loaded machine the CPU time estimates the wall time of a quiet one (an upper bound
    where pyarrow uses both cores)."""
    walls, cpus = [], []
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
        walls.append(time.perf_counter() - start)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        if done.returncode not in (0, 3):
            raise RuntimeError(f"{' '.join(map(str, cmd))} failed: {done.stderr.decode()}")
    return statistics.median(walls), statistics.median(cpus)


def cpu_in_process(func, repeat: int) -> float:
    """Median CPU time (s) of ``func()`` in this process."""
    times = []
    for _ in range(repeat):
        start = time.process_time()
        func()
        times.append(time.process_time() - start)
    return statistics.median(times)


def peak_memory(cmd: list[str]) -> float:
    """Peak resident memory (MB) of ``cmd``, from the kernel's accounting of the child."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    code = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:]); "
            "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    out = subprocess.run([sys.executable, "-c", code, *cmd], capture_output=True, text=True)
    del before
    return int(out.stdout.split()[-1]) / 1024


def median_in_process(func, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def make_tables(folder: Path, rows: int) -> dict[str, Path]:
    rng = np.random.default_rng(0)
    m = pkmkit.machine("linear-delta")
    x = np.round(rng.uniform(-0.25, 0.25, (rows, 3)), 6)
    q = m.ik(x)
    paths = {}
    for name, cols in (("poses", {"x": x[:, 0], "y": x[:, 1], "z": x[:, 2]}),
                       ("q", {"q1": q[:, 0], "q2": q[:, 1], "q3": q[:, 2]})):
        table = pa.table(cols)
        paths[f"{name}.csv"] = folder / f"{name}.csv"
        pcsv.write_csv(table, paths[f"{name}.csv"],
                       write_options=pcsv.WriteOptions(quoting_style="none"))
        paths[f"{name}.parquet"] = folder / f"{name}.parquet"
        pq.write_table(table, paths[f"{name}.parquet"])
    return paths


def library_read_write(src: Path, produced: Path, repeat: int, cpu: bool = False,
                       plain: bool = False) -> float:
    """pyarrow reading ``src`` and writing the table held in ``produced`` (same format): median
    wall time, or CPU time with ``cpu``; ``plain`` (Parquet): written with the command's
    encoding (only the text columns dictionary-encoded) instead of pyarrow's defaults."""
    if src.suffix == ".csv":
        with open(produced, "rb") as handle:  # the command's "# units: m" line
            skip = 1 if handle.readline().startswith(b"#") else 0
        out_table = pcsv.read_csv(produced, read_options=pcsv.ReadOptions(skip_rows=skip))

        def run():
            pcsv.read_csv(src)
            pcsv.write_csv(out_table, produced.with_suffix(".lib.csv"))
    else:
        out_table = pq.read_table(produced)
        options = {} if not plain else {"use_dictionary": [
            f.name for f in out_table.schema if pa.types.is_dictionary(f.type)]}

        def run():
            pq.read_table(src)
            pq.write_table(out_table, produced.with_suffix(".lib.parquet"), **options)
    return cpu_in_process(run, repeat) if cpu else median_in_process(run, repeat)


def old_implementation(src: Path, dst: Path, rows: int, columns: list[str]) -> None:
    """The former batch path: csv module, per-cell float(), .17g, per-row labels."""
    m = pkmkit.machine("linear-delta")
    with open(src, newline="", encoding="utf-8-sig") as handle:
        data = [(n, r) for n, r in enumerate(csv.reader(handle), start=1)
                if r and not r[0].lstrip().startswith("#")][: rows + 1]
    header = data[0][1]
    index = [header.index(c) for c in columns]
    values = np.empty((len(data) - 1, len(columns)))
    for k, (_, row) in enumerate(data[1:]):
        for j, c in enumerate(index):
            values[k, j] = float(row[c])
    res = m.ik(values, full_output=True)
    labels = [pkmkit.Status(int(s)).label for s in res.status]
    with open(dst, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow([*columns, "q1", "q2", "q3", "mode", "status"])
        for k, lab in enumerate(labels):
            writer.writerow([f"{float(v):.17g}" for v in (*values[k], *res.q[k])]
                            + [m.mode_label(res.mode[k]) if res.mode[k] else "", lab])


#: A fresh process running ``pkmkit ik linear-delta --input argv[1] --output argv[2]`` with
#: its stages timed (CPU) by wrappers; prints ``stage seconds`` lines.
PHASES = r"""
import collections, importlib, sys, time
t0 = time.process_time()
main = importlib.import_module("pkmkit.cli.main")
ik_cmd = importlib.import_module("pkmkit.cli.ik_cmd")
imports = time.process_time() - t0
acc = collections.Counter()
def wrap(owner, name, label):
    function = getattr(owner, name)
    def wrapper(*args, **kwargs):
        start = time.process_time()
        try:
            return function(*args, **kwargs)
        finally:
            acc[label] += time.process_time() - start
    setattr(owner, name, wrapper)
sources = importlib.import_module("pkmkit.io.table_sources")
writer = importlib.import_module("pkmkit.io.table_writer")
wrap(sources.ArrowSource, "_convert", "read:batches-to-float64")
wrap(sources.CsvSource, "_parse", "read:csv-parse-to-float64")
wrap(ik_cmd, "inverse", "kernel:ik-full-output")
wrap(writer.TableWriter, "write", "write:table-and-encode")
wrap(writer.TableWriter, "close", "write:close-rename")
if sys.argv[3:] and sys.argv[3] != "linear-delta":  # a six-axis machine's own stages
    wrap(ik_cmd, "pose_from_cli", "angles:to-rotation-vectors")
    wrap(importlib.import_module("pkmkit.cli.stroke_flags").BatchFlags, "__call__",
         "flags:strokes")
    # a position-controlled machine's (the Verne module's) own stages; "in ik:" stages are
    # parts of kernel:ik-full-output (session 35)
    position = importlib.import_module("pkmkit.machines.full_pose_position")
    wrap(position, "slide_columns", "in ik: slide-columns")
    wrap(position.PositionInverse, "_compiled_rows", "in ik: position-solve")
    wrap(ik_cmd, "pose_to_cli", "angles:from-rotation-vectors")
sys.argv = ["pkmkit", "ik", sys.argv[3] if sys.argv[3:] else "linear-delta", "--input",
            sys.argv[1], "--output", sys.argv[2]]
start = time.process_time()
try:
    main.main()
except SystemExit:
    pass
body = time.process_time() - start
print("imports", imports)
for label, seconds in acc.items():
    print(label, seconds)
print("rest", body - sum(v for k, v in acc.items() if not k.startswith("in ik:")))
print("total", imports + body)
"""


def phases(paths: dict[str, Path], folder: Path, repeat: int,
           name: str = "linear-delta") -> None:
    """Median CPU time of each stage of a fresh ``pkmkit ik`` process (``PHASES``) of machine
    ``name`` (a six-axis one adds its angle conversion and stroke flags)."""
    for fmt in ("parquet", "csv"):
        runs: dict[str, list[float]] = {}
        for _ in range(repeat):
            done = subprocess.run([sys.executable, "-c", PHASES, str(paths[f"poses.{fmt}"]),
                                   str(folder / f"phases.{fmt}"), name], capture_output=True,
                                  text=True)
            if done.returncode not in (0, 3):
                raise RuntimeError(done.stderr)
            for line in done.stdout.splitlines():
                label, value = line.rsplit(maxsplit=1)
                runs.setdefault(label, []).append(float(value))
        print(f"\npkmkit ik {name}, {fmt} -> {fmt}, CPU s (median of {repeat} fresh "
              f"processes; load average {os.getloadavg()[0]:.2f})")
        for label, values in runs.items():
            print(f"  {label:28s} {statistics.median(values):6.3f}")


def six_axis_tables(folder: Path, name: str, rows: int) -> tuple[dict[str, Path], np.ndarray]:
    """A ``rows``-row pose table of machine ``name`` about its home (CSV and Parquet, m and
    degrees of the xyz convention; positions alone for a machine commanded by them) and its
    rows in SI (rotation vectors) as the engine takes them."""
    from pkmkit.boundary.coordinates import pose_from_cli

    m = pkmkit.machine(name)
    rng = np.random.default_rng(0)
    width = 3 if m.position_controlled else 6
    spread = np.array([0.05, 0.05, 0.05, 10.0, 10.0, 10.0])[:width]
    home = np.asarray(m.home_pose, dtype=float)[:width].copy()
    if width == 6:
        home[3:] = 0.0
    values = np.round(home + rng.uniform(-1.0, 1.0, (rows, width)) * spread, 6)
    table = pa.table({c: values[:, j] for j, c in enumerate("xyzABC"[:width])})
    paths = {"poses.csv": folder / f"{name}.csv", "poses.parquet": folder / f"{name}.parquet"}
    pcsv.write_csv(table, paths["poses.csv"], write_options=pcsv.WriteOptions(
        quoting_style="none"))
    pq.write_table(table, paths["poses.parquet"])
    return paths, pose_from_cli(values, m, "m", "xyz")


def six_axis(args, folder: Path, label: str) -> None:
    """``pkmkit ik`` of the ``--six-axis`` machines against pyarrow's read + write of the
    same tables and the engine call, in one run."""
    cmd = _pkmkit_command()
    print(f"\n== {label}: pkmkit ik of six-axis machines, {args.rows} rows (load average "
          f"{os.getloadavg()[0]:.2f})")
    print(f"{'machine':<15} {'format':<8} {'s':>7} {'lib s':>7} {'xlib':>6} {'solve s':>8} "
          f"{'cpu s':>6} {'lib cpu':>7} {'xlib cpu':>8} {'solve cpu':>9}")
    for name in args.six_axis:
        m = pkmkit.machine(name)
        paths, x = six_axis_tables(folder, name, args.rows)
        solve = median_in_process(lambda m=m, x=x: m.ik(x, full_output=True),
                                  args.repeat)
        solve_cpu = cpu_in_process(lambda m=m, x=x: m.ik(x, full_output=True),
                                   args.repeat)
        for fmt in args.formats:
            src, dst = paths[f"poses.{fmt}"], folder / f"out-{name}.{fmt}"
            t, cpu = run_times([*cmd, "ik", name, "--input", str(src), "--output", str(dst)],
                               args.repeat)
            lib = library_read_write(src, dst, args.repeat)
            lib_cpu = library_read_write(src, dst, args.repeat, cpu=True)
            print(f"{name:<15} {fmt:<8} {t:7.3f} {lib:7.3f} {t / lib:6.2f} {solve:8.3f} "
                  f"{cpu:6.3f} {lib_cpu:7.3f} {cpu / lib_cpu:8.2f} {solve_cpu:9.3f}")


def busy() -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", "while True: pass"])


def run_all(args, folder: Path, paths: dict[str, Path], label: str) -> None:
    cmd = _pkmkit_command()
    print(f"\n== {label}")
    print(f"{'command':<20} {'format':<8} {'s':>7} {'lib s':>7} {'xlib':>6} {'solve s':>8} "
          f"{'rest/lib':>8} {'cpu s':>6} {'lib cpu':>7} {'solve cpu':>9}")
    m = pkmkit.machine("linear-delta")
    x = np.column_stack([pq.read_table(paths["poses.parquet"]).column(c).to_numpy()
                         for c in "xyz"])
    q = np.column_stack([pq.read_table(paths["q.parquet"]).column(c).to_numpy()
                         for c in ("q1", "q2", "q3")])
    solves = {
        "ik": lambda: m.ik(x, full_output=True),
        "fk": lambda: m.fk(q, full_output=True),
        "jacobian": lambda: m.jacobian(x, q=m.ik(x, full_output=True).q),
    }
    statuses_at_kernel_cost(m, x, args.repeat)
    for command, src_name in (("ik", "poses"), ("fk", "q"), ("jacobian", "poses")):
        if command not in args.commands:
            continue
        solve = median_in_process(solves[command], args.repeat)
        solve_cpu = cpu_in_process(solves[command], args.repeat)
        for fmt in args.formats:
            src = paths[f"{src_name}.{fmt}"]
            dst = folder / f"out-{command}.{fmt}"
            t, cpu = run_times([*cmd, command, "linear-delta", "--input", str(src), "--output",
                                str(dst)], args.repeat)
            lib = library_read_write(src, dst, args.repeat)
            lib_cpu = library_read_write(src, dst, args.repeat, cpu=True)
            print(f"pkmkit {command:<13} {fmt:<8} {t:7.3f} {lib:7.3f} {t / lib:6.2f} "
                  f"{solve:8.3f} {(t - solve) / lib:8.2f} {cpu:6.3f} {lib_cpu:7.3f} "
                  f"{solve_cpu:9.3f}")
            if fmt == "parquet":
                plain = library_read_write(src, dst, args.repeat, plain=True)
                plain_cpu = library_read_write(src, dst, args.repeat, cpu=True, plain=True)
                print(f"{'':<29} plain s {plain:7.3f} xplain {t / plain:6.2f} "
                      f"plain cpu {plain_cpu:6.3f}")
    old_rows = min(args.old_rows, args.rows)
    if old_rows:
        start = time.perf_counter()
        old_implementation(paths["poses.csv"], folder / "old.csv", old_rows, ["x", "y", "z"])
        old = (time.perf_counter() - start) * args.rows / old_rows
        t_ik = wall([*cmd, "ik", "linear-delta", "--input", str(paths["poses.csv"]),
                     "--output", str(folder / "out-ik.csv")], args.repeat)
        print(f"former CSV path (csv module, .17g), ik on {old_rows} rows scaled to "
              f"{args.rows}: {old:.2f} s; pkmkit ik now {t_ik:.3f} s, xold {old / t_ik:.1f}")
    print(f"{'start-up':<34} {'s':>7} {'x python':>9} {'x numpy':>8} {'cpu s':>6}")
    t_pass = wall([sys.executable, "-c", "pass"], args.repeat)
    t_numpy = wall([sys.executable, "-c", "import numpy"], args.repeat)
    for name, extra in (("pkmkit --help", ["--help"]),
                        ("pkmkit ik (one pose)", ["ik", "linear-delta", "--pose", "0.25,0.25,0"]),
                        ("pkmkit path --help", ["path", "--help"])):
        t, cpu = run_times([*cmd, *extra], args.repeat)
        print(f"{name:<34} {t:7.3f} {t / t_pass:9.1f} {t / t_numpy:8.2f} {cpu:6.3f}")
    if not args.no_first_calls:
        first_calls(args.repeat)


def statuses_at_kernel_cost(m, x: np.ndarray, repeat: int) -> None:
    """CPU time of ``m.ik(X)`` and ``m.ik(X, full_output=True)`` in this process, before
    Numba is imported (the C twins of ``pkmkit.native`` where built, else NumPy) and after
    (where the extension is built the C twins still run: the same figures)."""
    for label in ("no Numba (C twins, else NumPy)", "compiled (Numba imported)"):
        if label.startswith("compiled"):
            if "numba" not in sys.modules:
                try:
                    import numba  # noqa: F401
                except ImportError:
                    return
                m.ik(x[:5000], full_output=True)  # load the cached kernels
        elif "numba" in sys.modules:
            continue
        bare = cpu_in_process(lambda: m.ik(x), repeat)
        full = cpu_in_process(lambda: m.ik(x, full_output=True), repeat)
        print(f"{label:<34} m.ik(X) {bare:.3f} s CPU, m.ik(X, full_output=True) {full:.3f} s "
              f"CPU, x{full / bare:.1f}")


#: A fresh process's first batch call (5,000 poses, above jit.MIN_ROWS), after ``import pkmkit``.
FIRST_CALL = ("import numpy as np, pkmkit; m = pkmkit.machine({name!r}); "
              "x = m.home_pose + np.random.default_rng(0).uniform(-0.05, 0.05, (5000, m.dims))")
#: A fresh process's first direct-model batch (200 configurations, above jit.SOLVER_ROWS).
FIRST_FK = ("import numpy as np, pkmkit; m = pkmkit.machine({name!r}); "
            "q = m.home_q + np.random.default_rng(0).uniform(-0.02, 0.02, (200, m.n_actuators))")
#: A fresh process's first position batch (5,000 positions of a machine commanded by its
#: position alone: the Verne module's iterative position inverse).
FIRST_POSITIONS = ("import numpy as np, pkmkit; m = pkmkit.machine({name!r}); "
                   "p = m.home_pose[:3] + np.random.default_rng(0).uniform(-0.05, 0.05, "
                   "(5000, 3))")
#: (machine, call, set-up, whether the C kernels of pkmkit.native serve it)
FIRST_CASES = (("linear-delta", "m.ik(x)", FIRST_CALL, False),
               ("linear-delta", "m.ik(x, full_output=True)", FIRST_CALL, False),
               ("gough-stewart", "m.ik(x)", FIRST_CALL, True),
               ("gough-stewart", "m.ik(x, full_output=True)", FIRST_CALL, True),
               ("gough-stewart", "m.fk(q)", FIRST_FK, True),
               ("verne", "m.fk(q)", FIRST_FK, True),
               ("verne", "m.ik(p)", FIRST_POSITIONS, True),
               ("verne", "m.ik(p, full_output=True)", FIRST_POSITIONS, True),
               ("tripteor-x7", "m.fk(q)", FIRST_FK, True),
               ("trimule-600", "m.fk(q)", FIRST_FK, True),
               ("tripteor-x7", "m.jacobian(q=q)", FIRST_FK, True),
               ("trimule-600", "m.jacobian(q=q)", FIRST_FK, True))


def first_calls(repeat: int) -> None:
    """CPU time of a fresh process's first batch call, over ``import pkmkit`` and over its
    set-up (``import pkmkit``, the machine built, the input drawn: run alone in the same way)
    in the same run: the default path (the C kernels where ``pkmkit.native`` was built), the
    Numba kernels (``PKMKIT_NATIVE=0``: Numba's import, its NumPy support loaded on the first
    call, the cached kernel) and the compiled path forced (``PKMKIT_COMPILED=1``)."""
    base = run_times([sys.executable, "-c", "import pkmkit"], repeat)[1]
    print(f"{'first batch call':<58} {'cpu s':>6} {'- import pkmkit':>16} {'- set-up':>9}")
    print(f"{'import pkmkit':<58} {base:6.3f}")
    setups: dict[str, float] = {}
    for name, call, setup, native in FIRST_CASES:
        code = setup.format(name=name)
        if code not in setups:
            setups[code] = run_times([sys.executable, "-c", code], repeat)[1]
            print(f"{name + ' set-up (machine, input)':<58} {setups[code]:6.3f} "
                  f"{setups[code] - base:16.3f}")
        variants = [("", {}), (" compiled", {"PKMKIT_COMPILED": "1"})]
        if native:
            variants.append((" Numba (PKMKIT_NATIVE=0)", {"PKMKIT_NATIVE": "0"}))
        for suffix, extra in variants:
            cpu = run_times([sys.executable, "-c", code + "; " + call], repeat,
                            env={**os.environ, **extra})[1]
            label = f"{name} {call}{suffix}"
            print(f"{label:<58} {cpu:6.3f} {cpu - base:16.3f} {cpu - setups[code]:9.3f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--old-rows", type=int, default=100_000)
    parser.add_argument("--big-rows", type=int, default=0)
    parser.add_argument("--load", action="store_true", help="also run beside a busy process")
    parser.add_argument("--commands", default="ik,fk,jacobian",
                        help="batch commands to time, comma-separated (default: all three)")
    parser.add_argument("--formats", default="csv,parquet",
                        help="batch table formats to time, comma-separated (default: both)")
    parser.add_argument("--first-calls-only", action="store_true",
                        help="only the table of a fresh process's first batch call")
    parser.add_argument("--phases", action="store_true",
                        help="only the CPU time of each stage of a fresh pkmkit ik process "
                             "(of the --six-axis machines if given)")
    parser.add_argument("--no-first-calls", action="store_true",
                        help="leave out the table of a fresh process's first batch call")
    parser.add_argument("--six-axis", default="",
                        help="only pkmkit ik of these machines, comma-separated (e.g. "
                             "gough-stewart,verne) on their own tables")
    args = parser.parse_args()
    args.six_axis = [name for name in args.six_axis.split(",") if name]
    args.commands = args.commands.split(",")
    args.formats = args.formats.split(",")
    if args.first_calls_only:
        first_calls(args.repeat)
        return
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, pyarrow {pa.__version__}, "
          f"Python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} cores")
    print(f"{args.rows} rows, median of {args.repeat} runs (wall time of a fresh process)")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if args.six_axis and args.phases:
            for name in args.six_axis:
                phases(six_axis_tables(folder, name, args.rows)[0], folder, args.repeat, name)
            return
        if args.six_axis:
            six_axis(args, folder, "quiet")
            if args.load:
                competitor = busy()
                try:
                    six_axis(args, folder, "beside a busy process")
                finally:
                    competitor.kill()
            return
        paths = make_tables(folder, args.rows)
        if args.phases:
            phases(paths, folder, args.repeat)
            return
        run_all(args, folder, paths, "quiet")
        if args.load:
            competitor = busy()
            try:
                run_all(args, folder, paths, "beside a busy process")
            finally:
                competitor.kill()
        if args.big_rows:
            cmd = _pkmkit_command()
            small = peak_memory([*cmd, "ik", "linear-delta", "--input",
                                 str(paths["poses.csv"]), "--output", str(folder / "m.parquet")])
            big_paths = make_big(folder, args.big_rows)
            start = time.perf_counter()
            big = peak_memory([*cmd, "ik", "linear-delta", "--input", str(big_paths),
                               "--output", str(folder / "big.parquet")])
            took = time.perf_counter() - start
            print(f"\npeak memory of pkmkit ik, CSV -> Parquet, chunks of 500000 rows: "
                  f"{args.rows} rows {small:.0f} MB; {args.big_rows} rows {big:.0f} MB "
                  f"({took:.1f} s, {pq.ParquetFile(folder / 'big.parquet').metadata.num_rows}"
                  " rows written)")


def make_big(folder: Path, rows: int) -> Path:
    """An N-row pose CSV written in pieces (never whole in memory)."""
    path = folder / "big.csv"
    rng = np.random.default_rng(1)
    with open(path, "wb") as handle:
        handle.write(b"x,y,z\n")
        left = rows
        while left:
            n = min(left, 1_000_000)
            block = pa.table({k: np.round(rng.uniform(-0.25, 0.25, n), 6) for k in "xyz"})
            sink = pa.BufferOutputStream()
            pcsv.write_csv(block, sink, write_options=pcsv.WriteOptions(include_header=False))
            handle.write(sink.getvalue().to_pybytes())
            left -= n
    return path


if __name__ == "__main__":
    main()
