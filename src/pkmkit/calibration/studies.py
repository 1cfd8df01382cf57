"""The seed reproductions of docs/calibration.md, as functions (the demo and the docs' figure
script call them; the tests call them small).

- :func:`tripteor_laser_tracker` — seed 002's protocol on the Tripteor X7: poses within Table
  5.3's joint ranges (platform-only and wrist-only moves), two tools, tracker noise, readings
  in the tracker's frame registered from four points and two-tool directions (Table 5.4's
  procedure; pkmkit's fit of the thesis's own four points gives 0.085 mm rms, a figure the thesis
  does not print), the frame then identified with the
  machine; compared with the thesis's residuals and baselines; and the thesis's own parameter
  set (Table 5.5) identified the thesis's way — finite differences, no identifiability
  analysis — to show where its 10.5° J41 comes from;
- :func:`verne_ballbar` and :func:`verne_part` — seed 003's module: the ball-bar procedure
  and the machined-part procedure (contours and slots along x and y, CMM sections, unknown
  part placement, joint-space error), then a validation part machined with and without
  compensation (< 0.02 mm along x, < 0.04 mm along y in the seed);
- :func:`delta_height_probe` — a linear Delta probed on its bed: which factors are
  identifiable (rod lengths vs radius) and the flatness achieved after compensation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.calibration.compensation import check_compensation
from pkmkit.calibration.controller import commanded_q, corrected_targets, reached
from pkmkit.calibration.diagnosis import calibrate
from pkmkit.calibration.identify import CalibrationResult, identification_problem
from pkmkit.calibration.registration import Registration, register_points
from pkmkit.calibration.simulate import (
    NOISE_SIGMA,
    SEED_TOOLS,
    Noise,
    default_configurations,
    part_paths,
    random_defects,
    simulate,
)
from pkmkit.model.defect_rule import add_defects
from pkmkit.model.measurement_set import MeasurementSet
from pkmkit.progress import tracked

#: Seed 002's results (m): identification and validation residuals (L2003, L2015) and the
#: baselines of Kang's data (neural network, Puchtler's model).
THESIS_TRIPTEOR = {"identification (thesis)": (21.6e-6, 48.1e-6),
                   "validation (thesis)": (44.1e-6, 77.9e-6),
                   "neural network (Kang)": (98.6e-6, 272.0e-6),
                   "Puchtler model (Kang)": (74.3e-6, 125.9e-6)}
#: Seed 002's Table 5.5 (52 parameters) in pkmkit's names: ``None`` for the 9 positions along
#: a joint's own axis, which a minimal parametrisation does not have (they are gauges of the
#: joint variables: notes §6.5).
TABLE_5_5 = {
    "J21": "dJ21", "A21": None, "B21": "db21", "C21": "dc21", "J41": "dJ41", "A51": "da51",
    "B51": None, "C51": "dc51",
    "J12": "dJ12", "K12": "dK12", "A12": None, "B12": "db12", "C12": "dc12",
    "J22": "dJ22", "K22": "dK22", "A22": None, "B22": "db22", "C22": "dc22",
    "J32": "dJ32", "K32": "dK32", "A32": None, "B32": "db32", "C32": "dc32",
    "I52": "dI52", "K52": "dK52", "A52": "da52", "B52": None, "C52": "dc52",
    "J62": "dJ62", "A62": "da62", "B62": "db62", "C62": "dc62",
    "A13": "da13", "C13": "dc13", "J23": "dJ23", "A23": None, "B23": "db23", "C23": "dc23",
    "J43": "dJ43", "A53": "da53", "B53": None, "C53": "dc53",
    "A63": "da63", "B63": "db63", "C63": "dc63",
    "A6": "da6", "B6": "db6", "I7": "dI7", "K7": "dK7", "A7": "da7", "B7": None, "C7": "dc7",
}
#: The tracker frame of the studies: Table 5.4's registration (tracker → controller frame),
#: rotation matrix and translation (m), from pkmkit register on the thesis's four points.
TABLE_5_4_ROTATION = np.array([[-0.99143, -0.13046, 0.00611], [0.00438, 0.01358, 0.99990],
                               [-0.13053, 0.99136, -0.01289]])
TABLE_5_4_TRANSLATION = np.array([0.799111, -0.007298, -2.643210])
#: σ per coordinate of the studies' tracker readings (m): ±(15 µm + 6 µm/m × 2.5 m) read as a
#: 2σ bound (``simulate``'s ``tracker`` noise).
TRACKER_SIGMA = 15e-6


def _orthonormal(rot: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(rot)
    return u @ vt


def tracker_frame() -> Registration:
    """Tracker → machine frame of the studies (Table 5.4's transform)."""
    return Registration(_orthonormal(TABLE_5_4_ROTATION), TABLE_5_4_TRANSLATION,
                        np.zeros((0, 3)), np.zeros(0))


@dataclass
class TripteorStudy:
    """Outcome of :func:`tripteor_laser_tracker` (SI)."""

    result: CalibrationResult
    registration: Registration
    compensation: Any
    data: MeasurementSet | None = None
    validation: MeasurementSet | None = None
    thesis_set: CalibrationResult | None = None
    thesis_way: dict[str, Any] = field(default_factory=dict)
    truth: np.ndarray | None = None

    def summary(self, scale: float = 1e-3) -> dict[str, Any]:
        """JSON-ready numbers (lengths divided by ``scale``; default mm)."""
        r = self.result
        out = {
            "poses": {"identification": int(r.after.per_pose.size),
                      "validation": int(r.validation.after.per_pose.size)},
            "registration_rms": self.registration.rms / scale,
            # pkmkit's fit of Table 5.4's four real points (the thesis prints no residual)
            "registration_rms_table_5_4": 0.085e-3 / scale,
            "identified": len(r.names), "rank": r.rank, "condition": r.condition,
            "seconds": r.seconds,
            "identification": {"mean_before": r.before.mean / scale,
                               "mean": r.after.mean / scale, "max": r.after.max / scale},
            "validation": {"mean_before": r.validation.before.mean / scale,
                           "mean": r.validation.after.mean / scale,
                           "max": r.validation.after.max / scale},
            "thesis": {k: {"mean": v[0] / scale, "max": v[1] / scale}
                       for k, v in THESIS_TRIPTEOR.items()},
            "compensation": self.compensation.to_dict(scale),
            "unidentifiable_no_effect": sorted(n for n, why in r.unidentifiable.items()
                                               if why.startswith("no effect")),
        }
        if self.thesis_set is not None:
            t = self.thesis_set
            out["thesis_set"] = {"candidates": t.candidates, "identified": len(t.names),
                                 "identification_mean": t.after.mean / scale,
                                 "validation_mean": t.validation.after.mean / scale,
                                 "J41": t.unidentifiable.get("dJ41", "identified")}
        if self.thesis_way:
            out["thesis_way"] = self.thesis_way
        return out


def _registration_measurements(true_machine, nominal, rng, frame: Registration,
                               noise_sigma: float):
    """Four registration points as Table 5.4 (two pairs ~10 mm apart: the long tool's tip at
    two head orientations, and the spindle direction from the two tools) in the tracker frame
    and in the controller's (nominal) frame. The directions follow Table 5.4's convention
    (docs/tripteor-x7.md §4): short-tool tip minus long-tool tip in the tracker frame, the
    tip-to-spindle unit vector (minus the tool axis) in the controller's frame."""
    home = nominal.home_q
    q = np.tile(home, (4, 1))
    q[1, 3], q[1, 4] = np.radians(-15.0), np.radians(55.0)
    q[2, :3] += [0.006, -0.006, 0.006]
    q[3, :3] += [0.006, -0.006, 0.006]
    q[3, 3], q[3, 4] = np.radians(-15.0), np.radians(55.0)
    long_, short = SEED_TOOLS
    tip_true = true_machine.fk(q, tool_length=long_)[:, :3]
    tip_short = true_machine.fk(q, tool_length=short)[:, :3]
    inverse = frame.inverse()
    measured = inverse.apply(tip_true + rng.standard_normal((4, 3)) * noise_sigma)
    measured_short = inverse.apply(tip_short + rng.standard_normal((4, 3)) * noise_sigma)
    nominal_pose = nominal.fk(q, tool_length=long_)
    return (measured, nominal_pose[:, :3], measured_short - measured, -nominal_pose[:, 3:])


def tripteor_laser_tracker(*, seed: int = 7, identification: int = 107, validation: int = 30,
                           thesis_set: bool = True, thesis_way: bool = False,
                           machine=None, noise_scale: float = 1.0) -> TripteorStudy:
    """Seed 002's laser-tracker protocol on synthetic data (module docstring).

    Args:
        seed: random seed (defects, poses, noise).
        identification, validation: numbers of poses (the seed: 107 and 30).
        noise_scale: multiplies the tracker noise (σ = 15 µm per coordinate) of the readings
            and of the registration points; the random draws are the same at every scale.
        thesis_set: also identify the thesis's Table 5.5 parameters (least-squares closure,
            pkmkit's identifiability analysis).
        thesis_way: also identify Table 5.5 the thesis's way: every parameter, finite
            differences, no identifiability analysis (slow: about a minute).
    """
    import pkmkit

    m = machine if machine is not None else pkmkit.machine("tripteor-x7")
    rng = np.random.default_rng(seed)
    delta = random_defects(m, rng)
    true = add_defects(m, delta)
    frame = tracker_frame()
    n = identification + validation
    q = default_configurations(m, n, rng)
    order = rng.permutation(n)
    data = simulate(true, m, "point", n, rng, q=q[order], noise=Noise("tracker", scale=noise_scale),
                    frame=frame)
    ident, valid = data.subset(np.arange(identification)), data.subset(
        np.arange(identification, n))
    measured, nominal, dm, dn = _registration_measurements(true, m, rng, frame,
                                                           8e-6 * noise_scale)
    reg = register_points(measured, nominal, measured_directions=dm, nominal_directions=dn)
    result = calibrate(m, ident, validation=valid, frame=(reg, "identify"))
    targets = reached(true, valid.q, valid.tool_length)
    compensation = check_compensation(true, m, result.machine, targets,
                                      tool_length=float(SEED_TOOLS[0]))
    study = TripteorStudy(result=result, registration=reg, compensation=compensation,
                          truth=delta, data=ident, validation=valid)
    names = [v for v in TABLE_5_5.values() if v is not None]
    if thesis_set:
        study.thesis_set = calibrate(m, ident, validation=valid, frame=(reg, "identify"),
                                     parameters=names, compatible=False)
    if thesis_way:
        study.thesis_way = thesis_way_identification(m, ident, names, reg)
    return study


def tripteor_noise_sweep(scales: tuple[float, ...] = (0.0, 1.0, 2.0), **kwargs: Any
                         ) -> list[dict[str, float]]:
    """:func:`tripteor_laser_tracker` with its tracker noise multiplied by each of ``scales``
    (same defects, poses and random draws): what the synthetic residuals are made of. The
    identified model is the seed's whole model, so the residual is the noise that the fit
    cannot absorb plus the few weakly identifiable defects left at nominal (the floor at
    scale 0).

    Args:
        scales: noise multipliers (1 = σ 15 µm per coordinate).
        kwargs: passed to :func:`tripteor_laser_tracker` (``seed``, ``identification``,
            ``validation``, ``machine``).

    Returns:
        one row per scale (SI): ``scale``, ``sigma`` (m per coordinate), ``identified``
        (parameters), ``identification_mean``, ``identification_max``, ``validation_mean``,
        ``validation_max`` (tool-point errors after calibration, m).
    """
    rows = []
    for scale in tracked(scales, total=len(scales), label="noise sweep", unit="level"):
        r = tripteor_laser_tracker(noise_scale=scale, thesis_set=False, **kwargs).result
        rows.append({"scale": float(scale), "sigma": float(scale) * TRACKER_SIGMA,
                     "identified": len(r.names),
                     "identification_mean": r.after.mean, "identification_max": r.after.max,
                     "validation_mean": r.validation.after.mean,
                     "validation_max": r.validation.after.max})
    return rows


def noise_sweep_table(rows: list[dict[str, float]]) -> str:
    """:func:`tripteor_noise_sweep`'s rows as a text table (µm), with the mean length of the
    3-D noise vector alone, σ·sqrt(8/π), for comparison."""
    lines = ["noise  σ (µm)  |noise| mean  identification mean / max  validation mean / max"]
    for r in rows:
        um = {k: v * 1e6 for k, v in r.items() if k not in ("scale", "identified")}
        alone = um["sigma"] * np.sqrt(8.0 / np.pi)
        lines.append(f"{r['scale']:.0f}×  {um['sigma']:6.1f}  {alone:11.1f}  "
                     f"{um['identification_mean']:19.1f} / {um['identification_max']:5.1f}  "
                     f"{um['validation_mean']:15.1f} / {um['validation_max']:5.1f}")
    return "\n".join(lines)


def _refit(problem, u: np.ndarray, free: np.ndarray, iterations: int = 30) -> np.ndarray:
    """``u`` with its entries ``free`` fitted again by Levenberg–Marquardt steps on the analytic
    Jacobian (damping scaled by the column norms; minimum-norm steps, the columns may be rank
    deficient), until the cost stops decreasing by more than 1e-10 of itself."""
    u = u.copy()
    r = problem.residual(u)
    damping = 1e-3
    for _ in range(iterations):
        jac = problem.jacobian(u)[:, free]
        norms = np.linalg.norm(jac, axis=0)
        norms = np.where(norms > 0, norms, 1.0)
        while damping < 1e12:
            a = np.vstack([jac, np.sqrt(damping) * np.diag(norms)])
            step = np.linalg.lstsq(a, np.concatenate([-r, np.zeros(free.size)]),
                                   rcond=None)[0]
            trial = u.copy()
            trial[free] += step
            r_trial = problem.residual(trial)
            if np.isfinite(r_trial).all() and r_trial @ r_trial < r @ r:
                break
            damping *= 10.0
        else:
            return u
        gain = r @ r - r_trial @ r_trial
        u, r, damping = trial, r_trial, max(damping / 10.0, 1e-9)
        if gain < 1e-10 * (r @ r):
            break
    return u


#: Relative size below which a singular value or a column norm is round-off (the ranks of
#: :func:`thesis_way_identification`).
ROUND_OFF = 1e-12
THESIS_GAUGES = ("dJ21", "dJ41", "dJ12", "dK12", "dJ22", "dK22", "dJ32", "dK32", "dJ23", "dJ43")


def thesis_way_identification(machine, data: MeasurementSet, names: list[str],
                              registration: Registration, *, max_nfev: int = 60
                              ) -> dict[str, Any]:
    """Identify ``names`` as seed 002 did: every parameter kept, the least-squares closure,
    finite-difference Jacobians (``scipy.optimize.least_squares``, trust region, at most
    ``max_nfev`` iterations), no identifiability analysis; then what that hides. Ranks
    count the singular values above :data:`ROUND_OFF` times the largest.

    Returns a JSON-ready dict: ``parameters``, ``evaluations`` (iterations used; equal to
    ``max_nfev`` when the solver stopped at its limit), ``nominal_zero_columns`` (names whose
    analytic column is zero to round-off, :data:`ROUND_OFF` of the largest, at the start: the
    nominal geometry), ``nominal_rank`` (the analytic Jacobian's there), ``fd_rank`` and
    ``fd_condition`` (the finite-difference Jacobian of the solver's last step), ``analytic_rank``
    and ``analytic_condition`` (the analytic Jacobian at the solution), ``angles_deg`` (the
    solution's :data:`THESIS_GAUGES`, degrees), ``rms`` (whitened residual RMS of the
    solution, units of σ), ``rms_reset`` and ``residual_change_when_reset`` (the same with
    the gauges set to zero and nothing else changed: RMS and largest change, σ), ``rms_refit``
    (the gauges at zero and every other parameter fitted again with the analytic Jacobian:
    what the data say without them).
    """
    from scipy.optimize import least_squares

    from pkmkit.calibration.identify import single_threaded_blas

    problem = identification_problem(machine, data, parameters=names, frame=registration,
                                     compatible=False, rcond=1e-30, prune=False)
    gauges = [problem.names.index(g) for g in THESIS_GAUGES]
    free = np.setdiff1d(np.arange(len(problem.names)), gauges)

    def rank_condition(jac: np.ndarray) -> tuple[int, float]:
        sv = np.linalg.svd(jac, compute_uv=False)
        return int((sv > ROUND_OFF * sv[0]).sum()), float(sv[0] / sv[-1])

    with single_threaded_blas():
        start = problem.jacobian(problem.u0)
        norms = np.linalg.norm(start, axis=0)
        zero = [problem.names[k] for k in np.flatnonzero(norms <= ROUND_OFF * norms.max())]
        nominal_rank, _ = rank_condition(start)
        sol = least_squares(problem.residual, problem.u0, jac="2-point", method="trf",
                            xtol=1e-8, ftol=1e-8, max_nfev=max_nfev)
        fd_rank, fd_condition = rank_condition(sol.jac)
        analytic_rank, analytic_condition = rank_condition(problem.jacobian(sol.x))
        values = dict(zip(problem.names, sol.x * problem.scale, strict=True))
        reset = sol.x.copy()
        reset[gauges] = 0.0
        r0, r1 = problem.residual(sol.x), problem.residual(reset)

        refit = _refit(problem, reset, free)

    def rms(r: np.ndarray) -> float:
        return float(np.sqrt(np.mean(r**2)))

    return {
        "parameters": len(names),
        "evaluations": int(sol.nfev),
        "nominal_zero_columns": zero,
        "nominal_rank": nominal_rank,
        "fd_rank": fd_rank, "fd_condition": fd_condition,
        "analytic_rank": analytic_rank, "analytic_condition": analytic_condition,
        "angles_deg": {g: float(np.degrees(np.arcsin(np.clip(values[g], -1, 1))))
                       for g in THESIS_GAUGES},
        "rms": rms(r0), "rms_reset": rms(r1),
        "residual_change_when_reset": float(np.abs(r1 - r0).max()),
        "rms_refit": rms(problem.residual(refit)),
    }


@dataclass
class PartStudy:
    """Outcome of :func:`verne_part` / :func:`verne_ballbar` (SI)."""

    result: CalibrationResult
    machined: dict[str, dict[str, float]]
    data: MeasurementSet | None = None
    validation: MeasurementSet | None = None

    def summary(self, scale: float = 1e-3) -> dict[str, Any]:
        r = self.result
        return {
            "identified": len(r.names), "rank": r.rank, "condition": r.condition,
            "seconds": r.seconds,
            "identification": {"rms_before": r.before.rms / scale, "rms": r.after.rms / scale},
            "validation": {"rms_before": r.validation.before.rms / scale,
                           "rms": r.validation.after.rms / scale},
            "machined": {k: {kk: vv / scale for kk, vv in v.items()}
                         for k, v in self.machined.items()},
            "seed_targets": {"x": 0.02e-3 / scale, "y": 0.04e-3 / scale},
        }


def machined_errors(true_machine, nominal, identified, *, levels: int = 3,
                    points: int = 30) -> dict[str, dict[str, float]]:
    """A validation part machined by ``true_machine`` under the nominal controller, without and
    with compensation by ``identified``: the largest deviation of the machined lines along x
    (in y and z) and along y (in x and z) from the programmed ones, once the part is aligned
    on its programmed geometry (best rigid motion: a CMM measures a part in its own frame),
    on ``levels`` heights 40 mm apart."""
    from pkmkit.calibration.registration import register_points

    out = {}
    for label, ident in (("nominal", None), ("compensated", identified)):
        wanted, done, along = [], [], []
        for name, seg in part_paths(nominal, levels=levels, depth_step=0.04):
            t = np.linspace(0.05, 0.95, points)
            x = seg[:3] + t[:, None] * (seg[3:] - seg[:3])
            cmd = x if ident is None else corrected_targets(nominal, ident, x)
            done.append(reached(true_machine, commanded_q(nominal, cmd))[:, :3])
            wanted.append(x)
            along += [name[0]] * points
        wanted, done, along = np.concatenate(wanted), np.concatenate(done), np.array(along)
        dev = register_points(done, wanted).point_residuals
        out[label] = {"along_x": float(np.abs(dev[along == "x"][:, 1:]).max()),
                      "along_y": float(np.abs(dev[along == "y"][:, [0, 2]]).max())}
    return out


def verne_part(*, seed: int = 1, sections: int = 240, machine=None,
               noise_scale: float = 1.0) -> PartStudy:
    """Seed 003's machined-part procedure (module docstring); ``noise_scale`` multiplies the
    CMM noise (σ 1.5 µm), the random draws being the same at every scale."""
    import pkmkit

    m = machine if machine is not None else pkmkit.machine("verne")
    rng = np.random.default_rng(seed)
    true = add_defects(m, random_defects(m, rng))
    cmm = Noise("cmm", scale=noise_scale)
    part = simulate(true, m, "part", sections, rng, noise=cmm)
    check = simulate(true, m, "part", sections // 2, rng, noise=cmm)
    result = calibrate(m, part, validation=check)
    return PartStudy(result=result, machined=machined_errors(true, m, result.machine),
                     data=part, validation=check)


def verne_noise_sweep(scales: tuple[float, ...] = (0.0, 1.0, 2.0), **kwargs: Any) -> str:
    """:func:`verne_part` with its CMM noise multiplied by each of ``scales`` (same defects,
    part and draws), as a text table (µm): the identification's joint-space RMS and the
    compensated validation part's largest deviations along x and y. ``kwargs`` go to
    :func:`verne_part` (``seed``, ``sections``, ``machine``)."""
    lines = ["noise  σ (µm)  identification RMS  part along x  along y"]
    for scale in scales:
        study = verne_part(noise_scale=scale, **kwargs)
        done = study.machined["compensated"]
        sigma = scale * NOISE_SIGMA["cmm"] * 1e6
        lines.append(f"{scale:.0f}×  {sigma:6.2f}  {study.result.after.rms * 1e6:18.2f}  "
                     f"{done['along_x'] * 1e6:12.2f}  {done['along_y'] * 1e6:7.2f}")
    return "\n".join(lines)


def verne_ballbar(*, seed: int = 1, readings: int = 240, machine=None) -> PartStudy:
    """The Fatronik-style ball-bar procedure on the Verne-type module: two pivots, two tool
    lengths, a 150 mm bar; then the same machined validation part as :func:`verne_part`."""
    import pkmkit

    m = machine if machine is not None else pkmkit.machine("verne")
    rng = np.random.default_rng(seed)
    true = add_defects(m, random_defects(m, rng))
    tools = (0.0, 0.1)
    data = simulate(true, m, "ballbar", readings, rng, tool_lengths=tools)
    check = simulate(true, m, "ballbar", readings // 2, rng, tool_lengths=tools)
    result = calibrate(m, data, validation=check)
    return PartStudy(result=result, machined=machined_errors(true, m, result.machine),
                     data=data, validation=check)


@dataclass
class HeightStudy:
    """Outcome of :func:`delta_height_probe` (SI)."""

    result: CalibrationResult
    flatness: dict[str, float]
    trap: dict[str, str]
    two_heights: CalibrationResult | None = None
    maps: dict[str, tuple] = field(default_factory=dict)

    def summary(self, scale: float = 1e-3) -> dict[str, Any]:
        r = self.result
        out = {"identified": list(r.names), "rank": r.rank, "condition": r.condition,
               "identification": {"rms_before": r.before.rms / scale, "rms": r.after.rms / scale},
               "validation": {"rms_before": r.validation.before.rms / scale,
                              "rms": r.validation.after.rms / scale},
               "flatness": {k: v / scale for k, v in self.flatness.items()},
               "rod_length_radius": self.trap}
        if self.two_heights is not None:
            out["two_heights_identified"] = list(self.two_heights.names)
        return out


def bed_surface(true_machine, nominal, identified, *, radius: float, z: float, n: int = 25
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The surface the true machine's tool traces when the nominal controller commands the
    height ``z`` over a disc of ``radius`` (compensated by ``identified`` unless None): grids
    ``(x, y, height)`` ``(n, n)`` with the best-fit plane removed (a tilted bed is levelled,
    not compensated); NaN outside the disc."""
    grid = np.linspace(-radius, radius, n)
    xx, yy = np.meshgrid(grid, grid)
    inside = xx**2 + yy**2 <= radius**2 * (1 + 1e-12)
    pts = np.column_stack([xx[inside], yy[inside], np.full(inside.sum(), z)])
    cmd = pts if identified is None else corrected_targets(nominal, identified, pts)
    done = reached(true_machine, commanded_q(nominal, cmd))
    a = np.column_stack([np.ones(len(done)), done[:, 0], done[:, 1]])
    fit = np.linalg.lstsq(a, done[:, 2], rcond=None)[0]
    height = np.full(xx.shape, np.nan)
    height[inside] = done[:, 2] - a @ fit
    return xx, yy, height


def delta_height_probe(*, seed: int = 2, points: int = 60, machine=None) -> HeightStudy:
    """A linear Delta probed on a flat bed (the printer calibration): identification,
    validation on other probe points, and the flatness of the bed surface the machine traces
    at a constant commanded height — nominal controller vs compensated — over a dense grid of
    the probed disc (its best-fit plane removed: a tilted bed is levelled, not compensated).
    Also probing at two heights, which separates rod lengths from radii."""
    import pkmkit
    from pkmkit.calibration.simulate import bed_configurations

    m = machine if machine is not None else pkmkit.machine("linear-delta")
    rng = np.random.default_rng(seed)
    true = add_defects(m, random_defects(m, rng))
    q = bed_configurations(m, points, rng)
    data = simulate(true, m, "height", points, rng, q=q)
    check = simulate(true, m, "height", points // 2, rng, q=bed_configurations(m, points // 2,
                                                                                  rng))
    result = calibrate(m, data, validation=check)
    trap = {n: why for n, why in result.unidentifiable.items() if n.startswith("dL")}
    # flatness over the probed disc at the probing height
    z = float(np.mean(reached(m, q)[:, 2]))
    radius = float(np.max(np.linalg.norm(reached(m, q)[:, :2], axis=1)))
    maps = {label: bed_surface(true, m, ident, radius=radius, z=z)
            for label, ident in (("nominal", None), ("compensated", result.machine))}
    flat = {label: float(np.nanmax(h) - np.nanmin(h)) for label, (_, _, h) in maps.items()}
    # the same bed probed again 300 mm higher (on a gauge block of known height, read as a
    # height above the bed): the extra height separates rod lengths from radii
    probed = reached(m, bed_configurations(m, points, rng))
    probed[:, 2] += 0.3
    lifted = commanded_q(m, probed)
    two = simulate(true, m, "height", points, rng, q=lifted)
    both = MeasurementSet(kind="height", values=np.concatenate([data.values, two.values]),
                          q=np.concatenate([data.q, two.q]))
    return HeightStudy(result=result, flatness=flat, trap=trap,
                       two_heights=calibrate(m, both), maps=maps)
