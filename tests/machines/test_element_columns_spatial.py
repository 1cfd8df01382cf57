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
from pkmkit.machines.parameter_vector import element_frame
from pkmkit.model.chains import FIXED, ElementSpec, invariant_frame
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
    # every other column, and always I6, J6: the axis of Q4 along the previous z, where (4.6)
    # alone spins the frame by 90° as soon as the axis tilts (with_parameters keeps it
    # continuous, as the defects do)
    composed = [k for i, k in enumerate(composed)
                if i % 2 == 0 or s.index.names[k] in ("I6", "J6")]
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


def _frame_turn(a: np.ndarray, b: np.ndarray) -> float:
    """The angle (rad) between two rotations ``(3, 3)``."""
    return float(np.linalg.norm(matrix_to_rotvec((a @ b.T)[None])[0]))


@pytest.mark.parametrize("component", [0, 1])
def test_a_tilted_axis_moves_its_frame_continuously(component, tmp_path):
    """Every element frame of the element-described Tripteor, and fixed frames with a spin along
    the previous z: tilting the axis by 1e-7 turns the frame by about 1e-7, never by (4.6)'s
    jump (90° for Q4's axis along z: the tool moved by 6 cm before)."""
    path = tmp_path / "tripteor-elements.toml"
    path.write_text(machine_file_text(pkmkit.machine("tripteor-x7")))
    m = pkmkit.load(path)
    model = m.model
    cases = [(spec, model.nominal_frames[e]) for e, spec in enumerate(model.elements)]
    for spin in (0.0, 0.5, -2.0):
        spec = ElementSpec(name="F", type=FIXED, axis=(0.0, 0.0, 1.0), point=(0.1, 0, 0),
                           spin=spin)
        cases.append((spec, invariant_frame(spec.axis, spec.point, spin)))
    h = 1e-7
    for spec, frame in cases:
        values = np.concatenate([frame[:3, 2], frame[:3, 3]])
        if spec.type == FIXED:
            base = invariant_frame(frame[:3, 2], frame[:3, 3])
            values = np.append(values, np.arctan2(base[:3, 1] @ frame[:3, 0],
                                                  base[:3, 0] @ frame[:3, 0]))
        for sign in (1.0, -1.0):
            moved = values.copy()
            moved[component] += sign * h
            turned = _frame_turn(element_frame(spec, frame, moved)[:3, :3], frame[:3, :3])
            assert turned < 2 * h, (spec.name, sign, turned)
            same = element_frame(spec, frame, values)
            np.testing.assert_allclose(same, frame, atol=1e-15, err_msg=spec.name)
