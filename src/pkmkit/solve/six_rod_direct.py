"""Every real solution of the direct kinematics of a six-rod (Gough–Stewart 6-6) platform.

Given six base joint centres a_j (fixed frame), six platform joint centres b_j (platform frame)
and six rod lengths ℓ_j, find **every** real pose (p, R) with ``|p + R b_j − a_j| = ℓ_j``,
j = 1…6. A general 6-6 platform has 40 complex solutions, of which up to 40 can be real
(Dietmaier 1998).

Method (details in ``docs/full-pose.md``):

1. **Normalise** each configuration: base and platform points centred on their centroids, all
   lengths divided by a characteristic length L (largest centred joint radius or rod length).
2. **Study coordinates**: the rod equations become six quadrics in P⁷, plus the Study quadric
   and a random linear patch (:mod:`pkmkit.solve.study_rods`); a generic system has 40 finite
   solutions.
3. **Coefficient-parameter homotopy** from a stored generic complex system with its 40 known
   solutions (:mod:`pkmkit.solve.six_rod_start`) to every target configuration: 40 paths per
   configuration, each followed on its own by the compiled tracker
   (:mod:`pkmkit.solve.six_rod_kernel`) or all together by the NumPy reference
   (:mod:`pkmkit.solve.path_tracking`), with the same rules; end points are classified and
   checked for completeness, and configurations that fail a check are tracked again with
   tighter tolerances (:mod:`pkmkit.solve.six_rod_paths`).
4. **Real solutions**: self-conjugate regular end points (and nearly real singular ones) are
   converted to poses and refined by Gauss–Newton / Levenberg–Marquardt on the original rod
   equations in squared form (:func:`pkmkit.solve.least_squares.solve_least_squares`); a
   solution is kept when its rod-length residual is below ``tol · L`` and the refinement did
   not carry it away from its end point; coinciding solutions are merged and their number of
   paths reported as a multiplicity.

Poses follow the project's 6-DOF convention: ``(x, y, z, φx, φy, φz)`` = position (m) and
rotation vector (rad) of the platform frame in the fixed frame.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.numerics.jit import numba_available
from pkmkit.solve.least_squares import solve_least_squares
from pkmkit.solve.six_rod_paths import EndKind, EndPoints, pair_distance, track_configurations
from pkmkit.solve.six_rod_start import GENERIC_COUNT, load_start_system
from pkmkit.solve.study_rods import RodParameters, study_to_pose
from pkmkit.spatial.euler import rotvec_from_quat
from pkmkit.spatial.rotation import compose_rotvec, rotvec_to_matrix
from pkmkit.status import Status

#: Largest number of solutions (padding of the result arrays).
MAX_SOLUTIONS = GENERIC_COUNT
#: Largest relative imaginary part of a real candidate: regular and singular end points.
_IMAG_REGULAR, _IMAG_SINGULAR = 1e-6, 1e-3
#: Largest move of a candidate under real refinement (normalised units, radians).
_MOVE_REGULAR, _MOVE_SINGULAR = 1e-6, 1e-2
#: Two refined solutions closer than this are one (normalised units, radians); looser when
#: one of them comes from a singular end point (known only to about the square root of the
#: working precision).
_SAME_REGULAR, _SAME_SINGULAR = 1e-9, 1e-5


#: Result fields with one entry per solution (sorted together).
_PER_SOLUTION = ("poses", "residual", "condition", "multiplicity")


@dataclass(frozen=True)
class SixRodSolutions:
    """Every real solution of a batch of N six-rod direct problems (padded to K = 40).

    Shapes are given for a batched call; a single call (no argument with a batch axis) drops the
    leading N axis.

    Attributes:
        poses: ``(N, K, 6)`` position (m) and rotation vector (rad) of each real solution,
            sorted by decreasing z; NaN rows past ``count``.
        count: ``(N,)`` number of distinct real solutions.
        residual: ``(N, K)`` largest rod-length error ``| |p + R b_j − a_j| − ℓ_j |`` of each
            solution after refinement, m (NaN where unused).
        condition: ``(N, K)`` condition number of the 6×6 rod Jacobian (unit rod directions;
            moments divided by the characteristic length L) at each solution: large near a
            direct-kinematic (parallel) singularity, infinite on it.
        multiplicity: ``(N, K)`` number of homotopy paths that ended at each solution: 1 for an
            isolated simple solution, 2 or more for a multiple solution (singular
            configuration); 0 where unused.
        n_finite: ``(N,)`` paths ending at finite complex solutions (regular or singular),
            i.e. finite solutions counted with multiplicity: 40 for a general geometry.
        n_singular: ``(N,)`` of those, the paths ending at a singular point.
        n_infinite: ``(N,)`` paths whose translation diverged (solutions at infinity).
        n_exceptional: ``(N,)`` paths ending on the exceptional quadric ``e·e = 0`` of Study
            coordinates (spurious, not rigid displacements; special geometries such as
            coincident joints).
        n_failed: ``(N,)`` paths that could not be tracked to the end.
        path_ends: ``(N, 40)`` the class of each path's end (−1 for invalid rows),
            :class:`~pkmkit.solve.six_rod_paths.EndKind` codes (regular, singular, infinite,
            exceptional, failed): which paths failed or ended singular.
        path_steps: ``(N,)`` accepted path-tracking steps, all paths and retries together.
        status: ``(N,)`` :class:`~pkmkit.status.Status` codes:

            - ``OK``: every path accounted for and every check passed, at least one real
              solution: **the list is complete**;
            - ``NO_ASSEMBLY``: complete, and there is no real solution;
            - ``SINGULAR``: some path ended at a singular point (the configuration is at or
              near a singularity, or the geometry is degenerate), or a nearly real end point
              could not be confirmed by real refinement. Each returned solution is verified;
              multiple solutions appear once (see ``multiplicity``);
            - ``NOT_CONVERGED``: completeness **not** certified: a path failed, two paths
              ended at the same regular point, or a finite solution's complex conjugate was
              missing, even after re-tracking with tighter tolerances (``n_failed`` tells
              whether paths failed). Each returned solution is verified;
            - ``INVALID_INPUT``: non-finite values or a rod length ≤ 0 (nothing computed).
        characteristic_length: ``(N,)`` the length L used to normalise each configuration, m
            (NaN for invalid rows).
    """

    poses: np.ndarray
    count: np.ndarray
    residual: np.ndarray
    condition: np.ndarray
    multiplicity: np.ndarray
    n_finite: np.ndarray
    n_singular: np.ndarray
    n_infinite: np.ndarray
    n_exceptional: np.ndarray
    n_failed: np.ndarray
    path_ends: np.ndarray
    path_steps: np.ndarray
    status: np.ndarray
    characteristic_length: np.ndarray

    @property
    def valid(self) -> np.ndarray:
        """``(N, K)`` bool, the slots holding a solution."""
        return ~np.isnan(self.poses[..., 0])

    @property
    def complete(self) -> np.ndarray:
        """``(N,)`` bool: the list of real solutions is certified complete."""
        return (self.status == Status.OK) | (self.status == Status.NO_ASSEMBLY)


# ----------------------------------------------------------------------------- input


def _as_rows(value, name: str, tail: tuple[int, ...]) -> tuple[np.ndarray, bool]:
    """``(N, *tail)`` float array and whether the argument had a batch axis."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be an array of real numbers: {exc}") from None
    if arr.shape == tail:
        return arr[None], False
    if arr.ndim == len(tail) + 1 and arr.shape[1:] == tail:
        if arr.shape[0] == 0:
            raise InputError(f"{name} is an empty batch (shape {arr.shape})")
        return arr, True
    batch = "(N, " + ", ".join(map(str, tail)) + ")"
    raise InputError(f"{name} must have shape {tail} or {batch}; got {arr.shape}")


def _broadcast_inputs(base, platform, lengths):
    """Arrays ``(N, 6, 3)``, ``(N, 6, 3)``, ``(N, 6)`` and whether no argument was batched."""
    args = {
        "base": _as_rows(base, "base", (6, 3)),
        "platform": _as_rows(platform, "platform", (6, 3)),
        "lengths": _as_rows(lengths, "lengths", (6,)),
    }
    sizes = {name: arr.shape[0] for name, (arr, batched) in args.items() if batched}
    if len(set(sizes.values())) > 1:
        detail = ", ".join(f"{k}: {v}" for k, v in sizes.items())
        raise InputError(f"batch sizes of base, platform and lengths differ ({detail})")
    n = next(iter(sizes.values()), 1)
    a, b, ell = (np.ascontiguousarray(np.broadcast_to(arr, (n, *arr.shape[1:])))
                 for arr, _ in args.values())
    return a, b, ell, not sizes


@dataclass(frozen=True)
class _Normalised:
    """Centred, scaled configurations: ``a' = (a − c_a)/L``, ``b' = (b − c_b)/L``,
    ``ℓ' = ℓ/L``; a normalised pose ``p'`` maps back to ``p = L p' + c_a − R c_b``."""

    base: np.ndarray
    platform: np.ndarray
    lengths: np.ndarray
    centre_base: np.ndarray
    centre_platform: np.ndarray
    scale: np.ndarray

    @classmethod
    def of(cls, a: np.ndarray, b: np.ndarray, ell: np.ndarray) -> _Normalised:
        ca, cb = a.mean(axis=1), b.mean(axis=1)
        an, bn = a - ca[:, None], b - cb[:, None]
        scale = np.maximum(np.maximum(np.linalg.norm(an, axis=2).max(axis=1),
                                      np.linalg.norm(bn, axis=2).max(axis=1)), ell.max(axis=1))
        s = scale[:, None, None]
        return cls(an / s, bn / s, ell / scale[:, None], ca, cb, scale)

    def to_caller(self, poses: np.ndarray) -> np.ndarray:
        """Poses ``(C, K, 6)`` in the caller's frame and units (NaN rows stay NaN)."""
        out = poses.copy()
        ok = ~np.isnan(poses[..., 0])
        conf = np.nonzero(ok)[0]
        rot = rotvec_to_matrix(poses[ok][:, 3:])
        out[ok, :3] = (self.scale[conf, None] * poses[ok][:, :3] + self.centre_base[conf]
                       - np.einsum("kij,kj->ki", rot, self.centre_platform[conf]))
        return out


# ----------------------------------------------------------------------------- solver


def six_rod_direct_all(
    base,
    platform,
    lengths,
    *,
    tol: float = 1e-10,
    predictor_tol: float = 1e-3,
    retries: int = 1,
    compiled: bool | None = None,
) -> SixRodSolutions:
    """Every real pose of six-rod platforms with given joint centres and rod lengths.

    Args:
        base: ``(6, 3)`` or ``(N, 6, 3)`` base joint centres a_j in the fixed frame, m (per
            configuration: on slide machines they move with the actuators).
        platform: ``(6, 3)`` or ``(N, 6, 3)`` platform joint centres b_j in the platform frame,
            m.
        lengths: ``(6,)`` or ``(N, 6)`` rod lengths ℓ_j, m.
        tol: a real solution is kept when its refined rod-length residual is below
            ``tol · L`` (L: the configuration's characteristic length, see the result).
        predictor_tol: path-tracking accuracy (relative predictor error accepted per step);
            smaller is slower and safer.
        retries: how many times configurations that fail a completeness check are tracked
            again, each time with a 100× tighter ``predictor_tol``.
        compiled: track the paths with the compiled tracker (True) or the NumPy reference
            (False); None (default): compiled when Numba is installed, for two configurations
            or more or once Numba is imported, never under ``PKMKIT_COMPILED=0``
            (:func:`~pkmkit.solve.six_rod_paths.use_compiled_tracker`: a one-shot single call
            does not pay Numba's import). Both follow the same rules and give the same
            solutions.

    Returns:
        :class:`SixRodSolutions`.

    Raises:
        InputError: an argument has the wrong shape (the message names it and the expected
            shape), the batch sizes differ, an option is out of range, or ``compiled=True``
            without Numba. Non-finite values and rod lengths ≤ 0 flag their rows
            (``INVALID_INPUT``) instead.

    Example:
        >>> import numpy as np
        >>> from pkmkit.solve.six_rod_direct import six_rod_direct_all
        >>> def circle(radius, degrees):
        ...     ang = np.radians(degrees)
        ...     return radius * np.c_[np.cos(ang), np.sin(ang), np.zeros(6)]
        >>> a = circle(1.0, [0, 100, 120, 220, 240, 340])
        >>> b = circle(0.5, [50, 70, 170, 190, 290, 310])
        >>> lengths = np.linalg.norm(b + [0.0, 0.0, 1.0] - a, axis=1)  # platform 1 m up
        >>> sols = six_rod_direct_all(a, b, lengths)
        >>> int(sols.status), int(sols.count), int(sols.n_finite)
        (0, 8, 28)
        >>> sols.poses[0].round(6) + 0.0
        array([0., 0., 1., 0., 0., 0.])
    """
    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tol must be a positive number, got {tol!r}")
    if not (np.isfinite(predictor_tol) and 0 < predictor_tol < 1):
        raise InputError(f"predictor_tol must lie in (0, 1), got {predictor_tol!r}")
    if int(retries) != retries or retries < 0:
        raise InputError(f"retries must be a non-negative integer, got {retries!r}")
    if compiled and not numba_available():
        raise InputError("compiled=True needs Numba, which is not installed")
    a, b, ell, single = _broadcast_inputs(base, platform, lengths)
    n_rows = a.shape[0]
    with np.errstate(invalid="ignore"):
        valid = (np.isfinite(a).all(axis=(1, 2)) & np.isfinite(b).all(axis=(1, 2))
                 & np.isfinite(ell).all(axis=1) & (ell > 0).all(axis=1))
    out = _empty_result(n_rows)
    out["status"][~valid] = Status.INVALID_INPUT
    rows = np.flatnonzero(valid)
    if rows.size:
        geo = _Normalised.of(a[rows], b[rows], ell[rows])
        target = RodParameters.from_geometry(geo.base, geo.platform, geo.lengths)
        ends = track_configurations(load_start_system(), target, predictor_tol, retries,
                                    compiled)
        found = _real_solutions(ends, geo, tol)
        found["poses"] = geo.to_caller(found["poses"])
        found["residual"] = found["residual"] * geo.scale[:, None]
        found["characteristic_length"] = geo.scale
        order = np.argsort(np.where(np.isnan(found["poses"][..., 2]), np.inf,
                                    -found["poses"][..., 2]), axis=1, kind="stable")
        for name in _PER_SOLUTION:
            value = found[name]
            found[name] = np.take_along_axis(
                value, order.reshape(order.shape + (1,) * (value.ndim - 2)), axis=1)
        for name, value in found.items():
            out[name][rows] = value
    result = SixRodSolutions(**out)
    if single:
        result = SixRodSolutions(**{f.name: getattr(result, f.name)[0] for f in fields(result)})
    return result


def _empty_result(n_rows: int) -> dict[str, np.ndarray]:
    k = MAX_SOLUTIONS
    counts = ("count", "n_finite", "n_singular", "n_infinite", "n_exceptional", "n_failed",
              "path_steps")
    return {
        "poses": np.full((n_rows, k, 6), np.nan),
        "residual": np.full((n_rows, k), np.nan),
        "condition": np.full((n_rows, k), np.nan),
        "multiplicity": np.zeros((n_rows, k), dtype=int),
        "path_ends": np.full((n_rows, GENERIC_COUNT), -1),
        **{name: np.zeros(n_rows, dtype=int) for name in counts},
        "status": np.full(n_rows, int(Status.OK)),
        "characteristic_length": np.full(n_rows, np.nan),
    }


# ----------------------------------------------------------------------------- real solutions


def _real_solutions(ends: EndPoints, geo: _Normalised, tol: float) -> dict[str, np.ndarray]:
    """Real solutions (normalised poses) and diagnostics of C tracked configurations."""
    kind = ends.kind
    n_conf, n_paths = kind.shape
    regular, singular = kind == EndKind.REGULAR, kind == EndKind.SINGULAR
    found = {
        "n_finite": (regular | singular).sum(axis=1),
        "n_singular": singular.sum(axis=1),
        "n_infinite": (kind == EndKind.INFINITE).sum(axis=1),
        "n_exceptional": (kind == EndKind.EXCEPTIONAL).sum(axis=1),
        "n_failed": (kind == EndKind.FAILED).sum(axis=1),
        "path_ends": kind,
        "path_steps": ends.steps,
    }
    # real candidates: regular end points equal to their own conjugate (and nearer to it than
    # to any other end point); singular end points with a small imaginary part
    normal = ends.normal
    scale = np.maximum(1.0, np.nan_to_num(np.abs(normal).max(axis=2), nan=1.0))
    imag = np.nan_to_num(np.abs(normal.imag).max(axis=2), nan=np.inf) / scale
    to_conj = pair_distance(np.conj(normal), normal)
    diag = np.arange(n_paths)
    self_gap = to_conj[:, diag, diag].copy()
    to_conj[:, diag, diag] = np.inf
    candidate = (regular & (imag <= _IMAG_REGULAR) & (self_gap < to_conj.min(axis=2))) | (
        singular & (imag <= _IMAG_SINGULAR))
    conf, path = np.nonzero(candidate)

    poses = np.full((n_conf, n_paths, 6), np.nan)
    residual = np.full((n_conf, n_paths), np.nan)
    condition = np.full((n_conf, n_paths), np.nan)
    unconfirmed = np.zeros(n_conf, dtype=bool)
    if conf.size:
        position, quat = study_to_pose(normal[conf, path].real)
        unit = quat[:, [1, 2, 3, 0]] / np.linalg.norm(quat, axis=1)[:, None]  # (x, y, z, w)
        rotvec = rotvec_from_quat(unit)  # scipy's Rotation arithmetic, without scipy.spatial
        u0 = np.concatenate([position, rotvec], axis=1)
        is_sing = singular[conf, path]
        u, res, cond = _refine(u0, geo.base[conf], geo.platform[conf], geo.lengths[conf], tol)
        moved = _pose_gap(u, u0)
        ok = (res <= tol) & (moved <= np.where(is_sing, _MOVE_SINGULAR, _MOVE_REGULAR))
        unconfirmed[conf[~ok]] = True
        poses[conf[ok], path[ok]] = u[ok]
        residual[conf[ok], path[ok]] = res[ok]
        condition[conf[ok], path[ok]] = cond[ok]
    multiplicity, merged_regular = _merge_duplicates(poses, singular)

    status = np.full(n_conf, int(Status.OK))
    status[singular.any(axis=1) | unconfirmed | merged_regular] = Status.SINGULAR
    status[~ends.certified] = Status.NOT_CONVERGED
    keep = multiplicity > 0
    count = keep.sum(axis=1)
    status[(count == 0) & (status == Status.OK)] = Status.NO_ASSEMBLY
    # compact the kept solutions to the first slots
    order = np.argsort(~keep, axis=1, kind="stable")
    found["poses"] = np.take_along_axis(np.where(keep[..., None], poses, np.nan),
                                        order[..., None], axis=1)
    found["residual"] = np.take_along_axis(np.where(keep, residual, np.nan), order, axis=1)
    found["condition"] = np.take_along_axis(np.where(keep, condition, np.nan), order, axis=1)
    found["multiplicity"] = np.take_along_axis(multiplicity, order, axis=1)
    found["count"] = count
    found["status"] = status
    return found


def _merge_duplicates(poses: np.ndarray, singular: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge coinciding solutions of each configuration.

    Args:
        poses: ``(C, P, 6)`` normalised poses, NaN where no solution.
        singular: ``(C, P)`` whether each came from a singular end point.

    Returns:
        ``multiplicity (C, P)``: for the first solution of each group, the group's size; 0 for
        the others and for empty slots; and ``(C,)`` whether two solutions from regular end
        points were merged (then some solution was found twice).
    """
    have = ~np.isnan(poses[..., 0])
    gap = _pose_gap(poses[:, :, None], poses[:, None, :])
    gap = np.where(have[:, :, None] & have[:, None, :], gap, np.inf)
    loose = singular[:, :, None] | singular[:, None, :]
    same = gap <= np.where(loose, _SAME_SINGULAR, _SAME_REGULAR)
    n = poses.shape[1]
    earlier = np.tril(np.ones((n, n), dtype=bool), -1)  # j < i
    duplicate = (same & earlier).any(axis=2)
    first = np.argmax(same, axis=2)  # first member of each solution's group (itself if none)
    multiplicity = np.zeros(have.shape, dtype=int)
    conf, member = np.nonzero(have)
    np.add.at(multiplicity, (conf, first[conf, member]), 1)
    multiplicity[duplicate] = 0
    merged_regular = (same & earlier & ~loose).any(axis=(1, 2))
    return multiplicity, merged_regular


def _pose_gap(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Distance between normalised poses ``(..., 6)``: the largest of the position difference
    and the rotation difference ``‖R_u − R_v‖_F / √2`` (≈ the angle between them, radians)."""
    shape = np.broadcast_shapes(u.shape, v.shape)[:-1]
    uu = np.broadcast_to(u, (*shape, 6)).reshape(-1, 6)
    vv = np.broadcast_to(v, (*shape, 6)).reshape(-1, 6)
    ok = ~(np.isnan(uu).any(axis=1) | np.isnan(vv).any(axis=1))
    gap = np.full(uu.shape[0], np.nan)
    if ok.any():
        ru, rv = rotvec_to_matrix(uu[ok, 3:]), rotvec_to_matrix(vv[ok, 3:])
        rot = np.sqrt(((ru - rv) ** 2).sum(axis=(1, 2)) / 2.0)
        gap[ok] = np.maximum(np.abs(uu[ok, :3] - vv[ok, :3]).max(axis=1), rot)
    return gap.reshape(shape)


def _refine(u0: np.ndarray, a: np.ndarray, b: np.ndarray, ell: np.ndarray, tol: float):
    """Gauss–Newton / LM on ``(|d_j|² − ℓ_j²) / (2 ℓ_j) = 0`` from poses ``u0 (k, 6)``
    (normalised units; ``d_j = p + R b_j − a_j``).

    Returns the refined poses ``(k, 6)``, their rod-length residuals ``max_j ||d_j| − ℓ_j|``
    ``(k,)`` and the condition numbers of their rod Jacobians ``(k,)``.
    """
    a_t = a.transpose(2, 1, 0)  # (3, 6, k)
    b_t = b.transpose(2, 1, 0)
    ell_t = ell.T  # (6, k)

    def evaluate(u: np.ndarray, rows: np.ndarray):
        rot = rotvec_to_matrix(u[3:].T).transpose(1, 2, 0)  # (3, 3, k)
        rb = np.einsum("ijk,jmk->imk", rot, b_t[:, :, rows])
        d = u[:3, None] + rb - a_t[:, :, rows]
        half = 0.5 / ell_t[:, rows]
        r = ((d * d).sum(axis=0) - ell_t[:, rows] ** 2) * half
        jac = np.concatenate([d * half, np.cross(rb, d, axis=0) * half], axis=0)
        return r, jac.transpose(1, 0, 2)

    def retract(u: np.ndarray, step: np.ndarray, rows: np.ndarray) -> np.ndarray:
        out = u + step
        out[3:] = compose_rotvec(step[3:].T, u[3:].T).T
        return out

    u = solve_least_squares(evaluate, u0, retract=retract, max_iter=30, residual_tol=tol,
                            compute_rank=False).u
    rot = rotvec_to_matrix(u[:, 3:])
    rb = np.einsum("kij,kmj->kmi", rot, b)
    d = u[:, None, :3] + rb - a
    dist = np.linalg.norm(d, axis=2)
    res = np.abs(dist - ell).max(axis=1)
    unit = d / dist[:, :, None]
    jac = np.concatenate([unit, np.cross(rb, unit)], axis=2)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        cond = np.linalg.cond(jac)
    return u, np.nan_to_num(res, nan=np.inf), np.nan_to_num(cond, nan=np.inf)
