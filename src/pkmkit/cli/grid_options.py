"""Grid and pose options of the analysis commands (``workspace``, ``map``, ``useful-workspace``):
bounds, orientation, slice and box parsing, and the study box widened until the workspace fits."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from pkmkit.analysis.grids import Grid, PoseFrame, make_grid, pose_frame
from pkmkit.analysis.workspace import (
    Criteria,
    compute_workspace,
)
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import MAX_COORDINATE
from pkmkit.numerics.magnitudes import check_plausible

#: Narrowest side (m) of a studied box: below it the cells' areas and volumes underflow and
#: the grid cannot be a machine tool's workspace (a unit slip).
MIN_EXTENT = 1e-9


def _numbers(text: str, what: str) -> list[float]:
    """Comma-separated finite numbers (no magnitude check)."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"{what}: cannot read {text!r} as comma-separated numbers") from None
    if not np.isfinite(values).all():
        raise InputError(f"{what}: every value must be finite, got {text!r}")
    return values


def _coordinates(text: str, what: str, scale: float) -> np.ndarray:
    """Comma-separated lengths in CLI units → m, each within ±MAX_COORDINATE."""
    values = np.asarray(_numbers(text, what)) * scale
    if (np.abs(values) > MAX_COORDINATE).any():
        raise InputError(f"{what}: coordinates beyond {MAX_COORDINATE:g} m are not supported, "
                         f"got {text!r}")
    return values


def parse_bounds(text: str | None) -> tuple[float, float] | None:
    """``"LO,HI"`` → (lo, hi), validated by :class:`Criteria`."""
    if text is None:
        return None
    values = _numbers(text, "--bounds")
    if len(values) != 2:
        raise InputError(f"--bounds needs LO,HI, got {text!r}")
    if not values[0] < values[1]:
        raise InputError(f"--bounds: LO = {values[0]:g} must be below HI = {values[1]:g}")
    for value in values:  # transmission factors: a bound of 1e300 is no bound (leave it out)
        check_plausible("--bounds", value, "factor")
    return values[0], values[1]


def parse_orientation(machine, text: str | None, convention: str) -> np.ndarray | None:
    """``--orientation``: the orientation a workspace grid holds — angles ``A,B,C`` in degrees
    (``--angles`` convention) for a full-pose machine, a tool axis ``I,J,K`` for a joint-chain
    machine — as a rotation vector / unit axis; None for the home orientation."""
    if text is None:
        return None
    values = np.asarray(_numbers(text, "--orientation"))
    if values.size != 3:
        raise InputError(f"--orientation needs 3 comma-separated values, got {text!r}")
    if machine.pose_orientation == "rotvec" and not machine.position_controlled:
        from pkmkit.spatial.poses import pose_from_angles

        return pose_from_angles(np.zeros(3), values, convention, degrees=True)[3:]
    return values


def machine_frame(machine, orientation: np.ndarray | None = None) -> PoseFrame:
    """:func:`pose_frame` of a machine, refusing a family without pose-space workspaces."""
    return pose_frame(machine, orientation)


def parse_slice(frame: PoseFrame, text: str | None, scale: float) -> tuple[int, float] | None:
    """``"z=0.2"`` → (coordinate index, value in m) of one of the frame's positions."""
    if text is None:
        return None
    if frame.positions == 2:
        raise InputError("--slice is for spatial machines; a planar machine is its own plane")
    names = frame.names[:frame.positions]
    name, sep, value = text.partition("=")
    name = name.strip()
    if not sep or name not in names:
        raise InputError(f"--slice expects NAME=VALUE with NAME in {', '.join(names)} (the "
                         f"orientation is held with --orientation), got {text!r}")
    values = _coordinates(value, "--slice", scale)
    if values.size != 1:
        raise InputError(f"--slice expects one value after {name}=, got {value!r}")
    return names.index(name), float(values[0])


def build_grid(frame: PoseFrame, box_text: str | None, slice_: tuple[int, float] | None,
               scale: float, resolution: int | None) -> Grid:
    """Grid over ``--box``/``--range`` (or the machine's default box) of the frame's
    positions, optionally a slice; the orientation is the frame's."""
    lower, upper = frame.lower, frame.upper
    free = list(range(frame.positions))
    base = frame.base.copy()
    names = frame.names
    if slice_ is not None:
        axis, value = slice_
        free.remove(axis)
        base[axis] = value
    if box_text is not None:
        values = _coordinates(box_text, "--box/--range", scale)
        if values.size == 2 * frame.positions and slice_ is not None:
            # a full box with a slice: the plane must cut the box
            axis, value = slice_
            a_lo, a_hi = values.reshape(-1, 2)[axis]
            name = names[axis]
            if not a_lo <= value <= a_hi:
                raise InputError(f"--slice {name} = {value / scale:g} lies outside the box's "
                                 f"{name} range [{a_lo / scale:g}, {a_hi / scale:g}]")
            values = values.reshape(-1, 2)[free].ravel()
        if values.size != 2 * len(free):
            text = ",".join(f"{names[k].upper()}MIN,{names[k].upper()}MAX" for k in free)
            raise InputError(f"the box needs {2 * len(free)} values: {text}")
        pairs = values.reshape(-1, 2)
        for k, (lo, hi) in zip(free, pairs, strict=True):
            if 0 < hi - lo < MIN_EXTENT:
                raise InputError(f"--box/--range: the {names[k]} range [{lo / scale:g}, "
                                 f"{hi / scale:g}] (--units) is narrower than 1 nm: check "
                                 "the units")
        lower, upper = lower.copy(), upper.copy()
        lower[free], upper[free] = pairs[:, 0], pairs[:, 1]
    resolution = resolution or (201 if len(free) == 2 else 61)
    return make_grid(lower[free], upper[free], free=free, base=base, names=names,
                     resolution=resolution)


#: Times the default box may be widened to hold the workspace (each time by half its extent
#: on every face the workspace reaches).
MAX_WIDENINGS = 4


def enclosing_frame(m, frame: PoseFrame, criteria: Criteria,
                    slice_: tuple[int, float] | None, scale: float, scheduler=None,
                    resolution: int | None = None) -> tuple[PoseFrame, int]:
    """The frame with its default box widened until the workspace (on a coarse grid) touches
    none of its faces, at most :data:`MAX_WIDENINGS` times, then moved out by one coarse step
    where the workspace comes within a step of a face: ``(frame, times widened)``. A
    machine's default box is a region of study; a workspace study wants all of the
    workspace. The coarse grid has 25 points along the longest side in 3-D, 61 in 2-D (fewer
    if ``resolution`` asks for fewer)."""
    coarse = 25 if frame.positions == 3 and slice_ is None else 61
    coarse = min(coarse, resolution or coarse)
    for widened in range(MAX_WIDENINGS + 1):
        grid = build_grid(frame, None, slice_, scale, coarse)
        found = compute_workspace(m, grid, criteria, scheduler=scheduler, inscribed=False,
                                  factors=False)
        faces = found.faces_reached()
        if not faces or widened == MAX_WIDENINGS:
            break
        frame = _moved_faces(frame, faces, (frame.upper - frame.lower) / 2)
    # the workspace within one coarse step of a face may cross it between samples: one step more
    near = [face for face in found.faces_reached(2) if face not in faces]
    steps = np.full(len(frame.names), float(grid.step))
    if not near:
        return frame, widened
    return _moved_faces(frame, near, steps), widened + 1


def _moved_faces(frame: PoseFrame, faces: list[str], by: np.ndarray) -> PoseFrame:
    """``frame`` with each face of ``faces`` (``"x-"``, ``"z+"``…) moved out by ``by`` (per
    axis, SI units), within ±:data:`MAX_COORDINATE`."""
    lower, upper = frame.lower.copy(), frame.upper.copy()
    for face in faces:
        k = frame.names.index(face[:-1])
        if face.endswith("-"):
            lower[k] = max(lower[k] - by[k], -MAX_COORDINATE)
        else:
            upper[k] = min(upper[k] + by[k], MAX_COORDINATE)
    return replace(frame, lower=lower, upper=upper)


