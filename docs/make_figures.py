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
    from pkmkit.demos.analysis import (
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
    from pkmkit.demos.design import delta_pareto, orthoglide_sizing

    orthoglide_sizing(OUT)
    delta_pareto(OUT, generations=40)


def motion() -> None:
    """The trajectory figures of docs/motion.md (the same studies as ``pkmkit demo``)."""
    from pkmkit.demos.motion import facing, seed_circle, seed_helix, seed_line

    seed_circle(OUT)
    seed_helix(OUT)
    seed_line(OUT)
    facing(OUT)


def errors() -> None:
    """The figures of docs/errors.md."""
    from pkmkit.demos.errors import hexapod_accuracy_map
    from pkmkit.geometric_errors.compatibility import compatibility
    from pkmkit.geometric_errors.sensitivity import sensitivity_analysis
    from pkmkit.plot.error_figures import plot_sensitivity

    hexapod_accuracy_map(OUT)
    tripteor = pkmkit.machine("tripteor-x7")
    table = sensitivity_analysis(tripteor, n_points=60, exact=True)
    plot_sensitivity(table, OUT / "errors-tripteor-sensitivity.png", unit="um", top=40,
                     title="Tripteor X7: largest tool-point displacement over the thesis's "
                     "strokes (10 µm, 20 µrad)")
    delta = pkmkit.machine("linear-delta")
    plot_sensitivity(sensitivity_analysis(delta, exact=True),
                     OUT / "errors-linear-delta-sensitivity.png", unit="um",
                     title="Linear Delta: largest tool displacement over the default box "
                     "(10 µm, 7.7 µrad)")
    fig = Figure(figsize=(8, 3.6))
    ax = fig.add_subplot(1, 1, 1)
    for label, result in (
            ("crank–slider (thesis set)", compatibility(pkmkit.machine("crank-slider"),
                                                        reference_nominal=True,
                                                        exclude="*F")),
            ("Tripteor, orientation only (thesis set)",
             compatibility(tripteor, orientation_only=True, reference_nominal=True)),
            ("Tripteor, every loop defect", compatibility(tripteor))):
        sv = np.maximum(result.singular_values / result.singular_values[0], 1e-17)
        ax.semilogy(np.arange(1, sv.size + 1), sv, "o-", ms=3,
                    label=f"{label}: rank {result.rank}")
    ax.axhline(1e-8, color="grey", ls=":", label="relative tolerance 1e-8")
    ax.set_xlabel("index")
    ax.set_ylabel("σ / σ₁ of the stacked projections")
    ax.legend(fontsize=7)
    ax.set_title("Compatibility rank test: the singular-value gap", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "errors-compatibility-gap.png", dpi=110)


def full_pose() -> None:
    """The figures of docs/full-pose.md: drawings of the full-pose machines, the hexapod's
    condition map and workspace (made by the commands the page shows), its orientation
    workspace at home, the Verne-type module's coupled tilt and Dietmaier's 40 assembly modes
    (plotted as by ``pkmkit demo``)."""
    from click.testing import CliRunner

    from pkmkit.analysis.orientation import coupled_orientation, orientation_workspace
    from pkmkit.cli.main import cli
    from pkmkit.demos.machines import _plot_modes, _plot_tilt, _plot_tilt_map

    hexapod = pkmkit.machine("gough-stewart")
    draw_machine(hexapod, hexapod.reference_poses()["tilted"], path=OUT / "gough-stewart.png")
    verne = pkmkit.machine("verne")
    draw_machine(verne, verne.ik(verne.reference_poses()["offset"], full_output=True).pose,
                 path=OUT / "verne.png")
    delta = pkmkit.machine("delta")
    draw_machine(delta, delta.reference_poses()["offset"], path=OUT / "delta.png")
    for args in (["map", "gough-stewart", "--index", "condition", "--slice", "z=0.85",
                  "--out", str(OUT / "gough-stewart-condition.png")],
                 ["workspace", "gough-stewart", "--units", "mm",
                  "--out", str(OUT / "gough-stewart-workspace.png")]):
        result = CliRunner().invoke(cli, args)
        assert result.exit_code == 0, result.output
    ows = orientation_workspace(hexapod, hexapod.home_pose[:3], max_tilt=np.radians(85),
                                azimuths=72, tilts=171)
    _plot_tilt(ows, OUT / "gough-stewart-orientation.png")
    xs = np.linspace(-0.2, 0.2, 61)
    gx, gy = np.meshgrid(xs, xs, indexing="ij")
    tilt = coupled_orientation(verne, np.column_stack([gx.ravel(), gy.ravel(),
                                                       np.zeros(gx.size)]))
    _plot_tilt_map(gx, gy, np.degrees(tilt.tilt).reshape(gx.shape), OUT / "verne-tilt.png")
    general = pkmkit.machine("dietmaier-hexapod")
    _plot_modes(general, general.fk_all(general.home_q), OUT / "dietmaier-modes.png")


if __name__ == "__main__":
    OUT.mkdir(exist_ok=True)
    machines()
    assembly_modes()
    analysis()
    design()
    motion()
    errors()
    full_pose()
    print(f"figures written to {OUT}")
