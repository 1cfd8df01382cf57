"""A corrected G-code program, built block by block from the parsed program.

The identified machine reaches X when commanded ``IGM_identified(X)``; the nominal controller
commands ``IGM_nominal(X')``, so every programmed point X is sent as
``X' = FGM_nominal(IGM_identified(X))`` (:func:`pkmkit.calibration.controller.corrected_targets`).

The corrected program has the original's moves, in order, with their motion types and feeds:

- a rapid (G0) keeps one move to its corrected end point — the path of a rapid is not
  controlled, so nothing between its ends is corrected (and no rapid is ever cut into pieces);
- a feed move (G1 line, G2/G3 arc or helix) is corrected at its end point and checked at points
  at most ``step`` apart: the corrected points must lie within ``tolerance`` of the straight line
  (of the arc, fitted through the corrected points and passing through the corrected ends) that
  the controller will interpolate between the corrected end points. Where they do not, the move
  is halved, recursively, into moves of the same type — subdivided only where the correction
  needs it;
- a further correction field (``aim``: the calibrated machine's gravity sag, ``X → X − δ(q_X)``)
  is applied to every programmed point before the calibration's, under the same rules;
- a correction larger than ``max_correction`` anywhere along a block (or a point the
  calibrated machine cannot reach, or one that commands an actuator beyond its stroke)
  refuses that block: :class:`CorrectionRefused` names every
  such block by its G-code line and text, and no program is produced.

The tool position before the first block is unknown (the machine is wherever it is): the
corrected program starts, as the original does, with the first block's move to its (corrected)
target, never subdivided (a first G1 is corrected at its end point only, like a rapid; a first
arc is refused).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pkmkit.calibration.controller import commanded_q, reached
from pkmkit.exceptions import InputError
from pkmkit.motion.limits import stroke_excess
from pkmkit.motion.paths import Arc, Line, Path

#: Default largest deviation between the corrected points and the interpolated corrected move, m.
DEFAULT_TOLERANCE = 1e-6
#: Default spacing of the points a feed move's correction is checked at, m.
DEFAULT_STEP = 1e-3
#: Default largest correction accepted, as a fraction of the machine's characteristic length
#: (:func:`default_max_correction`; beyond: not a calibration of this machine, a unit mistake, or
#: defects the nominal controller should not be asked to absorb blindly).
MAX_CORRECTION_FRACTION = 0.01
#: Most points checked along a program (memory and time bound: ~10⁷ corrections).
MAX_CHECK_POINTS = 10_000_000


class CorrectionRefused(InputError):
    """Blocks whose correction exceeds the bound or cannot be computed.

    Attributes:
        blocks: ``[(line, text, correction)]`` one per refused block: its G-code line, its
            text and its largest correction (m; NaN: a point out of reach of the calibrated
            machine; inf: an actuator out of stroke, listed in ``strokes``).
        strokes: ``[(line, text, actuator, excess, angular)]`` the blocks that command an
            actuator beyond its stroke (excess in m, or rad when ``angular``).
    """

    def __init__(self, message: str, blocks: list[tuple[int, str, float]],
                 strokes: list[tuple[int, str, str, float, bool]] = ()):
        super().__init__(message)
        self.blocks = blocks
        self.strokes = list(strokes)


def refusal_reason(correction: float, bound: float, scale: float = 1.0,
                   unit: str = "m") -> str:
    """Why a block is refused: its ``correction`` (m, NaN: out of reach) against ``bound``
    (m), in ``unit`` (``scale`` m per unit)."""
    if np.isnan(correction):
        return "out of reach of the calibrated machine"
    if np.isinf(correction):
        return "an actuator out of stroke"
    return f"correction {correction / scale:.4g} {unit} > {bound / scale:g} {unit}"


@dataclass(frozen=True)
class CorrectedPath:
    """The moves of a corrected program (K moves, K ≥ the number of blocks).

    Attributes:
        targets: ``(K, 3)`` programmed end point of each move (m, machine coordinates).
        corrected: ``(K, 3)`` corrected end point, what the nominal controller is sent.
        kind: ``(K,)`` motion type ``"G0"``, ``"G1"``, ``"G2"`` or ``"G3"``.
        center: ``(K, 3)`` corrected arc centre (NaN for lines).
        normal: ``(K, 3)`` arc plane normal (NaN for lines).
        rapid: ``(K,)`` the move is a rapid (G0).
        feed: ``(K,)`` programmed feed (m/s, NaN for rapids).
        source: ``(K,)`` G-code line of the block the move comes from.
        text: ``(K,)`` that block's text.
        blocks: number of blocks of the original program.
        deviation: largest deviation left between the corrected points checked and the
            corrected moves (m).
        tolerance, step, max_correction: the settings used (m).
    """

    targets: np.ndarray
    corrected: np.ndarray
    kind: np.ndarray
    center: np.ndarray
    normal: np.ndarray
    rapid: np.ndarray
    feed: np.ndarray
    source: np.ndarray
    text: tuple[str, ...]
    blocks: int
    deviation: float
    tolerance: float
    step: float
    max_correction: float

    @property
    def correction(self) -> np.ndarray:
        """``(K,)`` size of the end-point corrections (m)."""
        return np.linalg.norm(self.corrected[:, :3] - self.targets[:, :3], axis=1)

    @property
    def subdivided(self) -> int:
        """Number of blocks cut into more than one move."""
        _, counts = np.unique(self._block_index, return_counts=True)
        return int((counts > 1).sum())

    @property
    def _block_index(self) -> np.ndarray:
        # a new block starts where the source line changes (a block is one line of G-code)
        return np.concatenate([[0], np.cumsum(self.source[1:] != self.source[:-1])])


def default_max_correction(machine) -> float:
    """Default largest correction, m: :data:`MAX_CORRECTION_FRACTION` of the machine's
    characteristic length (the mean leg length of a rod machine — 13 mm for the linear Delta —,
    the closure scale of a joint chain — 5 mm for the Tripteor X7)."""
    from pkmkit.geometric_errors.identifiability import characteristic_length

    return MAX_CORRECTION_FRACTION * characteristic_length(machine)


def _check_positive(value: float, what: str) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"{what} must be a finite number > 0, got {value!r}")
    return value


def _samples(seg, step: float) -> np.ndarray:
    """``(2n + 1, 3)`` points along a feed segment at most ``step`` apart (ends included;
    an even count of intervals, so every piece between even indices has an interior point)."""
    n = max(2 if isinstance(seg, Arc) else 1, int(np.ceil(seg.length / (2 * step))))
    s = np.linspace(0.0, seg.length, 2 * n + 1)
    return seg.evaluate(s)[0]


def _line_deviation(c: np.ndarray) -> float:
    """Largest distance of ``c[1:-1]`` from the segment ``c[0]``–``c[-1]``."""
    a, d = c[0], c[-1] - c[0]
    inner = c[1:-1] - a
    dd = float(d @ d)
    u = np.clip(inner @ d / dd, 0.0, 1.0) if dd > 0 else np.zeros(len(inner))
    return float(np.linalg.norm(inner - u[:, None] * d, axis=1).max(initial=0.0))


def _arc_fit(c: np.ndarray, seg: Arc) -> tuple[np.ndarray, float]:
    """Centre ``(3,)`` of the arc (helix) in ``seg``'s plane through ``c[0]`` and ``c[-1]``
    best fitting the corrected points ``c`` (least squares on the equal-radius conditions),
    and the largest deviation of ``c`` from that arc (radial and axial, the axial position
    interpolated linearly in angle as G2/G3 do)."""
    n, e1, e2 = seg.normal, seg.e1, seg.e2
    rel = c - c[0]
    p = np.column_stack([rel @ e1, rel @ e2])  # in-plane, origin at the corrected start
    axial = rel @ n
    inner = p[1:-1]
    rhs = -np.einsum("ij,ij->i", inner, inner)  # |p0|² − |pk|² with p0 = 0
    rows = -2.0 * inner                          # 2 (p0 − pk)
    chord = p[-1]
    if np.linalg.norm(chord) > 1e-9 * max(seg.radius, 1e-9):
        mid = 0.5 * chord
        perp = np.array([-chord[1], chord[0]]) / np.linalg.norm(chord)
        a = rows @ perp
        t = float(a @ (rhs - rows @ mid) / (a @ a))
        centre2 = mid + t * perp
    else:  # a full circle: the centre is free in the plane
        centre2 = np.linalg.lstsq(rows, rhs, rcond=None)[0]
    radius = float(np.linalg.norm(centre2))
    v = p - centre2
    phi = np.unwrap(np.arctan2(v[:, 1], v[:, 0]))
    phi = phi - phi[0]
    if np.sign(phi[-1]) != np.sign(seg.sweep) or abs(phi[-1]) < 1e-12:
        # the sweep runs the other way round (or a full turn): follow the programmed direction
        phi[-1] = phi[-1] + np.sign(seg.sweep) * 2 * np.pi
    radial = np.abs(np.linalg.norm(v, axis=1) - radius)
    along = axial - axial[-1] * phi / phi[-1]
    deviation = float(np.hypot(radial, along)[1:-1].max(initial=0.0))
    centre = c[0] + centre2[0] * e1 + centre2[1] * e2
    return centre, deviation


def _pieces(c: np.ndarray, seg, tolerance: float) -> list[tuple[int, int, np.ndarray | None,
                                                                 float]]:
    """Pieces ``(i, j, centre, deviation)`` (even indices into ``c``) of a feed segment,
    halved until each is within ``tolerance`` (or spans two sampling intervals)."""
    i, j = 0, len(c) - 1
    out = []
    stack = [(i, j)]
    while stack:
        i, j = stack.pop()
        if isinstance(seg, Arc):
            centre, dev = _arc_fit(c[i:j + 1], seg)
        else:
            centre, dev = None, _line_deviation(c[i:j + 1])
        if dev <= tolerance or j - i <= 2:
            out.append((i, j, centre, dev))
            continue
        m = i + 2 * ((j - i) // 4) if (j - i) >= 4 else i + 2
        stack += [(m, j), (i, m)]
    return out


def correct_path(nominal, identified, path: Path, *, step: float = DEFAULT_STEP,
                 tolerance: float = DEFAULT_TOLERANCE,
                 max_correction: float | None = None,
                 tool_length: float | None = None, progress: bool = False,
                 aim: Callable[[np.ndarray], np.ndarray] | None = None) -> CorrectedPath:
    """The corrected moves of a parsed G-code program (module docstring).

    Args:
        nominal, identified: the controller's machine and the calibrated one.
        path: the program (:func:`pkmkit.motion.gcode.read_gcode`; its ``source`` lines and
            ``blocks`` texts name the blocks).
        step: spacing of the checked points along feed moves, m.
        tolerance: largest deviation of the corrected points from a corrected move, m.
        max_correction: largest correction accepted, m (default:
            :func:`default_max_correction` of ``nominal``).
        tool_length: for machines with a tool length.
        progress: show a progress bar.
        aim: a further correction field applied to every programmed point before the
            calibration's, ``(k, 3) → (k, 3)`` m (NaN rows: no aim there, the block is refused),
            e.g. :class:`pkmkit.calibration.gravity.LoadedAim`: the loaded tool point aimed at
            the program (``X → X − δ(q_X)``).

    Raises:
        InputError: ``step``, ``tolerance`` or ``max_correction`` not finite and > 0, or more
            than :data:`MAX_CHECK_POINTS` points to check.
        CorrectionRefused: blocks whose correction exceeds ``max_correction`` or that the
            calibrated machine cannot reach (each with its line and text).
    """
    from pkmkit.calibration.compensation import chunked

    step = _check_positive(step, "the checking step")
    tolerance = _check_positive(tolerance, "the tolerance")
    if max_correction is None:
        max_correction = default_max_correction(nominal)
    max_correction = _check_positive(max_correction, "the largest correction")
    segs = path.segments
    lines = list(path.source) if path.source else list(range(1, len(segs) + 1))
    texts = list(path.blocks) if path.blocks else [""] * len(segs)
    if isinstance(segs[0], Arc):
        raise InputError(f"line {lines[0]} {texts[0]!r}: the program starts with an arc, whose "
                         "start is wherever the machine happens to be; begin with a G0 or G1 "
                         "move")
    planned = sum(1 if seg.rapid or k == 0
                  else 2 * max(1, int(np.ceil(seg.length / (2 * step)))) + 1
                  for k, seg in enumerate(segs))
    if planned > MAX_CHECK_POINTS:
        raise InputError(f"checking the correction every {step:g} m needs {planned} points "
                         f"(limit {MAX_CHECK_POINTS}); increase the step")
    points, owner = [], []
    for k, seg in enumerate(segs):
        # the first block starts wherever the machine is: only its end point is known
        pts = np.atleast_2d(seg.end) if seg.rapid or k == 0 else _samples(seg, step)
        points.append(pts)
        owner.append(np.full(len(pts), k))
    x = np.concatenate(points)
    who = np.concatenate(owner)
    n = identified.n_actuators

    def command(part: np.ndarray) -> np.ndarray:
        q = commanded_q(identified, part if aim is None else aim(part), tool_length)
        return np.concatenate([reached(nominal, q, tool_length)[:, :3], q], axis=1)

    both = chunked(command, x, progress, "compensating")
    fixed, q = both[:, :3], both[:, 3:3 + n]
    size = np.linalg.norm(fixed - x, axis=1)
    outside = stroke_excess(identified, q)
    angular = np.asarray(identified.angular_actuators, dtype=bool)
    refused: list[tuple[int, str, float]] = []
    stroke: list[tuple[int, str, str, float, bool]] = []
    for k in np.unique(who[~np.isfinite(size) | (size > max_correction)
                           | (np.nan_to_num(outside) > 0).any(axis=1)]):
        rows = who == k
        worst = size[rows]
        if np.isfinite(worst).all() and worst.max() <= max_correction:
            over = outside[rows].max(axis=0)
            a = int(np.argmax(over))
            stroke.append((lines[k], texts[k], identified.actuator_names[a], float(over[a]),
                           bool(angular[a])))
            continue
        refused.append((lines[k], texts[k],
                        float(worst.max()) if np.isfinite(worst).all() else np.nan))
    if refused or stroke:
        listed = "; ".join([f"line {ln} {text!r}: {refusal_reason(c, max_correction)}"
                            for ln, text, c in refused[:10]]
                           + [f"line {ln} {text!r}: {name} out of stroke by {by:.4g} "
                              f"{'rad' if rad else 'm'}"
                              for ln, text, name, by, rad in stroke[:10]])
        refused += [(ln, text, np.inf) for ln, text, *_ in stroke]
        more = f" (and {len(refused) - 10} more)" if len(refused) > 10 else ""
        raise CorrectionRefused(f"{len(refused)} block(s) refused: {listed}{more}",
                                sorted(refused), strokes=stroke)
    rows = []  # (target, corrected, kind, centre, normal, feed, k)
    deviation = 0.0
    nan3 = np.full(3, np.nan)
    start = 0
    for k, seg in enumerate(segs):
        count = int((who == k).sum())
        prog, corr = x[start:start + count], fixed[start:start + count]
        start += count
        if seg.rapid:
            rows.append((prog[-1], corr[-1], "G0", nan3, nan3, np.nan, k))
            continue
        feed = np.nan if seg.feed is None else float(seg.feed)
        if k == 0:  # a first G1 from an unknown start: its end point only
            rows.append((prog[-1], corr[-1], "G1", nan3, nan3, feed, k))
            continue
        kind = "G1" if isinstance(seg, Line) else ("G2" if seg.sweep < 0 else "G3")
        normal = seg.normal if isinstance(seg, Arc) else nan3
        for _, j, centre, dev in _pieces(corr, seg, tolerance):
            deviation = max(deviation, dev)
            rows.append((prog[j], corr[j], kind, nan3 if centre is None else centre, normal,
                         feed, k))
    ks = [r[6] for r in rows]
    return CorrectedPath(
        targets=np.array([r[0] for r in rows]), corrected=np.array([r[1] for r in rows]),
        kind=np.array([r[2] for r in rows]), center=np.array([r[3] for r in rows]),
        normal=np.array([r[4] for r in rows]), rapid=np.array([r[2] == "G0" for r in rows]),
        feed=np.array([r[5] for r in rows]), source=np.array([lines[k] for k in ks]),
        text=tuple(texts[k] for k in ks), blocks=len(segs), deviation=deviation,
        tolerance=tolerance, step=step, max_correction=max_correction)
