"""Chains drawn in one layout frame, re-expressed element by element: walking the returned
elements with 4×4 products from the start frame gives back every axis, point and fixed frame
of the drawing."""

import numpy as np
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.model.chain_layout import chain_from_layout
from pkmkit.model.chains import FIXED, ElementSpec, invariant_frame


def _local(spec):
    if spec.rotation is not None:
        frame = np.eye(4)
        frame[:3, :3], frame[:3, 3] = np.asarray(spec.rotation), spec.point
        return frame
    return invariant_frame(spec.axis, spec.point, spec.spin)


def test_walking_the_relative_elements_gives_back_the_layout():
    start = np.eye(4)
    start[:3, :3] = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix()
    start[:3, 3] = [0.1, -0.2, 0.3]
    axis_f = np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0)
    fixed_rot = Rotation.from_rotvec([0.0, 0.4, 0.2]).as_matrix()
    chain = [ElementSpec("q1", "P", axis=(0.0, 0.0, 1.0), point=(0.1, -0.2, 0.3)),
             ElementSpec("a", "R", axis=(1.0, 0.0, 0.0), point=(0.2, 0.0, 0.1)),
             ElementSpec("F1", FIXED, axis=tuple(axis_f), point=(0.2, 0.1, 0.0), spin=0.3),
             ElementSpec("b", "R", axis=(0.0, 0.6, 0.8), point=(0.3, 0.1, -0.1)),
             ElementSpec("F2", FIXED, rotation=fixed_rot, point=(0.4, 0.0, 0.2))]
    out = chain_from_layout(chain, start)
    frame = start
    for spec, drawn in zip(out, chain, strict=True):
        frame = frame @ _local(spec)
        np.testing.assert_allclose(frame[:3, :3].T @ frame[:3, :3], np.eye(3), atol=1e-12)
        np.testing.assert_allclose(frame[:3, 3], drawn.point, atol=1e-12)
        if drawn.type == FIXED and drawn.rotation is not None:
            np.testing.assert_allclose(frame[:3, :3], fixed_rot, atol=1e-12)
        else:
            axis = np.asarray(drawn.axis) / np.linalg.norm(drawn.axis)
            np.testing.assert_allclose(frame[:3, 2], axis, atol=1e-12)
    # the first fixed frame: its x turned by the spin from the invariant frame's
    walked = start @ _local(out[0]) @ _local(out[1]) @ _local(out[2])
    drawn = invariant_frame(axis_f, (0.2, 0.1, 0.0), 0.3)
    np.testing.assert_allclose(walked, drawn, atol=1e-12)


def test_parameter_values_read_back_the_invariants_of_the_elements():
    """The Tripteor X7's parameter vector read back from its frames: each element's unit axis
    (I, J, K), its point (A, B, C, m) and, for fixed frames, the spin (S, rad), as the
    elements state them."""
    model = pkmkit.machine("tripteor-x7").model
    values = dict(zip(model.parameter_names(), model.parameter_values(), strict=True))
    for spec in model.elements:
        if spec.rotation is not None:
            continue
        label = spec.label or spec.name
        axis = np.asarray(spec.axis) / np.linalg.norm(spec.axis)
        np.testing.assert_allclose([values[f"{c}{label}"] for c in "IJK"], axis, atol=1e-12)
        np.testing.assert_allclose([values[f"{c}{label}"] for c in "ABC"], spec.point,
                                   atol=1e-12)
        if spec.type == FIXED:
            assert abs(values[f"S{label}"] - spec.spin) < 1e-12
