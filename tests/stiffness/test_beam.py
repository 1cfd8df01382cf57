"""Beam compliance against the 12×12 Euler–Bernoulli element; sections; reference point."""

from __future__ import annotations

import numpy as np
import pytest

from pkmkit.exceptions import ParameterError
from pkmkit.stiffness.beam import Material, Section, beam_compliance, parse_section
from pkmkit.stiffness.frames import move_compliance, move_stiffness, shift_matrix


def element_stiffness(length: float, s: Section, m: Material) -> np.ndarray:
    """The 12×12 stiffness of a 3-D Euler–Bernoulli frame element along x (nodes 1 and 2,
    DOFs u, v, w, θx, θy, θz each), as in the textbooks (Przemieniecki)."""
    ell, e, g = length, m.E, m.G
    k = np.zeros((12, 12))
    ea, gj = e * s.area / ell, g * s.J / ell
    for a, b, c in ((0, 6, ea), (3, 9, gj)):
        k[a, a] = k[b, b] = c
        k[a, b] = k[b, a] = -c
    # bending in x-y (v, θz) with I_z, in x-z (w, θy) with I_y (sign of θy opposite)
    for (v, t, inertia, sign) in ((1, 5, s.I_z, 1.0), (2, 4, s.I_y, -1.0)):
        ei = e * inertia
        idx = [v, t, v + 6, t + 6]
        block = ei / ell**3 * np.array([
            [12, 6 * ell * sign, -12, 6 * ell * sign],
            [6 * ell * sign, 4 * ell**2, -6 * ell * sign, 2 * ell**2],
            [-12, -6 * ell * sign, 12, -6 * ell * sign],
            [6 * ell * sign, 2 * ell**2, -6 * ell * sign, 4 * ell**2]])
        k[np.ix_(idx, idx)] = block
    return k


@pytest.mark.parametrize("section", [Section.circle(0.03), Section.tube(0.05, 0.04),
                                     Section.rectangle(0.02, 0.05)])
def test_cantilever_compliance_is_the_inverse_of_the_free_node_block(section):
    length, material = 0.7, Material(70e9, 26e9)
    k = element_stiffness(length, section, material)
    free = np.linalg.inv(k[6:, 6:])  # node 1 clamped
    np.testing.assert_allclose(beam_compliance(length, section, material), free,
                               rtol=1e-10, atol=1e-12 * np.abs(free).max())


def test_element_has_six_rigid_modes():
    k = element_stiffness(0.5, Section.circle(0.02), Material())
    assert np.sum(np.abs(np.linalg.eigvalsh(k)) < 1e-6 * np.abs(k).max()) == 6


def test_batched_lengths_and_zero_length():
    s = Section.circle(0.01)
    out = beam_compliance(np.array([0.0, 0.3]), s, Material())
    assert (out[0] == 0).all()
    np.testing.assert_allclose(out[1], beam_compliance(0.3, s, Material()))


def test_section_errors():
    with pytest.raises(ParameterError, match="larger than a link"):
        beam_compliance(0.02, Section.circle(0.03), Material())
    with pytest.raises(ParameterError, match="inner"):
        Section.tube(0.02, 0.03)
    with pytest.raises(ParameterError, match="material E"):
        Material(E=-1.0)
    with pytest.raises(ParameterError, match="shape"):
        parse_section("hexagon:3")
    # 1e308 m: OverflowError raising d⁴ (issue 18 §7 fuzz, --set rod_section=circle:1e308)
    for text in ("circle:1e308", "tube:1e308,1", "rect:1,1e200"):
        with pytest.raises(ParameterError, match=r"beyond 1e\+06 m: check the units"):
            parse_section(text)
    assert parse_section("tube:50,40", 1e-3).area == pytest.approx(
        np.pi * (0.05**2 - 0.04**2) / 4)


def test_moving_the_reference_point():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(6, 6))
    k = (a @ a.T + 6 * np.eye(6))[None]
    r = np.array([[0.1, -0.2, 0.3]])
    c = np.linalg.inv(k)
    np.testing.assert_allclose(np.linalg.inv(move_stiffness(k, r)), move_compliance(c, r),
                               rtol=1e-10)
    # a rigid-body displacement of point a seen from b = a + r
    t_a = rng.normal(size=6)
    t_b = shift_matrix(r)[0] @ t_a
    np.testing.assert_allclose(t_b[:3], t_a[:3] + np.cross(t_a[3:], r[0]))
    # moving there and back is the identity
    np.testing.assert_allclose(move_stiffness(move_stiffness(k, r), -r), k, rtol=1e-10)
