"""Pose selection for identification: choose N configurations among candidates that maximise an
observability index of the identifiable (base) parameters, and report the gain over random
choices of the same size.

**Method.** The identification Jacobian of every candidate is computed once; the base
parameters are those of all candidates together (:mod:`pkmkit.geometric_errors.identifiability`).
Each
candidate c contributes its information ``A_c = J_cᵀ J_c`` (base columns) and a selection's
singular values are the square roots of the eigenvalues of ``Σ A_c``. A greedy pass adds the
candidate that most increases the index (``log det`` while the selection has fewer readings
than base parameters), then exchange passes (Fedorov's exchange, as in DETMAX) swap a chosen
pose for a candidate while the index improves. The baseline: the same index for ``n_random``
random selections of N candidates; the gain is the chosen value over their median.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.exceptions import IdentifiabilityError, InputError
from pkmkit.geometric_errors.blas_threads import single_blas
from pkmkit.geometric_errors.configurations import sample_configurations
from pkmkit.geometric_errors.identifiability import (
    INDICES,
    RTOL,
    analyse_jacobian,
    identification_jacobian,
)


@dataclass(frozen=True)
class PoseSelection:
    """Outcome of :func:`select_poses`.

    Attributes:
        q: ``(N, n)`` the chosen configurations; chosen: their indices among the candidates.
        index: the index maximised; value: its value for the chosen poses.
        indices: every index (and the condition number) of the chosen poses.
        random_values: ``(R,)`` the index for R random selections of N candidates.
        gain: value / median(random_values).
        greedy_value: the index after the greedy pass (before exchanges); passes: exchange
            passes run.
        base: the base parameters the indices are computed on; n_parameters: all parameters.
        n_candidates: candidates considered (within the strokes).
        beyond_strokes: candidates given that were left out because an actuator or passive
            joint of theirs lies beyond its stroke (:mod:`pkmkit.machines.strokes`): a selected
            pose is always one the machine can take.
    """

    q: np.ndarray
    chosen: np.ndarray
    index: str
    value: float
    indices: dict[str, float]
    random_values: np.ndarray
    gain: float
    greedy_value: float
    passes: int
    base: tuple[str, ...]
    n_parameters: int
    n_candidates: int
    candidates: np.ndarray = field(repr=False)
    beyond_strokes: int = 0

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary."""
        rv = self.random_values
        return {"index": self.index, "value": self.value, "indices": self.indices,
                "random_median": float(np.median(rv)), "random_best": float(rv.max()),
                "random_worst": float(rv.min()), "n_random": int(rv.size), "gain": self.gain,
                "greedy_value": self.greedy_value, "exchange_passes": self.passes,
                "n_poses": len(self.chosen), "n_candidates": self.n_candidates,
                "base_parameters": list(self.base), "n_parameters": self.n_parameters,
                "chosen": self.chosen.tolist(), "beyond_strokes": self.beyond_strokes}


def _index_values(info: np.ndarray, m: int, index: str) -> np.ndarray:
    """Index of each information matrix ``(K, b, b)`` with m readings."""
    lam = np.linalg.eigvalsh(info)
    sv = np.sqrt(np.clip(lam, 0.0, None))[:, ::-1]  # descending
    smax, smin = sv[:, 0], sv[:, -1]
    with np.errstate(divide="ignore", invalid="ignore"):
        if index == "O1":
            out = np.exp(np.mean(np.log(np.where(sv > 0, sv, 1e-300)), axis=1)) / np.sqrt(m)
        elif index == "O2":
            out = smin / np.where(smax > 0, smax, 1.0)
        elif index == "O3":
            out = smin.copy()
        elif index == "O4":
            out = smin ** 2 / np.where(smax > 0, smax, 1.0)
        else:
            out = 1.0 / np.sum(1.0 / np.where(sv > 0, sv, 1e-300), axis=1)
    out = np.where(smin > 0, out, 0.0)
    return out


def _log_det(info: np.ndarray, eps: float) -> np.ndarray:
    lam = np.linalg.eigvalsh(info + eps * np.eye(info.shape[-1]))
    return np.sum(np.log(np.clip(lam, 1e-300, None)), axis=1)


@single_blas
def select_poses(machine, kind: str, n: int, *, candidates: Any = None,
                 n_candidates: int | None = None, region: Any = None,
                 setup: dict | None = None, parameters: Any = None, kinds: Any = None,
                 exclude: Any = None, scope: str = "all", index: str = "O1",
                 scaling: str = "length", rtol: float = RTOL, seed: int | None = 0,
                 n_random: int = 50, max_passes: int = 20) -> PoseSelection:
    """Choose ``n`` configurations maximising ``index`` (module docstring).

    Args:
        machine, kind, setup, parameters, kinds, exclude, scope, scaling, rtol: as for
            :func:`pkmkit.geometric_errors.identifiability.identifiability`.
        n: poses to choose.
        candidates: ``(C, n_act)`` candidate configurations (those beyond the strokes are
            left out and counted); default ``n_candidates`` (max(20 n, 200)) Halton points of
            ``region`` within the strokes.
        index: ``"O1"`` … ``"O5"``.
        seed: for the candidates and the random baseline.
        n_random: random selections for the baseline.

    Raises:
        InputError: an unknown index, n < 1, fewer candidates than n.
        IdentifiabilityError: n poses give fewer readings than base parameters.
    """
    if index not in INDICES:
        raise InputError(f"unknown index {index!r}; valid: {', '.join(INDICES)}")
    if int(n) < 1:
        raise InputError(f"the number of poses must be ≥ 1, got {n}")
    n = int(n)
    cand, beyond = _candidates(machine, n, candidates, n_candidates, region, seed)
    ij = identification_jacobian(machine, kind, cand, setup, parameters=parameters,
                                 kinds=kinds, exclude=exclude, scope=scope, scaling=scaling)
    analysis = analyse_jacobian(ij.matrix, ij.names, ij.column_scale, rtol=rtol)
    base_cols = [ij.names.index(b) for b in analysis["base"]]
    b = len(base_cols)
    rows = ij.rows
    if n * rows < b:
        raise IdentifiabilityError(
            f"{n} poses × {rows} {kind} readings = {n * rows} scalar measurements for {b} "
            f"identifiable combinations (rank {b} of {len(ij.names)} parameters over the "
            f"candidates): choose at least {-(-b // rows)} poses", rank=b,
            n_parameters=len(ij.names), n_measurements=n * rows)
    blocks = ij.matrix.reshape(len(cand), rows, -1)[:, :, base_cols]
    info = np.einsum("cri,crj->cij", blocks, blocks)
    chosen, available, total = _greedy(info, n, rows, index)
    m_rows = n * rows
    greedy_value = float(_index_values(total[None], m_rows, index)[0])
    value, passes = _exchange(info, chosen, available, total, m_rows, index, greedy_value,
                              max_passes)
    rng = np.random.default_rng(None if seed is None else seed + 1)
    picks = np.array([rng.choice(len(cand), n, replace=False) for _ in range(n_random)])
    random_values = _index_values(info[picks].sum(axis=1), m_rows, index)
    chosen_arr = np.array(chosen)
    jb = blocks[chosen_arr].reshape(-1, b)
    sv = np.linalg.svd(jb, compute_uv=False)
    from pkmkit.geometric_errors.identifiability import indices_from_singular_values

    all_indices = indices_from_singular_values(sv, m_rows)
    median = float(np.median(random_values))
    return PoseSelection(q=cand[chosen_arr], chosen=chosen_arr, index=index, value=value,
                         indices=all_indices, random_values=random_values,
                         gain=value / median if median > 0 else float("inf"),
                         greedy_value=greedy_value, passes=passes,
                         base=tuple(analysis["base"]), n_parameters=len(ij.names),
                         n_candidates=len(cand), candidates=cand, beyond_strokes=beyond)


def _candidates(machine, n: int, candidates: Any, n_candidates: int | None, region: Any,
                seed: int | None) -> tuple[np.ndarray, int]:
    """``(C, n_act)`` candidate configurations within the strokes and how many given ones
    were left out beyond them; fewer than ``n`` raises :class:`InputError`."""
    beyond = 0
    if candidates is None:
        count = n_candidates if n_candidates is not None else max(20 * n, 200)
        cand = sample_configurations(machine, count, region=region, seed=seed,
                                     method="halton", within_strokes=True).q
    else:
        from pkmkit.machines.strokes import stroke_excess

        cand = np.atleast_2d(np.asarray(candidates, dtype=float))
        out = stroke_excess(machine, cand).out_of_stroke
        beyond = int(out.sum())
        cand = cand[~out]
    if len(cand) < n:
        left = f" ({beyond} others are beyond the strokes)" if beyond else ""
        raise InputError(f"{len(cand)} candidates{left} for {n} poses: give more candidates")
    return cand, beyond


def _greedy(info: np.ndarray, n: int, rows: int,
            index: str) -> tuple[list[int], np.ndarray, np.ndarray]:
    """Greedy choice of ``n`` candidates from their information matrices ``info (C, b, b)``:
    log det while the readings are fewer than ``b``, then ``index``. Returns the chosen
    indices, the mask of candidates still available and the chosen information ``(b, b)``."""
    b = info.shape[1]
    eps = 1e-12 * float(np.trace(info.mean(axis=0))) / max(b, 1)
    chosen: list[int] = []
    total = np.zeros((b, b))
    available = np.ones(len(info), dtype=bool)
    for k in range(n):
        trial = total[None] + info
        m_rows = (k + 1) * rows
        score = _log_det(trial, eps) if m_rows < b else _index_values(trial, m_rows, index)
        if m_rows >= b and not np.any(score[available] > 0):
            score = _log_det(trial, eps)
        score = np.where(available, score, -np.inf)
        best = int(np.argmax(score))
        chosen.append(best)
        available[best] = False
        total = total + info[best]
    return chosen, available, total


def _exchange(info: np.ndarray, chosen: list[int], available: np.ndarray, total: np.ndarray,
              m_rows: int, index: str, value: float, max_passes: int) -> tuple[float, int]:
    """Exchange passes (Fedorov): replace one chosen pose by the best available one while
    ``index`` improves; ``chosen`` and ``available`` are updated in place. Returns the final
    value and the number of passes."""
    passes = 0
    for passes in range(1, max_passes + 1):  # noqa: B007 - the count is reported
        improved = False
        for slot in range(len(chosen)):
            without = total - info[chosen[slot]]
            trial = without[None] + info
            score = np.where(available, _index_values(trial, m_rows, index), -np.inf)
            best = int(np.argmax(score))
            if score[best] > value * (1 + 1e-9) + 1e-300:
                available[chosen[slot]] = True
                available[best] = False
                chosen[slot] = best
                total = without + info[best]
                value = float(score[best])
                improved = True
        if not improved:
            break
    return value, passes
