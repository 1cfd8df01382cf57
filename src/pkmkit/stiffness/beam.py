"""Euler–Bernoulli beam compliance of a link, from its section and material.

A link is a straight prismatic beam of length ℓ along its local x axis, clamped at its proximal
end; a wrench (F, M) on its distal end, in the beam's local axes and reduced at that end,
displaces the end by the small displacement (δ, δθ) = C (F, M) with (twist order: translation
then rotation; SI units, m/N, m/(N·m), rad/N, rad/(N·m))::

    δx  = ℓ/(EA) Fx                         δθx = ℓ/(GJ) Mx
    δy  = ℓ³/(3EI_z) Fy + ℓ²/(2EI_z) Mz      δθz = ℓ²/(2EI_z) Fy + ℓ/(EI_z) Mz
    δz  = ℓ³/(3EI_y) Fz − ℓ²/(2EI_y) My      δθy = −ℓ²/(2EI_y) Fz + ℓ/(EI_y) My

(shear deformation neglected: slender links). ``tests/stiffness/test_beam.py`` checks C against
the inverse of the free-end block of the 12×12 Euler–Bernoulli element stiffness matrix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.model.parameters import MAX_LENGTH


def _positive(value: float, what: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{what} must be a number, got {value!r}", what) from None
    if not (math.isfinite(number) and number > 0):
        raise ParameterError(f"{what} must be a finite number > 0, got {value!r}", what)
    return number


def _dimension(value: float, what: str) -> float:
    """A section dimension: > 0 and at most MAX_LENGTH (beyond, its fourth power overflows:
    a unit mistake)."""
    number = _positive(value, what)
    if number > MAX_LENGTH:
        raise ParameterError(f"{what} = {number:g} m is beyond {MAX_LENGTH:g} m: check the units",
                             what)
    return number


@dataclass(frozen=True)
class Material:
    """Elastic material: Young's modulus E and shear modulus G (Pa). Default: steel."""

    E: float = 210e9
    G: float = 81e9

    def __post_init__(self) -> None:
        object.__setattr__(self, "E", _positive(self.E, "material E"))
        object.__setattr__(self, "G", _positive(self.G, "material G"))


@dataclass(frozen=True)
class Section:
    """Cross-section properties (SI): area A (m²), second moments I_y, I_z about the local y
    and z axes (m⁴), torsion constant J (m⁴), and its largest dimension (m, for checks against
    the link length)."""

    area: float
    I_y: float
    I_z: float
    J: float
    size: float
    label: str = ""

    def __post_init__(self) -> None:
        for name in ("area", "I_y", "I_z", "J", "size"):
            object.__setattr__(self, name, _positive(getattr(self, name), f"section {name}"))

    @classmethod
    def circle(cls, diameter: float) -> Section:
        """Solid circular section of ``diameter`` (m)."""
        d = _dimension(diameter, "section diameter")
        i = math.pi * d**4 / 64.0
        return cls(math.pi * d * d / 4.0, i, i, 2.0 * i, d, f"circle D={d:g} m")

    @classmethod
    def tube(cls, outer: float, inner: float) -> Section:
        """Hollow circular section (m); ``inner`` < ``outer``."""
        d_o = _dimension(outer, "tube outer diameter")
        d_i = float(inner)
        if not (math.isfinite(d_i) and 0.0 <= d_i < d_o):
            raise ParameterError(f"tube inner diameter must be in [0, {d_o:g}) m, got {inner!r}",
                                 "section")
        i = math.pi * (d_o**4 - d_i**4) / 64.0
        return cls(math.pi * (d_o**2 - d_i**2) / 4.0, i, i, 2.0 * i, d_o,
                   f"tube D={d_o:g} m d={d_i:g} m")

    @classmethod
    def rectangle(cls, width: float, height: float) -> Section:
        """Solid rectangle (m): ``width`` along local y, ``height`` along local z; torsion
        constant by the usual series approximation J ≈ a b³ (1/3 − 0.21 (b/a)(1 − b⁴/(12a⁴)))
        with a ≥ b."""
        b_y = _dimension(width, "section width")
        h_z = _dimension(height, "section height")
        a, b = max(b_y, h_z), min(b_y, h_z)
        torsion = a * b**3 * (1.0 / 3.0 - 0.21 * (b / a) * (1.0 - b**4 / (12.0 * a**4)))
        return cls(b_y * h_z, b_y * h_z**3 / 12.0, h_z * b_y**3 / 12.0, torsion, max(b_y, h_z),
                   f"rectangle {b_y:g}×{h_z:g} m")


def beam_compliance(length: float | np.ndarray, section: Section, material: Material
                    ) -> np.ndarray:
    """Compliance ``(6, 6)`` (or ``(N, 6, 6)`` for lengths ``(N,)``) of a cantilever beam at
    its free end, local axes (module doc). A zero length gives a zero (rigid) compliance.

    Raises:
        ParameterError: a negative or non-finite length, or a section larger than a link of
            non-zero length.
    """
    ell = np.asarray(length, dtype=float)
    if not (np.isfinite(ell).all() and (ell >= 0).all()):
        raise ParameterError(f"a link length must be finite and ≥ 0, got {length!r}", "length")
    if ((ell > 0) & (ell < section.size)).any():
        short = float(ell[(ell > 0) & (ell < section.size)].min())
        raise ParameterError(f"section {section.label or section.size} is larger than a link "
                             f"({short:g} m): not a beam", "section")
    e, g = material.E, material.G
    c = np.zeros((*ell.shape, 6, 6))
    c[..., 0, 0] = ell / (e * section.area)
    c[..., 3, 3] = ell / (g * section.J)
    c[..., 1, 1] = ell**3 / (3 * e * section.I_z)
    c[..., 1, 5] = c[..., 5, 1] = ell**2 / (2 * e * section.I_z)
    c[..., 5, 5] = ell / (e * section.I_z)
    c[..., 2, 2] = ell**3 / (3 * e * section.I_y)
    c[..., 2, 4] = c[..., 4, 2] = -(ell**2) / (2 * e * section.I_y)
    c[..., 4, 4] = ell / (e * section.I_y)
    return c


def axial_stiffness(length: float, section: Section, material: Material) -> float:
    """EA/ℓ (N/m) of a rod of ``length`` (m)."""
    return material.E * section.area / _positive(length, "rod length")


def parse_section(text: str, scale: float = 1.0) -> Section:
    """A section from text: ``circle:D``, ``tube:D,d`` or ``rect:b,h`` (lengths × ``scale``
    to metres).

    Raises:
        ParameterError: an unknown shape or unreadable numbers.
    """
    shape, _, rest = str(text).partition(":")
    try:
        values = [float(v) * scale for v in rest.split(",")] if rest else []
    except ValueError:
        raise ParameterError(f"section {text!r}: cannot read the dimensions", "section") from None
    makers = {"circle": (Section.circle, 1), "tube": (Section.tube, 2),
              "rect": (Section.rectangle, 2)}
    if shape.strip() not in makers:
        raise ParameterError(f"section {text!r}: the shape must be circle:D, tube:D,d or "
                             "rect:b,h", "section")
    make, count = makers[shape.strip()]
    if len(values) != count:
        raise ParameterError(f"section {text!r}: {shape} takes {count} dimension(s)", "section")
    return make(*values)
