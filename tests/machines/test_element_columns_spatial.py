"""The element-invariant columns of an element-described joint chain (the twist of each
element frame composed with the closure sensitivity) against central differences of the
machine rebuilt with the parameter moved, on the Tripteor written element by element (a
spatial chain whose element frames turn about different axes) (issue 18 §9, plausible bugs: the
frame's rotation change taken as R₀ᵀ R₋ instead of R₋ R₀ᵀ on one side passed every test,
whose element-described machines are planar: rotations about one axis commute)."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import PkmError
from pkmkit.geometric_errors.parameter_sensitivity import parameter_sensitivity
from pkmkit.machines.chain_file import machine_file_text
from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix

H = 1e-6


def _tool(m, q):
    r = m.fk(q[None], full_output=True, strokes="ignore")
    return r.pose[0, :3], rotvec_to_matrix(r.tool_frame[:, 3:])[0]


@pytest.mark.ci
def test_element_columns_match_central_differences_on_a_spatial_chain(tmp_path):
    path = tmp_path / "tripteor-elements.toml"
    path.write_text(machine_file_text(pkmkit.machine("tripteor-x7")))
    m = pkmkit.load(path)
    q = m.home_q
    s = parameter_sensitivity(m, q, roles=("nominal",))
    v = m.parameters()
    composed = [k for k, how in enumerate(s.method) if how == "composition"]
    assert len(composed) >= 100
    # I6, J6: the frame of the head's last element (axis along z, spin from x) jumps when its
    # axis leaves z: the central differences are 3·10⁴ m per unit and disagree with the
    # composition (seen, left for the owners of the chain model: docs/testing.md)
    composed = [k for k in composed if s.index.names[k] not in ("I6", "J6")][::2]
    checked = 0
    for k in composed:
        name = s.index.names[k]
        h = H * max(1.0, abs(v[name]))
        try:
            sides = [m.with_parameters(v.replace({name: v[name] + e * h})) for e in (1, -1)]
        except PkmError:  # a hyperstatic chain that no longer closes: nothing to compare
            continue
        (p1, r1), (p2, r2) = (_tool(side, q) for side in sides)
        np.testing.assert_allclose(s.point[0, :, k], (p1 - p2) / (2 * h), atol=1e-7,
                                   err_msg=name)
        omega = matrix_to_rotvec((r1 @ r2.T)[None])[0] / (2 * h)
        np.testing.assert_allclose(s.rotation[0, :, k], omega, atol=1e-7, err_msg=name)
        checked += 1
    assert checked >= 40
