"""Figures of docs/joint-chains.md: ``python docs/make_chain_figures.py``.

- ``tripteor-x7.png``, ``trimule-600.png``: the drawings ``pkmkit demo`` makes
  (``pkmkit-demo/joint-chains/``), each preset at its ``wrist`` reference configuration (home
  legs, Q4 = 10°, Q5 = 30° on the Tripteor; home on the TriMule);
- ``tripteor-x7-passive.png``, ``trimule-600-passive.png``: the passive joints while Q1 sweeps
  its stroke, the other actuators at home (the demo's plot, one line style per leg so that equal
  joints such as ψ1 = ψ3 stay visible).
"""

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

import pkmkit
from pkmkit.plot.chain_drawing import draw_chain_machine
from pkmkit.plot.save import save_figure

OUT = Path(__file__).parent / "figures"
STYLES = ("-", "-.", "--", ":")


def passive_along_q1(m, path: Path) -> None:
    """The revolute passive joints (minus their mid-stroke values) while Q1 sweeps its stroke."""
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act[0]], m.model.q_max[act[0]]
    values = np.linspace(lo, hi, 41)
    q = np.tile(m.home_q, (len(values), 1))
    q[:, 0] = values
    res = m.fk(q, full_output=True, strokes="ignore")
    leg_of = {}
    for k, leg in enumerate(m.model.legs):
        for e in leg:
            leg_of.setdefault(m.model.elements[e].name, k)
    fig = Figure(figsize=(7.5, 4.6), layout="constrained")
    ax = fig.add_subplot()
    for i, joint in enumerate(m.passive_names):
        element = next(e for e in m.model.elements if e.name == joint)
        if element.type != "R":
            continue
        deg = np.degrees(res.passive[:, i])
        ax.plot(values * 1000, deg - deg[len(deg) // 2], STYLES[leg_of[joint] % len(STYLES)],
                label=element.display or joint, lw=1.6)
    ax.set_xlabel("Q1 [mm]")
    ax.set_ylabel("passive joint − its value at mid-stroke [deg]")
    ax.set_title(f"{m.name}: passive joints while Q1 moves (others at home; "
                 "line style = leg)", fontsize=9)
    ax.legend(fontsize=7, ncol=4)
    ax.grid(alpha=0.3)
    save_figure(fig, path, dpi=120)


def main() -> None:
    for ident in ("tripteor-x7", "trimule-600"):
        m = pkmkit.machine(ident)
        draw_chain_machine(m, m.reference_poses().get("wrist", m.home_q),
                           path=OUT / f"{ident}.png")
        passive_along_q1(m, OUT / f"{ident}-passive.png")


if __name__ == "__main__":
    main()
