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


def check_linuxcnc_source(machine, text: str, units: str = "mm") -> float:
    """Read the geometry back from a generated module and close its rods at pkmkit's
    configurations (home, the named poses, random poses near home): the largest
    ``| |p + R b_j − a_j(q_j)| − ρ_j(q_j) |`` (m), with q from pkmkit's inverse model.

    Raises:
        ExportCheckError: beyond 1e-9 m (the file's numbers are not pkmkit's machine).
    """
    scale = length_scale(units)
    n = machine.n_actuators
    kind = _read_array(text, "rod_kind", n)
    base = _read_array(text, "rod_base", 3 * n).reshape(n, 3) * scale
    platform = _read_array(text, "rod_platform", 3 * n).reshape(n, 3) * scale
    axis = _read_array(text, "rod_axis", 3 * n).reshape(n, 3)
    length = _read_array(text, "rod_length", n) * scale
    crank = kind == 2
    joint_scale = np.where(crank, np.pi / 180.0, scale)
    home_q = _read_array(text, "home_joints", n) * joint_scale
    x, q = sample_poses(machine)
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
