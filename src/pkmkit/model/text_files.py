"""Reading the text files pkmkit accepts (machine, masses, G-code): text only, bounded nesting,
numbers that fit a double.

Every reader goes through :func:`read_text` (a binary file gets "not a text file", a file that
is not UTF-8 names the line) and checks its numbers with :func:`number_problem` (a value that
overflows to infinity, or a non-zero value that underflows to 0, names its line), so a typo like
``1e400`` or ``1e-400`` never reaches a computation.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path

#: Deepest nesting of arrays/tables accepted in TOML and YAML files (the parsers recurse).
MAX_NESTING = 32

#: Largest text file read (bytes): machine, masses and G-code files are small.
MAX_TEXT_BYTES = 256 * 1024 * 1024

_NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d[\d_]*\.?[\d_]*|\.\d[\d_]*)(?:[eE][-+]?\d+)?(?![\w.])")


def read_text(path: str | Path, error: Callable[[str, int | None], Exception],
              *, strip_bom: bool = True) -> str:
    """The UTF-8 text of ``path``.

    ``error(message, line)`` builds the exception raised for: an unreadable file, a file larger
    than :data:`MAX_TEXT_BYTES`, a binary file (NUL bytes: "not a text file"), or bytes that are
    not UTF-8 (with the line).
    """
    p = Path(path)
    try:
        size = p.stat().st_size
        if size > MAX_TEXT_BYTES:
            raise error(f"file of {size / 2**20:.0f} MiB, above the {MAX_TEXT_BYTES / 2**20:.0f} "
                        "MiB accepted for a text file", None)
        data = p.read_bytes()
    except OSError as exc:
        raise error(f"cannot read file: {exc.strerror or exc}", None) from None
    if b"\x00" in data:
        line = data[:data.index(b"\x00")].count(b"\n") + 1
        raise error("not a text file (it holds NUL bytes: binary data?)", line)
    if strip_bom and data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise error(f"not a UTF-8 text file (byte 0x{data[exc.start]:02x})", line) from None


def toml_nesting(text: str) -> tuple[int, int]:
    """Deepest ``[``/``{`` nesting of TOML ``text`` outside strings and comments, and its line
    (tomllib recurses once per level: a pathological depth would overflow the stack)."""
    depth = deepest = 0
    line = deepest_line = 1
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch == "\n":
            line += 1
        elif ch == "#":
            end = text.find("\n", i)
            i = n if end < 0 else end
            continue
        elif ch in "\"'":
            quote = ch * 3 if text.startswith(ch * 3, i) else ch
            j = i + len(quote)
            while j < n and not text.startswith(quote, j):
                if text[j] == "\\" and ch == '"':
                    j += 1
                elif text[j] == "\n":
                    if len(quote) == 1:
                        break
                    line += 1
                j += 1
            i = j + len(quote)
            continue
        elif ch in "[{":
            depth += 1
            if depth > deepest:
                deepest, deepest_line = depth, line
        elif ch in "]}":
            depth = max(depth - 1, 0)
        i += 1
    return deepest, deepest_line


def number_problem(text: str) -> str | None:
    """What is wrong with the numbers written in ``text`` (one line of a file), or None: a
    number that overflows a double (``1e400``) or a non-zero one that underflows to 0
    (``1e-400``)."""
    for token in _NUMBER.findall(text):
        try:
            value = float(token.replace("_", ""))
        except ValueError:
            continue
        shown = token if len(token) <= 24 else f"{token[:12]}… ({len(token)} characters)"
        if math.isinf(value):
            return f"{shown} overflows a double (largest: 1.8e308)"
        if value == 0.0 and re.search(r"[1-9]", token.split("e")[0].split("E")[0]):
            return f"{shown} underflows to 0 (smallest: 4.9e-324)"
    return None
