"""How poses and actuator coordinates appear on the command line, for every machine family.

- Lengths are in ``--units`` (m or mm), angles in **degrees**.
- Actuators: slides and struts in ``--units``; rotary actuators (cranks, the revolute joints of
  a joint-chain machine's head) in degrees.
- Poses: a translational machine's ``x, y[, z]``; a full-pose machine's ``x, y, z, A, B, C`` —
  the position, then three angles in a named convention (``--angles``, default ``xyz``: fixed
  axes, ``R = Rz(C) Ry(B) Rx(A)``; see :mod:`pkmkit.spatial.rotation`); a joint-chain machine's
  tool point and unit tool axis ``x, y, z, i, j, k``. A Verne-type module (fewer than six
  actuators) also takes a position ``x, y, z`` alone.

Everything is converted to SI at this boundary; the library never sees degrees or millimetres.
"""

from __future__ import annotations

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.model.parameters import length_scale
from pkmkit.numerics.magnitudes import check_plausible

ANGLE_NAMES = ("A", "B", "C")
AXIS_NAMES = ("i", "j", "k")


def actuator_scales(m, units: str) -> np.ndarray:
    """SI value of one CLI unit of each actuator ``(n,)``: the length unit, or one degree."""
    length = length_scale(units)
    return np.array([np.pi / 180.0 if q == "angle" else length
                     for q in m.actuator_quantities])


def actuator_units(m, units: str) -> list[str]:
    """The CLI unit of each actuator (``"mm"``, ``"deg"``)."""
    return ["deg" if q == "angle" else units for q in m.actuator_quantities]


def parse_numbers(text: str, what: str, sizes: tuple[int, ...]) -> np.ndarray:
    """Comma-separated numbers, as many as one of ``sizes``."""
    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(f"{what}: cannot read {text!r} as comma-separated numbers") from None
    if len(values) not in sizes:
        need = " or ".join(str(s) for s in sizes)
        raise InputError(f"{what} needs {need} comma-separated values, got {len(values)}")
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise InputError(f"{what}: value {bad[0] + 1} is not finite ({values[bad[0]]}), got "
                         f"{text!r}")
    return values


def parse_actuators(text: str, m, units: str, what: str = "--q") -> np.ndarray:
    """Actuator values from the command line (CLI units) → SI ``(n,)``, each within the
    plausible range of a position (±1 km) or an angle (±720°), else :class:`InputError`
    naming the option and the actuator."""
    values = parse_numbers(text, what, (m.n_actuators,))
    scales = actuator_scales(m, units)
    for k, (unit, v, scale) in enumerate(zip(actuator_units(m, units), values, scales,
                                             strict=True)):
        check_plausible(f"{what} q{k + 1}", v, "angle" if unit == "deg" else "offset",
                        scale=scale, unit=unit)
    return values * scales


def parse_pose(text: str, m, what: str = "--pose", units: str = "m") -> np.ndarray:
    """Pose values from the command line ``(w,)`` in CLI units (:func:`pose_widths` values),
    each within the plausible range of its column — a position ±1 km, an angle ±720°, a tool
    axis component ±1000 — else :class:`InputError` naming the option and the column."""
    values = parse_numbers(text, what, pose_widths(m))
    names = pose_columns(m)
    for name, unit, v in zip(names, pose_units(m, units, len(values)), values, strict=False):
        if unit == "deg":
            check_plausible(f"{what} {name}", v, "angle", scale=np.pi / 180.0, unit=unit)
        elif unit is None:
            check_plausible(f"{what} {name}", v, "offset", unit="")
        else:
            check_plausible(f"{what} {name}", v, "offset", scale=length_scale(unit), unit=unit)
    return values


def pose_columns(m) -> list[str]:
    """Names of the pose columns of batch files and text output."""
    return list(_ORIENTATION_COLUMNS.get(m.pose_orientation, m.pose_names))


#: The pose columns of each orientation form (position-only poses use the machine's names).
_ORIENTATION_COLUMNS = {"rotvec": ("x", "y", "z", *ANGLE_NAMES),
                        "axis": ("x", "y", "z", *AXIS_NAMES)}


def pose_units(m, units: str, width: int | None = None) -> list[str | None]:
    """The unit of each pose column (:func:`pose_columns`, or its first ``width``): ``units``
    for positions, ``"deg"`` for angles, None for the components of a unit tool axis."""
    out: list[str | None] = [units if name in ("x", "y", "z") else
                             "deg" if name in ANGLE_NAMES else None for name in pose_columns(m)]
    if m.pose_orientation is None:  # position-only poses: every column a length
        out = [units] * len(out)
    return out[:width] if width is not None else out


def pose_widths(m) -> tuple[int, ...]:
    """Accepted numbers of pose values on the command line."""
    width = len(pose_columns(m))
    return (width, 3) if m.position_controlled else (width,)


def pose_from_cli(values: np.ndarray, m, units: str, convention: str) -> np.ndarray:
    """CLI pose rows ``(N, w)`` → SI rows ``(N, dims)`` (or positions ``(N, 3)`` for a
    position-controlled module given positions)."""
    values = np.atleast_2d(np.asarray(values, dtype=float))
    scale = length_scale(units)
    if m.pose_orientation is None or values.shape[1] == 3:
        return values * scale
    return _FROM_CLI[m.pose_orientation](values, scale, convention)


def _axis_from_cli(values: np.ndarray, scale: float, convention: str) -> np.ndarray:
    out = values.copy()
    out[:, :3] *= scale
    return out


#: Rows per block of the angle conversion of a table's poses (:func:`pose_from_cli`).
ANGLE_BLOCK_ROWS = 32768


def _angles_from_cli(values: np.ndarray, scale: float, convention: str) -> np.ndarray:
    from pkmkit.numerics.jit import native_kernels

    kernels = native_kernels()
    if kernels is not None:
        return _angles_native(kernels, values, scale, convention)
    return _angles_numpy(values, scale, convention)


def _angles_native(kernels, values: np.ndarray, scale: float, convention: str) -> np.ndarray:
    """:func:`_angles_numpy`'s rows and bits, its quaternion algebra in C
    (``pkmkit.native.kernels.euler_quat``, ``euler_rotvec``: one pass per row instead of some
    forty NumPy passes, issue 22 §5) and its transcendental functions NumPy's, on the same
    values (NumPy's arctan2 is a vectorised one on AVX-512 CPUs, not the C library's)."""
    values = np.ascontiguousarray(values, dtype=float)
    out = np.empty((len(values), 6))
    quat = np.empty((min(len(values), ANGLE_BLOCK_ROWS), 5))
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):  # non-finite rows: NaN
        for start in range(0, len(values), ANGLE_BLOCK_ROWS):
            block = values[start:start + ANGLE_BLOCK_ROWS]
            q = quat[:len(block)]
            half = np.deg2rad(block[:, 3:]) / 2.0
            kernels.euler_quat(np.sin(half), np.cos(half), convention, q)
            angle = 2.0 * np.arctan2(q[:, 4], q[:, 3])
            kernels.euler_rotvec(block, q, angle, np.sin(angle / 2.0), float(scale),
                                 out[start:start + len(block)])
    return out


def _angles_numpy(values: np.ndarray, scale: float, convention: str) -> np.ndarray:
    from pkmkit.spatial.poses import pose_from_angles

    out = np.full((len(values), 6), np.nan)
    finite = np.isfinite(values).all(axis=1)
    # in blocks that stay in cache: the quaternion passes over 10⁶ rows cost ≈ 1.5× more
    # whole (issue 22 §5); every row's arithmetic is the same, so are its bits
    for start in range(0, len(values), ANGLE_BLOCK_ROWS):
        rows = slice(start, start + ANGLE_BLOCK_ROWS)
        block, ok = values[rows], finite[rows]
        if ok.any():
            out[rows][ok] = pose_from_angles(block[ok, :3] * scale, block[ok, 3:],
                                             convention, degrees=True)
    return out


def pose_to_cli(poses: np.ndarray, m, units: str, convention: str) -> np.ndarray:
    """SI pose rows → CLI rows (positions in ``units``, angles in degrees or axis components)."""
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    scale = length_scale(units)
    if m.pose_orientation is None:
        return poses / scale
    out = poses.copy()
    out[:, :3] /= scale
    if m.pose_orientation == "rotvec":
        from pkmkit.spatial.rotation import angles_from_rotvec

        finite = np.isfinite(poses).all(axis=1)
        # in blocks that stay in cache, as _angles_from_cli (the Verne module's table: ≈ 0.2 s
        # of CPU per 10⁶ rows spared, issue 22 §5); each row's arithmetic is the same (the
        # same contiguity), so are its bits; a block of finite rows is taken as a view
        for start in range(0, len(poses), ANGLE_BLOCK_ROWS):
            rows = slice(start, start + ANGLE_BLOCK_ROWS)
            block, ok = poses[rows], finite[rows]
            whole = bool(ok.all())
            if not whole:
                out[rows][~ok, 3:] = np.nan
                if not ok.any():
                    continue
                block = block[ok]
            angles = angles_from_rotvec(block[:, 3:], convention, degrees=True)
            if whole:
                out[rows, 3:] = angles
            else:
                out[rows][ok, 3:] = angles
    return out


#: SI rows from CLI rows, per orientation form.
_FROM_CLI = {"axis": _axis_from_cli, "rotvec": _angles_from_cli}
