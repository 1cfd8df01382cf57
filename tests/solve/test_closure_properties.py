"""The closure Jacobians ∂r/∂pose and ∂r/∂q of the rod closure r = |p + R b − a(q)| − ℓ on random
machines of every kind (tests/strategies.py), against central differences — rotations by left
increments, as the engine retracts them."""

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from pkmkit.solve.rod_closure import closure_jacobians, rod_vectors, split_pose
from pkmkit.spatial.rotation import compose_rotvec
from tests.strategies import FAMILIES, near_home, well_posed


def residual(model, u, q, dof):
    p, rot = split_pose(model, u, dof)
    v = rod_vectors(model, p, q, rot)
    return v.dist - v.length


@pytest.mark.parametrize("family", sorted(FAMILIES))
@given(data=st.data())
def test_closure_jacobians_against_finite_differences(family, data):
    m = data.draw(FAMILIES[family])
    x = near_home(data.draw, m)
    assume(well_posed(m, x))
    model = m.model
    q = m.ik(x)
    dofs = ["translation"] + (["full"] if m.dims == 3 else [])
    scale = float(model.leg_length.max())
    for dof in dofs:
        jp, jq = closure_jacobians(model, x[None], q[None], dof=dof)
        n = jp.shape[2]
        u = np.zeros((n, 1))
        u[: m.dims, 0] = x
        h = 1e-6 * scale
        for j in range(n):
            up, um = u.copy(), u.copy()
            if j < m.dims:
                up[j] += h
                um[j] -= h
                step = h
            else:  # left rotation increment about axis j − 3
                step = 1e-6
                e = np.zeros((1, 3))
                e[0, j - 3] = step
                up[3:] = compose_rotvec(e, u[3:].T).T
                um[3:] = compose_rotvec(-e, u[3:].T).T
            fd = (residual(model, up, q[:, None], dof)
                  - residual(model, um, q[:, None], dof)) / (2 * step)
            np.testing.assert_allclose(jp[0, :, j], fd[:, 0], rtol=0,
                                       atol=1e-7 * max(np.abs(fd).max(), 1.0))
        for j in range(m.n_actuators):
            dq = np.zeros_like(q)
            dq[j] = 1e-6 * scale
            fd = (residual(model, u[:3] if dof == "translation" else u, (q + dq)[:, None], dof)
                  - residual(model, u[:3] if dof == "translation" else u, (q - dq)[:, None],
                             dof)) / (2e-6 * scale)
            np.testing.assert_allclose(jq[0, :, j], fd[:, 0], rtol=0, atol=1e-7)
