"""Deprecated alias of :mod:`pkmkit.exceptions` and :mod:`pkmkit.geometric_errors`.

``pkmkit.errors`` used to hold both the typed exceptions and the geometric-error algorithms.
The exceptions now live in :mod:`pkmkit.exceptions` and the algorithms in
:mod:`pkmkit.geometric_errors`. This alias keeps old imports working for one release:
``from pkmkit.errors import InputError`` and ``from pkmkit.errors.model import defect_set`` both
work and warn with a :class:`DeprecationWarning`. Nothing inside pkmkit imports it.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

from pkmkit import exceptions as _exceptions

_NEW_PACKAGE = "pkmkit.geometric_errors"


def __getattr__(name: str):
    if hasattr(_exceptions, name):
        warnings.warn(f"pkmkit.errors.{name} moved to pkmkit.exceptions.{name}",
                      DeprecationWarning, stacklevel=2)
        return getattr(_exceptions, name)
    raise AttributeError(f"module 'pkmkit.errors' has no attribute {name!r}")


class _AliasLoader(importlib.abc.Loader):
    """Hands out the module of the new package under the old name (one module object)."""

    def __init__(self, target: str):
        self.target = target
        self.spec = None

    def create_module(self, spec):
        module = importlib.import_module(self.target)
        self.spec = module.__spec__
        return module

    def exec_module(self, module) -> None:
        module.__spec__ = self.spec  # the import system wrote the alias's spec over it


class _AliasFinder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        if not fullname.startswith(__name__ + "."):
            return None
        new = _NEW_PACKAGE + fullname[len(__name__):]
        if importlib.util.find_spec(new) is None:
            return None
        warnings.warn(f"{fullname} moved to {new}", DeprecationWarning, stacklevel=2)
        return importlib.util.spec_from_loader(fullname, _AliasLoader(new))


if not any(isinstance(f, _AliasFinder) for f in sys.meta_path):
    sys.meta_path.insert(0, _AliasFinder())
