"""The MJCF export of any machine: the writer of its structure (rod legs:
:mod:`pkmkit.export.mjcf`; joint chains: :mod:`pkmkit.export.mjcf_chains`) and the matching
load-back check. What ``pkmkit export --to mjcf`` calls."""

from __future__ import annotations

from pkmkit.export.base import machine_family
from pkmkit.export.mjcf import MjcfLayout, check_mjcf_model, mjcf_layout
from pkmkit.export.mjcf_chains import ChainMjcf, chain_mjcf, check_chain_mjcf


def write_mjcf(machine, masses=None) -> MjcfLayout | ChainMjcf:
    """The MJCF model of ``machine``: joint chains as their spanning tree welded to the
    platform, rod legs with ``connect`` constraints at the rod tips. ``masses`` applies to
    rod-leg machines; a joint-chain machine has no dynamics masses and refuses them.

    Raises:
        UnsupportedExportError: what the format or the writer cannot express.
    """
    if machine_family(machine) == "chain":  # the format's own table: chains vs rod legs
        return chain_mjcf(machine, masses)
    return mjcf_layout(machine, masses)


def check_mjcf(machine, export: MjcfLayout | ChainMjcf) -> float | None:
    """Load ``export`` in MuJoCo (when installed) and check it at pkmkit's configurations:
    the largest error (m), or None without MuJoCo.

    Raises:
        ExportCheckError: MuJoCo refuses the model, or it does not close pkmkit's
            configurations.
    """
    if isinstance(export, ChainMjcf):
        return check_chain_mjcf(machine, export)
    return check_mjcf_model(machine, export.xml)

