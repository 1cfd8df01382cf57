"""The geometric-error part of ``pkmkit demo``: the Tripteor's hyperstatic compatibility beside
the thesis (seed 002, Table 4.6), what tool-point measurements can identify, and an accuracy
map of the hexapod from tolerances. :func:`error_summary` returns a small JSON-ready summary
and writes the figures."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

#: The thesis's Table 4.6 orientation conditions on legs 1 and 3 (the 12 our rank test finds).
THESIS_LEGS_1_3 = ("dK21", "dK41", "dI51", "dK51", "dI13", "dK13", "dK23", "dK43", "dI53",
                   "dK53", "dI63", "dJ63")
#: The thesis's leg-2 conditions that the rank test does not reproduce.
THESIS_LEG_2 = ("dI42", "dJ42", "dK52", "dK62")
#: Hexapod tolerances of the demo (half-widths, SI).
HEXAPOD_TOLERANCES = {"base": 2e-5, "platform": 2e-5, "length": 1e-5, "offset": 1e-5}


def tripteor_compatibility_summary() -> dict[str, Any]:
    """The Tripteor's compatibility as the thesis did it (orientation only, D_ICS^L11
    nominal), with position defects, and with every loop defect of pkmkit's model."""
    import pkmkit
    from pkmkit.geometric_errors.compatibility import compatibility

    m = pkmkit.machine("tripteor-x7")
    orient = compatibility(m, orientation_only=True, reference_nominal=True)
    positions = compatibility(m, reference_nominal=True, exclude=["dS*", "da62", "dc63"])
    full = compatibility(m)
    return {
        "orientation_only": {
            "forced_zero": list(orient.forced_zero),
            "compatible_dimension": orient.compatible_dimension,
            "n_parameters": len(orient.names),
            "matches_thesis_legs_1_3": set(orient.forced_zero) == set(THESIS_LEGS_1_3),
            "thesis_leg_2_not_required": [n for n in THESIS_LEG_2
                                          if n not in orient.forced_zero],
        },
        "with_positions": {
            "forced_zero": list(positions.forced_zero),
            "added_by_positions": [n for n in positions.forced_zero
                                   if n not in orient.forced_zero],
            "compatible_dimension": positions.compatible_dimension,
            "n_parameters": len(positions.names),
        },
        "every_loop_defect": {
            "forced_zero": list(full.forced_zero),
            "conditions": [c.text() for c in full.conditions],
            "compatible_dimension": full.compatible_dimension,
            "n_parameters": len(full.names),
            "singular_value_gap": [full.gap[0], full.gap[1]],
        },
    }


def tripteor_identifiability_summary() -> dict[str, Any]:
    """Tool-point identifiability of the compatible parallel part (notes §4.5)."""
    import pkmkit
    from pkmkit.geometric_errors.compatibility import compatibility_configurations
    from pkmkit.geometric_errors.identifiability import identifiability

    m = pkmkit.machine("tripteor-x7")
    q = compatibility_configurations(m, 40, seed=3)
    q[:, 3:] = np.random.default_rng(1).uniform([-0.26, 0.0], [0.26, 0.96], (40, 2))
    r = identifiability(m, "point", q, compatible=True, scope="loops",
                        exclude=["*11", "dS*", "da62", "dc63"])
    return {"rank": r.rank, "n_parameters": r.n_parameters,
            "unidentifiable": list(r.unidentifiable),
            "together": [list(g) for g in r.together], "condition": r.condition}


def hexapod_accuracy_map(out_dir: Path) -> dict[str, Any]:
    """95th-percentile accuracy map of the hexapod (z at mid-height) from the demo
    tolerances; writes ``errors-hexapod-accuracy-map.png``."""
    import pkmkit
    from pkmkit.geometric_errors.tolerance import accuracy_map, tolerances
    from pkmkit.plot.error_figures import plot_accuracy_map

    m = pkmkit.machine("gough-stewart")
    tol = tolerances(m, classes=HEXAPOD_TOLERANCES)
    amap = accuracy_map(m, tol, n_samples=400, resolution=21)
    path = plot_accuracy_map(amap, Path(out_dir) / "errors-hexapod-accuracy-map.png",
                             unit="um", title="Gough–Stewart hexapod: 95th percentile of the "
                             "tool-point error (±20 µm joints, ±10 µm lengths and offsets)")
    return {"figure": str(path), "tolerances_m": HEXAPOD_TOLERANCES,
            "p95_min_m": float(np.nanmin(amap.exact)), "p95_max_m": float(np.nanmax(amap.exact)),
            "first_order_p95_max_m": float(np.nanmax(amap.first_order)),
            "nonlinearity_m": amap.result.nonlinearity}


def error_summary(out_dir: str | Path) -> dict[str, Any]:
    """The demo's geometric-error section (a few seconds): Tripteor compatibility and
    identifiability summaries, and the hexapod accuracy map written into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return {"tripteor_compatibility": tripteor_compatibility_summary(),
            "tripteor_identifiability": tripteor_identifiability_summary(),
            "hexapod_accuracy_map": hexapod_accuracy_map(out)}
