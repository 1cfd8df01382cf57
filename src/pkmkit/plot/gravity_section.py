"""The calibration report's gravity paragraph: the deflection of the identified machine under
its own weight, predicted at the measured configurations
(:func:`pkmkit.calibration.gravity.gravity_beside_residual`), beside the residual — whether
elasticity could explain what the geometric model leaves."""

from __future__ import annotations

import html
from typing import Any


def gravity_json(gravity: dict[str, Any], scale: float) -> dict[str, Any]:
    """The figures of ``gravity`` in the report's length unit (``scale`` m per unit)."""
    if not gravity.get("available"):
        return dict(gravity)
    lengths = ("rms", "max", "rms_varying", "residual_rms")
    return {k: (v / scale if k in lengths else v) for k, v in gravity.items()}


def gravity_html(gravity: dict[str, Any], scale: float, units: str) -> str:
    """One paragraph (HTML) stating the predicted deflection beside the residual."""
    esc = html.escape
    if not gravity.get("available"):
        return (f"<p class='gravity'>Gravity deflection: not estimated "
                f"({esc(str(gravity.get('reason', '')))}).</p>")
    g = gravity_json(gravity, scale)
    ratio = g["rms_varying"] / g["residual_rms"] if g["residual_rms"] > 0 else float("inf")
    verdict = ("could explain a large part of the residual: an elastic model (or poses chosen "
               "where the sag is alike) may do better than more geometric parameters"
               if ratio >= 0.5 else "is small beside the residual: elasticity does not explain "
               "it")
    return (f"<h3>Geometric and elastic error</h3><p class='gravity'>Predicted deflection of "
            f"the identified machine under its own weight at the {g['configurations']} measured "
            f"configurations: RMS {g['rms']:.3g} {esc(units)}, max {g['max']:.3g} "
            f"{esc(units)}; its part that varies between configurations (what a fitted frame "
            f"cannot absorb) RMS {g['rms_varying']:.3g} {esc(units)}, beside the residual RMS "
            f"{g['residual_rms']:.3g} {esc(units)} after identification — the varying sag "
            f"{verdict}. Part of a sag that varies is absorbed into the identified geometric "
            f"parameters. {esc(g['note'])}.</p>")
