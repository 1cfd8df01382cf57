"""Text form of a machine's description (``pkmkit show``); the description itself is
:func:`pkmkit.boundary.describe.describe_machine`."""

from __future__ import annotations

from typing import Any

import click

from pkmkit.boundary.describe import describe_chain_machine, describe_machine

from .options import fmt

__all__ = ["describe_chain_machine", "describe_machine", "print_description"]


def print_description(info: dict[str, Any]) -> None:
    """Human-readable form of :func:`describe_machine`'s output."""
    if info.get("family") == "joint-chain":
        _print_chain(info)
        return
    u = info["units"]
    click.echo(f"{info['id']}: {info['name']}  [{info['kind']}, {info['dims']}-D]")
    for key in ("description", "source"):
        if info[key]:
            click.echo(f"  {key}: {info[key]}")
    if info["parameters"]:
        click.echo("parameters:")
        for p in info["parameters"]:
            click.echo(f"  {p['name']:<20} = {fmt(p['value'])} {p['unit']:<4} {p['doc']}")
    click.echo("legs:")
    for leg in info["legs"]:
        axis = f" axis {fmt(leg['axis'])}" if leg["axis"] is not None else ""
        pivot = f" pivot {fmt(leg['pivot'])}" if leg.get("pivot") is not None else ""
        click.echo(
            f"  {leg['name']} ({leg['type']} {leg['actuator']}):{pivot} base "
            f"{fmt(leg['base'])}{axis} platform {fmt(leg['platform'])} length "
            f"{fmt(leg['length'])} {u} branch {leg['branch']:+d}, {leg['rods']} rod(s)"
        )
    home = info["home"]
    q_units = sorted(set(info["actuator_units"]))
    click.echo(f"home: pose ({', '.join(info['pose_columns'])}) {fmt(home['pose'])}, "
               f"{', '.join(info['actuators'])} = {fmt(home['q'])} {'/'.join(q_units)}")
    modes = info["assembly_modes"]
    click.echo(f"assembly modes: working {modes['working']!r}, other {modes['other']!r}")
    if "characteristic_length" in info:
        how = ("given" if info["characteristic_length_given"] else
               "default: the platform joints' mean radius")
        click.echo(f"characteristic length L = {fmt(info['characteristic_length'])} {u} "
                   f"({how}): J_h = diag(1, 1, 1, L, L, L) J")
    g, inst = info["mobility"]["grubler"], info["mobility"]["instantaneous"]
    joints = ", ".join(f"{n} {k}" for k, n in g["joints_by_type"].items())
    click.echo(
        f"mobility (Grübler): m = {g['motion_space']}({g['bodies']} - 1 - {g['joints']}) + "
        f"{g['joint_freedoms']} - {g['internal_mobilities']} = {g['mobility']}  "
        f"[{g['bodies']} bodies incl. base; joints: {joints}]"
    )
    click.echo(
        f"mobility (rank of the closure at home): {inst['mobility']}; "
        f"redundant constraints: {inst['redundant_constraints']}; platform freedom with "
        f"actuators locked: {inst['platform_freedom_locked']}"
    )
    for text in info["warnings"]:
        click.echo(f"warning: {text}")
    click.echo(f"reference poses ({u}, deg): " + "; ".join(
        f"{k} {fmt(v)}" for k, v in info["reference_poses"].items()))
    _print_elastic(info)


def _print_elastic(info: dict[str, Any]) -> None:
    click.echo("elastic data (pkmkit stiffness): " + "; ".join(info["elastic_data"]["notes"]))


def _print_chain(info: dict[str, Any]) -> None:
    u = info["units"]
    click.echo(f"{info['id']}: {info['name']}  [{info['kind']}, joint chains]")
    for key in ("description", "source"):
        if info[key]:
            click.echo(f"  {key}: {info[key]}")
    if info["parameters"]:
        click.echo("parameters:")
        for p in info["parameters"]:
            click.echo(f"  {p['name']:<22} = {fmt(p['value'])} {p['unit']:<4} {p['doc']}")
    click.echo(f"elements (axis I,J,K and point A,B,C in the previous frame, {u}):")
    for e in info["elements"]:
        act = " actuated" if e["actuated"] else ""
        click.echo(f"  {e['name']:<10} {e['type']}{act:<9} label {e['label']:<4} axis "
                   f"{fmt(e['axis'], 4)} point {fmt(e['point'], 6)}")
    for leg, chain in info["legs"].items():
        click.echo(f"{leg}: {' → '.join(chain)}")
    if info["head"]:
        click.echo(f"head: {' → '.join(info['head'])}; tool length {info['tool_length']:.6g} {u}")
    h = info["hyperstatism"]
    joints = ", ".join(f"{n} {k}" for k, n in h["joints_by_type"].items())
    click.echo(f"parallel part: {h['joints']} one-DOF joints ({joints}), {h['bodies']} bodies, "
               f"{h['loops']} loops; mobility {h['mobility']}; degree of hyperstatism "
               f"h = 6·{h['loops']} − {h['joints']} + {h['mobility']} = {h['hyperstatism']} "
               f"(rank test: {h['rank_hyperstatism']} redundant closure equations)")
    home = info["home"]
    click.echo(f"home: {', '.join(info['actuators'])} = {fmt(home['q'])} "
               f"({'/'.join(sorted(set(info['actuator_units'])))}); tool point and axis "
               f"{fmt(home['pose'])}")
    click.echo("  passive joints (deg or " + u + "): " + ", ".join(
        f"{k} = {v:.6g}" for k, v in home["passive"].items()))
    click.echo(f"defects: {info['defects']} (pkmkit errors {info['id']} lists them)")
    _print_elastic(info)
