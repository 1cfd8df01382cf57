"""Elastostatics of parallel kinematic machines: stiffness, compliance and deflection.

Virtual-joint method (VJM) with the conventions of the whole package: twists ``(δp, δθ)`` —
translation then rotation, base frame, at a named reference point (the platform reference point
of rod-leg machines, the tool point of joint-chain machines); SI units (N/m, N, N·m/rad).

- :func:`stiffness` — one call for every machine family (:mod:`pkmkit.stiffness.api`);
- :mod:`~pkmkit.stiffness.rod_legs` — rods with an actuator and an axial spring in series
  (:func:`rod_leg_stiffness`: K and C of many poses, compiled for large batches,
  :mod:`~pkmkit.stiffness.compiled`);
- :mod:`~pkmkit.stiffness.joint_chains` — joint chains, hyperstatic closures included;
- :mod:`~pkmkit.stiffness.beam` — Euler–Bernoulli link compliance from section and material;
- :mod:`~pkmkit.stiffness.frames` — moving the reference point;
- :func:`loaded_equilibrium` — the loaded equilibrium of rod machines beside the linear
  deflection (the geometric-stiffness term, :mod:`~pkmkit.stiffness.equilibrium`);
- :mod:`~pkmkit.stiffness.loads`, :mod:`~pkmkit.stiffness.platform_gravity`,
  :mod:`~pkmkit.stiffness.chain_gravity` — deflections under the moving parts' weight;
- :mod:`~pkmkit.stiffness.data` — a machine's elastic data (actuators, sections, materials).
"""

from pkmkit.stiffness.api import stiffness, twist_names
from pkmkit.stiffness.beam import Material, Section, beam_compliance
from pkmkit.stiffness.data import StiffnessData, default_data, with_settings
from pkmkit.stiffness.equilibrium import LoadedDeflection, loaded_equilibrium
from pkmkit.stiffness.results import StiffnessResult
from pkmkit.stiffness.rod_legs import rod_leg_stiffness

__all__ = ["LoadedDeflection", "Material", "Section", "StiffnessData", "StiffnessResult",
           "beam_compliance", "default_data", "loaded_equilibrium", "rod_leg_stiffness",
           "stiffness", "twist_names", "with_settings"]
