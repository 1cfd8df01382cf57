"""The machining simulation: a program's straight passes run by a machine with defects under the
nominal controller, and the surfaces its cutters leave on the part, section by section.

**Tool-centre path.** A pass commands ``X_d(t) = start + t (end − start)``; the controller sends
``V_d = IGM_nominal(X_d)`` and the real machine puts the tool centre at
``X_r(t) = FGM_true(V_d(t))`` (batched, exact: :func:`pkmkit.calibration.controller.reached`),
expressed in the part frame with the part's placement (:class:`~.part.Placement`).

**Swept surfaces** (cutter axis vertical: seed 003's perfect-orientation hypothesis, §4.3 — the
Verne-type model's own platform tilt is *not* applied to the cutter). In a CMM section plane
``a = s`` (``a`` the part-frame axis the pass runs along, ``b`` the other horizontal axis):

- the **contour wall** is the envelope of the end mill (a vertical cylinder of radius ``R_e``)
  moving along ``X_r``: the horizontal offset curve ``X_r(t) + R_e u(t)``, ``u`` the horizontal
  unit normal to the path on the material side; its point in the plane is the root ``t`` of
  ``X_r,a(t) + R_e u_a(t) = s``. The wall is vertical: every height has the same ``b``;
- the **slot bottom** ``Q`` is the lowest point of the section of the tube the ball (radius
  ``R_b``) sweeps: ``X_r(t) + R_b u(t)`` with ``u`` the unit vector perpendicular to the path's
  tangent in the vertical plane through the pass axis, pointing down (at the lowest point of a
  section the tube's normal has no ``b`` component), again at the root of ``Q_a(t) = s``.

The tangent is a central difference of the exact path over ±0.1 mm (relative error ~10⁻¹⁰ on
the defects' curvature); the roots are Newton iterations on ``t``.

The **truth** kept for tests is the tool centre where its path crosses the section plane
(``X_r,a(t) = s``): the point seed 003 reconstructs from ``Q``, ``M``, ``N``.

Sections: evenly spaced over the middle 90 % of each pass (at least 2 cutter radii from its
ends); a section within two end-mill radii (horizontally) of another pass less than 20 mm
higher or lower is not probed, since that pass's cut would cross its wall or slot. The probing
heights of the wall points ``M`` and ``N`` are 3 and 7 mm above the commanded tool centre (the
end mill's floor).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.calibration.controller import commanded_q, reached
from pkmkit.exceptions import InputError
from pkmkit.machining.part import Cutters, Pass, Placement

#: Heights of the wall probe points M and N above the commanded tool centre (m).
PROBE_HEIGHTS = (0.003, 0.007)
#: Step of the tangent's central difference along the pass (m).
TANGENT_STEP = 1e-4
#: Passes closer than this in height (m) interfere where they cross (a wall 10 mm high, a slot
#: 8 mm deep): sections near such a crossing are not probed.
CROSSING_HEIGHT = 0.02
#: Newton iterations of the section roots (each divides the error by ~10⁴), and the largest
#: distance (m) from its section plane a root may keep.
ITERATIONS = 8
ROOT_TOL = 1e-12


@dataclass(frozen=True)
class MachinedPart:
    """The part after machining, section by section (part frame, m).

    Attributes:
        passes: the program's passes (machine frame).
        placement: the part's true placement.
        cutters: the cutters that machined it.
        path: ``(K,)`` pass (G-code line) of each section.
        axis: ``(K,)`` part-frame axis the pass runs along (0: x, 1: y).
        s: ``(K,)`` section plane coordinate along ``axis``.
        side: ``(K,)`` ±1: the wall's side along the other horizontal axis.
        centre: ``(K, 3)`` the true tool centre in the section plane (the truth).
        wall: ``(K,)`` the wall's coordinate along the other horizontal axis.
        slot: ``(K, 3)`` the slot bottom Q.
        heights: ``(K, 2)`` heights of the wall points M and N.
        probe_radius: the CMM tip radius (m) of ``tip_wall`` and ``tip_slot``: where a tip's
            centre touches the wall and settles in the slot (the surfaces the cutters of radii
            reduced by the tip radius would leave).
    """

    passes: tuple[Pass, ...]
    placement: Placement
    cutters: Cutters
    path: tuple[str, ...]
    axis: np.ndarray
    s: np.ndarray
    side: np.ndarray
    centre: np.ndarray
    wall: np.ndarray
    slot: np.ndarray
    heights: np.ndarray
    probe_radius: float
    tip_wall: np.ndarray
    tip_slot: np.ndarray


class _CentrePath:
    """The reached tool-centre path of one pass in the part frame, at any parameter t."""

    def __init__(self, true_machine, nominal, p: Pass, placement: Placement):
        self.true, self.nominal, self.p, self.placement = true_machine, nominal, p, placement
        self.dt = TANGENT_STEP / float(np.linalg.norm(p.end - p.start))

    def __call__(self, t: np.ndarray) -> np.ndarray:
        x = reached(self.true, commanded_q(self.nominal, self.p.at(t)))[:, :3]
        if not np.isfinite(x).all():
            raise InputError(f"pass at line {self.p.path}: the machine cannot follow it (the "
                             "commanded line leaves its workspace)")
        return self.placement.to_part(x)

    def with_tangent(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        k = len(t)
        pts = self(np.concatenate([t, t - self.dt, t + self.dt]))
        return pts[:k], (pts[2 * k:] - pts[k:2 * k]) / (2 * self.dt)


def _wall_normal(tangent: np.ndarray, left: float) -> np.ndarray:
    u = np.zeros_like(tangent)
    u[:, 0], u[:, 1] = -tangent[:, 1], tangent[:, 0]
    return left * u / np.hypot(u[:, 0], u[:, 1])[:, None]


def _slot_normal(tangent: np.ndarray, a: int) -> np.ndarray:
    ta, tz = tangent[:, a], tangent[:, 2]
    u = np.zeros_like(tangent)
    u[:, a], u[:, 2] = tz, -ta
    return np.sign(ta)[:, None] * u / np.hypot(ta, tz)[:, None]


def _section_roots(curve: _CentrePath, s: np.ndarray, t0: np.ndarray, a: int, offsets
                   ) -> list[np.ndarray]:
    """For each offset function, the points ``(K, 3)`` of ``c(t) + offset(c'(t))`` in the planes
    ``a = s`` (Newton on t, all offsets in one batch)."""
    n = len(offsets)
    k = len(s)
    t = np.tile(t0, n)
    target = np.tile(s, n)

    def points(t):
        c, dc = curve.with_tangent(t)
        return c + np.concatenate([off(dc[j * k:(j + 1) * k]) for j, off in
                                   enumerate(offsets)]), dc

    for _ in range(ITERATIONS):
        point, dc = points(t)
        miss = point[:, a] - target
        t = t - miss / dc[:, a]
        if np.abs(miss).max() < 1e-14:  # metres: the rounding of FGM(IGM(x)) is ~1e-14
            break
    point, _ = points(t)
    miss = np.abs(point[:, a] - target).max()
    if not miss < ROOT_TOL:
        raise InputError(f"pass at line {curve.p.path}: the section planes' intersections did "
                         f"not converge in {ITERATIONS} iterations (off by {miss:.3g} m); is "
                         "the pass folding back?")
    return [point[j * k:(j + 1) * k] for j in range(n)]


def machine_part(true_machine, nominal, passes, *, placement: Placement | None = None,
                 cutters: Cutters | None = None, sections: int = 240, wall_side: str = "left",
                 probe_radius: float = 0.001) -> MachinedPart:
    """Machine the part (module docstring).

    Args:
        true_machine: the machine with its defects.
        nominal: the machine whose inverse model the controller uses.
        passes: the program's straight passes (:func:`~.part.part_passes`).
        placement: the part's placement (default: none).
        cutters: the cutters (default: seed 003's Ø20 end mill and Ø16 ball-end mill).
        sections: sections to lay out in all (spread evenly over the passes, before those near
            another pass are dropped).
        wall_side: ``"left"`` or ``"right"`` of the direction of travel: the side the material
            (the contour wall) is on.
        probe_radius: the CMM's tip radius (m; MachinedPart).

    Raises:
        InputError: a pass the true machine cannot follow, no section left, a bad option.
    """
    placement = placement or Placement()
    cutters = cutters or Cutters()
    tip = cutters.reduced(probe_radius)
    if wall_side not in ("left", "right"):
        raise InputError(f"wall_side must be 'left' or 'right', got {wall_side!r}")
    if sections < 1:
        raise InputError(f"sections must be ≥ 1, got {sections}")
    passes = tuple(passes)
    left = 1.0 if wall_side == "left" else -1.0
    per_pass = max(3, -(-sections // len(passes)))
    # the other passes in the part frame (horizontal), for the crossing exclusion
    ends = [(placement.to_part(p.start), placement.to_part(p.end)) for p in passes]
    out: dict[str, list] = {k: [] for k in ("path", "axis", "s", "side", "centre", "wall",
                                            "slot", "heights", "tip_wall", "tip_slot")}
    for i, p in enumerate(passes):
        kept = _pass_sections(p, i, ends, placement, cutters, per_pass)
        if kept is None:
            continue
        t0, nominal_pts = kept
        a = p.axis
        s = nominal_pts[:, a]
        curve = _CentrePath(true_machine, nominal, p, placement)
        centre, wall, slot, tip_wall, tip_slot = _section_roots(curve, s, t0, a, [
            lambda dc: 0.0 * dc,
            lambda dc: cutters.end_mill * _wall_normal(dc, left),
            lambda dc, a=a: cutters.ball * _slot_normal(dc, a),
            lambda dc: tip.end_mill * _wall_normal(dc, left),
            lambda dc, a=a: tip.ball * _slot_normal(dc, a)])
        side = np.sign(wall[:, 1 - a] - centre[:, 1 - a])
        k = len(s)
        out["path"] += [p.path] * k
        out["axis"].append(np.full(k, a))
        out["s"].append(s)
        out["side"].append(side)
        out["centre"].append(centre)
        out["wall"].append(wall[:, 1 - a])
        out["slot"].append(slot)
        out["heights"].append(nominal_pts[:, 2:3] + np.array(PROBE_HEIGHTS))
        out["tip_wall"].append(tip_wall[:, 1 - a])
        out["tip_slot"].append(tip_slot)
    if not out["path"]:
        raise InputError("no section left to probe: every section lies within two end-mill "
                         "radii of another pass")
    cat = {k: np.concatenate(v) for k, v in out.items() if k != "path"}
    return MachinedPart(passes=passes, placement=placement, cutters=cutters,
                        path=tuple(out["path"]), probe_radius=float(probe_radius), **cat)


def _pass_sections(p, i: int, ends: list, placement: Placement, cutters: Cutters,
                   per_pass: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Pass ``i``'s section parameters ``t (k,)`` and nominal points ``(k, 3)`` in the part
    frame, spread between end margins, less those within two end-mill radii of another pass
    at the same height (None when none is left)."""
    length = float(np.linalg.norm(p.end - p.start))
    margin = max(0.05, 2 * cutters.end_mill / length)
    t0 = np.linspace(margin, 1 - margin, per_pass)
    nominal_pts = placement.to_part(p.at(t0))
    keep = np.ones(len(t0), dtype=bool)
    for j, (e0, e1) in enumerate(ends):
        near_height = abs((e0[2] + e1[2]) / 2 - nominal_pts[:, 2].mean()) < CROSSING_HEIGHT
        if j != i and near_height:
            keep &= (_distance_to_segment(nominal_pts[:, :2], e0[:2], e1[:2])
                     > 2 * cutters.end_mill)
    if not keep.any():
        return None
    return t0[keep], nominal_pts[keep]


def _distance_to_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = b - a
    t = np.clip((points - a) @ d / (d @ d), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * d), axis=1)
