"""Synthetic calibration measurements: realistic defects, configurations in a documented default
region, the readings the true machine gives, and instrument noise.

- :func:`random_defects` draws every defect with a random sign and a magnitude log-uniform
  between 1 % and 100 % of a realistic bound (positions and lengths 0.1 mm, directions and
  angles 0.5°: seed 002's magnitudes — most defects small, a few near the bound, as in its
  Table 5.6) and, for a hyperstatic machine, keeps it in the compatible subspace (the dependent
  defects follow the free ones: :func:`pkmkit.calibration.identifiability.
  compatible_directions`);
- :func:`default_configurations` draws actuator coordinates in a machine's default region: for a
  joint-chain machine with a head, seed 002's protocol — half *platform-only* moves (the legs
  within their strokes, the head at zero) and half *wrist-only* moves (the legs at mid-stroke,
  the head within its strokes; for the Tripteor, the strokes are Table 5.3's joint ranges); for
  rod machines, tool points uniform in the machine's default box (a full-pose machine at its
  home orientation ± 5° about each axis), kept where the inverse model and the strokes allow;
- :func:`simulate` produces a :class:`MeasurementSet` of each type with a noise model:

  ============ ==============================================================================
  ``tracker``  laser tracker: ±(15 µm + 6 µm/m × distance) read as a 2σ bound, isotropic, the
               tracker 2.5 m from the centre of the measured points (seed 002, Table 5.1);
               orientations (``pose``) 2·10⁻⁵ rad
  ``cmm``      coordinate measuring machine: σ = 1.5 µm per coordinate
  ``probe``    touch probe on a bed: σ = 2 µm
  ``ballbar``  telescopic ball-bar: σ = 0.5 µm
  ``none``     exact readings
  a number     isotropic σ (m)
  ============ ==============================================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.calibration.controller import commanded_q, reached
from pkmkit.calibration.identifiability import compatible_directions
from pkmkit.calibration.models import tool_state
from pkmkit.calibration.registration import Registration
from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.model import defect_set, tool_sensitivity
from pkmkit.machines.measurement_models import (  # noqa: F401  (SEED_TOOLS, TILT re-exported)
    SEED_TOOLS,
    TILT,
    within_strokes,
)
from pkmkit.model.measurement_set import KINDS, MeasurementSet
from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix

#: Default magnitude of random defects by unit: ±0.1 mm, ±0.5° (direction components, angles).
DEFECT_MAGNITUDE = {"m": 1e-4, "1": np.sin(np.radians(0.5)), "rad": np.radians(0.5)}
#: Laser tracker: constant and distance terms of the ±bound (m, m/m) and its distance (m).
TRACKER_CONSTANT, TRACKER_PER_METRE, TRACKER_DISTANCE = 15e-6, 6e-6, 2.5
#: σ of the other instruments (m) and of a 6-D tracker probe's orientation (rad).
NOISE_SIGMA = {"cmm": 1.5e-6, "probe": 2e-6, "ballbar": 5e-7}
TRACKER_ROTATION_SIGMA = 2e-5
#: Instrument of each measurement type for ``noise="realistic"``.
REALISTIC = {"point": "tracker", "pose": "tracker", "ballbar": "ballbar", "height": "probe",
             "part": "cmm"}


def random_defects(machine, rng: np.random.Generator, *, magnitude: dict | None = None,
                   compatible: bool = True) -> np.ndarray:
    """A random defect vector ``(d,)`` (SI) of realistic magnitude (module docstring)."""
    dset = defect_set(machine)
    mag = {**DEFECT_MAGNITUDE, **(magnitude or {})}
    scale = np.array([mag[u] for u in dset.units])
    size = np.exp(rng.uniform(np.log(0.01), 0.0, len(dset)))
    delta = rng.choice([-1.0, 1.0], len(dset)) * size * scale
    if compatible and machine.incompatible_defects:
        q = default_configurations(machine, 40, np.random.default_rng(0))
        sens = tool_sensitivity(machine, q)
        comp = compatible_directions(sens.closure_defect, dset.names, scale)
        delta = comp.basis @ delta[comp.free]
    return delta


def default_configurations(machine, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` actuator vectors ``(n, n_act)`` in the machine's default region (module
    docstring).

    Raises:
        InputError: n < 1, or a region where too few configurations are reachable.
    """
    if n < 1:
        raise InputError(f"the number of poses must be ≥ 1, got {n}")
    return machine.measurement_configurations(n, rng)


def _within(machine, q: np.ndarray) -> np.ndarray:
    """``(N,)`` rows that assemble with every actuator and passive joint within its stroke
    (:func:`pkmkit.machines.measurement_models.within_strokes`)."""
    return within_strokes(machine, q)


def _refuse_beyond_strokes(machine, q: np.ndarray) -> None:
    """A typed error naming the given configurations (1-based) beyond the strokes: a machine
    cannot be measured where it cannot go."""
    from pkmkit.machines.strokes import stroke_excess

    finite = np.isfinite(q).all(axis=1)
    if not finite.all():
        raise InputError(f"configuration {int(np.flatnonzero(~finite)[0]) + 1} of the given ones "
                         "is not finite")
    check = stroke_excess(machine, q)
    bad = np.flatnonzero(check.out_of_stroke)
    if bad.size:
        more = f" (and {bad.size - 3} more)" if bad.size > 3 else ""
        listed = "; ".join(f"configuration {i + 1}: {check.message(int(i))}" for i in bad[:3])
        raise InputError(f"{bad.size} of the given configurations are out of stroke: "
                         f"{listed}{more}")


def _tool_lengths(machine, n: int, tool_lengths) -> np.ndarray | None:
    if tool_lengths is None:
        tool_lengths = machine.default_tool_lengths
        if tool_lengths is None:
            return None
    tl = np.asarray(tool_lengths, dtype=float).reshape(-1)
    return tl[np.arange(n) % len(tl)]


@dataclass(frozen=True)
class Noise:
    """A noise model: ``kind`` (``tracker``, ``cmm``, ``probe``, ``ballbar``, ``none`` or
    ``sigma``) and its σ (m) for ``sigma``; ``scale`` multiplies every σ (noise studies: the
    same draws at 0, 1, 2 times an instrument's noise)."""

    kind: str
    sigma: float = 0.0
    scale: float = 1.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.scale) and self.scale >= 0):
            raise InputError(f"noise scale must be a finite number ≥ 0, got {self.scale!r}")

    @classmethod
    def parse(cls, spec: Any, measure: str) -> Noise:
        """From ``"none"``, ``"realistic"``, an instrument name or a σ (m, a number)."""
        if isinstance(spec, int | float) and not isinstance(spec, bool):
            if not (np.isfinite(spec) and spec >= 0):
                raise InputError(f"noise σ must be ≥ 0, got {spec!r}")
            return cls("sigma", float(spec))
        if spec in (None, "realistic"):
            return cls(REALISTIC[measure])
        if spec in ("tracker", "cmm", "probe", "ballbar", "none"):
            return cls(spec)
        raise InputError(f"unknown noise model {spec!r}; use none, realistic, tracker, cmm, "
                         "probe, ballbar or a standard deviation")

    def position_sigma(self, points: np.ndarray) -> np.ndarray:
        """σ per point ``(N,)`` (m)."""
        return self.scale * self._position_sigma(points)

    def _position_sigma(self, points: np.ndarray) -> np.ndarray:
        n = len(points)
        if self.kind == "none":
            return np.zeros(n)
        if self.kind == "sigma":
            return np.full(n, self.sigma)
        if self.kind == "tracker":
            centre = np.nanmean(points, axis=0)
            tracker = centre + np.array([0.0, -TRACKER_DISTANCE, 0.0])
            dist = np.linalg.norm(points - tracker, axis=1)
            return (TRACKER_CONSTANT + TRACKER_PER_METRE * dist) / 2.0
        return np.full(n, NOISE_SIGMA[self.kind])

    def rotation_sigma(self) -> float:
        base = {"none": 0.0, "tracker": TRACKER_ROTATION_SIGMA}.get(
            self.kind, self.sigma if self.kind == "sigma" else 1e-5)
        return self.scale * base


def simulate(true_machine, nominal, kind: str, n: int, rng: np.random.Generator, *,
             noise: Any = "realistic", q: np.ndarray | None = None,
             tool_lengths: Any = None, frame: Registration | None = None,
             bar_length: float = 0.15, pivots: np.ndarray | None = None,
             source: str = "simulated") -> MeasurementSet:
    """Synthetic measurements of ``kind`` taken on ``true_machine`` commanded by ``nominal``'s
    controller.

    Args:
        true_machine: the machine with its defects (the truth).
        nominal: the machine whose controller commands the moves (the calibration's start).
        kind: point, pose, ballbar, height or part.
        n: number of rows (for ``part``: the approximate number of sections).
        rng: random generator (configurations, noise).
        noise: noise model (a :class:`Noise`, or what :meth:`Noise.parse` reads):
            ``"realistic"`` picks the instrument of the type.
        q: actuator coordinates to use instead of :func:`default_configurations` (point, pose,
            height).
        tool_lengths: tool lengths cycled over the rows (m); default seed 002's two tools for a
            joint-chain machine, none otherwise.
        frame: measurement-to-machine transform: point and pose readings are returned in the
            measurement frame (``frame.inverse()`` applied).
        bar_length: ball-bar length (m). pivots: ``(k, 3)`` ball-bar pivots (default: one at the
            centre of the default box, one 0.1 m lower).
    """
    if kind not in KINDS:
        raise InputError(f"unknown measurement type {kind!r}; valid types: {', '.join(KINDS)}")
    model = noise if isinstance(noise, Noise) else Noise.parse(noise, kind)
    if kind == "part":
        return simulate_part(true_machine, nominal, rng, sections=n, noise=model,
                             source=source)
    if kind == "ballbar":
        return _simulate_ballbar(true_machine, nominal, n, rng, model, tool_lengths,
                                 bar_length, pivots, source)
    if kind == "height":
        return _simulate_height(true_machine, nominal, n, rng, model, q, source)
    drawn = q is None
    if drawn:
        q = default_configurations(nominal, n, rng)
    q = np.atleast_2d(np.asarray(q, dtype=float)).copy()
    if not drawn:
        _refuse_beyond_strokes(nominal, q)
    tl = _tool_lengths(nominal, len(q), tool_lengths)
    state = tool_state(true_machine, q, tl, jacobian=False, rotation=kind == "pose")
    ok = np.isfinite(state.point).all(axis=1)
    for _ in range(10 if drawn else 0):
        # near the workspace's edge the true machine may not assemble where the nominal one
        # does: draw replacements for those rows
        if ok.all():
            break
        bad = np.flatnonzero(~ok)
        q[bad] = default_configurations(nominal, len(bad), rng)
        state = tool_state(true_machine, q, tl, jacobian=False, rotation=kind == "pose")
        ok = np.isfinite(state.point).all(axis=1)
    if not ok.all():
        bad = int(np.flatnonzero(~ok)[0])
        raise InputError(f"the true machine does not assemble at configuration {bad + 1}"
                         + ("" if drawn else " of the given ones"))
    sigma = model.position_sigma(state.point)
    points = state.point + rng.standard_normal(state.point.shape) * sigma[:, None]
    inverse = frame.inverse() if frame is not None else None
    if inverse is not None:
        points = inverse.apply(points)
    values = points
    if kind == "pose":
        s_rot = model.rotation_sigma()
        tilt = rotvec_to_matrix(rng.standard_normal((len(q), 3)) * s_rot)
        rot = tilt @ state.rotation
        if inverse is not None:
            rot = inverse.rotation[None] @ rot
        values = np.concatenate([points, matrix_to_rotvec(rot)], axis=1)
    return MeasurementSet(kind=kind, values=values, q=q, tool_length=tl,
                          tool=None if tl is None else tuple(
                              f"T{int(np.flatnonzero(np.unique(tl) == v)[0]) + 1}" for v in tl),
                          source=source)


def _simulate_ballbar(true_machine, nominal, n, rng, noise, tool_lengths, bar_length, pivots,
                      source):
    lo, hi = nominal.default_box()
    lo, hi = np.asarray(lo, dtype=float)[:3], np.asarray(hi, dtype=float)[:3]
    if pivots is None:
        centre = (lo + hi) / 2
        if len(lo) == 3:
            pivots = np.array([centre, centre - [0.0, 0.0, 0.1]])
        else:
            pivots = np.array([centre])
    pivots = np.atleast_2d(np.asarray(pivots, dtype=float))
    pivots3 = np.zeros((len(pivots), 3))
    pivots3[:, :pivots.shape[1]] = pivots
    tl = _tool_lengths(nominal, n, tool_lengths)
    which = np.arange(n) % len(pivots3)
    # directions over a hemisphere above the pivot (a bar cannot go through the table)
    rows = []
    for _ in range(50):
        d = rng.standard_normal((4 * n, 3))
        d[:, 2] = np.abs(d[:, 2]) + 0.3
        d /= np.linalg.norm(d, axis=1)[:, None]
        k = np.arange(4 * n) % len(pivots3)
        targets = pivots3[k] + bar_length * d
        tk = None if tl is None else np.resize(tl, 4 * n)
        q = commanded_q(nominal, targets, tk)
        ok = np.isfinite(q).all(axis=1) & _within(nominal, np.nan_to_num(q, nan=np.inf))
        rows.extend((q[i], k[i], None if tk is None else tk[i]) for i in np.flatnonzero(ok))
        if len(rows) >= n:
            break
    if len(rows) < n:
        raise InputError(f"fewer than {n} ball-bar configurations reachable around the pivots")
    rows = rows[:n]
    q = np.array([r[0] for r in rows])
    which = np.array([r[1] for r in rows])
    tl = None if tl is None else np.array([r[2] for r in rows])
    true_pivots = pivots3 + rng.uniform(-2e-4, 2e-4, pivots3.shape)
    point = tool_state(true_machine, q, tl, jacobian=False).point
    length = np.linalg.norm(point - true_pivots[which], axis=1)
    length = length + rng.standard_normal(n) * noise.position_sigma(point)
    return MeasurementSet(kind="ballbar", values=length[:, None], q=q, tool_length=tl,
                          pivot=pivots3[which], source=source)


def _simulate_height(true_machine, nominal, n, rng, noise, q, source):
    lo, hi = nominal.default_box()
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if q is None:
        q = bed_configurations(nominal, n, rng)
    else:
        _refuse_beyond_strokes(nominal, np.atleast_2d(np.asarray(q, dtype=float)))
    q = np.atleast_2d(np.asarray(q, dtype=float))
    point = tool_state(true_machine, q, None, jacobian=False).point
    bed_z = float(np.mean(point[:, 2])) - 1e-3  # the bed, 1 mm below the probing height
    slope = rng.uniform(-2e-4, 2e-4, 2)
    centre = point[:, :2].mean(axis=0)
    bed = bed_z + (point[:, :2] - centre) @ slope
    h = point[:, 2] - bed + rng.standard_normal(len(q)) * noise.position_sigma(point)
    return MeasurementSet(kind="height", values=h[:, None], q=q, source=source)


def bed_configurations(machine, n: int, rng: np.random.Generator) -> np.ndarray:
    """Probe configurations ``(n, n_act)`` on a printer-like bed: points uniform on a disc of
    80 % of the default box's half-width, at the lowest height (of 40 tried from the box's
    bottom up) where the whole disc is within the strokes."""
    lo, hi = machine.default_box()
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    radius = 0.8 * float(min(hi[0] - lo[0], hi[1] - lo[1])) / 2
    centre = (lo[:2] + hi[:2]) / 2
    r = radius * np.sqrt(rng.random(n))
    a = 2 * np.pi * rng.random(n)
    ring = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    edge = np.column_stack([centre[0] + radius * np.cos(ring), centre[1] + radius * np.sin(ring)])
    top = hi[2] if len(hi) > 2 else 0.0
    for z in np.linspace(lo[2] if len(lo) > 2 else 0.0, top, 40):
        test = np.column_stack([edge, np.full(len(edge), z)])
        qe = commanded_q(machine, test)
        if np.isfinite(qe).all() and _within(machine, qe).all():
            pts = np.column_stack([centre[0] + r * np.cos(a), centre[1] + r * np.sin(a),
                                   np.full(n, z)])
            q = commanded_q(machine, pts)
            if np.isfinite(q).all() and _within(machine, q).all():
                return q
    raise InputError(f"no bed height of the default box of {machine.id!r} keeps a probing "
                     "disc within the strokes")


def part_paths(machine, *, size: float | None = None, levels: int = 2,
               depth_step: float = 0.03) -> list[tuple[str, np.ndarray]]:
    """Seed 003's test part: straight contours/slots along x and along y, ``(label, (6,))``
    commanded segments (start, end; machine frame, m). Lines along x at three y positions and
    along y at three x positions, over 80 % of the default box's width (or ``size``), at
    ``levels`` heights ``depth_step`` apart near the bottom of the box."""
    lo, hi = machine.default_box()
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    centre = (lo + hi) / 2
    half = 0.4 * float(min(hi[0] - lo[0], hi[1] - lo[1])) if size is None else size / 2
    z0 = lo[2] + 0.25 * (hi[2] - lo[2])
    out = []
    for level in range(levels):
        z = z0 + level * depth_step
        for k, off in enumerate((-0.8 * half, 0.0, 0.8 * half)):
            y = centre[1] + off
            out.append((f"x{k + 1}-z{level + 1}", np.array([centre[0] - half, y, z,
                                                            centre[0] + half, y, z])))
            x = centre[0] + off
            out.append((f"y{k + 1}-z{level + 1}", np.array([x, centre[1] - half, z,
                                                            x, centre[1] + half, z])))
    return out


def simulate_part(true_machine, nominal, rng: np.random.Generator, *, sections: int = 200,
                  noise: Any = "cmm", paths: list | None = None,
                  placement: np.ndarray | None = None, source: str = "simulated part"
                  ) -> MeasurementSet:
    """A machined part measured on a CMM (seed 003): each commanded line is cut by the true
    machine under the nominal controller; the tool centre is measured in sections (about
    ``sections`` in all, spread over the lines) in the part frame, whose placement on the
    machine ``(Δx, Δy, Δz, φ)`` is unknown (default: 0.2 m below-left of the box centre,
    turned 0.3°)."""
    model = noise if isinstance(noise, Noise) else Noise.parse(noise, "part")
    paths = part_paths(nominal) if paths is None else paths
    if placement is None:
        corner = np.asarray(nominal.default_box()[0], dtype=float)[:3]
        placement = np.array([*corner, np.radians(0.3)])
    per_path = max(3, sections // len(paths))
    labels, commanded, measured = [], [], []
    c, s = np.cos(placement[3]), np.sin(placement[3])
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    for label, seg in paths:
        t = np.linspace(0.05, 0.95, per_path)
        targets = seg[:3] + t[:, None] * (seg[3:] - seg[:3])
        q = commanded_q(nominal, targets)
        real = reached(true_machine, q)
        if not np.isfinite(real).all():
            raise InputError(f"path {label}: the true machine cannot follow it")
        part = (real[:, :3] - placement[:3]) @ rz
        part = part + rng.standard_normal(part.shape) * model.position_sigma(part)[:, None]
        labels += [label] * per_path
        commanded.append(np.tile(seg, (per_path, 1)))
        measured.append(part)
    return MeasurementSet(kind="part", values=np.concatenate(measured), path=tuple(labels),
                          commanded=np.concatenate(commanded), source=source)
