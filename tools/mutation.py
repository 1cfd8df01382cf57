"""Mutation testing of one pkmkit package or module with mutmut, optionally on a random sample.

Usage (from the repository root, in the project's virtual environment with the ``dev`` extra)::

    python tools/mutation.py pkmkit.spatial                       # every mutant of the package
    python tools/mutation.py pkmkit.machines --sample 120 --seed 15 --jobs 1
    python tools/mutation.py pkmkit.motion.gcode --report          # scores from the last runs only
    python tools/mutation.py pkmkit.machines --sample 120 --survivors  # the sample's survivors
    python tools/mutation.py pkmkit.spatial --plausible            # plausible bugs (below)
    python tools/mutation.py pkmkit.exceptions --plausible --sample 30 --seed 1
    python tools/mutation.py pkmkit.machines --plausible --sample 20 --resume  # continue a run
    python tools/mutation.py pkmkit.cli --plausible --sample 20 --tests-for cli  # per command
    python tools/mutation.py pkmkit.machines --plausible --sample 20  # the tests calling each
                                                    # mutant's function (BY_CALLS, --by-calls)

``--plausible`` plants, instead of mutmut's operator and constant changes, the one-line bugs
people make in geometric code (``tools/plausible_mutants.py``: operands of ``@``, of ``*`` on
rotations and of ``np.cross`` swapped, rotation matrices transposed or a transpose dropped, unit
and scale factors dropped or inverted, the wrong half of a 6-vector, slices and indices shifted
by one), one at a time in a copy of ``src/``, and runs the package's tests (``--tests``, default
:data:`PLAUSIBLE_TESTS`; never the documentation comparisons of ``tests/docs``, which check
outputs recorded from the code itself). Results are appended to ``--results`` (JSON lines).

mutmut's configuration is ``[tool.mutmut]`` in pyproject.toml. mutmut writes a mutated copy of the
source and the tests to ``./mutants/`` (git-ignored); its first run also runs the whole suite once
to learn which tests reach which function (cached afterwards). A sample is drawn with
``random.Random(seed)`` from the sorted mutant names of the target, so the same command draws the
same mutants. The score printed is killed / (killed + survived), where a timeout counts as killed
(an infinite loop is observable), mutants that no test reaches count as survived, and mutants
listed in ``tools/equivalent_mutants.txt`` (no observable change; one per line with the reason)
are left out.
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import random
import subprocess
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EQUIVALENT = ROOT / "tools" / "equivalent_mutants.txt"
KILLED = {1, 3, 36, 24, -24, 152, 255}  # test failure, pytest internal error, timeouts
SURVIVED = {0, 5, 33}  # no test failed, or no test reaches the function


def _mutants_of(target: str) -> dict[str, int | None]:
    """All mutant names of ``target`` with their last exit code (None: not run yet)."""
    found: dict[str, int | None] = {}
    for meta in sorted((ROOT / "mutants" / "src").rglob("*.py.meta")):
        for key, code in json.loads(meta.read_text())["exit_code_by_key"].items():
            if fnmatch.fnmatch(key, target + ".*") or fnmatch.fnmatch(key, target + "__*"):
                found[key] = code
    return found


def _generate() -> None:
    """Write the mutated source under ./mutants (no test is run)."""
    code = (
        "import sys; from mutmut.__main__ import copy_src_dir, copy_also_copy_files, "
        "setup_source_paths, create_mutants; from mutmut.mutation.trampoline import "
        "set_mutant_under_test; set_mutant_under_test('mutant_generation'); copy_src_dir(); "
        "copy_also_copy_files(); setup_source_paths(); create_mutants(1)"
    )
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, check=True, stdout=subprocess.DEVNULL)


def _equivalent() -> dict[str, str]:
    """Mutant name → why it is equivalent, from ``tools/equivalent_mutants.txt``."""
    out = {}
    if EQUIVALENT.exists():
        for line in EQUIVALENT.read_text().splitlines():
            if line.strip() and not line.startswith("#"):
                name, _, reason = line.partition(" ")
                out[name] = reason.strip()
    return out


def _report(names: list[str], codes: dict[str, int | None]) -> int:
    counts = Counter()
    survivors = []
    equivalent = _equivalent()
    for name in names:
        code = codes.get(name)
        if name in equivalent:
            counts["equivalent"] += 1
        elif code in KILLED:
            counts["killed"] += 1
        elif code in SURVIVED:
            counts["survived"] += 1
            survivors.append(name)
        else:
            counts[f"not run ({code})"] += 1
    decided = counts["killed"] + counts["survived"]
    score = 100.0 * counts["killed"] / decided if decided else float("nan")
    for name in survivors:
        print(f"survived: {name}")
    print(
        f"{len(names)} mutants: {counts['killed']} killed, {counts['survived']} survived"
        + "".join(f", {v} {k}" for k, v in counts.items() if k not in ("killed", "survived"))
        + f"; score {score:.1f} %"
    )
    return 0


#: The tests run on a plausible mutant of each package (its own tests and those of the
#: layers that exercise it most directly); any other package: ``tests/<last name>``.
PLAUSIBLE_TESTS = {
    "pkmkit.spatial": ["tests/spatial", "tests/machines/test_full_pose.py",
                       "tests/calibration/test_registration.py"],
    "pkmkit.exceptions": ["tests/test_exceptions.py", "tests/calibration/test_identifiability.py"],
    "pkmkit.calibration": ["tests/calibration"],
    "pkmkit.model": ["tests/model", "tests/machines/test_chain_files.py",
                     "tests/machines/test_tripteor.py", "tests/machines/test_trimule.py"],
}


#: ``--tests-for cli``: the test files that run each command module's code (the whole of
#: ``tests/cli`` takes longer than the time limit per mutant on a loaded 2-core machine).
TESTS_FOR = {
    "cli": {
        "analysis_cmds.py": ["tests/cli/test_analysis_cli.py",
                             "tests/cli/test_workspace_families_cli.py"],
        "grid_options.py": ["tests/cli/test_analysis_cli.py",
                            "tests/cli/test_workspace_families_cli.py"],
        "calibration_cmds.py": ["tests/cli/test_calibration_cli.py",
                                "tests/cli/test_calibration_verdict_cli.py",
                                "tests/cli/test_calibration_tolerance_units.py",
                                "tests/cli/test_simulate_tool_lengths_units.py"],
        "compensate_cmd.py": ["tests/cli/test_calibration_cli.py",
                              "tests/cli/test_compensate_gravity.py",
                              "tests/cli/test_outputs_in_mm_and_m.py",
                              "tests/cli/test_compensate_rotary_stroke.py"],
        "register_cmd.py": ["tests/cli/test_calibration_cli.py",
                            "tests/cli/test_calibration_verdict_cli.py",
                            "tests/cli/test_register_directions_both_files.py"],
        "design_cmds.py": ["tests/cli/test_design_cli.py",
                           "tests/cli/test_design_machine_file.py",
                           "tests/cli/test_units_of_sizing_and_origin.py"],
        "errors_cmds.py": ["tests/cli/test_errors_cli.py", "tests/cli/test_error_units.py",
                           "tests/cli/test_errors_sensitivity_degrees.py"],
        "ik_cmd.py": ["tests/cli/test_cli.py", "tests/cli/test_ik_one_path.py",
                      "tests/cli/test_batch.py", "tests/cli/test_batch_units.py",
                      "tests/cli/test_ik_chain_tool_axis.py",
                      "tests/cli/test_units_invariance_path_ik.py"],
        "machining_cmds.py": ["tests/cli/test_machining_cmds.py",
                              "tests/cli/test_outputs_in_mm_and_m.py",
                              "tests/cli/test_units_of_sizing_and_origin.py"],
        "main.py": ["tests/cli/test_cli.py", "tests/cli/test_strokes_cli.py"],
        "motion_cmds.py": ["tests/cli/test_motion_cli.py", "tests/cli/test_limits.py",
                           "tests/cli/test_units_invariance_path_ik.py"],
        "pose_cmds.py": ["tests/cli/test_cli.py", "tests/cli/test_chain_cli.py",
                         "tests/cli/test_fk_full_pose_text.py",
                         "tests/cli/test_jacobian_chain_pose.py"],
        "stiffness_cmds.py": ["tests/cli/test_stiffness_cli.py",
                              "tests/cli/test_stiffness_text_units.py"],
        "stiffness_options.py": ["tests/cli/test_stiffness_cli.py",
                                 "tests/cli/test_stiffness_text_units.py"],
        "unit_text.py": ["tests/cli/test_cli.py", "tests/cli/test_batch_units.py",
                         "tests/cli/test_error_units.py"],
    },
}


#: Packages whose mutants each run the test files that call the function they change (a map
#: derived by one traced run of the package's tests: ``tools/mutant_tests.py``); any module no
#: test calls falls back to the package's tests. ``--tests-for`` or ``--tests`` override it.
BY_CALLS = ("pkmkit.machines",)


def _tests_for(name: str | None) -> dict[str, list[str]] | None:
    if name is None:
        return None
    return TESTS_FOR[name]


def _plausible(args) -> int:
    sys.path.insert(0, str(ROOT / "tools"))
    import plausible_mutants

    tests = args.tests or PLAUSIBLE_TESTS.get(
        args.target, [f"tests/{args.target.split('.')[-1]}"])
    # pytest's exit status 4 (a path not found) would count every mutant as killed
    paths = [*tests, *(p for ps in (_tests_for(args.tests_for) or {}).values() for p in ps)]
    missing = sorted({p for p in paths if not (ROOT / p.split("::")[0]).exists()})
    if missing and not args.report:
        print(f"test paths not found: {', '.join(missing)}", file=sys.stderr)
        return 2
    operators = tuple(args.operators.split(",")) if args.operators \
        else plausible_mutants.OPERATORS
    if args.report:
        for row in plausible_mutants.report(Path(args.results)):
            for line in row.pop("survivors"):
                print(f"survived: {line}")
            print(row)
        return 0
    if args.list:
        every = [m for m in plausible_mutants.mutants_of_package(args.target)
                 if m.operator in operators]
        for m in plausible_mutants.stratified_sample(every, args.sample, args.seed):
            print(f"{m.name}  {m.original!r} -> {m.replacement!r}")
        return 0
    plausible_mutants.run(args.target, tests, sample=args.sample, seed=args.seed,
                          operators=operators, timeout=args.timeout,
                          workdir=Path(args.workdir), results=Path(args.results),
                          again=args.survivors, resume=args.resume,
                          tests_for=_tests_for(args.tests_for), markers=args.markers,
                          by_calls=args.by_calls if args.by_calls is not None else (
                              not args.tests and not args.tests_for
                              and args.target.startswith(BY_CALLS)))
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("target", help="package or module, e.g. pkmkit.motion.gcode")
    parser.add_argument("--sample", type=int, default=0, help="random mutants to run (0: all)")
    parser.add_argument("--seed", type=int, default=15, help="seed of the random sample")
    parser.add_argument("--jobs", type=int, default=1, help="mutants tested in parallel")
    parser.add_argument("--report", action="store_true", help="only report the last results")
    parser.add_argument("--survivors", action="store_true",
                        help="re-run only the mutants of the sample that survived last time")
    parser.add_argument("--tests-for", choices=sorted(TESTS_FOR),
                        help="(--plausible) per source file, the tests of TESTS_FOR (others: "
                             "--tests or the default)")
    parser.add_argument("--by-calls", action=argparse.BooleanOptionalAction, default=None,
                        help="(--plausible) each mutant runs the tests that call its function "
                             "(tools/mutant_tests.py; default for BY_CALLS packages)")
    parser.add_argument("--resume", action="store_true",
                        help="(--plausible) skip the sample's mutants --results already has")
    parser.add_argument("--plausible", action="store_true",
                        help="plant the plausible one-line bugs of tools/plausible_mutants.py")
    parser.add_argument("--tests", nargs="*", help="(--plausible) test paths to run")
    parser.add_argument("--markers", default="not slow",
                        help="(--plausible) pytest -m selection; 'not slow and not ci' for the "
                             "ordinary run alone")
    parser.add_argument("--operators", help="(--plausible) comma-separated operators")
    parser.add_argument("--list", action="store_true",
                        help="(--plausible) list the sample's mutants, run nothing")
    parser.add_argument("--timeout", type=float, default=600.0,
                        help="(--plausible) seconds per mutant")
    parser.add_argument("--workdir", default="/tmp/pkmkit-plausible",
                        help="(--plausible) where the mutated copy of src/ is written")
    parser.add_argument("--results", default="mutants/plausible.jsonl",
                        help="(--plausible) JSON-lines file the outcomes are appended to")
    args = parser.parse_args(argv)
    if args.plausible:
        return _plausible(args)

    _generate()
    codes = _mutants_of(args.target)
    if not codes:
        print(f"no mutant found for {args.target!r}", file=sys.stderr)
        return 2
    names = sorted(codes)
    if args.sample and args.sample < len(names):
        names = sorted(random.Random(args.seed).sample(names, args.sample))
    print(f"{args.target}: {len(codes)} mutants, testing {len(names)}")
    todo = names
    if args.survivors:
        equivalent = _equivalent()
        todo = [n for n in names if codes.get(n) in SURVIVED and n not in equivalent]
        print(f"re-running {len(todo)} survivors")
    if not args.report and todo:
        subprocess.run(
            [sys.executable, "-m", "mutmut", "run", "--max-children", str(args.jobs), *todo],
            cwd=ROOT,
            check=False,
        )
        codes = _mutants_of(args.target)
    return _report(names, codes)


if __name__ == "__main__":
    raise SystemExit(main())
