"""Reading a generated LinuxCNC module back: its numbers must close pkmkit's configurations
(what ``pkmkit export --to linuxcnc`` checks before it writes the file; the C logic itself is
checked compiled, in ``tests/export/test_linuxcnc.py``)."""

from __future__ import annotations

import re

import numpy as np

from pkmkit.export.base import ExportCheckError, sample_poses
from pkmkit.export.linuxcnc import KIND_NAMES
from pkmkit.model.parameters import length_scale


def _read_array(text: str, name: str, size: int) -> np.ndarray:
    """The numbers of ``static const ... name[...] = {...};`` in C source (comments removed)."""
    bare = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    found = re.search(rf"\b{name}\b(?:\[[^\]]*\])+\s*=\s*\{{(.*?)\}};", bare, flags=re.S)
    if found is None:
        raise ExportCheckError(f"the generated source has no {name} array")
    words = re.findall(r"PKM_[A-Z]+|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?",
                       found.group(1))
    codes = {v: float(k) for k, v in KIND_NAMES.items()}
    values = np.array([codes[w] if w.startswith("PKM")
                       else float(w) for w in words])
    if values.shape != (size,):
        raise ExportCheckError(f"the generated {name} holds {values.size} numbers, not {size}")
    return values


def check_sentence(machine) -> str:
    """What :func:`check_linuxcnc_source` checked, for the command's report."""
    if machine.export_layout == "chain":
        return "its chains close at pkmkit's configurations and place the tool (≤ 1e-9 m)"
    return "its rods close at pkmkit's configurations (≤ 1e-9 m)"


def check_linuxcnc_source(machine, text: str, units: str = "mm") -> float:
    """Read the geometry back from a generated module and close its rods at pkmkit's
    configurations (home, the named poses, random poses near home): the largest
    ``| |p + R b_j − a_j(q_j)| − ρ_j(q_j) |`` (m), with q from pkmkit's inverse model.

    A joint-chain machine's module is read back by :func:`check_chain_linuxcnc_source`.

    Raises:
        ExportCheckError: beyond 1e-9 m (the file's numbers are not pkmkit's machine).
    """
    if machine.export_layout == "chain":
        return check_chain_linuxcnc_source(machine, text, units)
    scale = length_scale(units)
    rods = re.search(r"#define N_RODS (\d+)", text)
    if rods is None:
        raise ExportCheckError("the generated source has no N_RODS")
    n = int(rods.group(1))
    joint = _read_array(text, "rod_joint", n).astype(int)
    kind = _read_array(text, "rod_kind", n)
    base = _read_array(text, "rod_base", 3 * n).reshape(n, 3) * scale
    platform = _read_array(text, "rod_platform", 3 * n).reshape(n, 3) * scale
    axis = _read_array(text, "rod_axis", 3 * n).reshape(n, 3)
    length = _read_array(text, "rod_length", n) * scale
    crank = kind == 2
    first = np.array([np.flatnonzero(joint == j)[0] for j in range(machine.n_actuators)])
    joint_scale = np.where(crank[first], np.pi / 180.0, scale)
    home_q = _read_array(text, "home_joints", machine.n_actuators) * joint_scale
    x, q = sample_poses(machine)
    q = q[:, joint]  # per rod
    if x.shape[1] == 2:
        x = np.concatenate([x, np.zeros((len(x), 1))], axis=1)
    if x.shape[1] == 6:
        from pkmkit.spatial.rotation import rotvec_to_matrix

        rot = rotvec_to_matrix(x[:, 3:])
    else:
        rot = np.broadcast_to(np.eye(3), (len(x), 3, 3))
    slide = kind == 0
    points = x[:, None, :3] + np.einsum("kab,jb->kja", rot, platform)
    d = points - base[None] - np.where(slide, q, 0.0)[:, :, None] * axis[None]
    if crank.any():
        pivot = _read_array(text, "crank_pivot", 3 * n).reshape(n, 3) * scale
        e1 = _read_array(text, "crank_e1", 3 * n).reshape(n, 3)
        e2 = _read_array(text, "crank_e2", 3 * n).reshape(n, 3)
        radius = _read_array(text, "crank_radius", n) * scale
        offset = _read_array(text, "crank_offset", n) * scale
        tip = (pivot + offset[:, None] * axis)[None] + radius[None, :, None] * (
            np.cos(q)[:, :, None] * e1[None] + np.sin(q)[:, :, None] * e2[None])
        d = np.where(crank[None, :, None], points - tip, d)
    rho = np.where(kind == 1, length + q, length)
    worst = float(np.abs(np.linalg.norm(d, axis=2) - rho).max())
    worst = max(worst, float(np.abs(home_q - machine.home_q).max()))
    if not worst <= 1e-9:
        raise ExportCheckError(f"the generated module does not close pkmkit's configurations "
                               f"(off by {worst:.3g} m): not written")
    return worst


def _chain_end(rotations: np.ndarray, positions: np.ndarray, types: list[str],
               variable: np.ndarray, chain, values: np.ndarray, start=None
               ) -> tuple[np.ndarray, np.ndarray]:
    """End frames ``(R (k, 3, 3), p (k, 3))`` of a chain of the file's elements at joint values
    ``(k, V)``: ``T = D_1 M_1(q_1) D_2 M_2(q_2) …`` (written here again, apart from pkmkit's
    solver, from the numbers read back)."""
    k = values.shape[0]
    rot = np.tile(np.eye(3), (k, 1, 1)) if start is None else start[0].copy()
    pos = np.zeros((k, 3)) if start is None else start[1].copy()
    for e in chain:
        pos = pos + rot @ positions[e]
        rot = rot @ rotations[e]
        if types[e] == "R":
            q = values[:, variable[e]]
            turn = np.zeros((k, 3, 3))
            turn[:, 0, 0] = turn[:, 1, 1] = np.cos(q)
            turn[:, 1, 0], turn[:, 0, 1] = np.sin(q), -np.sin(q)
            turn[:, 2, 2] = 1.0
            rot = rot @ turn
        elif types[e] == "P":
            pos = pos + values[:, variable[e], None] * rot[:, :, 2]
    return rot, pos


def check_chain_linuxcnc_source(machine, text: str, units: str = "mm") -> float:
    """Read a joint-chain module's element frames back and close its legs at pkmkit's
    configurations (home and random actuator sets within the strokes, solved by pkmkit's direct
    model): the largest leg-to-platform gap and tool point / axis error (m; rotations × the
    closure length), and the home joints.

    Raises:
        ExportCheckError: beyond 1e-9 m (the file's numbers are not pkmkit's machine).
    """
    from pkmkit.spatial.rotation import rotvec_to_matrix

    scale = length_scale(units)
    t = machine.chain_tables()
    n_el, n_var = len(t.element_names), len(t.variables)
    rotations = _read_array(text, "element_rotation", 9 * n_el).reshape(n_el, 3, 3)
    positions = _read_array(text, "element_position", 3 * n_el).reshape(n_el, 3) * scale
    variable = _read_array(text, "element_variable", n_el).astype(int)
    joint_scale = np.where(t.revolute, 1.0, scale)
    home = _read_array(text, "home_values", n_var) * joint_scale
    found = re.search(r"\btool_length = ([-+0-9.eE]+);", text)
    if found is None:
        raise ExportCheckError("the generated source has no tool_length")
    tool = float(found.group(1)) * scale
    length = t.closure_length
    rng = np.random.default_rng(0)
    act = t.actuated
    lo = np.where(np.isfinite(t.q_min[act]), t.q_min[act], t.home_values[act] - 0.05)
    hi = np.where(np.isfinite(t.q_max[act]), t.q_max[act], t.home_values[act] + 0.05)
    q = np.vstack([t.home_values[act], lo + rng.uniform(0.2, 0.8, (23, len(act))) * (hi - lo)])
    res = machine.fk(q, full_output=True, strokes="ignore")
    ok = np.asarray(res.status) == 0
    values = np.tile(t.home_values, (int(ok.sum()), 1))
    values[:, act], values[:, t.passive] = q[ok], res.passive[ok]
    rot_x, p_x = rotvec_to_matrix(res.platform[ok, 3:]), res.platform[ok, :3]
    worst = float(np.abs(home - t.home_values).max())
    for leg in t.legs:
        rot, pos = _chain_end(rotations, positions, t.element_types, variable, leg, values)
        worst = max(worst, float(np.abs(pos - p_x).max()),
                    length * float(np.abs(rot - rot_x).max()))
    rot, pos = _chain_end(rotations, positions, t.element_types, variable, t.head, values,
                          start=(rot_x, p_x))
    point = pos + tool * rot[:, :, 2]
    worst = max(worst, float(np.abs(point - res.pose[ok, :3]).max()),
                length * float(np.abs(rot[:, :, 2] - res.pose[ok, 3:]).max()))
    if not worst <= 1e-9 or not ok[0]:
        raise ExportCheckError(f"the generated module does not close pkmkit's configurations "
                               f"(off by {worst:.3g} m): not written")
    return worst
