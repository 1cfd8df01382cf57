"""Old module paths that keep working for one release, with a :class:`DeprecationWarning`.

When a public module moves, the package it left installs a :class:`ModuleAliases` finder: an
import of the old path hands out the module of the new path (one module object, so attributes,
monkeypatching and ``is`` tests agree) and warns. Used by :mod:`pkmkit.errors` (→
:mod:`pkmkit.exceptions`, :mod:`pkmkit.geometric_errors`) and :mod:`pkmkit.cli` (the demos →
:mod:`pkmkit.demos`, the coordinates → :mod:`pkmkit.boundary`). Imports nothing of pkmkit.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
import warnings
from collections.abc import Mapping


class _AliasLoader:
    """Hands out the module of the new path under the old name (one module object). A loader
    by protocol (``create_module``, ``exec_module``), not a subclass of ``importlib.abc.Loader``:
    importing ``importlib.abc`` pulls in ``importlib.resources``, ``tempfile`` and ``random``
    (≈ 10–25 ms of every command's start-up)."""

    def __init__(self, target: str):
        self.target = target
        self.spec = None

    def create_module(self, spec):
        module = importlib.import_module(self.target)
        self.spec = module.__spec__
        return module

    def exec_module(self, module) -> None:
        module.__spec__ = self.spec  # the import system wrote the alias's spec over it


class ModuleAliases:
    """Finder of moved modules (a meta path finder by protocol: ``find_spec``).

    ``modules``: old dotted name → new dotted name, one module each; ``prefixes``: old package →
    new package, every sub-module included (``old.x.y`` → ``new.x.y`` when ``new.x.y`` exists).
    """

    def __init__(self, modules: Mapping[str, str] | None = None,
                 prefixes: Mapping[str, str] | None = None):
        self.modules = dict(modules or {})
        self.prefixes = dict(prefixes or {})

    def target(self, fullname: str) -> str | None:
        """The new name of ``fullname``, or None if it did not move."""
        if fullname in self.modules:
            return self.modules[fullname]
        for old, new in self.prefixes.items():
            if fullname.startswith(old + "."):
                return new + fullname[len(old):]
        return None

    def find_spec(self, fullname, path=None, target=None):
        new = self.target(fullname)
        if new is None or importlib.util.find_spec(new) is None:
            return None
        warnings.warn(f"{fullname} moved to {new}", DeprecationWarning, stacklevel=2)
        return importlib.util.spec_from_loader(fullname, _AliasLoader(new))


def install(modules: Mapping[str, str] | None = None,
            prefixes: Mapping[str, str] | None = None) -> ModuleAliases:
    """Put a :class:`ModuleAliases` finder first on ``sys.meta_path`` (once per set of names)
    and return it."""
    finder = ModuleAliases(modules, prefixes)
    for found in sys.meta_path:
        if (isinstance(found, ModuleAliases) and found.modules == finder.modules
                and found.prefixes == finder.prefixes):
            return found
    sys.meta_path.insert(0, finder)
    return finder
