"""The stiffness part of ``pkmkit demo``: every built-in machine's stiffness at home (its drives
as assumed, rigid rods and links except where the sources give sections; the joint-chain
machines also with tubular links), a map of the Orthoglide's smallest translational stiffness
over its z = 0 plane, and the Tripteor's deflection under a 1 kN axial cutting force at its
reference configurations. :func:`run_stiffness_demo` returns a JSON-ready summary and writes
the figure into ``out_dir``."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import click
import numpy as np

#: Links of the joint-chain machines in the demo's second case: steel tubes Ø 120/100 mm.
DEMO_LINK = (0.12, 0.10)
#: The cutting force of the Tripteor study (N, along −z of the base, at the tool point).
CUTTING_FORCE = np.array([0.0, 0.0, -1000.0, 0.0, 0.0, 0.0])


def _home_row(m) -> dict[str, Any]:
    from pkmkit.stiffness import default_data, stiffness

    data = default_data(m)
    chains = m.stiffness_from_actuators  # joint chains: configured by q, links as beams
    if chains:
        r = stiffness(m, q=m.home_q, data=data)
    else:
        pose = m.home_pose[:3] if m.position_controlled else m.home_pose
        r = stiffness(m, pose, data=data)
    row = {"smallest_translational_N_per_um": float(r.translational[0]) / 1e6,
           "rigid_directions": int(r.rigid), "notes": list(data.notes)}
    if chains:
        from pkmkit.stiffness import Section

        soft = replace(data, link_section=Section.tube(*DEMO_LINK))
        rs = stiffness(m, q=m.home_q, data=soft)
        row["with_tube_links_N_per_um"] = float(rs.translational[0]) / 1e6
    return row


def run_stiffness_demo(out_dir: Path, quick: bool = False) -> dict[str, Any]:
    """Run the stiffness studies (see the module docstring), print a few lines, return the
    summary; the figure goes to ``out_dir/orthoglide-stiffness-map.png``."""
    from pkmkit.analysis.grids import make_grid
    from pkmkit.machines.registry import ALIASES, machine, machines
    from pkmkit.plot.maps import plot_scalar_map
    from pkmkit.stiffness import Section, default_data, stiffness

    out_dir.mkdir(parents=True, exist_ok=True)
    click.echo("\n== stiffness (virtual-joint model; drives as assumed, see pkmkit show)")
    homes = {}
    for ident in machines():
        if ident in ALIASES:
            continue
        homes[ident] = row = _home_row(machine(ident))
        extra = (f", {row['with_tube_links_N_per_um']:.3g} N/µm with Ø120/100 mm tube links"
                 if "with_tube_links_N_per_um" in row else "")
        rigid = f" ({row['rigid_directions']} rigid)" if row["rigid_directions"] else ""
        click.echo(f"   {ident:<24} smallest translational stiffness at home "
                   f"{row['smallest_translational_N_per_um']:.3g} N/µm{rigid}{extra}")
    m = machine("orthoglide")
    grid = make_grid([-0.1, -0.1], [0.1, 0.1], free=[0, 1], base=np.zeros(3),
                     names=m.pose_names, resolution=21 if quick else 81)
    r = stiffness(m, grid.points)
    values = (r.translational[:, 0] / 1e6).reshape(grid.shape)
    plot_scalar_map(grid, values, title="Orthoglide, z = 0: smallest translational stiffness",
                    label="N/µm", path=out_dir / "orthoglide-stiffness-map.png")
    finite = values[np.isfinite(values)]
    click.echo(f"   Orthoglide over the 200 mm square at z = 0: {finite.min():.3g}–"
               f"{finite.max():.3g} N/µm (100 at the isotropic centre)")
    t = machine("tripteor-x7")
    data = replace(default_data(t), link_section=Section.tube(*DEMO_LINK))
    configs = np.array(list(t.reference_poses().values()))
    rt = stiffness(t, q=configs, data=data, wrench=CUTTING_FORCE)
    deflection = np.linalg.norm(rt.deflection[:, :3], axis=1) * 1e6
    click.echo(f"   Tripteor X7 under 1 kN along −z at its {len(configs)} reference "
               f"configurations: tool-point deflection {deflection.min():.3g}–"
               f"{deflection.max():.3g} µm")
    return {"home": homes,
            "orthoglide_map": {"figure": "orthoglide-stiffness-map.png",
                               "min_N_per_um": float(finite.min()),
                               "max_N_per_um": float(finite.max())},
            "tripteor_deflection_um": dict(zip(t.reference_poses(), deflection.tolist(),
                                               strict=True))}
