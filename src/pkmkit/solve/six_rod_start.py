"""The generic start system of the six-rod direct kinematics: 40 solutions, computed once.

The coefficient-parameter homotopy of :mod:`pkmkit.solve.six_rod_direct` starts from one
*generic complex* six-rod system (random complex base points, platform points and offsets d_j)
whose 40 finite solutions in Study coordinates are known. They are computed ab initio by
**monodromy**, stored as package data (``data/six_rod_start.npz``) and loaded at first use:

1. draw a random complex displacement ``x₀`` (Study point) and random complex a_j, b_j; choose
   the offsets d_j so that ``x₀`` solves every rod equation (they enter linearly): one solution
   of a generic system is known;
2. move the parameters around random loops ``π₀ → π₁ → π₂ → π₀`` (straight segments between
   random complex parameter points), tracking every known solution; the ends of the loops are
   again solutions of the start system, and new ones are added;
3. stop when 40 solutions are known — the number of finite solutions of a generic
   Gough–Stewart platform (Raghavan 1993, Ronga–Vust 1995, Wampler 1996) — and check each one
   (residual, regular Jacobian, pairwise distinct).

A test re-derives the count independently with a total-degree homotopy (128 paths) and checks
that its finite regular end points are these 40. Regenerate the file with::

    python -m pkmkit.solve.six_rod_start
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from pkmkit.solve.path_tracking import PathStatus, track_paths
from pkmkit.solve.study_rods import (
    N_VARS,
    RodParameters,
    StudyHomotopy,
    pose_to_study,
    rod_quadrics,
)

#: Number of finite solutions of a generic six-rod (Gough–Stewart 6-6) system.
GENERIC_COUNT = 40
#: Seed of the random start system stored as package data.
SEED = 20_260_611
DATA_FILE = "six_rod_start.npz"


@dataclass(frozen=True)
class StartSystem:
    """A generic complex six-rod system and all its finite solutions.

    Attributes:
        parameters: one-column complex :class:`RodParameters`.
        patch: ``(8,)`` complex patch vector v (solutions satisfy ``v·x = 1``).
        solutions: ``(40, 8)`` complex Study points on the patch.
    """

    parameters: RodParameters
    patch: np.ndarray
    solutions: np.ndarray

    def residual(self) -> np.ndarray:
        """``(40,)`` largest |equation| of each solution (rods, Study quadric, patch)."""
        x = self.solutions
        rods = rod_quadrics(x.T, self.parameters.take(np.zeros(len(x), dtype=int)))
        study = np.abs(np.einsum("pk,pk->p", x[:, :4], x[:, 4:]))
        patch = np.abs(x @ self.patch - 1.0)
        return np.maximum(np.abs(rods).max(axis=0), np.maximum(study, patch))


def _complex_normal(rng: np.random.Generator, *shape: int) -> np.ndarray:
    return (rng.normal(size=shape) + 1j * rng.normal(size=shape)) / np.sqrt(2.0)


def _random_parameters(rng: np.random.Generator) -> RodParameters:
    return RodParameters(
        _complex_normal(rng, 3, 6, 1), _complex_normal(rng, 3, 6, 1), _complex_normal(rng, 6, 1)
    )


def _track_between(
    start: RodParameters, target: RodParameters, patch: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    homotopy = StudyHomotopy.between(start, target, patch)
    result = track_paths(
        lambda xk, tk, rows: homotopy.evaluate(xk, tk, None),
        x,
        predictor_tol=1e-6,
        corrector_tol=1e-11,
    )
    return result.x, result.status == PathStatus.REACHED


def generate_start_system(seed: int = SEED, max_loops: int = 200) -> StartSystem:
    """Compute a generic start system and its 40 solutions by monodromy (see module docstring).

    Raises:
        RuntimeError: fewer than 40 solutions after ``max_loops`` loops, or a solution that
            fails its checks.
    """
    rng = np.random.default_rng(seed)
    patch = _complex_normal(rng, N_VARS)
    a, b = _complex_normal(rng, 3, 6, 1), _complex_normal(rng, 3, 6, 1)
    x0 = pose_to_study(_complex_normal(rng, 1, 3), _complex_normal(rng, 1, 4))[0]
    no_offset = rod_quadrics(x0[:, None], RodParameters(a, b, np.zeros((6, 1), complex)))
    offset = -no_offset / (x0[:4] @ x0[:4])
    params = RodParameters(a, b, offset)
    known = (x0 / (patch @ x0))[None]
    for _ in range(max_loops):
        if len(known) >= GENERIC_COUNT:
            break
        p1, p2 = _random_parameters(rng), _random_parameters(rng)
        x1, ok1 = _track_between(params, p1, patch, known)
        x2, ok2 = _track_between(p1, p2, patch, x1)
        x3, ok3 = _track_between(p2, params, patch, x2)
        for y in x3[ok1 & ok2 & ok3]:
            if np.abs(known - y).max(axis=1).min() > 1e-6 * max(1.0, np.abs(y).max()):
                known = np.vstack([known, y])
    if len(known) != GENERIC_COUNT:
        raise RuntimeError(f"monodromy found {len(known)} solutions, expected {GENERIC_COUNT}")
    system = StartSystem(params, patch, known)
    check_start_system(system)
    return system


def check_start_system(system: StartSystem, tol: float = 1e-10) -> None:
    """Raise RuntimeError unless the solutions solve the system, are regular and distinct."""
    x = system.solutions
    if x.shape != (GENERIC_COUNT, N_VARS):
        raise RuntimeError(f"start system has {x.shape[0]} solutions, expected {GENERIC_COUNT}")
    if not (system.residual() <= tol).all():
        raise RuntimeError("a start solution does not solve the start system")
    homotopy = StudyHomotopy.between(system.parameters, system.parameters, system.patch)
    _, jac, _ = homotopy.evaluate(x, np.ones(len(x)), None)
    if not (np.linalg.cond(jac) < 1e8).all():
        raise RuntimeError("a start solution is singular")
    gap = np.abs(x[:, None] - x[None]).max(axis=2)
    np.fill_diagonal(gap, np.inf)
    if not (gap.min() > 1e-6):
        raise RuntimeError("two start solutions coincide")


def save_start_system(system: StartSystem, path: str | Path) -> None:
    """Write ``system`` to an ``.npz`` file."""
    np.savez(
        path,
        base=system.parameters.base,
        platform=system.parameters.platform,
        offset=system.parameters.offset,
        patch=system.patch,
        solutions=system.solutions,
    )


def read_start_system(path: str | Path) -> StartSystem:
    """Read a start system written by :func:`save_start_system` and check it."""
    with np.load(path) as data:
        system = StartSystem(
            RodParameters(data["base"], data["platform"], data["offset"]),
            data["patch"],
            data["solutions"],
        )
    check_start_system(system)
    return system


@functools.cache
def load_start_system() -> StartSystem:
    """The stored start system (package data), read and checked once per process (its arrays
    are read-only: the cached value is shared)."""
    with resources.as_file(resources.files("pkmkit.solve") / "data" / DATA_FILE) as path:
        system = read_start_system(path)
    par = system.parameters
    for arr in (par.base, par.platform, par.offset, system.patch, system.solutions):
        arr.flags.writeable = False
    return system


def main() -> None:  # pragma: no cover - regeneration script
    """Regenerate the package data file next to this module."""
    target = Path(__file__).with_name("data") / DATA_FILE
    target.parent.mkdir(exist_ok=True)
    system = generate_start_system()
    save_start_system(system, target)
    print(f"wrote {target}: {len(system.solutions)} solutions, "
          f"largest residual {system.residual().max():.1e}")


if __name__ == "__main__":  # pragma: no cover
    main()
