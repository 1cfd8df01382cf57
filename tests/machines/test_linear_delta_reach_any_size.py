"""Where the batch inverse model's reach ends on a linear Delta (slides in space) of any size:
the slide kernels' boundary tolerance is relative to the squared rod length (a plausible bug,
the tolerance taken as absolute, passed every test at the built-in size, where L² = 1.69 m²;
at a thousandth of the size it accepts poses ~10⁻⁶ of the size beyond the reach). Oracle:
a similarity leaves the reach at the same fraction of the size (the 1 m machine's reach along
a ray from home, times the scale), found by bisection, on the NumPy path (one row) and the
compiled kernel (a batch of 4096 copies once Numba is imported)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit

SIZES = ("R", "r", "L", "parallelogram_width", "q_min", "q_max")
RAY = np.array([0.48, -0.6, -0.64])


def _scaled(scale: float):
    m = pkmkit.machine("linear-delta")
    return m.with_params(**{k: np.multiply(m.params[k], scale).tolist()
                            if isinstance(m.params[k], tuple) else m.params[k] * scale
                            for k in SIZES})


def _reach(scale: float, rows: int) -> float:
    m = _scaled(scale)
    lo, hi = 0.0, 3.0 * scale
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        q = m.ik(np.tile(m.home_pose + mid * RAY, (rows, 1)), strokes="ignore")[-1]
        lo, hi = (mid, hi) if np.isfinite(q).all() else (lo, mid)
    return lo


@pytest.mark.parametrize("compiled", ["0", "1"])
def test_reach_scales_with_the_machine(compiled, monkeypatch):
    if compiled == "1":
        pytest.importorskip("numba")  # the closed form runs compiled once Numba is imported
    monkeypatch.setenv("PKMKIT_COMPILED", compiled)
    rows = 4096 if compiled == "1" else 1
    reach = {s: _reach(s, rows) for s in (1.0, 1e-3, 1e3)}
    assert 0.0 < reach[1.0] < 3.0
    for s in (1e-3, 1e3):
        assert reach[s] == pytest.approx(reach[1.0] * s, rel=1e-9), s
