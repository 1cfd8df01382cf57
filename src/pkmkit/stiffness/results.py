"""The result of a stiffness evaluation and its derived quantities (eigen-stiffnesses, the
translational stiffness, deflections), computed from the compliance, batched."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.status import Status

#: Largest deflection the linear (small-displacement) model describes: a translation of this
#: fraction of the machine's size, a rotation of this many radians. Beyond, the load would
#: deform the machine far outside what a constant compliance predicts (second-order terms
#: ~1e-4 of the first at these bounds).
SMALL_TRANSLATION = 0.01
SMALL_ROTATION = 0.01  # rad

#: A compliance eigenvalue below this fraction of the largest is a rigid direction (the model's
#: rigid rods, links or constraints hold it: infinite stiffness).
RIGID_TOL = 1e-12


@dataclass(frozen=True)
class StiffnessResult:
    """Elastostatic model at N configurations (d = 2, 3 or 6 twist coordinates: translation,
    then rotation; base frame; reference point as in ``reference``).

    Attributes:
        compliance: ``(N, d, d)`` C (m/N, m/(N·m) = 1/N, rad/(N·m)); finite wherever the
            configuration is regular.
        stiffness: ``(N, d, d)`` K = C⁻¹ (N/m, N, N·m/rad); NaN rows where C is singular
            (``rigid`` > 0) or the configuration failed.
        eigenvalues: ``(N, d)`` eigen-stiffnesses, ascending (inf for rigid directions).
        directions: ``(N, d, d)`` their unit directions (columns).
        translational: ``(N, min(d, 3))`` eigenvalues of the translational stiffness
            ``(C_tt)⁻¹`` (N/m, ascending): the stiffness felt by a pure force at the reference
            point; ``[:, 0]`` the smallest.
        rotational: ``(N, 3)`` eigenvalues of ``(C_rr)⁻¹`` (N·m/rad, ascending) — the
            stiffness felt by a pure moment — or None for a translating platform.
        deflection: ``(N, d)`` C w under the wrench (m, rad), or None.
        rigid: ``(N,)`` number of rigid directions.
        status: ``(N,)`` :class:`~pkmkit.status.Status` codes.
        coordinates: names of the twist coordinates.
        reference: where the twist's point is (text).
    """

    compliance: np.ndarray
    stiffness: np.ndarray
    eigenvalues: np.ndarray
    directions: np.ndarray
    translational: np.ndarray
    rotational: np.ndarray | None
    deflection: np.ndarray | None
    rigid: np.ndarray
    status: np.ndarray
    coordinates: tuple[str, ...]
    reference: str

    def single(self) -> StiffnessResult:
        """The first row without its batch axis (for one configuration)."""
        fields = {k: getattr(self, k) for k in self.__dataclass_fields__}
        for k in ("compliance", "stiffness", "eigenvalues", "directions", "translational",
                  "rotational", "deflection", "rigid", "status"):
            if fields[k] is not None:
                fields[k] = fields[k][0]
        return StiffnessResult(**fields)


def summarize(compliance: np.ndarray, status: np.ndarray, coordinates: tuple[str, ...],
              reference: str, wrench: np.ndarray | None = None) -> StiffnessResult:
    """A :class:`StiffnessResult` from compliances ``(N, d, d)`` (NaN rows: failed
    configurations with their ``status``) and an optional wrench ``(d,)`` or ``(N, d)``."""
    c = 0.5 * (compliance + np.swapaxes(compliance, 1, 2))
    n, d = c.shape[:2]
    status = np.asarray(status, dtype=int).copy()
    ok = (status == Status.OK) & np.isfinite(c).all(axis=(1, 2))
    deflection = None
    if wrench is not None:
        w = np.broadcast_to(np.asarray(wrench, dtype=float), (n, d))
        with np.errstate(over="ignore", invalid="ignore"):
            deflection = np.einsum("nij,nj->ni", np.where(ok[:, None, None], c, np.nan), w)
        # a compliance so large that C w overflows is a mechanism in all but name: flagged
        ok &= np.isfinite(deflection).all(axis=1)
        deflection[~ok] = np.nan
    status[~ok & (status == Status.OK)] = Status.SINGULAR
    eig = np.full((n, d), np.nan)
    vec = np.full((n, d, d), np.nan)
    stiff = np.full((n, d, d), np.nan)
    rigid = np.zeros(n, dtype=int)
    trans = np.full((n, min(d, 3)), np.nan)
    if ok.any():
        lam, v = np.linalg.eigh(c[ok])
        top = np.abs(lam[:, -1:])
        is_rigid = lam <= RIGID_TOL * top
        rigid[ok] = is_rigid.sum(axis=1)
        with np.errstate(divide="ignore"):
            k_eig = np.where(is_rigid, np.inf, 1.0 / np.where(is_rigid, 1.0, lam))
        eig[ok] = k_eig[:, ::-1]
        vec[ok] = v[:, :, ::-1]
        full = rigid[ok] == 0
        rows = np.flatnonzero(ok)[full]
        if rows.size:
            inv = np.einsum("nij,nj,nkj->nik", v[full], 1.0 / lam[full], v[full])
            stiff[rows] = 0.5 * (inv + np.swapaxes(inv, 1, 2))
        # a translating platform's compliance is its translational block: its eigenvalues
        trans[ok] = eig[ok] if d <= 3 else _block_stiffness(c[ok][:, :3, :3], top)
    rot = None
    if d == 6:
        rot = np.full((n, 3), np.nan)
        if ok.any():
            rot[ok] = _block_stiffness(c[ok][:, 3:, 3:], top)
    return StiffnessResult(compliance=np.where(ok[:, None, None], c, np.nan), stiffness=stiff,
                           eigenvalues=eig, directions=vec, translational=trans, rotational=rot,
                           deflection=deflection, rigid=rigid, status=status,
                           coordinates=coordinates, reference=reference)


def _block_stiffness(block: np.ndarray, top: np.ndarray) -> np.ndarray:
    """Ascending eigenvalues of the inverse of compliance blocks ``(N, b, b)`` (inf where a
    block eigenvalue is rigid: below :data:`RIGID_TOL` × ``top (N, 1)``, the whole
    compliance's largest eigenvalue)."""
    lam = np.linalg.eigvalsh(block)
    rigid = lam <= RIGID_TOL * top
    with np.errstate(divide="ignore"):
        return np.where(rigid, np.inf, 1.0 / np.where(rigid, 1.0, lam))[:, ::-1]


def beyond_linear_range(deflection: np.ndarray, length: float) -> np.ndarray:
    """Rows of ``deflection`` ``(N, d)`` (m, then rad when d = 6) beyond the linear model's
    range: a translation above :data:`SMALL_TRANSLATION` × ``length`` (m, the machine's size)
    or a rotation above :data:`SMALL_ROTATION`. Returns ``(N,)`` bool (False on NaN rows)."""
    d = np.atleast_2d(np.asarray(deflection, dtype=float))
    t = np.linalg.norm(d[:, :min(d.shape[1], 3)], axis=1)
    r = np.linalg.norm(d[:, 3:], axis=1) if d.shape[1] > 3 else np.zeros(len(d))
    return (t > SMALL_TRANSLATION * length) | (r > SMALL_ROTATION)


def linear_range_problem(deflection: np.ndarray, length: float, units: str = "m") -> str:
    """Why the deflection ``(d,)`` (m, rad) of a machine of size ``length`` (m) is beyond the
    linear model's range (:func:`beyond_linear_range`), in words with lengths in ``units``;
    ``""`` when it is within."""
    from pkmkit.model.parameters import length_scale

    if not beyond_linear_range(deflection, length)[0]:
        return ""
    scale = length_scale(units)
    return (f"the deflection is beyond the range of the linear (small-displacement) model "
            f"(a translation beyond {SMALL_TRANSLATION * length / scale:.4g} {units}, "
            f"{SMALL_TRANSLATION:.0%} of the machine's size, or a rotation beyond "
            f"{SMALL_ROTATION:g} rad): under this load the machine would bend, yield or break "
            "long before; the figure is not a prediction")
