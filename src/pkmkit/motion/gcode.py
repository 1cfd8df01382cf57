"""A G-code reader for the usual milling subset.

Supported: ``G0`` (rapid), ``G1`` (line), ``G2``/``G3`` (clockwise / counter-clockwise arcs and
helices, centre by ``I``/``J``/``K`` offsets from the start point or radius ``R`` — negative for an
arc over 180°), planes ``G17`` (XY), ``G18`` (ZX), ``G19`` (YZ), units ``G20`` (inch) / ``G21``
(mm, default), ``G90`` absolute / ``G91`` incremental coordinates, ``F`` feed (units per minute),
``N`` line numbers, comments in parentheses or after ``;``, and ``%`` tape marks. Motion modes are
modal; a line with coordinates only repeats the last motion. Arcs whose end radius differs from
the start radius by up to 0.1 % or 5 µm (rounded CAM output) are accepted, ending exactly at the
programmed point. Anything else — an unknown word, two codes of one modal group on a line, an
offset letter outside the arc's plane (K in G17) — is an error naming the file line.

The words every CAM post-processor writes around the moves and that leave the tool path and the
feeds unchanged are read and ignored: program numbers ``O``, spindle ``S``, tools ``T``,
``M`` codes (spindle, coolant, tool change, stops; ``M2``/``M30`` end the program — later lines
are not read), and the modal codes ``G40`` (cutter compensation off), ``G49`` (tool length
offset off), ``G80`` (canned cycle off), ``G94`` (feed per minute, the only feed mode), ``G54``–
``G59`` (work offset selection: the offset itself is ``origin``), ``G61``/``G64`` (path control:
the time law stops at corners anyway). Codes that would change the path — cutter or length
compensation on (``G41``–``G43``), canned cycles, ``G28`` homing, inverse-time feed — are
refused.

Program coordinates are added to ``origin`` (a work offset, m) to give machine coordinates.
"""

from __future__ import annotations

import re
from pathlib import Path as FilePath

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.model.text_files import number_problem, read_text
from pkmkit.motion.paths import (
    ARC_ABS_TOL,
    ARC_REL_TOL,
    MAX_SEGMENTS,
    SEGMENT_BYTES,
    Arc,
    Line,
    Path,
    arc_through,
)

_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")
_UNITS = {20: 0.0254, 21: 1e-3}
_UNIT_NAMES = {0.0254: "in", 1e-3: "mm"}
_PLANES = {17: (np.array([0.0, 0.0, 1.0]), "IJ"), 18: (np.array([0.0, 1.0, 0.0]), "IK"),
           19: (np.array([1.0, 0.0, 0.0]), "JK")}
_ALLOWED_G = {0, 1, 2, 3, 17, 18, 19, 20, 21, 90, 91}
#: Modal codes that leave the tool path and the feeds unchanged (see the module documentation).
_IGNORED_G = {40, 49, 80, 94, 54, 55, 56, 57, 58, 59, 61, 64}
#: Words that leave the tool path and the feeds unchanged.
_IGNORED_WORDS = "OSTM"
#: M codes that end the program.
_PROGRAM_END = {2, 30}


def _strip(line: str) -> str:
    line = re.sub(r"\([^)]*\)", " ", line)
    return line.split(";", 1)[0].strip()


def read_gcode(source: str | FilePath, *, origin=(0.0, 0.0, 0.0), start=None,
               name: str | None = None) -> Path:
    """Parse G-code text or a file into a :class:`~pkmkit.motion.paths.Path`.

    Args:
        source: a file path, or the program text itself (when it contains a newline).
        origin: work offset added to program coordinates, m.
        start: tool position before the first move (machine coordinates, m; default ``origin``).
        name: label used in error messages (default: the file name).

    Raises:
        InputError: unsupported words, malformed numbers, arcs whose radius is inconsistent,
            moves without a feed, an empty program — each with ``name:line``.
    """
    if isinstance(source, str) and "\n" in source:
        text, label = source, name or "<gcode>"
    else:
        label = name or str(source)
        text = read_text(source, lambda message, line: InputError(
            f"{label}:{line}: {message}" if line else f"{label}: {message}"))
    offset = np.asarray(origin, dtype=float).reshape(3)
    position = offset.copy() if start is None else np.asarray(start, dtype=float).reshape(3)
    program = _Interpreter(label, offset, position)
    for number, raw in enumerate(text.splitlines(), start=1):
        body = _strip(raw)
        if body and body != "%":
            program.block(number, body)
        if program.ended:
            break
    if not program.segments:
        raise InputError(f"{label}: the program contains no motion")
    return Path(tuple(program.segments), tuple(program.lines), tuple(program.blocks))


class _Interpreter:
    """The modal state of a G-code program (units, plane, distance mode, motion, feed,
    position) and the moves read so far; :meth:`block` reads one block."""

    def __init__(self, label: str, offset: np.ndarray, position: np.ndarray) -> None:
        self.label, self.offset, self.position = label, offset, position
        self.scale, self.plane, self.absolute = _UNITS[21], 17, True
        self.motion: int | None = None
        self.feed: float | None = None
        self.ended = False
        self.segments: list[Line | Arc] = []
        self.lines: list[int] = []
        self.blocks: list[str] = []

    def error(self, number: int, message: str) -> InputError:
        return InputError(f"{self.label}:{number}: {message}")

    def block(self, number: int, body: str) -> None:
        """Read one non-empty block (``body`` without comments) at file line ``number``."""
        values, g_codes = self._words(number, body)
        self._modes(number, g_codes)
        if "F" in values:
            if not values["F"] > 0:
                raise self.error(number, f"the feed must be > 0, got F{values['F']:g}")
            self.feed = values["F"] * self.scale / 60.0
        if any(k in values for k in "XYZIJKR"):
            self._move(number, values, body)

    def _words(self, number: int, body: str) -> tuple[dict[str, float], list[int]]:
        """The block's X Y Z I J K R F values and its G codes (M2/M30 set :attr:`ended`)."""
        words = _WORD.findall(body)
        leftover = _WORD.sub("", body).strip()
        if leftover:
            raise self.error(number, f"cannot read {leftover!r}")
        values: dict[str, float] = {}
        g_codes = []
        for letter, number_text in words:
            letter = letter.upper()
            value = float(number_text)
            problem = number_problem(number_text)
            if problem:
                raise self.error(number, f"{letter} word: {problem}")
            if letter == "G":
                g = self._g_code(number, value, number_text)
                if g is not None:
                    g_codes.append(g)
            elif letter == "M" and value in _PROGRAM_END:
                self.ended = True
            elif letter == "N" or letter in _IGNORED_WORDS:
                continue
            elif letter in "XYZIJKRF":
                if letter in values:
                    raise self.error(number, f"{letter} appears twice")
                values[letter] = value
            else:
                raise self.error(number, f"unsupported word {letter}{number_text} (only G0-G3, "
                                 "G17-G21, G90, G91, X Y Z I J K R F and N are read; O S T M "
                                 "are ignored)")
        return values, g_codes

    def _g_code(self, number: int, value: float, number_text: str) -> int | None:
        """The G code as an int, None for an ignored one; unsupported ones raise."""
        if value == int(value) and int(value) in _IGNORED_G:
            return None
        if value != int(value) or int(value) not in _ALLOWED_G:
            raise self.error(number, f"unsupported G code G{number_text}; supported: "
                             + ", ".join(f"G{g}" for g in sorted(_ALLOWED_G))
                             + " (and, ignored, "
                             + ", ".join(f"G{g}" for g in sorted(_IGNORED_G)) + ")")
        return int(value)

    def _modes(self, number: int, g_codes: list[int]) -> None:
        """Apply the block's modal G codes (one per group)."""
        for group, what in ((set(_UNITS), "unit"), (set(_PLANES), "plane"),
                            ({90, 91}, "distance"), ({0, 1, 2, 3}, "motion")):
            clash = [g for g in g_codes if g in group]
            if len(clash) > 1:
                raise self.error(number, f"two {what} codes on one line: "
                                 + " ".join(f"G{g}" for g in clash))
        for g in g_codes:
            if g in _UNITS:
                self.scale = _UNITS[g]
            elif g in _PLANES:
                self.plane = g
            elif g in (90, 91):
                self.absolute = g == 90
            else:
                self.motion = g

    def _target(self, values: dict[str, float]) -> np.ndarray:
        """The block's end point (m, machine coordinates) in the current distance mode."""
        target = self.position.copy()
        for axis, letter in enumerate("XYZ"):
            if letter in values:
                v = values[letter] * self.scale
                target[axis] = (v + self.offset[axis] if self.absolute
                                else self.position[axis] + v)
        return target

    def _move(self, number: int, values: dict[str, float], body: str) -> None:
        """Append the block's line or arc (a zero-length line is skipped)."""
        motion = self.motion
        if motion is None:
            raise self.error(number, "coordinates without a motion mode (G0, G1, G2 or G3)")
        target = self._target(values)
        if motion in (1, 2, 3) and self.feed is None:
            raise self.error(number, "a feed move needs a feed rate F first")
        if motion in (0, 1):
            if any(k in values for k in "IJKR"):
                raise self.error(number, f"I/J/K/R make no sense with G{motion}")
            if np.linalg.norm(target - self.position) == 0:
                return
            self.segments.append(Line(self.position, target, rapid=motion == 0,
                                      feed=None if motion == 0 else self.feed))
        else:
            self.segments.append(_arc(self.position, target, values, self.plane, motion == 2,
                                      self.scale, self.feed,
                                      lambda m, n=number: self.error(n, m)))
        if not np.isfinite(target).all() or not np.isfinite(self.segments[-1].length):
            raise self.error(number, "the move's coordinates overflow (a length beyond 1e308 m)")
        if len(self.segments) > MAX_SEGMENTS:
            raise self.error(number, f"more than {MAX_SEGMENTS} moves (about "
                             f"{MAX_SEGMENTS * SEGMENT_BYTES / 2**30:.1f} GiB of path before any "
                             "sampling); split the program")
        self.lines.append(number)
        self.blocks.append(body)
        self.position = target

def _arc(start, end, values, plane, clockwise, scale, feed, error) -> Arc:
    normal, letters = _PLANES[plane]
    off_plane = ({"I", "J", "K"} - set(letters)).pop()
    if off_plane in values:
        raise error(f"{off_plane} is not an offset of an arc in the G{plane} plane (use "
                    f"{letters[0]} and {letters[1]})")
    in_plane = [i for i in range(3) if normal[i] == 0]
    if "R" in values:
        if any(k in values for k in "IJK"):
            raise error("give the arc centre by I/J/K or by R, not both")
        radius = values["R"] * scale
        chord_vec = (end - start)[in_plane]
        chord = float(np.linalg.norm(chord_vec))
        if chord == 0:
            raise error("an R arc cannot describe a full circle; use I/J/K")
        half = chord / 2
        if abs(radius) < half - max(ARC_REL_TOL * half, ARC_ABS_TOL):
            raise error(f"inconsistent arc: radius {abs(radius) / scale:g} is smaller than half "
                        f"the chord ({half / scale:g})")
        h = np.sqrt(max(radius**2 - half**2, 0.0))
        mid = 0.5 * (start + end)[in_plane]
        perp = np.array([-chord_vec[1], chord_vec[0]]) / chord  # left of the chord
        # in the plane seen from +normal: CCW short arcs have their centre on the left
        sign = (1.0 if not clockwise else -1.0) * (1.0 if radius > 0 else -1.0)
        if plane == 18:  # the ZX plane's (first, second) axes are (x, z) but it is seen from +y
            sign = -sign
        center = start.copy()
        center[in_plane] = mid + sign * h * perp
    else:
        center = start.copy()
        for axis, letter in zip(in_plane, [letters[0], letters[1]], strict=True):
            center[axis] += values.get(letter, 0.0) * scale
        if all(values.get(letter, 0.0) == 0.0 for letter in letters):
            raise error(f"an arc needs its centre: {letters[0]}/{letters[1]} offsets or R")
    try:
        return arc_through(start, end, center, normal, clockwise=clockwise, feed=feed,
                           units=(_UNIT_NAMES[scale], scale))
    except InputError as exc:
        raise error(str(exc)) from None
