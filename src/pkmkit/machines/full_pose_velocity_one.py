"""The velocity model of one full pose of a rod machine, compiled (issue 22 §1).

With the C extension, :meth:`FullPoseMachine.jacobian` of one plain pose (a list, tuple,
float64 or int64 vector) of a machine of up to six rods takes ``PoseOne.jacobian``
(:func:`pkmkit.machines.full_pose_one.native_one`, ``native/pose_one.c``): the inverse, the
stroke test and the record in one C call, the fields from one more when first read — the
bits of this module's C twin below. This module answers the rest: no extension, more than
six rods, a pose of another type (a float32 array).

:meth:`FullPoseMachine.jacobian` of one plain pose row ``(x, y, z, rx, ry, rz)`` whose inverse
model (:class:`~pkmkit.machines.full_pose_one.OnePoseInverse`) lies within the strokes returns
a :class:`OnePoseFullJacobians`: a :class:`~pkmkit.machines.full_pose.FullPoseJacobians` with
the batch path's fields, shapes and types for one pose, computed when first read by one call of
the compiled kernel :func:`pkmkit.machines.full_pose_velocity_kernel.velocity_one` (tens of
microseconds where the batch path of one row costs 0.6–0.8 ms). The kernel agrees with the
batch path to rounding: the same formulas; J by LAPACK's solve (Numba's) where the batch path
calls NumPy's; singular values by one-sided Jacobi where the batch path calls LAPACK (1e-15 of
σ_max). A row the kernel refuses (not finite, a singular A) is handed to the batch path.

With the C extension (six rods), the kernel is its C twin ``pkmkit.native.kernels.
pose_velocity`` instead: plain Python floats in, the output vector as a bytearray, no Numba at
any call; its own 6×6 LU where Numba calls LAPACK (the same numbers to 1e-12 of their scale,
tests/native/test_pose_velocity.py). Without it, as for the direct model
(:func:`pkmkit.machines.full_pose_direct.direct_one`), a one-shot call does not pay Numba's
import: until Numba is imported the machine's first single call
takes the batch path and the next one imports it; ``PKMKIT_COMPILED=0`` (or no Numba) keeps
the batch path.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Mapping
from functools import lru_cache
from types import MappingProxyType
from typing import Any

import numpy as np

from pkmkit.machines.lazy_records import lazy_record_class
from pkmkit.numerics import jit

#: Fields of a :class:`FullPoseJacobians`, in its order.
FIELDS = ("A", "B", "J", "J_inv", "singular_values", "condition", "det_A", "det_B",
          "parallel_measure", "serial_measure", "singularity", "tolerance", "q", "mode",
          "J_homogeneous", "characteristic_length", "translation_singular_values",
          "rotation_singular_values")

_kernel_module = None


def _kernel():
    global _kernel_module
    if _kernel_module is None:
        from pkmkit.machines import full_pose_velocity_kernel

        _kernel_module = full_pose_velocity_kernel
    return _kernel_module


#: Fields that need the singular values of J (the full kernel); the others take
#: :func:`~pkmkit.machines.full_pose_velocity_kernel.velocity_matrices`.
_SINGULAR = frozenset(("singular_values", "translation_singular_values",
                       "rotation_singular_values", "condition", "parallel_measure"))
#: The kernel's level each field needs (:meth:`OnePoseFullVelocity._run`).
#: (bits: 1 the singular values of J_h, 2 those of J's linear and angular rows, 4 the
#: parallel measure where its bound settles the flags)
_LEVEL = {"singular_values": 1, "condition": 1, "parallel_measure": 4,
          "translation_singular_values": 3, "rotation_singular_values": 3}


class OnePoseFullVelocity:
    """The velocity model of one full pose, computed by the compiled kernel when first read:
    ``J``, ``A``, ``B``, ``J_inv``, the determinants and the flags by
    :func:`~pkmkit.machines.full_pose_velocity_kernel.velocity_matrices` (no singular values;
    the parallel measure only where its bound cannot settle the flags), the singular values,
    condition and parallel measure by ``velocity_one`` (the same matrices, the same bits).

    Args:
        geom: the rods (:class:`~pkmkit.machines.full_pose_direct.DirectKernel` ``geom``).
        n: actuators. length: the characteristic length L (m).
        x: the pose (6 floats). q: its actuator coordinates (``n`` floats). tol: singularity
            threshold.
        batch: the batch path's single-pose model of the same pose (called if the kernel
            refuses the row).
    """

    __slots__ = ("_array", "_batch", "_full", "_out", "_spot", "_state", "batch", "geom",
                 "length", "n", "q", "tol", "x")

    def __init__(self, geom: np.ndarray, n: int, length: float, x: list[float],
                 q: list[float], tol: float, batch: Callable[[], Any]):
        self.geom, self.n, self.length, self.x, self.q, self.tol = geom, n, length, x, q, tol
        self.batch = batch
        self._out: np.ndarray | None = None
        self._state: bytearray | None = None  # the C kernel's result (its arrays: _array)
        self._array: Callable[..., np.ndarray] | None = None
        self._batch = None
        self._full = 0  # the level computed (see _run)

    def field(self, name: str):
        """The value of field ``name`` of the single-pose model."""
        if name == "q":
            return np.array(self.q)
        if name == "tolerance":
            return self.tol
        if name == "characteristic_length":
            return self.length
        level = _LEVEL.get(name, 0)
        if self._batch is None and ((self._out is None and self._state is None)
                                    or level & ~self._full):
            self._run(level | self._full)
        if self._batch is not None:
            return getattr(self._batch, name)
        return self._build(name)

    def _run(self, level: int) -> None:
        """Fill ``_out``: the matrices (level 0) and the pieces of :data:`_LEVEL`'s bits in
        ``level`` (the Numba kernel computes them all for any)."""
        geom = self.geom
        native = _native_twin(geom)
        if native is not None:  # the C twin: no arrays but the result's, no Numba
            self._spot = layout(geom.shape[0], self.n)
            x, q = self.x, self.q
            if type(x) is not list:  # (a caller's array)
                x = np.asarray(x, dtype=float).tolist()
            if type(q) is not list:
                q = np.asarray(q, dtype=float).tolist()
            state = native(geom, x, q, self.length, self.tol, level)
            if state is None:
                self._batch = self.batch()
            else:
                self._state, self._out, self._full = state, None, level
                self._array = jit.native_kernels_now().state_array
            return
        kernel = _kernel()
        self._spot = spot = kernel.layout(geom.shape[0], self.n)
        out = np.empty(spot["flags"][1])
        full = level > 0
        run = kernel.velocity_one if full else kernel.velocity_matrices
        try:
            refused = run(np.array(self.x, dtype=float), np.array(self.q, dtype=float), geom,
                          self.n, self.length, self.tol, out)
        except np.linalg.LinAlgError:  # an exactly singular A: the batch path decides
            refused = 1
        if refused:
            self._batch = self.batch()
        else:
            self._out, self._full = out, 7 if full else 0

    def _build(self, name: str):
        m, n, spot, state = self.geom.shape[0], self.n, self._spot, self._state
        shape = _SHAPES.get(name)
        if state is not None and shape is not None:  # one C call: a new array of the field
            key, rows, cols = shape(m, n)
            j = self._array(state, spot[key][0], rows, cols)
            if name == "J_homogeneous":
                j[3:] *= self.length
            return j
        out = self._out
        if out is None:  # the C kernel's result, for its scalars
            out = self._out = np.frombuffer(state)

        def part(key: str) -> np.ndarray:
            start, stop = spot[key]
            return out[start:stop]

        if name == "A":
            return part("A").reshape(m, 6).copy()
        if name == "B":
            return part("B").reshape(m, n).copy()
        if name in ("J", "J_homogeneous"):
            j = part("J").reshape(6, n).copy()
            if name == "J_homogeneous":
                j[3:] *= self.length
            return j
        if name == "J_inv":
            return part("J_inv").reshape(n, 6).copy()
        if name in ("singular_values", "translation_singular_values",
                    "rotation_singular_values"):
            key = {"singular_values": "sv", "translation_singular_values": "sv_t"}.get(
                name, "sv_r")
            return part(key).copy()
        if name == "singularity":
            return np.int64(part("flags")[0])
        if name == "mode":
            det_a = part("det_A")[0]
            return np.int64(np.sign(det_a)) if det_a == det_a else np.int64(0)
        key = {"parallel_measure": "parallel", "serial_measure": "serial"}.get(name, name)
        return np.float64(part(key)[0])


#: The array fields of the C kernel's result: ``(key, rows, cols)`` for m rods, n actuators
#: (cols 0: a vector).
_SHAPES: dict[str, Callable[[int, int], tuple[str, int, int]]] = {
    "A": lambda m, n: ("A", m, 6), "B": lambda m, n: ("B", m, n),
    "J": lambda m, n: ("J", 6, n), "J_homogeneous": lambda m, n: ("J", 6, n),
    "J_inv": lambda m, n: ("J_inv", n, 6),
    "singular_values": lambda m, n: ("sv", min(6, n), 0),
    "translation_singular_values": lambda m, n: ("sv_t", min(3, n), 0),
    "rotation_singular_values": lambda m, n: ("sv_r", min(3, n), 0)}


def _native_twin(geom: np.ndarray) -> Callable[..., Any] | None:
    """``pkmkit.native.kernels.pose_velocity`` when the extension is present (and enabled)
    and the machine has six rods, else None (the Numba kernel)."""
    if geom.shape[0] != 6:
        return None
    return getattr(jit.native_kernels_now(), "pose_velocity", None)


@lru_cache(maxsize=64)
def layout(m: int, n: int) -> Mapping[str, tuple[int, int]]:
    """``name -> (start, stop)`` of each field in the output vector of the velocity kernels
    (:func:`pkmkit.machines.full_pose_velocity_kernel.layout`, without importing Numba)."""
    sizes = [("A", 6 * m), ("B", m * n), ("J", 6 * n), ("J_inv", 6 * n), ("sv", min(6, n)),
             ("sv_t", min(3, n)), ("sv_r", min(3, n)), ("condition", 1), ("det_A", 1),
             ("det_B", 1), ("parallel", 1), ("serial", 1), ("flags", 1)]
    out, start = {}, 0
    for name, size in sizes:
        out[name] = (start, start + size)
        start += size
    return MappingProxyType(out)  # cached: every caller reads the same mapping


def one_pose_class(base: type) -> type:
    """The lazy single-pose subclass of the record class ``base`` (a
    :class:`FullPoseJacobians`): every field read from an :class:`OnePoseFullVelocity` when
    not given (:func:`~pkmkit.machines.lazy_records.lazy_record_class`)."""
    return lazy_record_class(
        base, "OnePose",
        lambda r: f"1 pose, {len(r.q)} actuators, tolerance {r.tolerance:g}; fields computed "
                  "when read",
        "A single-pose velocity model computed when read (module doc).")


def usable(machine: Any) -> bool:
    """Whether a single pose of ``machine`` takes the compiled path now: always with the C
    twin (:func:`_native_twin`: no import), else the rule of
    :func:`pkmkit.machines.full_pose_direct.direct_one` (a one-shot call does not import
    Numba; the machine's next single call does)."""
    if _native_twin(machine.direct_kernel().geom) is not None:
        return True
    if "numba" in sys.modules and "PKMKIT_COMPILED" not in os.environ:
        return jit.numba_available()  # the common case, without reading the mode
    return jit.compiled_from_second_call(machine, "velocity")
