"""Extract the runnable blocks of the Markdown documentation and compare what they print.

A ``console`` block holds commands (``$ ...``, continued by a trailing ``\\``) each followed by
the output it shows; a ``python`` block is a program, or a session when it starts with ``>>>``
(statements after ``>>>``, continued by ``...``, each followed by what it prints or the value it
shows, as in the interpreter). A block may be preceded by a marker comment
``<!-- docs-test: ... -->`` with any of:

- ``skip (reason)``: not run;
- ``ci``: a long example, with the pytest marker ``ci``: the ordinary run leaves it out,
  ``.ci/run`` runs it;
- ``any-numbers``: the numbers printed are not compared (timings);
- ``command="..."``: a ``text`` block is the output of this command;
- ``output``: a ``text`` block is what the ``python`` program right above it prints;
- ``fresh``: run in a new process even where the fork server could run it (a block that
  measures its own start-up or imports, see ``fork_server``).

Shown output is compared line by line: numbers to their printed precision (one unit in the
last digit shown), everything else exactly (runs of spaces as one); a line ``...`` stands for
any number of omitted lines and ``...`` inside a line for omitted text; an annotation after
two spaces and ``# `` at the end of a line is the documentation's, not the program's. A command
whose shown output starts with ``Error:`` must fail (exit status 1); the others must succeed
(exit status 0, or 3: flagged rows or exceeded limits, which the output then shows). A command
shown without output is run and its exit status checked.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_NUMBER_RE = re.compile(NUMBER)
_MARKER = re.compile(r"<!--\s*docs-test:\s*(.*?)\s*-->")
_ANNOTATION = re.compile(r"\s{2,}#\s.*$")


@dataclass
class Command:
    text: str
    expected: list[str]
    line: int


@dataclass
class Block:
    path: Path
    line: int
    lang: str
    body: list[str]
    options: dict[str, str] = field(default_factory=dict)
    shown: list[str] = field(default_factory=list)  # a program's output (an ``output`` block)

    @property
    def name(self) -> str:
        return f"{self.path.name}:{self.line}"

    def commands(self) -> list[Command]:
        """The commands of a console block (or the ``command=`` of a text block)."""
        if self.lang == "text":
            return [Command(self.options["command"], self.body, self.line)]
        out: list[Command] = []
        lines = iter(enumerate(self.body, start=self.line + 1))
        for number, raw in lines:
            if raw.startswith("$ "):
                text = raw[2:]
                while text.endswith("\\"):
                    text = text[:-1] + " " + next(lines)[1].strip()
                out.append(Command(text, [], number))
            elif out:
                out[-1].expected.append(raw)
            elif raw.strip():
                raise ValueError(f"{self.name}: output before any command: {raw!r}")
        for command in out:  # a blank line between a command's output and the next command
            while command.expected and not command.expected[-1].strip():
                command.expected.pop()
        return out

    def program(self) -> tuple[str, list[str]]:
        """A ``python`` block's program and the output it shows (a session's is run statement by
        statement, each expression's value shown as the interpreter shows it)."""
        if not self.body or not self.body[0].startswith(">>>"):
            return "\n".join(self.body), self.shown
        statements: list[str] = []
        expected: list[str] = []
        continuing = False
        for raw in self.body:
            if raw.startswith(">>> ") or raw == ">>>":
                statements.append(raw[4:] + "\n")
                continuing = True
            elif continuing and (raw.startswith("... ") or raw == "..."):
                statements[-1] += raw[4:] + "\n"
            else:
                continuing = False
                expected.append(raw)
        return _SESSION.format(statements=statements), expected


_SESSION = """_namespace = {{"__name__": "__main__"}}
for _statement in {statements!r}:
    exec(compile(_statement, "<session>", "single"), _namespace)
"""


def blocks(path: Path) -> list[Block]:
    """The ``console``, ``python`` and (with a ``command=`` marker) ``text`` blocks of a file."""
    found: list[Block] = []
    lines = path.read_text(encoding="utf-8").splitlines()
    k = 0
    while k < len(lines):
        fence = re.match(r"^```(\w*)\s*$", lines[k])
        if not fence:
            k += 1
            continue
        lang, start = fence.group(1), k
        k += 1
        body = []
        while k < len(lines) and not lines[k].startswith("```"):
            body.append(lines[k])
            k += 1
        k += 1
        options = _options(lines, start)
        if lang == "text" and "output" in options:
            if not found or found[-1].lang != "python" or found[-1].shown:
                raise ValueError(f"{path.name}:{start + 1}: an output block must follow a "
                                 "python program")
            found[-1].shown = body
        elif lang in ("console", "python") or (lang == "text" and "command" in options):
            found.append(Block(path, start + 1, lang, body, options))
    return found


def _options(lines: list[str], fence: int) -> dict[str, str]:
    """Options of the marker comments right above a fence (blank lines allowed)."""
    options: dict[str, str] = {}
    k = fence - 1
    while k >= 0 and (not lines[k].strip() or _MARKER.search(lines[k])):
        match = _MARKER.search(lines[k])
        if match:
            text = match.group(1)
            command = re.search(r'command="([^"]*)"', text)
            if command:
                options["command"] = command.group(1)
                text = text.replace(command.group(0), "")
            skip = re.search(r"skip\s*\((.*)\)", text)
            if skip:
                options["skip"] = skip.group(1)
                text = text.replace(skip.group(0), "")
            for word in re.split(r"[\s,]+", text):
                if word:
                    options[word] = "yes"
        elif lines[k].strip():
            break
        k -= 1
    return options


def line_patterns(expected: list[str]) -> list[tuple[re.Pattern, list[str]] | None]:
    """One pattern per shown line (None for a ``...`` line: any number of omitted lines), each
    with the number texts it captures, in order."""
    out: list[tuple[re.Pattern, list[str]] | None] = []
    for raw in expected:
        line = _ANNOTATION.sub("", raw.rstrip())
        if line.strip() == "...":
            out.append(None)
            continue
        pieces = []
        numbers: list[str] = []
        position = 0
        for match in re.finditer(NUMBER + r"|\.\.\.|\s+", line):
            pieces.append(re.escape(line[position:match.start()]))
            token = match.group(0)
            if token == "...":
                pieces.append(r".*?")
            elif token.isspace():
                pieces.append(r"[ \t]+" if match.start() > 0 else r"[ \t]*")
            else:
                pieces.append(f"({NUMBER}|nan|inf|-inf)")
                numbers.append(token)
            position = match.end()
        pieces.append(re.escape(line[position:]))
        out.append((re.compile("".join(pieces) + r"[ \t]*"), numbers))
    return out


def match_lines(patterns: list[tuple[re.Pattern, list[str]] | None], lines: list[str]
                ) -> list[tuple[list[str], tuple[str, ...]]] | None:
    """Align the shown lines with the actual ones: ``[(number texts, captured texts)]`` of the
    matched lines in order, or None. A table over (shown line, actual line) — linear in the
    product of the two lengths, never the exponential backtracking of one regex over the whole
    output; a ``...`` line takes as few lines as it can (as a lazy regex would)."""
    e, a = len(patterns), len(lines)
    hits: dict[tuple[int, int], re.Match | None] = {}

    def hit(i: int, j: int) -> re.Match | None:
        if (i, j) not in hits:
            hits[(i, j)] = patterns[i][0].fullmatch(lines[j])
        return hits[(i, j)]

    ok = [[False] * (a + 1) for _ in range(e + 1)]
    ok[e][a] = True
    for i in range(e - 1, -1, -1):
        for j in range(a, -1, -1):
            if patterns[i] is None:
                ok[i][j] = ok[i + 1][j] or (j < a and ok[i][j + 1])
            else:
                ok[i][j] = j < a and ok[i + 1][j + 1] and hit(i, j) is not None
    if not ok[0][0]:
        return None
    found, i, j = [], 0, 0
    while i < e:
        if patterns[i] is None:
            if ok[i + 1][j]:
                i += 1
            else:
                j += 1
            continue
        found.append((patterns[i][1], hit(i, j).groups()))
        i, j = i + 1, j + 1
    return found


def last_digit_unit(text: str) -> float:
    """Value of one unit in the last digit of a printed number."""
    mantissa, _, exponent = text.lower().partition("e")
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 10.0 ** (int(exponent or 0) - decimals)


def compare(expected: list[str], actual: str, *, numbers: bool = True) -> str | None:
    """None if ``actual`` shows ``expected`` (see the module docstring), else why not."""
    lines = [line.rstrip() for line in actual.replace("\r\n", "\n").split("\n")]
    while lines and not lines[-1]:
        lines.pop()
    text = "\n".join(lines) + "\n"
    found = match_lines(line_patterns(expected), lines)
    if found is None:
        return ("the output does not have the shown form\n--- shown:\n" + "\n".join(expected)
                + "\n--- actual:\n" + text)
    if not numbers:
        return None
    for texts, groups in found:
        for shown, got in zip(texts, groups, strict=True):
            value = float(got)
            want = float(shown)
            if math.isnan(value) or abs(value - want) > 1.0001 * last_digit_unit(shown):
                return (f"number {shown} is now {got}\n--- shown:\n" + "\n".join(expected)
                        + "\n--- actual:\n" + text)
    return None
