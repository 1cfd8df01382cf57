"""Reading machine files (TOML or YAML) with line numbers for error messages.

A machine file is a mapping with a ``[machine]`` table (``kind``, ``name``, ``units``, ...) and,
depending on the kind, a ``[parameters]`` table or ``[[legs]]`` entries. This module only parses
the text and keeps, for every key, the line where it was written, so that the machine builders
can report *which line* of the file is wrong. Building the machine is the job of
:mod:`pkmkit.machines.registry`.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pkmkit.exceptions import MachineFileError
from pkmkit.model.text_files import MAX_NESTING, read_text, toml_nesting

if TYPE_CHECKING:
    import yaml

KeyPath = tuple[str | int, ...]

SUFFIXES = {".toml": "toml", ".yaml": "yaml", ".yml": "yaml"}


@dataclass(frozen=True)
class MachineDocument:
    """Parsed machine file.

    Attributes:
        path: the file path as given.
        data: the parsed mapping.
        lines: 1-based line of each key path that was located (e.g. ``("parameters", "L")`` or
            ``("legs", 2, "axis")``).
    """

    path: str
    data: dict[str, Any]
    lines: dict[KeyPath, int]

    def line_of(self, key_path: KeyPath) -> int | None:
        """Line of ``key_path``, or of its longest located prefix; ``None`` if nothing matches."""
        for end in range(len(key_path), 0, -1):
            line = self.lines.get(tuple(key_path[:end]))
            if line is not None:
                return line
        return None

    def error(self, message: str, key_path: KeyPath = ()) -> MachineFileError:
        """A :class:`MachineFileError` for this file, at the line of ``key_path``."""
        return MachineFileError(self.path, message, self.line_of(key_path))


def read_machine_document(path: str | Path) -> MachineDocument:
    """Parse a ``.toml``, ``.yaml`` or ``.yml`` machine file.

    Raises:
        MachineFileError: missing file, unknown extension, a binary or non-UTF-8 file, syntax
            error, a key given twice, nesting deeper than :data:`MAX_NESTING` (each with its
            line), or a document that is not a mapping.
    """
    return parse_machine_document(path, read_machine_text(path))


def read_machine_text(path: str | Path) -> str:
    """The text of a machine file, unparsed (what :func:`read_machine_document` parses).

    Raises:
        MachineFileError: unknown extension, missing, binary or non-UTF-8 file.
    """
    _format(path)
    return read_text(Path(path), lambda message, line: MachineFileError(str(path), message, line))


def _format(path: str | Path) -> str:
    p = Path(path)
    fmt = SUFFIXES.get(p.suffix.lower())
    if fmt is None:
        raise MachineFileError(
            str(path), f"unknown machine file type {p.suffix!r}; use one of {sorted(SUFFIXES)}"
        )
    return fmt


def parse_machine_document(path: str | Path, text: str) -> MachineDocument:
    """Parse ``text``, the content of the machine file ``path`` (:func:`read_machine_text`).

    Raises:
        MachineFileError: as :func:`read_machine_document`, but for reading the file.
    """
    parse: Callable[[str, str], tuple[Any, dict[KeyPath, int]]] = (
        _parse_toml if _format(path) == "toml" else _parse_yaml
    )
    data, lines = parse(text, str(path))
    if not isinstance(data, dict):
        raise MachineFileError(str(path), "a machine file must hold a mapping of tables", 1)
    return MachineDocument(str(path), data, lines)


_TOML_LINE = re.compile(r"at line (\d+)")
_TABLE = re.compile(r"^\s*\[\s*([^\[\]]+?)\s*\]\s*(#.*)?$")
_ARRAY_TABLE = re.compile(r"^\s*\[\[\s*([^\[\]]+?)\s*\]\]\s*(#.*)?$")
_KEY = re.compile(r"^\s*([A-Za-z0-9_\-\.\"']+)\s*=")


def parse_toml(text: str, path: str) -> tuple[Any, dict[KeyPath, int]]:
    """Parse TOML ``text`` (from file ``path``): the data and the line of each key.

    Raises:
        MachineFileError: nesting deeper than :data:`MAX_NESTING`, or a syntax error (a key
            given twice included), with its line.
    """
    return _parse_toml(text, path)


def _parse_toml(text: str, path: str) -> tuple[Any, dict[KeyPath, int]]:
    depth, line = toml_nesting(text)
    if depth > MAX_NESTING:
        raise MachineFileError(path, f"arrays/tables nested {depth} deep; at most {MAX_NESTING} "
                               "levels are accepted", line)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        match = _TOML_LINE.search(str(exc))
        line = int(match.group(1)) if match else None
        message = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        raise MachineFileError(path, f"TOML syntax error: {message}", line) from None
    except ValueError:  # an integer of more than 4300 digits (Python's conversion limit)
        raise _too_long_number(text, path) from None
    return data, _toml_lines(text)


def _too_long_number(text: str, path: str) -> MachineFileError:
    """The error for a number too long to convert, at the line of its first long digit run."""
    line = next((k for k, raw in enumerate(text.splitlines(), start=1)
                 if re.search(r"\d{4300}", raw)), None)
    return MachineFileError(path, "a number of more than 4300 digits", line)


def _split_key(key: str) -> tuple[str, ...]:
    return tuple(part.strip().strip("\"'") for part in key.split("."))


def _toml_lines(text: str) -> dict[KeyPath, int]:
    """Locate table headers and keys line by line (tomllib keeps no positions)."""
    lines: dict[KeyPath, int] = {}
    table: KeyPath = ()
    array_counts: dict[tuple[str, ...], int] = {}
    open_quote: str | None = None  # inside a multi-line string
    for number, raw in enumerate(text.splitlines(), start=1):
        if open_quote is not None:
            if raw.count(open_quote) % 2 == 1:
                open_quote = None
            continue
        for quote in ('"""', "'''"):
            if raw.count(quote) % 2 == 1:
                open_quote = quote
        if m := _ARRAY_TABLE.match(raw):
            name = _split_key(m.group(1))
            index = array_counts.get(name, -1) + 1
            array_counts[name] = index
            table = (*name, index)
            lines.setdefault(name, number)
            lines[table] = number
        elif m := _TABLE.match(raw):
            table = _split_key(m.group(1))
            lines.setdefault(table, number)
        elif m := _KEY.match(raw):
            lines.setdefault((*table, *_split_key(m.group(1))), number)
    return lines


def _reject_aliases(text: str, path: str) -> None:
    """Anchors and aliases can expand exponentially (or recursively): machine files may not use
    them. Nesting deeper than :data:`MAX_NESTING` is refused too (the composer recurses), both
    from the event stream, before anything is built."""
    import yaml  # lazy: only YAML files need it

    depth = 0
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None):
            raise MachineFileError(path, "YAML anchors and aliases (&name, *name) are not "
                                   "allowed in machine files", event.start_mark.line + 1)
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_NESTING:
                raise MachineFileError(path, f"mappings/sequences nested more than "
                                       f"{MAX_NESTING} deep", event.start_mark.line + 1)
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1


def _parse_yaml(text: str, path: str) -> tuple[Any, dict[KeyPath, int]]:
    import yaml

    try:
        _reject_aliases(text, path)
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.safe_load(text)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        problem = exc.problem or exc.context or "invalid YAML"
        raise MachineFileError(path, f"YAML syntax error: {problem}", line) from None
    except yaml.YAMLError as exc:
        raise MachineFileError(path, f"YAML error: {exc}") from None
    except MachineFileError:  # (a ValueError too) anchors and aliases refused
        raise
    except ValueError:  # an integer of more than 4300 digits (Python's conversion limit)
        raise _too_long_number(text, path) from None
    lines: dict[KeyPath, int] = {}
    if node is not None:
        _yaml_lines(node, (), lines, path)
    return data, lines


def _yaml_lines(node: yaml.Node, prefix: KeyPath, lines: dict[KeyPath, int],
                path: str = "") -> None:
    """Record the line of every key; a key given twice in one mapping is an error (PyYAML would
    keep the last one silently)."""
    import yaml

    if isinstance(node, yaml.MappingNode):
        seen: dict[str, int] = {}
        for key_node, value_node in node.value:
            name = str(key_node.value)
            line = key_node.start_mark.line + 1
            if name in seen:
                raise MachineFileError(path, f"key {name!r} given twice (first at line "
                                       f"{seen[name]})", line)
            seen[name] = line
            key = (*prefix, name)
            lines[key] = line
            _yaml_lines(value_node, key, lines, path)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            key = (*prefix, index)
            lines[key] = item.start_mark.line + 1
            _yaml_lines(item, key, lines, path)
