"""The batched per-sample direct model flags samples that do not assemble and keeps the others."""

import numpy as np

import pkmkit
from pkmkit.geometric_errors.model import _rod_index
from pkmkit.geometric_errors.tolerance import exact_rod_points, nominal_gains
from pkmkit.solve.rod_samples import sampled_geometry, solve_sampled_direct


def test_impossible_samples_are_nan_and_flagged():
    m = pkmkit.machine("linear-delta")
    index = _rod_index(m)
    samples = np.zeros((3, len(index)))
    samples[1, index.index("dL1")] = -0.9  # a rod far too short: no assembly near home
    q = np.atleast_2d(m.home_q)
    position, rot, gain = nominal_gains(m, q)
    out = solve_sampled_direct(sampled_geometry(m.model, index, samples), q, position, rot,
                               gain, dims=3)
    assert out.converged.tolist() == [[True, False, True]]
    assert np.isnan(out.position[0, 1]).all()
    np.testing.assert_allclose(out.position[0, [0, 2]], [m.home_pose, m.home_pose], atol=1e-12)
    pts = exact_rod_points(m, q, samples)
    assert np.isnan(pts[0, 1]).all() and np.isfinite(pts[0, 0]).all()


def test_one_configuration_path_equals_the_chunked_path():
    from pkmkit.geometric_errors.configurations import sample_configurations
    from pkmkit.geometric_errors.model import with_defects
    from pkmkit.geometric_errors.tolerance import tolerances

    for name in ("gough-stewart", "verne", "linear-delta", "five-bar"):
        m = pkmkit.machine(name)
        index = _rod_index(m)
        kinds = set(pkmkit.geometric_errors.model.defect_set(m).kinds)
        tol = tolerances(m, classes=dict.fromkeys(kinds, 1e-4))
        samples = tol.sample(5, np.random.default_rng(3))
        q = sample_configurations(m, 3, seed=4).q
        position, rot, gain = nominal_gains(m, q)
        geom = sampled_geometry(m.model, index, samples)
        dims = 3 if m.dims == 6 else m.dims
        single = solve_sampled_direct(geom, q, position, rot, gain, dims=dims, chunk=1)
        batch = solve_sampled_direct(geom, q, position, rot, gain, dims=dims)
        np.testing.assert_allclose(single.position, batch.position, atol=1e-13, err_msg=name)
        ref = np.atleast_2d(with_defects(m, samples[2]).fk(q))[:, :dims]
        np.testing.assert_allclose(single.position[:, 2, :dims], ref, atol=1e-12, err_msg=name)
