"""Joint chains described in one common frame, re-expressed element by element.

The thesis's invariants (Table 4.2) place every element in the frame of the element before it,
which is how the kinematics read them (:mod:`pkmkit.model.chains`) but not how a designer draws a
machine. :func:`chain_from_layout` takes each chain drawn in one frame (the base, or the platform
for a head) **at zero joint values** — every joint axis and point, every fixed frame's pose, in
that frame — and returns the same elements with their invariants relative to the previous
element, ready for :func:`~pkmkit.model.chains.build_chain_model`. An element shared by several
chains (the TriMule's ψ1) must then come out the same in each; :func:`chains_from_layout` checks
it.

Components within :data:`SNAP` of 0 or ±1 are snapped to those values, so that axes drawn along
coordinate axes give the exact invariants of a hand-written table.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.model.chains import FIXED, ElementSpec, invariant_frame

#: Components closer than this to 0, 1 or −1 are snapped to them.
SNAP = 1e-12


def _snap(v: np.ndarray) -> np.ndarray:
    out = np.array(v, dtype=float)
    for target in (0.0, 1.0, -1.0):
        out[np.abs(out - target) < SNAP] = target
    return out


def chain_from_layout(chain: Sequence[ElementSpec], start: np.ndarray | None = None
                      ) -> list[ElementSpec]:
    """Elements of one chain re-expressed relative to their predecessors.

    Args:
        chain: the chain's elements with ``axis`` and ``point`` (and, for fixed frames,
            ``rotation``) given in the layout frame at zero joint values (m).
        start: ``(4, 4)`` pose of the chain's first frame in the layout frame (default the
            identity: the chain starts at the layout frame).

    Returns:
        The elements with ``axis``/``point``/``rotation`` in the previous element's frame and
        ``spin`` 0; every other field unchanged.
    """
    current = np.eye(4) if start is None else np.asarray(start, dtype=float)
    out = []
    for spec in chain:
        rot, origin = current[:3, :3], current[:3, 3]
        point = _snap(rot.T @ (np.asarray(spec.point, dtype=float) - origin))
        if spec.type == FIXED:
            if spec.rotation is None:
                world = invariant_frame(spec.axis, spec.point, spec.spin)[:3, :3]
            else:
                world = np.asarray(spec.rotation, dtype=float)
            local = _snap(rot.T @ world)
            out.append(replace(spec, rotation=tuple(map(tuple, local)), point=tuple(point),
                               spin=0.0))
            frame = np.eye(4)
            frame[:3, :3], frame[:3, 3] = local, point
        else:
            axis = np.asarray(spec.axis, dtype=float)
            if axis.shape != (3,) or not np.linalg.norm(axis) > 0:
                raise ParameterError(f"element {spec.name!r}: axis must be 3 numbers, not all "
                                     "zero", spec.name)
            axis = _snap(rot.T @ (axis / np.linalg.norm(axis)))
            out.append(replace(spec, axis=tuple(axis), point=tuple(point), spin=0.0))
            frame = invariant_frame(axis, point)
        current = current @ frame
    return out


def chains_from_layout(chains: Sequence[Sequence[ElementSpec]],
                       starts: Sequence[np.ndarray | None] | None = None
                       ) -> list[ElementSpec]:
    """Every element of several chains, each once, re-expressed (:func:`chain_from_layout`).

    Raises:
        ParameterError: an element shared by two chains whose relative invariant differs
            between them (it is not at the same place in both).
    """
    starts = list(starts) if starts is not None else [None] * len(chains)
    seen: dict[str, ElementSpec] = {}
    for chain, start in zip(chains, starts, strict=True):
        for spec in chain_from_layout(chain, start):
            if spec.name in seen:
                other = seen[spec.name]
                same = (np.allclose(other.axis, spec.axis, atol=1e-12)
                        and np.allclose(other.point, spec.point, atol=1e-12))
                if not same:
                    raise ParameterError(f"element {spec.name!r} is shared by two chains but "
                                         "not placed the same way in both", spec.name)
                continue
            seen[spec.name] = spec
    return list(seen.values())
