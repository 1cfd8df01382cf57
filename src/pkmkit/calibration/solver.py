"""The identification's least-squares solver: the scaled problem, a chord iteration then
Levenberg–Marquardt with stall and divergence detection, and the fit of set-up parameters."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.calibration.models import ResidualModel
from pkmkit.exceptions import ConvergenceError, ParameterError
from pkmkit.geometric_errors.model import defect_set
from pkmkit.model.defect_rule import add_defects
from pkmkit.status import Status


@dataclass
class ScaledProblem:
    """The least-squares problem in scaled unknowns u = θ / scale."""

    machine: Any
    model: ResidualModel
    basis: np.ndarray          # (d, p) machine unknowns → full defect vector
    setup_index: np.ndarray    # indices of the identified set-up parameters
    setup_base: np.ndarray     # (s,) values of every set-up parameter (unidentified ones kept)
    scale: np.ndarray          # (p + s_id,)
    prior: bool
    weights: np.ndarray        # (N,) robust weights
    evaluations: int = 0
    _last: tuple | None = None
    progress: Any = None       # a tqdm counter of model evaluations, or None
    #: (p,) |θ| of each machine unknown (SI) beyond which the identification has diverged
    #: (an accepted iterate there stops the solve, :class:`Diverged`), or None
    bound: np.ndarray | None = None

    @property
    def n_machine(self) -> int:
        return self.basis.shape[1]

    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        theta = u * self.scale
        setup = self.setup_base.copy()
        setup[self.setup_index] = theta[self.n_machine:]
        return self.basis @ theta[:self.n_machine], setup

    def machine_at(self, delta: np.ndarray):
        """The machine with ``delta`` added to its own defects (the last one is cached: a
        Jacobian is often evaluated where the last residual was)."""
        key = delta.tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        machine = add_defects(self.machine, delta)
        self._last = (key, machine)
        return machine

    def evaluate(self, u: np.ndarray, jacobian: bool = True):
        """Whitened residual ``(M,)``, Jacobian ``(M, p)`` in scaled unknowns (None without
        ``jacobian``) and the raw residual rows ``(N, w)``; ``(None, None, None)`` when the
        defects are not admissible."""
        self.evaluations += 1
        if self.progress is not None:
            self.progress.update(1)
        if jacobian and self.bound is not None and np.any(
                np.abs(u[:self.n_machine] * self.scale[:self.n_machine]) > self.bound):
            raise Diverged(np.array(u, dtype=float))  # an accepted iterate: linearised here
        delta, setup = self.unpack(u)
        try:
            m = self.machine_at(delta)
        except ParameterError:
            return None, None, None
        r, jd, js = self.model.residuals(m, setup, jacobian=jacobian)
        return self.assemble(u, r, jd, js)

    def assemble(self, u, r, jd, js):
        """Whitened, scaled residual and Jacobian from a model's raw ones (prior rows
        appended)."""
        w = np.sqrt(self.weights)[:, None] / self.model.sigma
        rw = (r * w).reshape(-1)
        if self.prior:
            rw = np.concatenate([rw, u[:self.n_machine]])
        if jd is None:
            return rw, None, r
        jac = np.concatenate([jd @ self.basis, js[:, :, self.setup_index]], axis=2)
        jw = (jac * w[:, :, None]).reshape(len(r) * r.shape[1], -1) * self.scale[None, :]
        if self.prior:
            jp = np.zeros((self.n_machine, len(u)))
            jp[:, :self.n_machine] = np.eye(self.n_machine)
            jw = np.concatenate([jw, jp])
        return rw, jw, r


#: A whitened residual norm below this is an exact fit.
EXACT = 1e-9
#: A decrease of the whitened squared residual below this per row over :data:`STALL`
#: evaluations is no progress.
NEGLIGIBLE = 1e-9
STALL = 12
#: A whitened residual row that cannot be evaluated (the machine does not assemble at a trial
#: point) counts as this: the step is rejected.
UNASSEMBLED = 1e8


@dataclass
class Solution:
    """What :func:`solve_scaled` found: the scaled unknowns ``u``, iterations, a
    :class:`~pkmkit.status.Status` code, and the whitened residual, Jacobian and raw residual
    rows at ``u`` (None where not evaluated)."""

    u: np.ndarray
    iterations: int
    status: int
    rw: np.ndarray | None
    jw: np.ndarray | None
    r: np.ndarray | None


def _finite(*arrays) -> bool:
    return all(a is not None and np.isfinite(a).all() for a in arrays)


#: Rounds of the chord stage of :func:`solve_scaled`, iterations per round, and its convergence
#: test on the gradient cosines.
CHORD_ROUNDS = 4
ROUND_ITER = 3
COSINE_TOL = 1e-6


def _cosines(rw: np.ndarray, jw: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.abs(jw.T @ rw) / (np.linalg.norm(jw, axis=0) * np.linalg.norm(rw))
    return np.nan_to_num(c, nan=0.0)


def solve_scaled(problem: ScaledProblem, u0: np.ndarray, max_iter: int,
                 start: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> Solution:
    """Least squares in two stages: a fast chord stage, then Levenberg–Marquardt if needed.

    1. :func:`_solve_chord` — the batched engine's Levenberg–Marquardt with the Jacobian
       frozen for a few iterations (defects are small: the Jacobian barely changes, and
       residual-only evaluations are cheap), refreshed between rounds; it usually reaches the
       optimum of a noisy calibration in two rounds;
    2. if the gradient cosines ``|Jᵀr|_j / (‖J_j‖ ‖r‖)`` are not all below
       :data:`COSINE_TOL` (ill-conditioned or exact-fit problems, where a frozen Jacobian
       crawls), :func:`_solve_lm` takes over from there.

    An accepted iterate beyond ``problem.bound`` (defects no built machine has) stops both:
    status NOT_CONVERGED at that iterate, no residual.
    """
    try:
        return _solve_stages(problem, u0, max_iter, start)
    except Diverged as exc:
        return Solution(exc.u, problem.evaluations, int(Status.NOT_CONVERGED), None, None, None)


class Diverged(Exception):
    """An accepted iterate (where a Jacobian is evaluated) beyond the problem's bound: the
    identification walks the defects away (readings no plausible machine fits)."""

    def __init__(self, u: np.ndarray):
        self.u = u
        super().__init__("the identification diverged")


def _solve_stages(problem: ScaledProblem, u0: np.ndarray, max_iter: int,
                  start: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> Solution:
    sol = _solve_chord(problem, u0, start, max_iter)
    if sol.status != Status.OK:
        if sol.rw is None:
            return sol
        sol = Solution(u0, sol.iterations, int(Status.OK), *(start or problem.evaluate(
            u0, jacobian=True)))
    if float(sol.rw @ sol.rw) <= EXACT**2 or not (_cosines(sol.rw, sol.jw) > COSINE_TOL).any():
        return sol
    if sol.iterations >= max_iter:
        return Solution(sol.u, sol.iterations, int(Status.NOT_CONVERGED), sol.rw, sol.jw,
                         sol.r)
    out = _solve_lm(problem, sol.u, max_iter - sol.iterations, (sol.rw, sol.jw, sol.r))
    return Solution(out.u, out.iterations + sol.iterations, out.status, out.rw, out.jw, out.r)


def _solve_chord(problem: ScaledProblem, u0: np.ndarray,
                 start: tuple[np.ndarray, np.ndarray, np.ndarray] | None,
                 max_iter: int) -> Solution:
    """Rounds of :data:`ROUND_ITER` engine iterations on residual-only evaluations with the
    Jacobian of the round's start."""
    from pkmkit.solve.least_squares import solve_least_squares

    u = np.array(u0, dtype=float)
    rw, jw, r = start if start is not None else problem.evaluate(u, jacobian=True)
    if not _finite(rw, jw):
        return Solution(u, 0, int(Status.INVALID_INPUT), None, None, r)
    total, m = 0, len(rw)
    for _ in range(CHORD_ROUNDS):
        if float(rw @ rw) <= EXACT**2 or not (_cosines(rw, jw) > COSINE_TOL).any():
            break
        frozen = jw[:, :, None]

        def evaluate(uu, rows, frozen=frozen):
            res, _, _ = problem.evaluate(uu[:, 0], jacobian=False)
            if res is None or not np.isfinite(res).all():
                return np.full((m, 1), np.nan), np.full_like(frozen, np.nan)
            return res[:, None], frozen

        if total >= max_iter:
            break
        res = solve_least_squares(evaluate, u[None], max_iter=min(ROUND_ITER, max_iter - total),
                                  xtol=1e-10,
                                  atol=EXACT, gtol=COSINE_TOL / 10, residual_tol=np.inf,
                                  damping=1e-8, stall=1e-12, compute_rank=False)
        total += int(res.iterations[0])
        if not np.isfinite(res.u[0]).all():
            break
        step = float(np.linalg.norm(res.u[0] - u))
        new = problem.evaluate(res.u[0], jacobian=True)
        if not _finite(new[0], new[1]):
            break
        u, (rw, jw, r) = res.u[0], new
        if step <= 1e-10 * (1.0 + float(np.linalg.norm(u))):
            break
    return Solution(u, total, int(Status.OK), rw, jw, r)


def _solve_lm(problem: ScaledProblem, u0: np.ndarray, max_iter: int,
              start: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> Solution:
    """Levenberg–Marquardt (MINPACK, via :func:`scipy.optimize.least_squares`) on the whitened
    residual with its analytic Jacobian: residuals at trial points, the Jacobian at accepted
    points only. (The batched engine of :mod:`pkmkit.solve` is built for many small problems;
    this is one dense, often ill-conditioned problem, for which MINPACK's trust-region damping
    is the proven tool.) A trial point where the machine does not assemble gets a huge
    residual, so the step is rejected and the damping raised.

    ``start``: ``(rw, jw, r)`` already evaluated at ``u0``.
    """
    from scipy.optimize import least_squares

    u0 = np.array(u0, dtype=float)
    rw0, jw0, r0 = start if start is not None else problem.evaluate(u0, jacobian=True)
    if not _finite(rw0, jw0):
        return Solution(u0, 0, int(Status.INVALID_INPUT), rw0, jw0, r0)
    if u0.size == 0:
        return Solution(u0, 0, int(Status.OK), rw0, jw0, r0)
    m = len(rw0)
    cache = {u0.tobytes(): (rw0, jw0, r0)}

    def fun(u):
        key = u.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = problem.evaluate(u, jacobian=False)
        rw = cache[key][0]
        if rw is None:
            return np.full(m, UNASSEMBLED)
        return np.where(np.isfinite(rw), rw, UNASSEMBLED)

    def jac(u):
        key = u.tobytes()
        hit = cache.get(key)
        if hit is None or hit[1] is None:
            cache.clear()
            cache[key] = problem.evaluate(u, jacobian=True)
        jw = cache[key][1]
        if jw is None or not np.isfinite(jw).all():
            raise _Unassembled(cache[key][2])
        return jw

    if m < u0.size:  # MINPACK needs at least as many rows as unknowns
        return Solution(u0, 0, int(Status.INVALID_INPUT), rw0, jw0, r0)
    # MINPACK's tests are relative; a residual with a floor (an exact fit down to the inner
    # closures' accuracy) would crawl: stop when the best cost has not dropped by a
    # statistically meaningful amount (NEGLIGIBLE per row) over STALL evaluations
    history = {"best": float(rw0 @ rw0), "u": u0.copy(), "since": 0, "mark": float(rw0 @ rw0)}

    def watched(u):
        out = fun(u)
        cost = float(out @ out)
        if cost < history["best"]:
            history["best"], history["u"] = cost, u.copy()
        history["since"] += 1
        if history["since"] >= STALL:
            if history["mark"] - history["best"] <= NEGLIGIBLE * m:
                raise _Stalled()
            history["since"], history["mark"] = 0, history["best"]
        return out

    try:
        sol = least_squares(watched, u0, jac=jac, method="lm", xtol=1e-10, ftol=1e-12,
                            gtol=1e-10, max_nfev=max_iter * 10)
        u, status, iterations = sol.x, sol.status, int(sol.njev or sol.nfev)
    except _Unassembled as exc:
        return Solution(u0, 0, int(Status.NO_ASSEMBLY), None, None, exc.residuals)
    except _Stalled:
        u, status, iterations = history["u"], 1, STALL
    rw, jw, r = problem.evaluate(u, jacobian=True)
    if status <= 0 or not _finite(rw, jw):
        status = Status.NOT_CONVERGED if _finite(rw, jw) else Status.NO_ASSEMBLY
        return Solution(u, iterations, int(status), rw, jw, r)
    return Solution(u, iterations, int(Status.OK), rw, jw, r)


class _Stalled(Exception):
    pass


class _Unassembled(Exception):
    def __init__(self, residuals):
        self.residuals = residuals
        super().__init__("the machine does not assemble")


def problem_rows(problem: ScaledProblem) -> int:
    """Rows of ``problem``'s whitened residual (readings, then prior rows)."""
    m = len(problem.model.data) * problem.model.width
    return m + (problem.n_machine if problem.prior else 0)


def fit_setup(machine, model: ResidualModel, max_iter: int = 50) -> np.ndarray:
    """The set-up parameters fitted alone on ``machine`` (the machine fixed)."""
    s = len(model.setup)
    if s == 0:
        return np.zeros(0)
    problem = ScaledProblem(machine=machine, model=model, basis=np.zeros((0, 0)),
                       setup_index=np.arange(s), setup_base=model.setup.initial.copy(),
                       scale=model.setup.scale.copy(), prior=False,
                       weights=np.ones(len(model.data)))
    problem.basis = np.zeros((len(defect_set(machine)), 0))
    u0 = model.setup.initial / model.setup.scale
    sol = solve_scaled(problem, u0, max_iter)
    if sol.status not in (Status.OK, Status.INCONSISTENT):
        raise ConvergenceError(f"the {model.data.kind} set-up parameters could not be fitted on "
                               f"the machine ({Status(sol.status).label})")
    return sol.u * model.setup.scale
