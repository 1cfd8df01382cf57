"""Shared checks of the sizing rules: admissible sizes, the tolerance of the brute-force
verifications, and notes on degenerate specifications."""

from __future__ import annotations

import numpy as np

from pkmkit.analysis.workspace import Criteria
from pkmkit.exceptions import InputError
from pkmkit.model.parameters import MAX_LENGTH

#: Smallest prescribed square/cube side accepted by the sizing rules, m (below it the squares of
#: the coordinates lose all precision and no machine tool is that small).
MIN_SIDE = 1e-6
#: Relative tolerance of the brute-force verifications on the transmission-factor bounds. The
#: sizing rules put reference points exactly where a factor reaches a bound (Q1 and Q2 of the
#: Orthoglide, to about 1e-15 relative), and the verification re-evaluates those points on the
#: scaled machine, where rounding may put a factor a few ulps beyond the bound. The singular
#: values are accurate to about eps relative, also where two of them coincide (the case at Q2
#: for many bounds, λ = (1.29, 0.9, 0.9) for [0.9, 2]: pkmkit.numerics.small falls back to
#: LAPACK there), so 1e-9 leaves a wide margin and is far below any meaningful change of a design.
VERIFY_RTOL = 1e-9
#: A sized machine whose legs exceed this multiple of the prescribed side gets a note: the
#: bounds are so tight that only a region tiny compared with the machine satisfies them.
DEGENERATE_RATIO = 20.0


def require_side(value: float, what: str = "side") -> float:
    """``value`` as a float if it is a finite size within [:data:`MIN_SIDE`, MAX_LENGTH] m.

    Raises:
        InputError: otherwise, saying which range is accepted.
    """
    try:
        side = float(value)
    except (TypeError, ValueError):
        raise InputError(f"the {what} must be a number, got {value!r}") from None
    if not (np.isfinite(side) and side > 0):
        raise InputError(f"the {what} must be > 0, got {value}")
    if not MIN_SIDE <= side <= MAX_LENGTH:
        raise InputError(f"the {what} must lie between {MIN_SIDE:g} m and {MAX_LENGTH:g} m, got "
                         f"{side:g} m; check the units")
    return side


def relaxed(criteria: Criteria, rtol: float = VERIFY_RTOL) -> Criteria:
    """``criteria`` for a verification: bounds widened by the relative tolerance ``rtol``
    (λ_min ≥ lo (1 − rtol), λ_max ≤ hi (1 + rtol)), κ_max by the same factor, and the
    singularity threshold lowered by it (ties at the reference points)."""
    bounds = None
    if criteria.bounds is not None:
        lo, hi = criteria.bounds
        bounds = (lo * (1.0 - rtol), hi * (1.0 + rtol))
    kappa = None if criteria.kappa_max is None else criteria.kappa_max * (1.0 + rtol)
    return Criteria(bounds=bounds, kappa_max=kappa, strokes=criteria.strokes,
                    q_limits=criteria.q_limits, connected=criteria.connected,
                    tol=criteria.tol * (1.0 - rtol))


def degenerate_note(length: float, side: float, bounds: tuple[float, float]) -> str | None:
    """A note when the legs are more than :data:`DEGENERATE_RATIO` times the prescribed side."""
    ratio = length / side
    if ratio <= DEGENERATE_RATIO:
        return None
    lo, hi = bounds
    return (f"degenerate specification: the legs are {ratio:.3g} times the prescribed side — "
            f"bounds [{lo:g}, {hi:g}] this narrow only hold in a region tiny compared with "
            "the machine; widen them for a practical design")
