"""A table's angles → rotation vectors, the C algebra (``pkmkit.native.kernels.euler_quat``,
``euler_rotvec``) against the NumPy path it replaces, bit for bit, and against scipy's
``Rotation`` (an independent oracle) — issue 22 §5, ``pkmkit ik gough-stewart --input``."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmkit.boundary import coordinates
from pkmkit.numerics.jit import native_kernels

KERNELS = native_kernels()
needs_native = pytest.mark.skipif(KERNELS is None, reason="pkmkit.native not built")
CONVENTIONS = ["xyz", "ZYX", "zyz", "XYX", "zxy", "YZY", "xzx", "ZXZ"]


def _rows(n: int = 40_000) -> np.ndarray:
    """Positions and angles in degrees: random, multiples of 90 (gimbal locks, zero
    components, rotations of π), tiny angles (the series), signed zeros, non-finite cells."""
    rng = np.random.default_rng(11)
    v = np.column_stack([rng.uniform(-1, 1, (n, 3)), rng.uniform(-200, 200, (n, 3))])
    v[::7, 3:] = np.round(v[::7, 3:] / 90.0) * 90.0
    v[::11, 3:] = 0.0
    v[::13, 4] = 90.0
    v[::17, 4] = -90.0
    v[::19, 3:] = 180.0
    v[::23, 3:] = -0.0
    v[::29, 3:] *= 1e-6
    v[5, 2], v[6, 4], v[7, 0], v[8, 5] = np.nan, np.inf, -np.inf, 1e300
    return v


@needs_native
@pytest.mark.parametrize("convention", CONVENTIONS)
def test_native_rows_are_the_numpy_bits(convention):
    v = _rows()
    numpy_rows = coordinates._angles_numpy(v, 1e-3, convention)
    native_rows = coordinates._angles_native(KERNELS, v, 1e-3, convention)
    assert np.isnan(native_rows[5:8]).all()
    # bit for bit, signed zeros included; NaN rows alike
    np.testing.assert_array_equal(np.isnan(numpy_rows), np.isnan(native_rows))
    finite = ~np.isnan(numpy_rows)
    assert (numpy_rows.view(np.uint64)[finite] == native_rows.view(np.uint64)[finite]).all()


@pytest.mark.parametrize("convention", ["xyz", "ZYX", "zyz"])
def test_rows_are_scipys_rotations(convention):
    v = _rows(5_000)
    rows = coordinates._angles_from_cli(v, 1e-3, convention)
    ok = np.isfinite(v).all(axis=1)
    assert np.isnan(rows[~ok]).all()
    np.testing.assert_array_equal(rows[ok, :3], v[ok, :3] * 1e-3)
    got = Rotation.from_rotvec(rows[ok, 3:]).as_matrix()
    want = Rotation.from_euler(convention, v[ok, 3:], degrees=True).as_matrix()
    np.testing.assert_allclose(got, want, atol=1e-12)
    assert (np.linalg.norm(rows[ok, 3:], axis=1) <= np.pi + 1e-12).all()


@needs_native
def test_native_faces_refuse_bad_arguments():
    s = np.zeros((4, 3))
    with pytest.raises(ValueError, match="seq"):
        KERNELS.euler_quat(s, s, "xYz", np.empty((4, 5)))
    with pytest.raises(ValueError, match="quat"):
        KERNELS.euler_quat(s, s, "xyz", np.empty((3, 5)))
    with pytest.raises(TypeError, match="cos_half"):
        KERNELS.euler_quat(s, s.astype(np.float32), "xyz", np.empty((4, 5)))
    with pytest.raises(TypeError, match="out"):
        KERNELS.euler_rotvec(np.zeros((4, 6)), np.zeros((4, 5)), np.zeros(4), np.ones(4), 1.0,
                             np.zeros((4, 6))[:, ::-1])

