"""Regenerate the figures of docs/ (run from the repository root: python docs/make_figures.py)."""

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

import pkmkit
from pkmkit.plot.drawing import draw_machine

OUT = Path(__file__).parent / "figures"


def machines() -> None:
    for ident in ("orthoglide", "linear-delta", "five-bar-isotropic", "five-bar-biglide"):
        draw_machine(pkmkit.machine(ident), path=OUT / f"{ident}.png")


def assembly_modes() -> None:
    """Both assembly modes of the same actuator coordinates, for a 2-D and a 3-D machine."""
    fig = Figure(figsize=(11, 5))
    five = pkmkit.machine("five-bar")
    q = five.ik([1.1, 0.1])
    modes = five.fk_all(q)
    for k in range(2):
        ax = fig.add_subplot(1, 3, k + 1)
        pose = modes.poses[k]
        draw_machine(five, pose, q=q, ax=ax,
                     title=f"five-bar, q = ({q[0]:.3f}, {q[1]:.3f}) m\n"
                           f"mode {modes.labels[k]!r}: P = ({pose[0]:.3f}, {pose[1]:.3f}) m")
    ortho = pkmkit.machine("orthoglide")
    ax = fig.add_subplot(1, 3, 3, projection="3d")
    rho = np.full(3, 0.31)
    both = ortho.fk_all(rho)
    draw_machine(ortho, both.poses[1], q=rho, ax=ax,
                 title="Orthoglide, ρ = (L, L, L): the far-side mode\n"
                       "p = (2L/3)(1, 1, 1) also has ρ_i > p_i")
    fig.tight_layout()
    fig.savefig(OUT / "assembly-modes.png", dpi=110)


def analysis() -> None:
    """The analysis figures of docs/analysis.md (the same studies as ``pkmkit demo``)."""
    from pkmkit.cli.demo_analysis import (
        delta_actuator_maps,
        five_bar_comparison,
        machine_analysis,
    )

    for ident in ("orthoglide", "linear-delta-ch3", "five-bar-isotropic"):
        machine_analysis(pkmkit.machine(ident), OUT)
    five_bar_comparison(OUT)
    delta_actuator_maps(OUT)


def design() -> None:
    """The design figures of docs/design.md (the same studies as ``pkmkit demo``)."""
    from pkmkit.cli.demo_design import delta_pareto, orthoglide_sizing

    orthoglide_sizing(OUT)
    delta_pareto(OUT, generations=40)


def motion() -> None:
    """The trajectory figures of docs/motion.md (the same studies as ``pkmkit demo``)."""
    from pkmkit.cli.demo_motion import facing, seed_circle, seed_helix, seed_line

    seed_circle(OUT)
    seed_helix(OUT)
    seed_line(OUT)
    facing(OUT)


if __name__ == "__main__":
    OUT.mkdir(exist_ok=True)
    machines()
    assembly_modes()
    analysis()
    design()
    motion()
    print(f"figures written to {OUT}")
