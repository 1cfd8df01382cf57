"""Plausible one-line bugs: mutation operators that model the mistakes people make in geometric
code, and a runner that plants each one and runs the ordinary tests.

mutmut's operators change operators and constants (``+`` → ``-``, ``1`` → ``2``); the suite kills
96–100 % of those. The bugs that reach users are of another kind (issue 18 §9): a rotation
composed in the wrong order, a transpose, a cross product reversed, a unit factor dropped, a
scale applied to the wrong half of a vector, an index shifted. The operators here plant exactly
those, one at a time, on a copy of ``src/`` (the working tree is never touched):

- ``matmul-swap``: ``a @ b`` → ``b @ a``;
- ``mul-swap``: ``a * b`` → ``b * a`` where an operand looks like a rotation (its text names
  ``rot``/``R``/``inv()``/``Rotation``: scipy rotations compose with ``*``);
- ``cross-swap``: ``np.cross(a, b)`` → ``np.cross(b, a)``;
- ``transpose``: the left operand of ``@`` transposed (``np.swapaxes(a, -1, -2)``), an
  existing transpose dropped (``a.T`` → ``a``, ``np.swapaxes(a, -1, -2)`` → ``a``), a scipy
  rotation's inverse dropped (``r.inv()`` → ``r``), and a batched matrix transposed inside
  ``np.einsum`` (its last two subscripts swapped: ``"kij,kj->ki"`` → ``"kji,kj->ki"``);
- ``factor-drop`` / ``factor-invert``: in ``a * f`` or ``a / f`` where f is a unit or scale
  factor (a literal 1000, 1e-3, 1e6, 1e-6, 180, π, or a name with ``scale``, ``factor``,
  ``unit``, ``length``, ``big_l``, ``per_``): the factor dropped, or ``*`` ↔ ``/``; an angle
  conversion (``np.deg2rad``, ``np.radians``, …) dropped, or turned the other way;
- ``half-swap``: ``x[..., :3]`` ↔ ``x[..., 3:]`` (the wrong half of a 6-vector);
- ``index-shift``: a slice with literal bounds shifted by one (``[1:4]`` → ``[2:5]``), or a
  literal index ``[k]`` → ``[k + 1]`` on the last axis of a small vector (k in 0..4).

A mutant is **killed** when the tests fail (or time out: counted apart), **survives** when they
pass. Mutants are drawn with ``random.Random(seed)`` from the sorted list, so the same command
plants the same ones. Docstrings, ``raise``/``warnings.warn`` statements and type annotations
are left alone.
"""

from __future__ import annotations

import ast
import json
import os
import random
import re
import shutil
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OPERATORS = ("matmul-swap", "mul-swap", "cross-swap", "transpose", "factor-drop",
             "factor-invert", "half-swap", "index-shift")
_ROTATION_TEXT = re.compile(r"((?i:rot|inv\(\)|quat)|\bR\b|\bR_)")
#: An operand that is certainly a scipy Rotation or RigidTransform (composed with ``*``).
_ROTATION_OBJECT = re.compile(r"(\.inv\(\)|from_rotvec|from_matrix|from_quat|from_euler"
                              r"|to_transform\(|from_components)")
_FACTOR_NAME = re.compile(r"(scale|factor|unit|length|big_l|per_|_to_m|to_si|MM|DEG)",
                          re.IGNORECASE)
#: Indexing that locates things rather than computing (shapes, positions of bad rows, text).
_BOOKKEEPING = re.compile(r"(\.shape$|nonzero|argwhere|where\(|argv|text$|name|split\()")
_FACTOR_VALUES = {1000.0, 1e-3, 1e6, 1e-6, 180.0, 3.141592653589793, 57.29577951308232,
                  0.017453292519943295}


@dataclass(frozen=True)
class Mutant:
    """One planted change: ``path`` (relative to the repository), line, column span of the
    replaced text on that line, and the replacement."""

    path: str
    line: int
    col: int
    end_col: int
    replacement: str
    operator: str
    original: str

    @property
    def name(self) -> str:
        return f"{self.path}:{self.line}:{self.col}:{self.operator}"


def _chars(line: str, byte_col: int) -> int:
    """Character column of a UTF-8 byte column (ast's offsets are in bytes)."""
    return len(line.encode()[:byte_col].decode())


def _span(lines: list[str], node: ast.AST) -> tuple[int, int]:
    line = lines[node.lineno - 1]
    return _chars(line, node.col_offset), _chars(line, node.end_col_offset)


def _text(lines: list[str], node: ast.AST) -> str | None:
    if node.lineno != node.end_lineno:
        return None
    col, end = _span(lines, node)
    return lines[node.lineno - 1][col:end]


def _wrap(text: str, node: ast.AST) -> str:
    """The operand's text, parenthesised unless it is atomic."""
    atomic = ast.Name | ast.Attribute | ast.Call | ast.Subscript | ast.Constant
    return text if isinstance(node, atomic) else f"({text})"


def _is_factor(node: ast.AST, text: str) -> bool:
    if isinstance(node, ast.Constant) and isinstance(node.value, int | float) \
            and not isinstance(node.value, bool):
        return float(node.value) in _FACTOR_VALUES
    if isinstance(node, ast.Attribute) and node.attr == "pi":
        return True
    return bool(_FACTOR_NAME.search(text)) and isinstance(node, ast.Name | ast.Attribute)


def _skipped_lines(tree: ast.AST) -> set[int]:
    """Lines of docstrings, raise statements, warnings and annotations (not mutated)."""
    out: set[int] = set()
    for node in ast.walk(tree):
        spans = []
        if isinstance(node, ast.Raise):
            spans.append(node)
        elif isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
            spans.append(node)
        elif isinstance(node, ast.Call) and ast.unparse(node.func).endswith("warn"):
            spans.append(node)
        elif isinstance(node, ast.arg) and node.annotation is not None:
            spans.append(node.annotation)
        elif isinstance(node, ast.FunctionDef) and node.returns is not None:
            spans.append(node.returns)
        for s in spans:
            out.update(range(s.lineno, s.end_lineno + 1))
    return out


#: Angle conversions (a unit factor written as a call): dropped, or turned the other way.
_UNIT_CALLS = {"deg2rad": "rad2deg", "rad2deg": "deg2rad", "radians": "degrees",
               "degrees": "radians"}


def _einsum_transposed(spec: str) -> list[str]:
    """The subscripts of ``np.einsum`` with one batched-matrix operand transposed (its last two
    letters swapped), one spec per such operand (``"kij,kj->ki"`` → ``"kji,kj->ki"``)."""
    inputs, arrow, output = spec.partition("->")
    terms = inputs.split(",")
    out = []
    for i, term in enumerate(terms):
        letters = term.replace("...", "").strip()
        if (len(letters) >= 3 or (term.startswith("...") and len(letters) >= 2)) \
                and letters[-1] != letters[-2] and term.endswith(letters[-2:]):
            swapped = term[:-2] + term[-1] + term[-2]
            out.append(",".join([*terms[:i], swapped, *terms[i + 1:]]) + arrow + output)
    return out


def _slice_bounds(node: ast.AST) -> ast.Slice | None:
    """The last-axis slice of a subscript (``x[..., a:b]`` or ``x[a:b]``)."""
    sl = node.slice
    if isinstance(sl, ast.Tuple) and sl.elts:
        sl = sl.elts[-1]
    return sl if isinstance(sl, ast.Slice) else None


def _int(node: ast.AST | None) -> int | None:
    if isinstance(node, ast.Constant) and type(node.value) is int:
        return node.value
    return None


def mutants_of_file(path: Path) -> list[Mutant]:
    """Every plausible mutant of one source file."""
    rel = str(path.relative_to(ROOT))
    source = _original(rel)
    lines = source.splitlines()
    tree = ast.parse(source)
    skip = _skipped_lines(tree)
    out: list[Mutant] = []

    def add(node, replacement, operator):
        text = _text(lines, node)
        if text is None or node.lineno in skip or replacement == text:
            return
        col, end = _span(lines, node)
        out.append(Mutant(rel, node.lineno, col, end, replacement, operator, text))

    for node in ast.walk(tree):
        if isinstance(node, ast.BinOp) and node.lineno == node.end_lineno:
            left, right = _text(lines, node.left), _text(lines, node.right)
            if left is None or right is None:
                continue
            lw, rw = _wrap(left, node.left), _wrap(right, node.right)
            if isinstance(node.op, ast.MatMult):
                add(node, f"{rw} @ {lw}", "matmul-swap")
                add(node, f"np.swapaxes({left}, -1, -2) @ {rw}", "transpose")
            if isinstance(node.op, ast.Mult) and (
                    (_ROTATION_TEXT.search(left) and _ROTATION_TEXT.search(right))
                    or _ROTATION_OBJECT.search(left + " " + right)):
                add(node, f"{rw} * {lw}", "mul-swap")
            if isinstance(node.op, ast.Mult | ast.Div):
                sym = "*" if isinstance(node.op, ast.Mult) else "/"
                inv = "/" if sym == "*" else "*"
                if _is_factor(node.right, right):
                    add(node, lw, "factor-drop")
                    add(node, f"{lw} {inv} {rw}", "factor-invert")
                elif sym == "*" and _is_factor(node.left, left):
                    add(node, rw, "factor-drop")
                    add(node, f"{rw} / {lw}", "factor-invert")
        elif isinstance(node, ast.Call) and node.lineno == node.end_lineno:
            func = ast.unparse(node.func)
            args = [_text(lines, a) for a in node.args]
            if None in args:
                continue
            if func.endswith("cross") and len(args) >= 2:
                rest = ", ".join(args[2:] + [_text(lines, k) or "" for k in node.keywords])
                add(node, f"{func}({args[1]}, {args[0]}{', ' + rest if rest else ''})",
                    "cross-swap")
            if func.endswith("swapaxes") and len(args) == 3 and args[1:] == ["-1", "-2"]:
                add(node, args[0], "transpose")
            if func.endswith("transpose") and len(args) == 1:
                add(node, args[0], "transpose")
            if func.endswith("einsum") and args and isinstance(node.args[0], ast.Constant) \
                    and isinstance(node.args[0].value, str):
                call = _text(lines, node)
                for spec in _einsum_transposed(node.args[0].value):
                    add(node, call.replace(args[0], args[0][0] + spec + args[0][-1], 1),
                        "transpose")
            name = func.rsplit(".", 1)[-1]
            if name in _UNIT_CALLS and len(args) == 1 and not node.keywords:
                add(node, args[0], "factor-drop")
                add(node, f"{func[:len(func) - len(name)]}{_UNIT_CALLS[name]}({args[0]})",
                    "factor-invert")
            if isinstance(node.func, ast.Attribute) and node.func.attr == "inv" \
                    and not args and not node.keywords:
                inner = _text(lines, node.func.value)
                if inner is not None:
                    add(node, inner, "transpose")
        elif isinstance(node, ast.Attribute) and node.attr == "T" \
                and node.lineno == node.end_lineno:
            inner = _text(lines, node.value)
            if inner is not None:
                add(node, inner, "transpose")
        elif isinstance(node, ast.Subscript) and node.lineno == node.end_lineno:
            text = _text(lines, node)
            base = _text(lines, node.value)
            if text is None or base is None:
                continue
            inner = text[len(base) + 1:-1]
            sl = _slice_bounds(node)
            if sl is not None and sl.step is None:
                lo, hi = _int(sl.lower), _int(sl.upper)
                sl_text = _text(lines, sl)
                if sl_text is None:
                    continue
                head = inner[:len(inner) - len(sl_text)]
                if not inner.endswith(sl_text):
                    continue
                if sl.lower is None and hi == 3:
                    add(node, f"{base}[{head}3:]", "half-swap")
                elif lo == 3 and sl.upper is None:
                    add(node, f"{base}[{head}:3]", "half-swap")
                if lo is not None and lo >= 0 and (hi is None or hi >= 0) \
                        and (lo, hi) not in ((0, None),):
                    new = f"{lo + 1}:{'' if hi is None else hi + 1}"
                    add(node, f"{base}[{head}{new}]", "index-shift")
            else:
                idx = node.slice.elts[-1] if isinstance(node.slice, ast.Tuple) \
                    and node.slice.elts else node.slice
                k = _int(idx)
                if k is not None and 0 <= k <= 4 and isinstance(node.ctx, ast.Load) \
                        and not _BOOKKEEPING.search(base):
                    idx_text = _text(lines, idx)
                    if idx_text is not None and inner.endswith(idx_text):
                        add(node, f"{base}[{inner[:len(inner) - len(idx_text)]}{k + 1}]",
                            "index-shift")
    return sorted((m for m in out if _compiles(m, lines)),
                  key=lambda m: (m.path, m.line, m.col, m.operator, m.replacement))


def _compiles(mutant: Mutant, lines: list[str]) -> bool:
    """The mutated file is valid Python with a different syntax tree."""
    new = list(lines)
    line = new[mutant.line - 1]
    new[mutant.line - 1] = line[:mutant.col] + mutant.replacement + line[mutant.end_col:]
    try:
        return ast.dump(ast.parse("\n".join(new))) != ast.dump(ast.parse("\n".join(lines)))
    except SyntaxError:
        return False


def mutants_of_package(package: str) -> list[Mutant]:
    """Every plausible mutant of a package or module (``pkmkit.spatial``)."""
    rel = Path("src", *package.split("."))
    files = [ROOT / rel.with_suffix(".py")] if (ROOT / rel.with_suffix(".py")).exists() \
        else sorted((ROOT / rel).rglob("*.py"))
    return [m for f in files for m in mutants_of_file(f)]


def stratified_sample(mutants: list[Mutant], n: int, seed: int) -> list[Mutant]:
    """``n`` mutants (all when n is 0 or too large), drawn round-robin over the operators so
    that the rare kinds (a reversed cross product) are not drowned by the common ones (index
    shifts); within an operator, in the order of ``random.Random(seed)``."""
    if not n or n >= len(mutants):
        return list(mutants)
    rng = random.Random(seed)
    pools = {}
    for m in mutants:
        pools.setdefault(m.operator, []).append(m)
    for pool in pools.values():
        rng.shuffle(pool)
    chosen: list[Mutant] = []
    while len(chosen) < n:
        for op in sorted(pools):
            if pools[op] and len(chosen) < n:
                chosen.append(pools[op].pop())
    return sorted(chosen, key=lambda m: m.name)


#: The source each mutant was made from (read once: the working tree may change meanwhile).
_ORIGINAL: dict[str, str] = {}


def _original(path: str) -> str:
    if path not in _ORIGINAL:
        _ORIGINAL[path] = (ROOT / path).read_text()
    return _ORIGINAL[path]


def plant(mutant: Mutant, root: Path) -> None:
    """Write the mutated file under ``root`` (a copy of the repository's ``src``)."""
    path = root / mutant.path
    lines = _original(mutant.path).splitlines(keepends=True)
    line = lines[mutant.line - 1]
    assert line[mutant.col:mutant.end_col] == mutant.original, mutant
    lines[mutant.line - 1] = line[:mutant.col] + mutant.replacement + line[mutant.end_col:]
    path.write_text("".join(lines))


def restore(mutant: Mutant, root: Path) -> None:
    (root / mutant.path).write_text(_original(mutant.path))


def run(package: str, tests: list[str], *, sample: int, seed: int, operators: tuple[str, ...],
        timeout: float, workdir: Path, results: Path, again: bool = False,
        resume: bool = False, tests_for: dict[str, list[str]] | None = None,
        markers: str = "not slow", by_calls: bool = False) -> dict:
    """Plant a sample of mutants one at a time in a copy of ``src`` and run ``tests`` on each
    (``pytest -x -m "not slow"``: the ordinary suite and the heavy checks marked ``ci``, as
    mutmut's selection in pyproject.toml). Results are appended to ``results`` (JSON
    lines) and summarised. With ``again``, only the survivors recorded in ``results``; with
    ``resume``, the sample less the mutants ``results`` already has an outcome for (a run
    stopped by its time limit, continued). ``tests_for`` maps a source file name (``ik_cmd.py``)
    to the tests its mutants run instead of ``tests`` (a package whose whole test directory
    takes longer than the time limit per mutant, such as ``cli``). ``by_calls``: each mutant
    runs the test files that call the function it changes (``tools/mutant_tests.py``, derived
    by one run of ``tests`` first), else those that call its module, else ``tests``
    (a package such as ``machines``). ``markers`` is the
    ``-m`` selection: ``"not slow and not ci"`` measures the ordinary run alone (what is left
    when the heavy checks marked ``ci`` are not run)."""
    every = [m for m in mutants_of_package(package) if m.operator in operators]
    chosen = stratified_sample(every, sample, seed)
    if resume and results.exists():
        done = {(r["name"], r["replacement"]) for r in
                map(json.loads, results.read_text().splitlines())}
        chosen = [m for m in chosen if (m.name, m.replacement) not in done]
    if again:
        chosen = [m for m in survivors_again(results)
                  if m.path.startswith("src/" + package.replace(".", "/"))]
    if workdir.exists():
        shutil.rmtree(workdir)
    shutil.copytree(ROOT / "src", workdir / "src",
                    ignore=shutil.ignore_patterns("*.nbi", "*.nbc"))
    for path in {m.path for m in every}:  # the sources the mutants were made from
        (workdir / path).write_text(_original(path))
    counts = {"killed": 0, "survived": 0, "timeout": 0, "error": 0}
    print(f"{package}: {len(every)} plausible mutants, testing {len(chosen)}", flush=True)
    # the ordinary suite's examples (dev profile), without shrinking a failure
    env = {**os.environ, "PYTHONPATH": str(workdir / "src"), "HYPOTHESIS_PROFILE": "mutation"}
    test_map = None
    if by_calls and chosen:
        import mutant_tests

        test_map = mutant_tests.derive(package.split(".")[1], tests, markers=markers,
                                       pythonpath=workdir / "src", timeout=20 * timeout)
    for m in chosen:
        run_tests = (tests_for or {}).get(Path(m.path).name, tests)
        if test_map is not None:
            run_tests = test_map.tests_for(Path(m.path).name, _original(m.path), m.line) \
                or tests
        plant(m, workdir)
        start = time.monotonic()
        try:
            proc = subprocess.run(
                [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
                 "-m", markers, *run_tests],
                cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout)
            code = proc.returncode
            # 1: a test failed; 2–4: collection or a conftest failed (the mutant breaks an
            # import: the suite fails too); 5: no test collected (a wrong --tests)
            outcome = {0: "survived", 5: "error"}.get(code, "killed")
            failed = re.findall(r"^FAILED (\S+)", proc.stdout, re.MULTILINE)
        except subprocess.TimeoutExpired:
            outcome, failed, code = "timeout", [], None
        finally:
            restore(m, workdir)
        counts[outcome] += 1
        record = {**asdict(m), "name": m.name, "outcome": outcome, "failed": failed[:1],
                  "tests": len(run_tests),
                  "exit": code, "seconds": round(time.monotonic() - start, 1), "package": package}
        results.parent.mkdir(parents=True, exist_ok=True)
        with results.open("a") as fh:
            fh.write(json.dumps(record) + "\n")
        print(f"{outcome:8s} {m.name}  {m.original!r} -> {m.replacement!r}", flush=True)
    decided = counts["killed"] + counts["survived"]
    score = 100.0 * counts["killed"] / decided if decided else float("nan")
    print(f"{package}: {len(chosen)} mutants: {counts['killed']} killed, {counts['survived']} "
          f"survived, {counts['timeout']} timeouts, {counts['error']} errors; score "
          f"{score:.1f} %", flush=True)
    return {"package": package, "mutants": len(every), "tested": len(chosen), **counts,
            "score": score}


EQUIVALENT = ROOT / "tools" / "equivalent_plausible.txt"


def equivalent() -> dict[str, str]:
    """Mutant name → why it cannot change any result (``tools/equivalent_plausible.txt``)."""
    out = {}
    if EQUIVALENT.exists():
        for line in EQUIVALENT.read_text().splitlines():
            if line.strip() and not line.startswith("#"):
                name, _, reason = line.partition(" ")
                out[name] = reason.strip()
    return out


def report(results: Path) -> list[dict]:
    """Scores per package from a results file (the last outcome of each mutant wins);
    equivalent mutants are left out, timeouts count as killed."""
    last: dict[str, dict] = {}
    for line in results.read_text().splitlines():
        record = json.loads(line)
        last[record["name"] + record["replacement"]] = record
    eq = equivalent()
    rows = {}
    for r in last.values():
        row = rows.setdefault(r["package"], {"package": r["package"], "killed": 0,
                                             "survived": 0, "equivalent": 0, "timeout": 0,
                                             "error": 0, "survivors": []})
        if r["name"] in eq:
            row["equivalent"] += 1
        else:
            row[r["outcome"]] += 1
            if r["outcome"] == "survived":
                row["survivors"].append(f"{r['name']} {r['original']!r} -> "
                                        f"{r['replacement']!r}")
    for row in rows.values():
        decided = row["killed"] + row["timeout"] + row["survived"]
        row["score"] = 100.0 * (row["killed"] + row["timeout"]) / decided if decided \
            else float("nan")
    return sorted(rows.values(), key=lambda r: r["package"])


def survivors_again(results: Path) -> list[Mutant]:
    """The survivors of a results file as mutants of today's source (each found again by its
    text at the same column, on the nearest line: the lines may have moved since)."""
    out = []
    eq = equivalent()
    last: dict[str, dict] = {}
    for line in results.read_text().splitlines():
        record = json.loads(line)
        last[record["name"] + record["replacement"]] = record
    for r in last.values():
        if r["outcome"] != "survived" or r["name"] in eq:
            continue
        lines = _original(r["path"]).splitlines()
        hits = [i + 1 for i, text in enumerate(lines)
                if text[r["col"]:r["end_col"]] == r["original"]]
        if hits:
            line = min(hits, key=lambda i: abs(i - r["line"]))
            out.append(Mutant(r["path"], line, r["col"], r["end_col"], r["replacement"],
                              r["operator"], r["original"]))
    return out
