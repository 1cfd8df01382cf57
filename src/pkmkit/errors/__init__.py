"""Deprecated alias of :mod:`pkmkit.exceptions` and :mod:`pkmkit.geometric_errors`.

``pkmkit.errors`` used to hold both the typed exceptions and the geometric-error algorithms.
The exceptions now live in :mod:`pkmkit.exceptions` and the algorithms in
:mod:`pkmkit.geometric_errors`. This alias keeps old imports working for one release:
``from pkmkit.errors import InputError`` and ``from pkmkit.errors.model import defect_set`` both
work and warn with a :class:`DeprecationWarning` (through :mod:`pkmkit.aliases`). Nothing inside
pkmkit imports it.
"""

from __future__ import annotations

import warnings

from pkmkit import aliases as _aliases
from pkmkit import exceptions as _exceptions


def __getattr__(name: str):
    if hasattr(_exceptions, name):
        warnings.warn(f"pkmkit.errors.{name} moved to pkmkit.exceptions.{name}",
                      DeprecationWarning, stacklevel=2)
        return getattr(_exceptions, name)
    raise AttributeError(f"module 'pkmkit.errors' has no attribute {name!r}")


_aliases.install(prefixes={__name__: "pkmkit.geometric_errors"})
