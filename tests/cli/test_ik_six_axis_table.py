"""``pkmkit ik <six-axis machine> --input`` row by row against the library (issue 22 §5).

The command skips the record fields it does not show (assembly modes, per-rod shortfalls): its
table must still be, row for row, what ``m.ik(X, full_output=True)`` says — statuses (the
library's OK rows beyond a stroke are ``out-of-stroke``), actuator values in the table's unit,
and for the Verne module the orientation the rods impose — on a table with bad rows (NaN, inf,
out of reach, beyond a stroke). Angles in degrees are converted by scipy's ``Rotation`` here,
an independent oracle of the command's conversion.
"""

import warnings

import numpy as np
import pyarrow as pa
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pytest
from scipy.spatial.transform import Rotation

import pkmkit

ROWS = 1500


def _poses(position_controlled: bool) -> np.ndarray:
    """Poses in mm and degrees: random, some far out of reach, some NaN or inf cells."""
    rng = np.random.default_rng(7)
    x = np.column_stack([rng.uniform(-300, 300, (ROWS, 3)), rng.uniform(-40, 40, (ROWS, 3))])
    x[::7, :3] *= 4.0  # out of reach
    x[::97, 1] = np.nan
    x[5::101, 4 if not position_controlled else 2] = np.inf
    if not position_controlled:
        x[:, 2] += 800.0
    return np.round(x[:, :3] if position_controlled else x, 6)


def _read(path) -> pa.Table:
    if path.suffix == ".parquet":
        return pq.read_table(path)
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    return pcsv.read_csv(pa.py_buffer("\n".join(lines).encode()))


@pytest.mark.parametrize("ident", ["gough-stewart", "verne"])
@pytest.mark.parametrize("ext", ["csv", "parquet"])
def test_table_rows_are_the_library_records(run, tmp_path, ident, ext):
    m = pkmkit.machine(ident)
    position = m.position_controlled
    x = _poses(position)
    names = ["x", "y", "z"] if position else ["x", "y", "z", "A", "B", "C"]
    src, out = tmp_path / "poses.csv", tmp_path / f"q.{ext}"
    pcsv.write_csv(pa.table({n: x[:, j] for j, n in enumerate(names)}), src,
                   write_options=pcsv.WriteOptions(quoting_style="none"))
    result = run("ik", ident, "--input", src, "--output", out, "--units", "mm")
    assert result.exit_code == 3, result.output  # bad rows flagged

    # the library on the same poses in SI, the angles converted by scipy
    si = x[:, :3] / 1000.0
    if not position:
        finite = np.isfinite(x[:, 3:]).all(axis=1)
        rotvec = np.full((ROWS, 3), np.nan)
        rotvec[finite] = Rotation.from_euler("xyz", x[finite, 3:], degrees=True).as_rotvec()
        rotvec[~finite] = x[~finite, 3:]  # NaN / inf stay invalid
        si = np.column_stack([si, rotvec])
    with warnings.catch_warnings():  # rows beyond a stroke warn
        warnings.simplefilter("ignore")
        rec = m.ik(si, full_output=True)
    table = _read(out)
    status = np.array(table.column("status").to_pylist())
    labels = np.array([pkmkit.status.Status(int(s)).label for s in rec.status], dtype=object)
    labels[(rec.status == 0) & rec.out_of_stroke] = "out-of-stroke"
    assert (status == labels).all(), np.flatnonzero(status != labels)[:10]
    assert {"ok", "out-of-stroke", "invalid-input"} <= set(status)
    assert ("unreachable" in set(status)) or not position

    q = np.column_stack([table.column(n).to_numpy() for n in m.actuator_names])
    want = rec.q * 1000.0  # the table's unit
    shown = status != "invalid-input"
    np.testing.assert_array_equal(np.isnan(q), np.isnan(want))
    np.testing.assert_allclose(q[shown], want[shown], rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(np.isnan(q[status == "ok"]).any(), False)
    if position:  # the orientation the rods impose, in degrees of the xyz convention
        abc = np.column_stack([table.column(n).to_numpy() for n in "ABC"])
        ok = np.isfinite(rec.pose).all(axis=1)
        expect = Rotation.from_rotvec(rec.pose[ok, 3:]).as_euler("xyz", degrees=True)
        np.testing.assert_allclose(abc[ok], expect, atol=1e-9)
        assert np.isnan(abc[~ok]).all()

