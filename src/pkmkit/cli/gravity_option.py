"""``pkmkit compensate --gravity``: aim the calibrated machine's loaded tool point at the
targets or the program (:func:`pkmkit.calibration.gravity.aim_loaded`,
:class:`~pkmkit.calibration.gravity.LoadedAim`); parsing and printing only."""

from __future__ import annotations

from typing import Any

import click
import numpy as np

GRAVITY_OPTION = click.option(
    "--gravity", is_flag=True,
    help="Include the calibrated machine's deflection under its own weight: the corrected "
         "targets (or the G-code program's points) aim its loaded tool point at the targets "
         "(illustrative masses; joint chains, rod machines on slides or struts).")


def aimed_targets(identified, targets: Any, tool_length: float | None, gravity: bool,
                  scale: float, unit: str, quiet: bool, nominal: Any = None
                  ) -> tuple[np.ndarray, dict | None]:
    """The targets to correct (moved against the gravity deflection with ``gravity``, the
    illustrative masses of ``nominal``'s kind) and the JSON summary of that move (None without
    ``gravity``); prints one line unless ``quiet``."""
    if not gravity:
        return targets, None
    from pkmkit.calibration.gravity import aim_loaded

    aimed, sag = aim_loaded(identified, targets, tool_length=tool_length, masses_of=nominal)
    size = np.linalg.norm(sag.deflection[:, :3], axis=1)
    size = size[np.isfinite(size)]
    info = {"deflection_rms": float(np.sqrt(np.mean(size**2))) / scale if size.size else None,
            "deflection_max": float(size.max()) / scale if size.size else None,
            "masses": sag.note}
    if not quiet and size.size:
        gravity_line(info, unit, "targets")
    return aimed, info


def gravity_line(info: dict, unit: str, what: str) -> None:
    """Print the sag the ``what`` (targets, program points) were moved against (``info``:
    ``deflection_rms``, ``deflection_max`` in ``unit``, ``masses``)."""
    if info["deflection_max"] is None:
        return
    click.echo(f"gravity: {what} moved against the calibrated machine's sag, RMS "
               f"{info['deflection_rms']:.4g} {unit}, max {info['deflection_max']:.4g} {unit}"
               f" ({info['masses']})")
