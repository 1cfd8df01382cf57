"""Virtual-joint-method (VJM) elastostatics of joint-chain machines, hyperstatic ones included.

Unknowns of the small-displacement problem at one configuration, z = (u, s, p):

- u = (δp_X, δθ_X): the platform's small displacement (its frame origin, base axes);
- s: the virtual springs — one per actuated joint (its stiffness k_a on the joint coordinate)
  and six per compliant link (the inverse of its beam compliance, :mod:`pkmkit.stiffness.links`);
- p: the passive joints of the legs (ideal: no energy).

Constraints: every leg closes on the platform to first order, ``G z = 0`` — the rows of the
closure's Jacobian (:func:`pkmkit.solve.chains.closure`), 6 per leg, with the springs' twists as
extra columns. A hyperstatic machine has more rows than independent ones: the redundant rows
are what makes it stiffer than its actuators alone, and they are kept, not dropped.

Energy ``½ zᵀ H z`` with H = blockdiag(0, K_s, 0); the tool's small displacement ``t = T z``
(tool point, base axes). Under a wrench w at the tool point the deflection minimises
``½ zᵀ H z − wᵀ T z`` on the null space N of G (columns: a basis from the SVD, rank relative
to σ_max): ``z = N (Nᵀ H N)⁻¹ Nᵀ Tᵀ w``, so the compliance is

    C = T N (Nᵀ H N)⁻¹ Nᵀ Tᵀ,        K = C⁻¹ where C is regular.

Redundant constraints cost nothing here (they do not change the null space), rigid links are
simply absent springs; a motion that costs no energy (``Nᵀ H N`` singular) is a mechanism —
the configuration is flagged SINGULAR — when it moves the tool, and is ignored (pseudo-inverse)
when it does not (internal motions: two coaxial passive joints, a rod turning on itself).
``tests/stiffness/test_joint_chains.py`` checks this
against a Lagrange-multiplier (KKT) solution and against Pashkevich's per-leg aggregation
``K = Σ K_leg``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.solve.chains import (
    chain_pose,
    closure,
    leg_residual,
    rotvec_matrices,
    tool_frame,
    twist_rows,
)
from pkmkit.spatial.rotation import skew
from pkmkit.status import Status
from pkmkit.stiffness.beam import beam_compliance
from pkmkit.stiffness.compiled import chain_reduced_compliance
from pkmkit.stiffness.data import StiffnessData
from pkmkit.stiffness.links import Link, chain_links, link_geometry, spring_twists

#: Singular values of G below this fraction of the largest are redundant rows.
RANK_TOL = 1e-10
#: Nᵀ H N with an eigenvalue below this fraction of the largest: a mechanism (singular).
MECHANISM_TOL = 1e-13


@dataclass(frozen=True)
class ChainSystem:
    """The assembled small-displacement problem at k configurations (batch axis FIRST).

    Attributes:
        G: ``(k, 6L, nz)`` closure constraints. H: ``(k, nz, nz)`` spring stiffness.
        T: ``(k, 6, nz)`` tool-point twist. P: ``(k, 6, nz)`` platform twist (its origin).
        leg_rows: row slices of each leg. columns: dict of column ranges by role
            (``"platform"``, ``"actuators"``, ``"links"``, ``"passive"``).
        link_columns: ``(leg or -1 for head, columns)`` of each link spring.
        springs: ``(ns,)`` names of the spring coordinates.
        tool_point: ``(k, 3)`` m. platform_point: ``(k, 3)`` m. status: ``(k,)``.
    """

    G: np.ndarray
    H: np.ndarray
    T: np.ndarray
    P: np.ndarray
    leg_rows: tuple[slice, ...]
    columns: dict
    link_columns: tuple
    springs: tuple[str, ...]
    tool_point: np.ndarray
    tool_axes: np.ndarray
    platform_point: np.ndarray
    status: np.ndarray


def _links(machine: Any) -> list[Link]:
    cached = machine.__dict__.get("_stiffness_links")
    if cached is None:
        model = machine.model
        values = model.home.copy()
        q_home = machine.home_q
        act = np.flatnonzero(model.actuated)
        values[act] = q_home
        res = machine.fk(q_home, full_output=True, strokes="ignore", check_singular=False)
        passive = [model.variables.index(n) for n in machine.passive_names]
        values[passive] = np.asarray(res.passive).reshape(-1)
        plat = np.asarray(res.platform).reshape(-1)
        rot = rotvec_matrices(plat[3:, None])[:, :, 0]
        cached = chain_links(model, values, (rot, plat[:3]))
        object.__setattr__(machine, "_stiffness_links", cached)
    return cached


def _compliant_links(machine: Any, data: StiffnessData) -> list[Link]:
    """The links that get a spring: those with a section; with the machine-wide
    ``link_section``, links shorter than the section's size are rigid blocks (joint housings);
    a section given for one link must fit it (:func:`beam_compliance` raises otherwise)."""
    names = machine.model.element_names()
    out = []
    for link in _links(machine):
        own = data.link_sections.get(names[link.element])
        if own is not None:
            out.append(link)
        elif data.link_section is not None and link.home_length >= data.link_section.size:
            out.append(link)
    return out


def _link_stiffness(data: StiffnessData, link: Link, model, length: np.ndarray) -> np.ndarray:
    names = model.element_names()
    section = data.link_sections.get(names[link.element], data.link_section)
    c = beam_compliance(length, section, data.link_material)
    return np.linalg.inv(c)


def assemble(machine: Any, q: np.ndarray, data: StiffnessData, *,
             tool_length: float | None = None) -> ChainSystem:
    """Assemble :class:`ChainSystem` at actuator coordinates ``q (k, n)``."""
    model = machine.model
    k = q.shape[0]
    if data.actuator_stiffness.shape != (machine.n_actuators,):
        raise InputError(f"actuator_stiffness has {data.actuator_stiffness.size} values for "
                         f"{machine.n_actuators} actuators")
    direct = machine.fk(q, full_output=True, strokes="ignore", check_singular=False,
                        tool_length=tool_length)
    status = np.atleast_1d(np.asarray(direct.status, dtype=int)).copy()
    status[status == Status.INCONSISTENT] = Status.OK  # defects: least-squares closure
    platform = np.atleast_2d(direct.platform)
    passive_values = np.atleast_2d(direct.passive)
    ok = (status == Status.OK) & np.isfinite(platform).all(axis=1)
    act = np.flatnonzero(model.actuated)
    passive = np.array([model.variables.index(n) for n in machine.passive_names], dtype=int)
    values = np.tile(model.home[:, None], (1, k))
    values[act] = np.nan_to_num(q.T)
    if passive.size:
        values[passive] = np.nan_to_num(passive_values.T)
    plat = np.nan_to_num(platform).T
    rot, p_x = rotvec_matrices(plat[3:]), plat[:3]
    c = closure(model, rot, p_x, values)
    length = model.characteristic_length
    links = _compliant_links(machine, data)
    n_legs = len(model.legs)
    n_a, n_l, n_p = act.size, 6 * len(links), passive.size
    nz = 6 + n_a + n_l + n_p
    g = np.zeros((6 * n_legs, nz, k))
    g[:, :6] = c.platform
    g[:, 6:6 + n_a] = c.variables[:, act]
    g[:, 6 + n_a + n_l:] = c.variables[:, passive]
    h = np.zeros((k, nz, nz))
    h[:, np.arange(6, 6 + n_a), np.arange(6, 6 + n_a)] = data.actuator_stiffness
    tool = tool_frame(model, rot, p_x, values, twists=True)
    tl = machine.tool_length if tool_length is None else float(tool_length)
    point = tool.p + tl * tool.R[:, 2]
    t = np.zeros((6, nz, k))
    t[:3, :3] = np.eye(3)[:, :, None]
    t[3:, 3:6] = np.eye(3)[:, :, None]
    t[:3, 3:6] = -skew((point - p_x).T).transpose(1, 2, 0)
    head_act = [j for j, v in enumerate(act) if not model.loop_variables[v]]
    for j in head_act:
        t[:, 6 + j] = _at_point(tool.variable_twists[:, act[j]], point)
    ends = []
    for leg in model.legs:
        end = chain_pose(model, leg, values)
        _, m = leg_residual(end, rot, p_x, length)
        ends.append((end.p, m))
    link_columns = []
    names = []
    for i, link in enumerate(links):
        cols = slice(6 + n_a + 6 * i, 6 + n_a + 6 * i + 6)
        distal, axes, ell = link_geometry(model, link, values, rot, p_x)
        tw = spring_twists(distal, axes)
        if link.chain == "leg":
            rows = slice(6 * link.index, 6 * link.index + 6)
            p_end, m = ends[link.index]
            g[rows, cols] = twist_rows(tw, p_end, m, length)
            # a link shared by several legs (same elements up to it) moves each of them
            prefix = _chain_prefix(model, link)
            for other, leg in enumerate(model.legs):
                if other != link.index and tuple(leg[:len(prefix)]) == prefix:
                    r2 = slice(6 * other, 6 * other + 6)
                    g[r2, cols] = twist_rows(tw, ends[other][0], ends[other][1], length)
            link_columns.append((link.index, cols))
        else:
            for j in range(6):
                t[:, cols.start + j] = _at_point(tw[:, j], point)
            link_columns.append((-1, cols))
        h[:, cols, cols] = _link_stiffness(data, link, model, ell)
        names += [f"{link.name} {a}" for a in ("dx", "dy", "dz", "rx", "ry", "rz")]
    p_t = np.zeros((6, nz, k))
    p_t[:6, :6] = np.eye(6)[:, :, None]
    status[~ok] = np.where(status[~ok] == Status.OK, Status.NO_ASSEMBLY, status[~ok])
    springs = tuple(model.variables[a] for a in act) + tuple(names)
    return ChainSystem(
        G=g.transpose(2, 0, 1), H=h, T=t.transpose(2, 0, 1), P=p_t.transpose(2, 0, 1),
        leg_rows=tuple(slice(6 * i, 6 * i + 6) for i in range(n_legs)),
        columns={"platform": slice(0, 6), "actuators": slice(6, 6 + n_a),
                 "links": slice(6 + n_a, 6 + n_a + n_l), "passive": slice(6 + n_a + n_l, nz)},
        link_columns=tuple(link_columns), springs=springs, tool_point=point.T,
        tool_axes=tool.R.transpose(2, 0, 1), platform_point=p_x.T, status=status)


def _chain_prefix(model, link: Link) -> tuple[int, ...]:
    chain = model.head if link.chain == "head" else model.legs[link.index]
    return chain[:link.position + 1]


def _at_point(tw: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Spatial twists ``(6, k)`` or ``(6, c, k)`` as small displacements of ``point (3, k)``:
    ``(v + ω × point, ω)``."""
    v, w = tw[:3], tw[3:]
    if tw.ndim == 2:
        return np.concatenate([v + np.cross(w.T, point.T).T, w])
    return np.concatenate([v + np.cross(w.transpose(1, 2, 0), point.T[None]).transpose(2, 0, 1),
                           w])


def null_space_compliance(g: np.ndarray, h: np.ndarray, t: np.ndarray,
                          status: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``C = T N (Nᵀ H N)⁻¹ Nᵀ Tᵀ`` ``(k, 6, 6)`` (module docstring) and the updated status.

    Args:
        g: ``(k, r, nz)`` constraints. h: ``(k, nz, nz)``. t: ``(k, 6, nz)``.
        status: ``(k,)`` status of the configurations (non-OK rows stay NaN).
    """
    out, status, _ = _null_space(g, h, t, status)
    return out, status


def _null_space(g: np.ndarray, h: np.ndarray, t: np.ndarray, status: np.ndarray,
                known: tuple[int, int] = (0, 0)) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`null_space_compliance` and the batch's most common rank of G, counting
    ``known = (rank, count)`` configurations solved elsewhere (-1: no configuration)."""
    k = g.shape[0]
    status = status.copy()
    out = np.full((k, t.shape[1], t.shape[1]), np.nan)
    ok = np.flatnonzero(status == Status.OK)
    if not ok.size:
        return out, status, known[0] if known[1] else -1
    _, sv, vt = np.linalg.svd(g[ok], full_matrices=True)
    rank = (sv > RANK_TOL * sv[:, :1]).sum(axis=1)
    counts = np.bincount(rank, minlength=known[0] + 1)
    counts[known[0]] += known[1]
    expected = int(counts.argmax())
    same = rank == expected
    status[ok[~same]] = Status.SINGULAR
    ok, vt = ok[same], vt[same]
    if not ok.size:
        return out, status, expected
    basis = np.swapaxes(vt[:, expected:, :], 1, 2)  # (k, nz, f)
    reduced = np.swapaxes(basis, 1, 2) @ h[ok] @ basis
    reduced = 0.5 * (reduced + np.swapaxes(reduced, 1, 2))
    lam, modes = np.linalg.eigh(reduced)
    free = lam <= MECHANISM_TOL * np.maximum(lam[:, -1:], 0.0)
    tn = t[ok] @ basis @ modes  # the tool's motion in each energy mode
    # a zero-energy mode that moves the tool is a mechanism; one that does not (a rod turning
    # about its own axis, two coaxial passive joints) is internal and ignored
    scale = np.abs(tn).max(axis=(1, 2), keepdims=True)
    moving = (np.abs(tn).max(axis=1) > 1e-9 * scale[:, 0]) & free
    regular = ~moving.any(axis=1)
    status[ok[~regular]] = Status.SINGULAR
    with np.errstate(divide="ignore"):
        inv_lam = np.where(free, 0.0, 1.0 / np.where(free, 1.0, lam))
    c = np.einsum("nia,na,nja->nij", tn, inv_lam, tn)
    out[ok[regular]] = c[regular]
    return out, status, expected


def chain_compliance(machine: Any, q: np.ndarray, data: StiffnessData, *,
                     tool_length: float | None = None
                     ) -> tuple[np.ndarray, np.ndarray, ChainSystem]:
    """Tool-point compliance ``(k, 6, 6)`` of a joint-chain machine at actuator coordinates
    ``q (k, n)``, the status ``(k,)`` and the assembled system."""
    system = assemble(machine, q, data, tool_length=tool_length)
    c, status = system_compliance(system.G, system.H, system.T, system.status, system.columns,
                                  1.0 / data.actuator_stiffness)
    return c, status, system


def system_compliance(g: np.ndarray, h: np.ndarray, t: np.ndarray, status: np.ndarray,
                      columns: dict, c_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`null_space_compliance`, the rows the compiled kernel can take solved there
    (:func:`pkmkit.stiffness.compiled.chain_reduced_compliance`, same numbers), the others by
    the SVD; the batch's most common rank is counted over both, as the SVD alone counts it.
    ``columns``: the system's column ranges; ``c_s (n_a,)`` the drive compliances."""
    fast = chain_reduced_compliance(g, t, columns, c_s, status, RANK_TOL)
    if fast is None:
        return null_space_compliance(g, h, t, status)
    c_fast, done = fast
    rest = ~done
    n_free = 6 + columns["passive"].stop - columns["passive"].start
    c, rest_status, expected = _null_space(g[rest], h[rest], t[rest], status[rest],
                                           known=(n_free, int(done.sum())))
    out = np.where(done[:, None, None], c_fast, np.nan)
    out[rest] = c
    status = status.copy()
    status[rest] = rest_status
    if expected != n_free:  # most configurations have another rank: these are singular
        status[done] = Status.SINGULAR
        out[done] = np.nan
    return out, status
