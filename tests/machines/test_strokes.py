"""One check of the strokes for every family (pkmkit.machines.strokes): a pose beyond a stroke
is flagged by ``ik`` and ``fk``, single and batch, naming the joint, its leg and the excess.

The configurations beyond the strokes are built from home: the first actuator pushed 10 % of
its stroke past an end (the first end past which the machine still assembles), so the excess
is known exactly (oracle: the stroke end and the value put there)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from pkmkit.exceptions import OutOfStrokeError, ParameterError, StrokeWarning
from pkmkit.machines.registry import machine
from pkmkit.machines.strokes import signed_excess, stroke_excess, stroke_limits

ROD = ["gough-stewart", "verne", "delta", "linear-delta", "orthoglide", "five-bar"]
CHAIN = ["tripteor-x7", "trimule-600"]  # the crank-slider: see the machine files below



def _quiet_fk(m, q):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        if hasattr(m.model, "element_variable"):
            return m.fk(q, full_output=True, strokes="ignore", check_singular=False)
        return m.fk(q, full_output=True, strokes="ignore")


def beyond(m):
    """``(q_out, pose_out, excess)``: actuator 0 10 % of its stroke past an end."""
    lo, hi = stroke_limits(m)
    span = hi[0] - lo[0]
    for end, sign in ((hi[0], 1.0), (lo[0], -1.0)):
        q = m.home_q.copy()
        q[0] = end + sign * 0.1 * span
        res = _quiet_fk(m, q)
        if np.isfinite(res.pose).all():
            return q, np.asarray(res.pose), sign * 0.1 * span
    raise AssertionError(f"{m.id}: no assembly past either end of q1's stroke")


def ik_target(m, pose):
    """The inverse model's input for a pose of fk: positions for the Verne module."""
    return pose[:3] if getattr(m, "position_controlled", False) else pose


@pytest.mark.parametrize("ident", ROD)
def test_rod_families_flag_single_and_batch(ident):
    m = machine(ident)
    q_out, pose, excess = beyond(m)
    x = ik_target(m, pose)
    # single: a warning naming the joint, its leg and the excess; the values are kept
    pattern = rf"{m.actuator_names[0]} \(leg 1.* = .* (beyond|below) its stroke"
    with pytest.warns(StrokeWarning, match=pattern):
        q = m.ik(x)
    np.testing.assert_allclose(q, q_out, atol=1e-7)
    # refuse: the typed error
    with pytest.raises(OutOfStrokeError) as err:
        m.ik(x, strokes="refuse")
    assert err.value.joint == m.actuator_names[0]
    assert err.value.value == pytest.approx(q_out[0], abs=1e-7)
    # batch: home is within, the other row flagged with its signed excess, q kept
    home = ik_target(m, m.home_pose)
    res = m.ik(np.array([home, x]), full_output=True)
    assert res.out_of_stroke.tolist() == [False, True]
    assert res.stroke_excess[1, 0] == pytest.approx(excess, abs=1e-7)
    assert (res.status == 0).all() and np.isfinite(res.q).all()
    refused = m.ik(np.array([home, x]), full_output=True, strokes="refuse")
    assert refused.status.tolist() == [0, 8] and np.isnan(refused.q[1]).all()
    # the direct model judges the q it is given the same way
    with pytest.warns(StrokeWarning):
        m.fk(q_out)
    direct = m.fk(np.array([m.home_q, q_out]), full_output=True)
    assert direct.out_of_stroke.tolist() == [False, True]
    with pytest.raises(OutOfStrokeError):
        m.fk(q_out, strokes="refuse")


@pytest.mark.parametrize("ident", CHAIN)
def test_chain_families_flag_through_the_same_check(ident):
    m = machine(ident)
    q_out, pose, excess = beyond(m)
    check = stroke_excess(m, np.array([m.home_q, q_out]))
    assert check.out_of_stroke.tolist() == [False, True]
    assert check.excess[1, 0] == pytest.approx(excess, abs=1e-9)
    assert check.joints[0] == m.actuator_names[0] and check.legs[0]
    # the machine's own flags are the shared check's
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        _, direct = m.ik(np.array([ik_target(m, _quiet_fk(m, m.home_q).pose), pose]),
                         full_output=True)
    assert np.asarray(direct.out_of_stroke).tolist() == [False, True]


def test_passive_joints_are_checked_for_chains():
    """TriMule: ψ1 = 35° is beyond the measured leg's ±30° with every actuator within."""
    from pkmkit.machines import trimule_forms as forms

    m = machine("trimule-600")
    q = np.r_[forms.actuators(m.params, 0.95, np.radians(35.0), 0.0)[0], 0.0, 0.0]
    check = stroke_excess(m, q)
    assert check.out_of_stroke[0] and not check.actuator_excess.any()
    k = check.joints.index("psi1")
    assert np.degrees(check.excess[0, k]) == pytest.approx(5.0, abs=1e-6)
    assert check.message(0).startswith("psi1 (leg 1")


def test_signed_excess_definition():
    v = np.array([[0.5, 1.2, -0.1, np.nan, 1.0 + 1e-13]])
    e = signed_excess(v, np.zeros(5), np.ones(5))
    np.testing.assert_allclose(e, [[0.0, 0.2, -0.1, 0.0, 0.0]], atol=1e-15)


def test_messages_in_the_units_asked():
    m = machine("gough-stewart")
    q = m.home_q.copy()
    q[2] = 1.83
    check = stroke_excess(m, q)
    assert check.message(0, "mm") == ("q3 (leg 3) = 1830 mm, 730 mm beyond its stroke "
                                      "[650, 1100] mm")
    assert check.details(0, "mm")[0]["excess"] == pytest.approx(730.0)


@pytest.mark.parametrize("ident, name, value", [("orthoglide", "L", 1040.0),
                                                 ("gough-stewart", "base_radius", 500.0)])
def test_home_orders_of_magnitude_beyond_the_strokes_is_refused_with_a_hint(ident, name, value):
    with pytest.raises(ParameterError, match="did you mean --units mm"):
        machine(ident).with_params(**{name: value})


def test_a_home_a_little_outside_still_loads():
    m = machine("orthoglide").with_params(L=0.45)  # home rho ≈ 0.45, stroke ends at 0.3831
    assert stroke_excess(m, m.home_q).out_of_stroke[0]


def _crank_slider_with_strokes(tmp_path):
    """The crank-slider (no strokes: its crank turns fully) with θ1 ∈ [0°, 60°] and the slider
    x4 ∈ [200, 260] mm, from a machine file."""
    from pkmkit.machines.chain_file import machine_file_text
    from pkmkit.machines.registry import load

    text = machine_file_text(machine("crank-slider"), "mm")
    text = text.replace('actuated = true\n', 'actuated = true\nstroke = [0, 60]\n', 1)
    text = text.replace('display = "x4"\n', 'display = "x4"\nstroke = [200, 260]\n', 1)
    path = tmp_path / "crank-slider-strokes.toml"
    path.write_text(text)
    return load(path), path


def _dietmaier_with_strokes(tmp_path):
    """The Dietmaier hexapod (no published strokes) with 0.5–1.6 m struts, leg 1's ending
    halfway between home (1 m) and its length at the home pose raised by 50 mm, from a machine
    file; and that raised pose."""
    from pkmkit.machines.registry import load, preset_path

    m = machine("dietmaier-hexapod")
    pose = m.home_pose + np.array([0, 0, 0.05, 0, 0, 0])
    q1 = float(m.ik(pose)[0])
    end = (q1 + 1.0) / 2
    first = f"[0.5, {end!r}]" if q1 > 1.0 else f"[{end!r}, 1.6]"
    parts = open(preset_path("dietmaier-hexapod")).read().split("length = 0\n")
    strokes = [first] + ["[0.5, 1.6]"] * 5
    text = parts[0] + "".join(f"length = 0\nstroke = {st}\n{rest}"
                              for st, rest in zip(strokes, parts[1:], strict=True))
    path = tmp_path / "dietmaier-strokes.toml"
    path.write_text(text)
    return load(path), path, pose, q1 - end


def test_machines_without_strokes_are_never_out_of_stroke():
    """The crank-slider and the Dietmaier hexapod declare no strokes: nothing is flagged (the
    files below give them strokes)."""
    for ident in ("crank-slider", "dietmaier-hexapod"):
        m = machine(ident)
        assert not stroke_excess(m, m.home_q * 3).out_of_stroke.any()


def test_machine_files_flag_beyond_their_strokes(tmp_path):
    crank, _ = _crank_slider_with_strokes(tmp_path)
    q_out, pose, excess = beyond(crank)
    check = stroke_excess(crank, np.array([crank.home_q, q_out]))
    assert check.out_of_stroke.tolist() == [False, True]
    assert np.degrees(check.excess[1, 0]) == pytest.approx(np.degrees(excess))
    with pytest.raises(OutOfStrokeError):
        crank.ik(pose, strokes="refuse")

    hexapod, _, pose, excess = _dietmaier_with_strokes(tmp_path)
    with pytest.warns(StrokeWarning, match=r"q1 \(leg 1\) = .* (beyond|below) its stroke"):
        hexapod.ik(pose)
    res = hexapod.ik(np.array([hexapod.home_pose, pose]), full_output=True)
    assert res.out_of_stroke.tolist() == [False, True]
    assert res.stroke_excess[1, 0] == pytest.approx(excess, abs=1e-7)


def test_a_chain_message_states_its_lengths_in_one_unit():
    """The legs' misses, the closure residual and the stroke excess of one message: all mm
    (the residual was in m and the stroke in m beside misses in mm)."""
    import re

    from pkmkit.exceptions import ClosureMissError

    m = machine("tripteor-x7")
    q = m.home_q.copy()
    q[:2] = 3.0, 0.3
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        with pytest.raises(ClosureMissError) as err:
            m.fk(q)
    text = str(err.value)
    assert re.search(r"largest closure residual [\d.]+ mm", text)
    assert "Q1 = 3000 mm is beyond its stroke [975, 995] mm by 2005 mm" in text
    assert not re.search(r"\d m\b", text)


def test_pose_selection_keeps_to_the_strokes():
    """Drawn candidates are within the strokes; given candidates beyond them are left out
    and counted (the orthoglide's default region is 75 % beyond its strokes)."""
    from pkmkit.geometric_errors.configurations import sample_configurations
    from pkmkit.geometric_errors.pose_selection import select_poses

    m = machine("orthoglide")
    drawn = sample_configurations(m, 40, method="halton", within_strokes=True).q
    assert not stroke_excess(m, drawn).out_of_stroke.any()
    wild = sample_configurations(m, 40, method="halton").q
    out = stroke_excess(m, wild).out_of_stroke
    assert out.sum() >= 10
    sel = select_poses(m, "point", 6, candidates=wild)
    assert sel.beyond_strokes == int(out.sum()) and sel.n_candidates == int((~out).sum())
    assert not stroke_excess(m, sel.q).out_of_stroke.any()
    default = select_poses(m, "point", 6, n_candidates=60)
    assert not stroke_excess(m, default.q).out_of_stroke.any()


def test_a_machine_file_in_mm_without_units_is_refused_with_a_hint(tmp_path):
    """Strokes in m, home in mm, no ``units``: the struts at home ~1000 m long, 600× their
    stroke — refused with the line and the hint (it loaded silently)."""
    from pkmkit.exceptions import MachineFileError
    from pkmkit.machines.registry import load, preset_path

    text = open(preset_path("dietmaier-hexapod")).read().replace('units = "m"\n', "")
    text = text.replace("length = 0\n", "length = 0\nstroke = [0.5, 1.6]\n")
    text = text.replace("home = [0.636111780657885, 0.771451960366541, 0.0149557799822003,",
                        "home = [636.111780657885, 771.451960366541, 14.9557799822003,")
    path = tmp_path / "big.toml"
    path.write_text(text)
    with pytest.raises((MachineFileError, ParameterError),
                       match=r"q1 \(leg 1\) = 1000 m, 998\.4 m beyond its stroke .*did you mean"):
        load(path)


def test_chain_stroke_violations_name_the_first_joint_of_each_row_as_the_one_row_message():
    """The batched messages of a joint chain (one pass over the bad rows) are the one-joint
    message of each row's first offending joint, below or beyond, degrees or mm."""
    from pkmkit.machines.chain_checks import stroke_message, stroke_violations

    m = machine("tripteor-x7")
    model = m.model
    joints = np.flatnonzero(model.loop_variables | model.actuated)
    rng = np.random.default_rng(5)
    lo, hi = model.q_min[joints], model.q_max[joints]
    finite = (np.abs(lo) < 1e3) & (np.abs(hi) < 1e3)
    span = np.where(finite, np.clip(hi, -1e3, 1e3) - np.clip(lo, -1e3, 1e3), 1.0)
    mid = np.where(finite, 0.5 * (np.clip(lo, -1e3, 1e3) + np.clip(hi, -1e3, 1e3)), 0.0)
    values = np.tile(m.home_values, (60, 1))
    values[:, joints] = mid + span * rng.uniform(-0.8, 0.8, size=(60, joints.size))
    rows = np.ones(60, dtype=bool)
    rows[:5] = False
    bad, texts = stroke_violations(model, values, joints, rows)
    assert 10 < bad.sum() < 55 and not bad[:5].any()
    assert any("below" in t for t in texts) and any("beyond" in t for t in texts)
    for i in range(60):
        if not bad[i]:
            assert texts[i] == ""
            continue
        excess = signed_excess(values[i:i + 1, joints], lo, hi)[0]
        k = int(np.flatnonzero(excess)[0])
        assert texts[i] == stroke_message(model, int(joints[k]), float(values[i, joints[k]]))


def test_details_in_the_units_asked():
    """The JSON details of a joint beyond its stroke (``--json`` of the commands): value,
    excess and both ends of the stroke in the unit asked (the hexapod's q3 stroke is
    [0.65, 1.1] m, as the message above says in mm)."""
    q = machine("gough-stewart").home_q.copy()
    q[2] = 1.83
    check = stroke_excess(machine("gough-stewart"), q)
    for units, factor in (("m", 1.0), ("mm", 1000.0)):
        (row,) = check.details(0, units)
        assert row["joint"] == "q3" and row["unit"] == units
        assert row["value"] == pytest.approx(1.83 * factor)
        assert row["excess"] == pytest.approx(0.73 * factor)
        assert row["stroke"] == pytest.approx([0.65 * factor, 1.1 * factor])
