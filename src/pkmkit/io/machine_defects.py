"""Writing machine files with a ``[defects]`` table: the calibrated machine (``pkmkit calibrate
--out``) and the true machine of a simulation (``pkmkit simulate-measurements --defects
random``), so that :func:`pkmkit.load` reads them back with their defects.

The new file is the source machine file's text (a preset or the user's file) with its
``[defects]`` table, if any, replaced by one holding the source's defects plus the new ones, in
the file's units (see :mod:`pkmkit.model.defects_table`). TOML and YAML sources keep their
format.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.io.atomic import write_text_atomic as atomic_write_text
from pkmkit.model.defects_table import defects_from_table, table_from_defects
from pkmkit.model.machine_file import SUFFIXES, read_machine_document
from pkmkit.model.parameters import length_scale

_TOML_TABLE = re.compile(r"^\s*\[\s*defects\s*\]\s*(#.*)?$")
_TOML_HEADER = re.compile(r"^\s*\[")
_YAML_KEY = re.compile(r"^defects\s*:")


def machine_text_with_defects(source: str | Path, machine, delta: np.ndarray, *,
                              note: str = "") -> str:
    """The text of ``source`` with ``delta`` (SI, ``machine``'s defect order, on top of the
    source's own ``[defects]``) as its ``[defects]`` table.

    Raises:
        InputError: an unreadable source or an unknown format.
    """
    path = Path(source)
    fmt = SUFFIXES.get(path.suffix.lower())
    if fmt is None:
        raise InputError(f"{source}: not a machine file (.toml, .yaml, .yml)")
    doc = read_machine_document(path)
    head = doc.data.get("machine", {}) if isinstance(doc.data.get("machine"), dict) else {}
    scale = length_scale(head.get("units", "m"))
    existing = doc.data.get("defects") or {}
    total = np.asarray(delta, dtype=float) + (defects_from_table(machine, existing, scale)
                                              if existing else 0.0)
    table = table_from_defects(machine, total, scale)
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines()
    comment = [f"# {line}" for line in note.splitlines()] if note else []
    if fmt == "toml":
        kept, skipping = [], False
        for line in lines:
            if _TOML_TABLE.match(line):
                skipping = True
                continue
            if skipping and _TOML_HEADER.match(line):
                skipping = False
            if not skipping:
                kept.append(line)
        body = ["", "[defects]", *comment] + [f"{k} = {v!r}" for k, v in table.items()]
    else:
        kept, skipping = [], False
        for line in lines:
            if _YAML_KEY.match(line):
                skipping = True
                continue
            if skipping and line and not line[0].isspace() and not line.startswith("#"):
                skipping = False
            if not skipping:
                kept.append(line)
        body = ["", *comment, "defects:"] + [f"  {k}: {v!r}" for k, v in table.items()]
        if not table:
            body[-1] = "defects: {}"
    while kept and not kept[-1].strip():
        kept.pop()
    return "\n".join(kept + body) + "\n"


def write_machine_with_defects(path: str | Path, source: str | Path, machine, delta: np.ndarray,
                               *, note: str = "") -> None:
    """Write :func:`machine_text_with_defects` to ``path`` (atomically); ``path`` should keep
    the source's extension."""
    atomic_write_text(path, machine_text_with_defects(source, machine, delta, note=note))
