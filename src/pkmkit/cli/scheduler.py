"""The ``--scheduler`` option: run a command's batched work on Dask (see :mod:`pkmkit.parallel`)."""

from __future__ import annotations

import click

SCHEDULER_OPTION = click.option(
    "--scheduler", "scheduler", metavar="ADDRESS",
    help="Run the batched work on a Dask cluster: a scheduler address (tcp://HOST:8786), or "
         "local[:N] for N worker processes here. Results are identical to the default serial "
         "run. Needs pip install 'pkmkit[dask]'.")
