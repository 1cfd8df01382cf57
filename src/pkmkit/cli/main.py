"""``pkmkit`` command line: machines, show, ik, fk, jacobian, analyze, map, workspace,
useful-workspace, demo.

Every command accepts ``--help``. Lengths are in metres unless ``--units mm``; angles in degrees.
Exit codes: 0 success; 1 an error (bad input, unreachable pose, malformed file: message on
stderr); 2 a usage error; 3 a batch run that completed but flagged some rows (see the ``status``
column of the output file).
"""

from __future__ import annotations

import contextlib
from pathlib import Path

import click

from pkmkit import __version__
from pkmkit.exceptions import PkmError

from .lazy import LazyGroup

# Every command but `demo` is listed by `LAZY_COMMANDS` and imported when it runs (the
# kinematics commands from `kinematics_cmds`): `pkmkit --help` imports click and these few
# modules, no NumPy and no machine library (issue 22 §5, `tests/cli/test_startup_modules.py`).


class PkmGroup(LazyGroup):
    """Turns pkmkit's typed errors into a one-line message (its lengths in ``--units``) and
    exit status 1."""

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except PkmError as exc:
            from .unit_text import in_units

            raise click.ClickException(in_units(str(exc), ctx.meta)) from None


@click.group(cls=PkmGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="pkmkit")
def cli() -> None:
    """pkmkit: parallel kinematic machine tools — models, kinematics, Jacobians.

    MACHINE is a built-in id (see `pkmkit machines`) or a machine file (.toml, .yaml).
    `ik`, `fk` and `jacobian` also run over tables (--input/--output, see their --help).
    """


@cli.command()
@click.option("--out", "out_dir", default="pkmkit-demo", show_default=True,
              type=click.Path(file_okay=False), help="Directory for the JSON and PNG files.")
@click.option("--quick", is_flag=True,
              help="Coarser grids, no refinement of the inscribed cubes and a shorter Pareto "
                   "search: every study runs, faster, with less refined numbers and figures.")
def demo(out_dir: str, quick: bool) -> None:
    """Kinematic summary and analysis of every built-in machine (text, JSON and figures)."""
    from pkmkit.demos.run import run_demo

    try:
        run_demo(Path(out_dir), quick=quick)
    except OSError as exc:
        raise click.ClickException(f"cannot write into {out_dir}: {exc.strerror or exc}") from None


def main() -> None:
    """Console-script entry point. SIGTERM ends the command as Ctrl-C does, through the normal
    exits, so that no temporary or partial output file is left (:mod:`pkmkit.io.atomic`).
    Warnings are shown as one-line notes (:mod:`pkmkit.cli.notes`), and work that runs past
    two seconds shows a progress bar on a terminal (:mod:`pkmkit.progress`)."""
    from pkmkit.cli.notes import install_warning_notes
    from pkmkit.progress import progress_display

    exit_on_sigterm()
    install_warning_notes()
    with progress_display():
        cli(prog_name="pkmkit")


def exit_on_sigterm() -> None:
    """Turn SIGTERM into ``SystemExit(143)`` in the main thread (cleanup handlers run)."""
    import signal

    def _terminate(signum, frame):
        raise SystemExit(128 + signum)

    with contextlib.suppress(ValueError):  # not in the main thread: leave the default
        signal.signal(signal.SIGTERM, _terminate)


if __name__ == "__main__":  # pragma: no cover
    main()
