"""The URDF export of any machine: the writer of its structure (spatial rod legs:
:mod:`pkmkit.export.urdf`; planar ones: :mod:`pkmkit.export.urdf_planar`; joint chains:
:mod:`pkmkit.export.urdf_chains`) and the matching
read-back check. What ``pkmkit export --to urdf`` calls."""

from __future__ import annotations

from pkmkit.export.base import machine_family
from pkmkit.export.urdf import UrdfExport, urdf_export
from pkmkit.export.urdf_chains import (
    ChainUrdfExport,
    chain_urdf_export,
    check_chain_urdf_export,
)
from pkmkit.export.urdf_check import check_urdf_export
from pkmkit.export.urdf_planar import planar_urdf_export


def write_urdf(machine, masses=None, *, name: str = "machine") -> UrdfExport | ChainUrdfExport:
    """The URDF tree and closures YAML of ``machine``: joint chains welded 6D at the platform,
    rod legs with cut ball joints (3D). ``masses``: a rod-leg machine's
    :class:`~pkmkit.dynamics.masses.MassProperties`, a joint-chain machine's bodies'
    (:class:`~pkmkit.export.chain_masses.ChainBodyMasses`, :func:`read_masses`).

    Raises:
        UnsupportedExportError: what the format or the writer cannot express.
    """
    if machine_family(machine) == "chain":  # the format's own table: chains vs rod legs
        from pkmkit.export.chain_masses import ChainBodyMasses

        if masses is not None and not isinstance(masses, ChainBodyMasses):
            from pkmkit.export.base import UnsupportedExportError

            raise UnsupportedExportError("urdf", machine.id, "rod-leg masses (carriages, rods) "
                                         "were given; a joint-chain machine takes its bodies' "
                                         "masses (pkmkit.export.chain_masses)")
        return chain_urdf_export(machine, name=name, masses=masses)
    if machine_family(machine) == "planar":  # a tree that stays in the plane
        return planar_urdf_export(machine, masses, name=name)
    return urdf_export(machine, masses, name=name)


def check_urdf(machine, export: UrdfExport | ChainUrdfExport) -> tuple[float, str]:
    """Read ``export`` back (Pinocchio when installed) and check it at pkmkit's
    configurations: ``(largest error (m), reader)``.

    Raises:
        ExportCheckError: the written tree does not close or misplaces the platform or tool.
    """
    if isinstance(export, ChainUrdfExport):
        return check_chain_urdf_export(machine, export)
    return check_urdf_export(machine, export)
