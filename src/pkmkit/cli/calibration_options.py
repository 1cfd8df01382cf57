"""Options shared by the calibration commands (``simulate-measurements``, ``register``,
``calibrate``, ``compensate``)."""

from __future__ import annotations

import click

from pkmkit.model.measurement_set import KINDS
from pkmkit.model.parameters import LENGTH_UNITS

#: ``--units`` of the calibration commands: None when not given (a file's own unit is then used
#: and a file in another unit is not a mismatch).
CAL_UNITS_OPTION = click.option(
    "--units", type=click.Choice(sorted(LENGTH_UNITS)), default=None,
    help="Length unit of the files and of the output (default: the file's '# units:' line, "
         "else m). A file declaring another unit is an error (units mismatch).")
MEASURE_OPTION = click.option("--measure", "kind", type=click.Choice(KINDS), required=True,
                              help="Measurement type (see docs/calibration.md).")
