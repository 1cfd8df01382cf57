"""The compliant links of a joint-chain machine and their virtual springs.

A *link* is the straight segment of a body between two consecutive elements of a chain: from
the joint location of element j−1 (its frame origin before its own motion: a prismatic joint's
moving part starts there) to the origin of element j. In a leg the links run from the first
joint to the last joint (what lies before is the base, after is the platform: both rigid; but
the sliding part of a last prismatic joint runs on to the next element); in
the head, from its first element to the tool frame. Each link is a cantilever beam
(:func:`pkmkit.stiffness.beam.beam_compliance`) whose distal end carries a 6-DOF virtual spring:
its coordinates are the small displacement of the distal end along the beam's local axes —
x along the link, z the proximal joint axis made orthogonal to x, y = z × x — then the small
rotation about them.

Links of zero length at the home configuration are rigid and have no spring.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.model.chains import FIXED, PRISMATIC, JointChainModel
from pkmkit.solve.chains import chain_pose

#: Links shorter than this at home (m) are rigid.
MIN_LINK = 1e-9


@dataclass(frozen=True)
class Link:
    """One compliant link: ``chain`` (``"leg"`` or ``"head"``), ``index`` (the leg's index),
    ``position`` j in the chain, ``element`` (model element index of its distal end),
    ``name`` (proximal → distal element names) and ``home_length`` (m)."""

    chain: str
    index: int
    position: int
    element: int
    name: str
    home_length: float = 0.0


def chain_links(model: JointChainModel, home_values: np.ndarray, home_platform: tuple) -> list:
    """The links of a model with non-zero length at home (see the module docstring).

    Args:
        home_values: ``(n_var,)`` joint values of the home configuration.
        home_platform: ``(R (3, 3), p (3,))`` platform frame at home.
    """
    out: list[Link] = []
    seen: set[int] = set()
    names = model.element_names()
    chains = [("leg", i, leg) for i, leg in enumerate(model.legs)]
    if model.head:
        chains.append(("head", 0, model.head))
    for kind, index, chain in chains:
        joints = [j for j, e in enumerate(chain) if model.elements[e].type != FIXED]
        last = len(chain) - 1 if kind == "head" else (joints[-1] if joints else -1)
        if kind == "leg" and joints and model.elements[chain[last]].type == PRISMATIC and (
                last + 1 < len(chain)):
            last += 1  # the sliding part of a last prismatic joint reaches the platform
        first = 1
        for j in range(first, last + 1):
            e = chain[j]
            if e in seen:
                continue
            link = Link(kind, index, j, e, f"{names[chain[j - 1]]}→{names[e]}")
            rot = home_platform[0][:, :, None]
            pos = home_platform[1][:, None]
            _, _, length = link_geometry(model, link, home_values[:, None], rot, pos)
            if length[0] > MIN_LINK:
                out.append(Link(kind, index, j, e, link.name, float(length[0])))
                seen.add(e)
    return out


def _chain_of(model: JointChainModel, link: Link) -> tuple[int, ...]:
    return model.head if link.chain == "head" else model.legs[link.index]


def link_geometry(model: JointChainModel, link: Link, values: np.ndarray, rot_x: np.ndarray,
                  p_x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distal point ``(3, k)``, local axes ``(3, 3, k)`` (columns x, y, z) and length ``(k,)``
    of a link at joint values ``values (n_var, k)`` (head links start from the platform frame
    ``rot_x (3, 3, k)``, ``p_x (3, k)``)."""
    chain = _chain_of(model, link)
    start = (rot_x, p_x) if link.chain == "head" else None
    prox = chain_pose(model, chain[: link.position], values, start=start)
    prev = model.elements[chain[link.position - 1]]
    origin = prox.p
    if prev.type == PRISMATIC:
        var = model.element_variable[chain[link.position - 1]]
        origin = prox.p - values[var] * prox.R[:, 2]
    offset = model.frames[chain[link.position]][:3, 3]
    distal = prox.p + np.einsum("abk,b->ak", prox.R, offset)
    chord = distal - origin
    length = np.linalg.norm(chord, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        x = np.where(length > 0, chord / length, prox.R[:, 0])
    z_ref = prox.R[:, 2]
    z = z_ref - np.einsum("ak,ak->k", z_ref, x) * x
    weak = np.linalg.norm(z, axis=0) < 1e-6
    if weak.any():
        alt = prox.R[:, 0] - np.einsum("ak,ak->k", prox.R[:, 0], x) * x
        z = np.where(weak, alt, z)
    z = z / np.linalg.norm(z, axis=0)
    y = np.cross(z.T, x.T).T
    return distal, np.stack([x, y, z], axis=1), length


def spring_twists(point: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Spatial twists ``(6, 6, k)`` (v, ω about the base origin) of a link spring's six
    coordinates: translations along the local axes, then rotations about them through the
    distal ``point``."""
    k = point.shape[1]
    out = np.zeros((6, 6, k))
    out[:3, :3] = axes
    out[3:, 3:] = axes
    out[:3, 3:] = np.cross(point.T[:, None, :], axes.transpose(2, 1, 0)).transpose(2, 1, 0)
    return out
