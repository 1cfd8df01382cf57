"""Writes ``src/pkmkit/native/shortest_table.h``: the powers of ten of the shortest-digits
formatter (``native/csv_text.c``, a Schubfach-style algorithm: R. Giulietti, "The Schubfach way
to render doubles", 2021), computed here with exact integers.

For each decimal exponent k with K_MIN ≤ k ≤ K_MAX (those of every finite double's
``k = floor(log10(2^q))`` or ``floor(log10(3/4 · 2^q))``), ``10^-k = β · 2^r`` with
``2^125 ≤ β < 2^126``, and ``g = floor(β) + 1`` is stored as ``g1 = g >> 63``,
``g0 = g mod 2^63``, so ``(g − 1) 2^r ≤ 10^-k < g 2^r``. The C file's integer logarithms
(``flog10pow2`` and friends) are checked here against exact ones over every q they meet.

Usage: ``python tools/shortest_table.py`` (rewrites the header; ``--check`` only compares).
"""

from __future__ import annotations

import sys
from fractions import Fraction
from pathlib import Path

Q_MIN, Q_MAX = -1074, 971  # a finite double is c · 2^q, c < 2^53, with q in this range
HEADER = Path(__file__).resolve().parents[1] / "src/pkmkit/native/shortest_table.h"


def flog10pow2(q: int) -> int:
    return (q * 661_971_961_083) >> 41


def flog10three_quarters_pow2(q: int) -> int:
    return (q * 661_971_961_083 - 274_743_187_321) >> 41


def flog2pow10(e: int) -> int:
    return (e * 913_124_641_741) >> 38


def exact_floor_log(x: Fraction, base: int) -> int:
    """floor(log_base(x)) for a rational x > 0, by exact comparisons."""
    k = 0
    while x >= base:
        x /= base
        k += 1
    while x < 1:
        x *= base
        k -= 1
    return k


def check_logarithms() -> None:
    for q in range(Q_MIN, Q_MAX + 1):
        two = Fraction(2) ** q
        assert flog10pow2(q) == exact_floor_log(two, 10), q
        assert flog10three_quarters_pow2(q) == exact_floor_log(Fraction(3, 4) * two, 10), q
    for e in range(-flog10pow2(Q_MAX) - 1, -flog10three_quarters_pow2(Q_MIN) + 2):
        assert flog2pow10(e) == exact_floor_log(Fraction(10) ** e, 2), e


def table() -> tuple[int, int, list[tuple[int, int]]]:
    k_min = min(flog10pow2(Q_MIN), flog10three_quarters_pow2(Q_MIN))
    k_max = max(flog10pow2(Q_MAX), flog10three_quarters_pow2(Q_MAX))
    rows = []
    for k in range(k_min, k_max + 1):
        r = flog2pow10(-k) - 125
        beta = Fraction(10) ** -k / Fraction(2) ** r
        assert 2**125 <= beta < 2**126, k
        g = beta.numerator // beta.denominator + 1
        rows.append((g >> 63, g & ((1 << 63) - 1)))
    return k_min, k_max, rows


def text() -> str:
    k_min, k_max, rows = table()
    lines = ["/* shortest_table.h: written by tools/shortest_table.py (do not edit):",
             " * g = g1 2^63 + g0 = floor(10^-k 2^-r) + 1 with 2^125 <= g < 2^126,",
             " * for k = PK_K_MIN .. PK_K_MAX. */",
             f"#define PK_K_MIN ({k_min})", f"#define PK_K_MAX ({k_max})",
             "static const uint64_t pk_g[][2] = {"]
    lines += [f"    {{0x{g1:016x}u, 0x{g0:016x}u}}, /* k = {k} */"
              for k, (g1, g0) in zip(range(k_min, k_max + 1), rows, strict=True)]
    lines.append("};")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    check_logarithms()
    if "--check" in sys.argv[1:]:
        sys.exit(0 if HEADER.read_text() == text() else "shortest_table.h differs: rerun")
    HEADER.write_text(text())
