"""Command-line fuzz with hostile files: each run is a subprocess ``pkmkit …`` reading a mutated
file (or given a hostile option value), classified as ok / typed error / traceback / hang /
partial file (``tests/fuzz/file_cases.py``). Prints the counts and every failing case with the
command that reproduces it; exits 1 if any run failed.

    PYTHONPATH=src python tools/fuzz_cli.py --seed 0 --runs 400 [--timeout 60] [--keep DIR]

The same seed draws the same cases (docs/reliability.md lists the published runs).
"""

from __future__ import annotations

import argparse
import collections
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.fuzz.file_cases import classify, corpus, draw_case

RUN = "import sys; from pkmkit.cli.main import cli; cli(prog_name='pkmkit')"


def run_one(case, root: Path, timeout: float) -> tuple[str, list[str], str]:
    """Run ``case`` in a fresh directory under ``root``: (class, argv, output)."""
    work = Path(tempfile.mkdtemp(dir=root))
    out = work / "out"
    out.mkdir()
    target = case.template.target
    file = work / ("input" + Path(target).suffix)
    if case.data is None:
        shutil.copyfile(corpus() / target, file)
    else:
        file.write_bytes(case.data)
    argv = case.argv(corpus(), out, file)
    env = dict(os.environ, PYTHONWARNINGS="ignore::DeprecationWarning")
    try:
        done = subprocess.run([sys.executable, "-c", RUN, *argv], capture_output=True,
                              timeout=timeout, env=env, cwd=work, check=False)
        code, output = done.returncode, (done.stdout + done.stderr).decode("utf-8", "replace")
    except subprocess.TimeoutExpired:
        code, output = None, ""
    return classify(code, output, out, case.template), argv, output


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--runs", type=int, default=400)
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--keep", type=Path, help="keep the failing inputs in this directory")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    root = Path(tempfile.mkdtemp(prefix="pkmkit-fuzz-cli-"))
    counts: collections.Counter = collections.Counter()
    by_template: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    start = time.monotonic()
    for k in range(args.runs):
        case = draw_case(rng, corpus())
        kind, argv, output = run_one(case, root, args.timeout)
        counts[kind] += 1
        by_template[case.template.name][kind] += 1
        if kind in ("traceback", "hang", "partial"):
            tail = "\n    ".join(output.strip().splitlines()[-4:])
            print(f"[{k}] {kind.upper()}: pkmkit {' '.join(argv)}\n    {tail}", flush=True)
            if args.keep:
                args.keep.mkdir(parents=True, exist_ok=True)
                data = case.data if case.data is not None else b""
                (args.keep / f"{k}-{Path(case.template.target).name}").write_bytes(data)
    elapsed = time.monotonic() - start
    shutil.rmtree(root, ignore_errors=True)
    for name in sorted(by_template):
        print(f"  {name:40s} " + ", ".join(f"{c} {n}" for c, n in sorted(
            by_template[name].items())))
    print(f"seed {args.seed}: {args.runs} runs in {elapsed:.0f} s: "
          + ", ".join(f"{c} {counts[c]}" for c in ("ok", "typed", "traceback", "hang",
                                                    "partial")))
    return 1 if counts["traceback"] + counts["hang"] + counts["partial"] else 0


if __name__ == "__main__":
    sys.exit(main())
