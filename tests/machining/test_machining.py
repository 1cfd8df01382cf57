"""Seed 003's machined-part chain: the swept surfaces against hand-computed cases, probing and
reconstruction as inverse steps, the CMM noise carried into the centres, and the chain from
G-code to identified parameters."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration.simulate import random_defects
from pkmkit.machining.cmm import probe
from pkmkit.machining.part import Cutters, Placement, part_passes, seed_part_program
from pkmkit.machining.reconstruct import reconstruct, reconstructed_measurements
from pkmkit.machining.sweep import machine_part
from pkmkit.model.defects_table import apply_defect_vector
from pkmkit.motion.gcode import read_gcode

R_E, R_B = 0.010, 0.008


@pytest.fixture(scope="module")
def verne():
    return pkmkit.machine("verne")


def _program(*moves: str) -> str:
    return "G21 G90\nG0 X-60 Y-20 Z-50\n" + "\n".join(moves) + "\nM30\n"


def test_straight_pass_on_a_perfect_machine_by_hand(verne):
    """A pass along +x at y = −20 mm, z = −50 mm; material on the left (+y): the wall is at
    y = −20 + 10 mm, the slot bottom at z = −50 − 8 mm, the centre on the commanded line."""
    passes = part_passes(read_gcode(_program("G1 X60 F1000")))
    part = machine_part(verne, verne, passes, sections=7)
    np.testing.assert_allclose(part.wall, -0.020 + R_E, atol=1e-13)
    np.testing.assert_allclose(part.slot[:, 2], -0.050 - R_B, atol=1e-13)
    np.testing.assert_allclose(part.slot[:, 1], -0.020, atol=1e-13)
    np.testing.assert_allclose(part.centre[:, 1:], [[-0.020, -0.050]] * 7, atol=1e-13)
    np.testing.assert_allclose(part.side, 1.0)
    # material on the right of a pass travelling −y at x = 30 mm: the wall at x = 30 − 10 mm
    back = part_passes(read_gcode(_program("G0 X30 Y40", "G1 Y-40 F1000")))
    part = machine_part(verne, verne, back, sections=5, wall_side="right")
    np.testing.assert_allclose(part.wall, 0.030 - R_E, atol=1e-13)  # right of −y is −x
    np.testing.assert_allclose(part.side, -1.0)


def test_oblique_and_sloped_pass_by_hand(verne):
    """The part turned by φ sees an x pass at slope −tan φ in its frame: the section x_m = s
    meets the wall R/cos φ from the centre line; a pass rising by h per unit length has its slot
    bottom R_b·√(1 + h²) below the centre line in the section."""
    phi = np.radians(2.0)
    passes = part_passes(read_gcode(_program("G1 X60 Z-44 F1000")))  # rises 6 mm over 120 mm
    place = Placement(0.01, -0.02, 0.003, phi)
    part = machine_part(verne, verne, passes, placement=place, sections=6)
    h = 0.006 / 0.120 / np.cos(phi)  # dz/dx_m along the part's x axis
    line = place.to_part(passes[0].at(np.linspace(0, 1, 50)))
    y_line = np.interp(part.s, line[:, 0], line[:, 1])
    z_line = np.interp(part.s, line[:, 0], line[:, 2])
    np.testing.assert_allclose(part.wall - y_line, R_E / np.cos(phi), atol=1e-13)
    np.testing.assert_allclose(z_line - part.slot[:, 2], R_B * np.sqrt(1 + h**2), atol=1e-13)
    np.testing.assert_allclose(part.centre[:, 1:], np.column_stack([y_line, z_line]),
                               atol=1e-13)


@pytest.mark.parametrize("points", ["surface", "tip"])
def test_reconstruction_inverts_probing_on_straight_passes(verne, points):
    phi = np.radians(0.7)
    passes = part_passes(read_gcode(_program("G1 X60 Z-47 F1000", "G0 X-20 Y-60",
                                             "G1 Y50 Z-52")))
    part = machine_part(verne, verne, passes, placement=Placement(-0.1, 0.05, 0.02, phi),
                        sections=16)
    rec = reconstruct(probe(part, sigma=0.0, points=points))
    assert np.abs(rec.centre - part.centre).max() < 1e-12


@pytest.fixture(scope="module")
def defected_part(verne):
    true = apply_defect_vector(verne, random_defects(verne, np.random.default_rng(5)))
    passes = part_passes(read_gcode(seed_part_program(verne, levels=1)))
    place = Placement(-0.2, -0.2, -0.2, np.radians(0.3))
    return machine_part(true, verne, passes, placement=place, sections=180), passes


def test_reconstruction_inverts_probing_on_paths_bent_by_defects(defected_part):
    """The defects bend the reached path (slopes up to ~0.01 in the part frame); the cubic fit of
    the slopes leaves an error of order R·g·δg (≈ 1e-9 m), far below the CMM's noise."""
    part, _ = defected_part
    assert np.abs(np.diff(part.wall)).max() > 1e-6  # the walls are not straight lines
    for points in ("surface", "tip"):
        rec = reconstruct(probe(part, sigma=0.0, points=points))
        assert np.abs(rec.centre - part.centre).max() < 5e-9


def test_cmm_noise_reaches_the_centres_as_expected(defected_part):
    """σ per coordinate: the centre's height comes from Q alone (σ), its offset across the pass
    from the mean of M and N (σ/√2), its position along the pass from the mean of three (σ/√3)."""
    part, _ = defected_part
    sigma = 2e-6
    rec = reconstruct(probe(part, np.random.default_rng(0), sigma=sigma))
    err = rec.centre - part.centre
    idx = np.arange(len(err))
    across, along = err[idx, 1 - part.axis], err[idx, part.axis]
    n = len(err)
    assert n > 100
    band = 4 / np.sqrt(2 * n)  # ±4 standard errors of a standard-deviation estimate
    for values, expected in ((err[:, 2], sigma), (across, sigma / np.sqrt(2)),
                             (along, sigma / np.sqrt(3))):
        assert abs(np.std(values) / expected - 1) < band
        assert abs(np.mean(values)) < 4 * expected / np.sqrt(n)


@pytest.mark.ci
def test_chain_identifies_injected_defects_back(verne):
    """Defects injected in the parameters the part identifies come back within their
    uncertainty, the part's placement too, from simulated CMM points through reconstruction."""
    from pkmkit.geometric_errors.model import defect_set
    from pkmkit.machining.study import machined_part_study

    first = machined_part_study(seed=4, sections=100)
    names = first.result.names
    dset = defect_set(verne)
    delta = np.zeros(len(dset))
    truth = random_defects(verne, np.random.default_rng(9))
    for n in names:
        delta[dset.index(n)] = truth[dset.index(n)]
    study = machined_part_study(seed=6, sections=100, defects=delta, parameters=list(names))
    r = study.result
    assert set(r.names) == set(names)
    for n, v, s in zip(r.names, r.values, r.std, strict=True):
        assert abs(v - delta[dset.index(n)]) < 4 * s, n
    for v, s, t in zip(r.setup_values, r.setup_std, study.placement.vector, strict=True):
        assert abs(v - t) < 4 * s
    assert r.after.rms < 0.01 * r.before.rms
    assert study.machined["compensated"]["along_x"] < 20e-6
    assert study.machined["compensated"]["along_y"] < 40e-6


def test_reconstructed_measurements_tie_sections_to_their_passes(defected_part):
    part, passes = defected_part
    data = reconstructed_measurements(reconstruct(probe(part, sigma=0.0)), passes)
    assert data.kind == "part" and len(data) == len(part.s)
    by_line = {p.path: p.segment for p in passes}
    np.testing.assert_array_equal(data.commanded, [by_line[p] for p in data.path])


def test_cutters_refuse_a_probe_tip_that_does_not_fit():
    with pytest.raises(pkmkit.exceptions.InputError, match="probe tip radius"):
        Cutters().reduced(0.009)


def test_sections_near_a_crossing_pass_are_not_probed(verne):
    """A y pass crossing the x pass at x = 0 at the same height hides ±20 mm of it; the same
    pass 30 mm higher leaves the x pass's wall and slot alone."""
    x_pass = "G1 X60 F1000"
    for z, hidden in ((-50, True), (-20, False)):
        prog = _program(x_pass, f"G0 X0 Y-40 Z{z}", "G1 Y40")
        part = machine_part(verne, verne, part_passes(read_gcode(prog)), sections=60)
        on_x = part.axis == 0
        near = np.abs(part.s[on_x]) < 2 * R_E
        assert near.any() != hidden
        assert (np.abs(part.s[on_x]) > 2 * R_E).sum() > 10


def test_unconverged_sections_are_an_error(verne, monkeypatch):
    from pkmkit.machining import sweep

    monkeypatch.setattr(sweep, "ITERATIONS", 0)
    passes = part_passes(read_gcode(_program("G1 X60 F1000")))
    with pytest.raises(pkmkit.exceptions.InputError, match=r"pass at line 3: the section planes' "
                                                       r"intersections did not converge"):
        machine_part(verne, verne, passes, placement=Placement(phi=0.05), sections=4)
