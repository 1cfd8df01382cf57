"""Fuzzing of the calibration-side readers: measurement files of every type, registration points
and frames, tolerance files, CMM files, ball-bar plans, compensation targets — valid files
mutated (cells, rows, columns, tokens, spans, truncation, encodings, oversized fields) or random
bytes. A reader returns values that pass their checks (finite, in SI, one file line per row, a
write → read round trip) or raises a PkmError naming the file; the registration recovers a
known rigid motion."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import pkmkit
from pkmkit.calibration.registration import load_registration, register_points
from pkmkit.geometric_errors.tolerance import read_tolerances
from pkmkit.io.measurements import format_measurements, read_csv_table, read_measurements
from pkmkit.machining.ballbar_plan import read_plan
from pkmkit.machining.cmm import read_cmm
from pkmkit.spatial.rotation import rotvec_to_matrix

from .file_cases import mutate_text
from .strategies import HOSTILE_FLOATS, call
from .test_fuzz_readers import cleanup, written

POINT = ("# units: mm\nq1,q2,q3,x,y,z\n"
         "1416.62064943,1103.19646972,1206.23111766,364.625169555,-102.863238344,135.617559338\n"
         "775.788345265,1146.82231638,980.97429171,-361.486014016,206.201047225,-121.969320984\n"
         "1515.14667588,1112.37950307,1339.66224168,387.065439283,-225.504481923,246.827851188\n")
SEEDS = {
    ("linear-delta", "point"): POINT,
    ("linear-delta", "height"): "# units: mm\nq1,q2,q3,z\n786.11,1128.01,986.00,0.34\n"
                                "955.59,1004.34,1112.82,0.79\n1145.9,908.78,917.97,0.99\n",
    ("gough-stewart", "pose"): "# units: mm\nq1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz,id\n"
                               "847.47,915.06,845.59,832.06,922.63,895.44,-17.8,136.5,799.9,1.95,"
                               "0.84,2.3,a\n983.5,987.8,969.5,960.0,991.6,974.7,-22.3,36.2,918.7,"
                               "0.21,-0.37,-2.15,b\n",
    ("verne", "ballbar"): "# units: mm\nq1,q2,q3,px,py,pz,length,tool_length,tool\n"
                          "1055.19,929.72,970.92,0,25,-200,152.10,0,T1\n"
                          "996.08,1065.21,975.11,0,25,-200,147.44,0,T1\n"
                          "1155.08,1029.17,1071.35,0,25,-200,152.31,100,T2\n",
    ("verne", "part"): "# units: mm\npath,x0,y0,z0,x1,y1,z1,x,y,z\n"
                       "36,-160,-88,-70,160,-88,-70,60.58,111.52,129.13\n"
                       "41,-88,-160,-70,-88,160,-70,114.87,59.41,129.02\n",
}
MACHINES = {name: pkmkit.machine(name) for name in ("linear-delta", "gough-stewart", "verne")}
REGISTRATION = ("# units: mm\nid,x,y,z,i,j,k\n1,-331.205,2567.607,389.687,0,0.7,0.7\n"
                "2,-809.819,2774.647,423.530,0,0,1\n3,-500,2600,900,1,0,0\n")
FRAME = ('{"units": "mm", "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], '
         '"translation": [10, 20, 30]}\n')
TOLERANCES = ('units = "mm"\ndistribution = "uniform"\n\n[classes]\nbase = 0.02\n'
              'platform = 0.02\nlength = 0.01\n\n[parameters]\n"dA1*" = 0.05\n')
CMM = ("# units: mm\n# points: surface\nsection,label,x,y,z,path,direction\n"
       "1,Q,60.58,111.51,121.13,36,x\n1,M,60.58,121.52,133.00,36,x\n"
       "1,N,60.58,121.51,136.99,36,x\n")
PLAN = ("# units: mm\nx,y,z,px,py,pz,tool_length,tool,id\n"
        "52.73362921,160.6315065,-163.6233756,0,25,-200,0,T1,P1\n"
        "-124.4137448,-36.38551099,-142.96458,0,25,-200,0,T1,P2\n"
        "52.73362921,160.6315065,-163.6233756,0,25,-200,100,T2,P3\n")


def hostile_file(text: str) -> st.SearchStrategy[bytes]:
    """``text`` mutated by :func:`file_cases.mutate_text` (cells, rows, tokens, encodings…)."""
    return st.randoms(use_true_random=False).map(lambda rng: mutate_text(rng, text, big=False))


def file_lines(labels, path) -> list[int]:
    """The line numbers of ``path:line`` labels."""
    assert all(label.startswith(f"{path}:") for label in labels)
    return [int(label.rsplit(":", 1)[1]) for label in labels]


@given(st.sampled_from(sorted(SEEDS)), st.data())
def test_measurement_files(key, data):
    name, kind = key
    machine = MACHINES[name]
    path = written(data.draw(hostile_file(SEEDS[key])), ".csv")
    try:
        m = call(read_measurements, path, machine, kind)
        if m is None:
            return
        n = len(m.values)
        assert n >= 1 and len(m.labels) == n
        lines = file_lines(m.labels, path)
        assert lines == sorted(set(lines)), "one file line per row, in order"
        assert np.isfinite(m.values).all()
        for extra in (m.q, m.tool_length, m.pivot, m.commanded):
            assert extra is None or (len(extra) == n and np.isfinite(extra).all())
        # what was read is what the file says: written back (mm) and read again, the same SI
        path.write_text(format_measurements(m, machine, units="mm"))
        back = read_measurements(path, machine, kind)
        np.testing.assert_allclose(back.values, m.values, rtol=1e-11, atol=1e-15)
        if m.q is not None:
            np.testing.assert_allclose(back.q, m.q, rtol=1e-11, atol=1e-15)
    finally:
        cleanup(path)


@given(st.sampled_from([("x", "y", "z"), ("x", "y", "z", "rx", "ry", "rz")]), st.data())
def test_point_tables(required, data):
    """Registration points and compensation targets (``read_csv_table``)."""
    seed = REGISTRATION if len(required) == 3 else (
        "x,y,z,rx,ry,rz\n0,0,0.8,0,0,0\n0.02,0.01,0.82,1,0,2\n")
    optional = ("i", "j", "k", "id") if len(required) == 3 else ()
    path = written(data.draw(hostile_file(seed)), ".csv")
    try:
        table = call(read_csv_table, path, required, optional)
    finally:
        cleanup(path)
    if table is not None:
        n = len(table.lines)
        assert n >= 1 and table.scale > 0
        for column in required:
            assert table.numbers[column].shape == (n,)
            assert np.isfinite(table.numbers[column]).all()


@given(st.data())
def test_registration_frames(data):
    path = written(data.draw(hostile_file(FRAME)), ".json")
    try:
        reg = call(load_registration, path)
    finally:
        cleanup(path)
    if reg is not None:
        np.testing.assert_allclose(reg.rotation.T @ reg.rotation, np.eye(3), atol=1e-6)
        assert np.linalg.det(reg.rotation) > 0 and np.isfinite(reg.translation).all()


@given(st.lists(st.floats(-np.pi, np.pi), min_size=3, max_size=3),
       st.lists(st.floats(-10.0, 10.0), min_size=3, max_size=3),
       st.lists(st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3), min_size=3,
                max_size=8),
       st.one_of(st.none(), HOSTILE_FLOATS))
def test_registration_recovers_a_known_motion(rotvec, t, points, spoil):
    """nominal = R · measured + t, exactly: the registration gives back R and t, or refuses
    (points that do not fix the rotation; a spoiled coordinate that is not finite)."""
    rot = rotvec_to_matrix(np.asarray(rotvec))
    measured = np.asarray(points)
    nominal = measured @ rot.T + np.asarray(t)
    if spoil is not None:
        measured = measured.copy()
        measured[0, 0] = spoil
    reg = call(register_points, measured, nominal)
    if reg is None:
        return
    if spoil is None:
        np.testing.assert_allclose(reg.apply(measured), nominal, atol=1e-9)
        np.testing.assert_allclose(reg.rotation, rot, atol=1e-6)
    np.testing.assert_allclose(reg.rotation.T @ reg.rotation, np.eye(3), atol=1e-9)
    assert np.isfinite(reg.translation).all() and np.isfinite(reg.rms)
    np.testing.assert_allclose(reg.apply(measured) - nominal, reg.point_residuals, atol=1e-6 * (
        1 + np.abs(nominal).max()))


HEXAPOD = pkmkit.machine("gough-stewart")


@given(st.data())
def test_tolerance_files(data):
    path = written(data.draw(hostile_file(TOLERANCES)), ".toml")
    try:
        tol = call(read_tolerances, str(path), HEXAPOD)
    finally:
        cleanup(path)
    if tol is not None:
        assert len(tol.half_width) == len(tol.names)
        assert np.isfinite(tol.half_width).all() and (tol.half_width >= 0).all()


@given(st.data())
def test_cmm_files(data):
    path = written(data.draw(hostile_file(CMM)), ".csv")
    try:
        cmm = call(read_cmm, path)
    finally:
        cleanup(path)
    if cmm is not None:
        assert np.isfinite(cmm.points).all() and len(cmm.points) >= 1


@given(st.data())
def test_ballbar_plans(data):
    path = written(data.draw(hostile_file(PLAN)), ".csv")
    try:
        plan = call(read_plan, path)
    finally:
        cleanup(path)
    if plan is not None:
        assert np.isfinite(plan.bar_length) and plan.bar_length > 0
        radius = np.linalg.norm(plan.targets - plan.pivot, axis=1)
        np.testing.assert_allclose(radius, plan.bar_length, rtol=1e-6, atol=1e-9)
        assert np.isfinite(plan.tool_length).all()
