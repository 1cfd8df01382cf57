"""Machines built from a file, kept so that loading the same file again costs a copy.

Building a machine (parsing its file, validating the parameters, solving and checking its home
pose, packing its kernels' constants) costs 1.3–10 ms; :func:`pkmkit.machines.registry.load`
(hence :func:`~pkmkit.machines.registry.machine`) asks here first. An entry is keyed by
everything the built machine depends on — the path as given (the machine's id is its stem), the
file's *text* (a file rewritten is a new key, whatever its time stamp), the id asked for, and the
engine state the build reads (``PKMKIT_COMPILED``, ``PKMKIT_NATIVE``, whether the C extension
is loaded, whether Numba is: a joint-chain machine closes its legs at home with the compiled
closure when there is one) — and holds a *template* nobody else sees. Each caller gets its own
copy (:func:`handed_out`): a new object whose dictionaries, lists, tuples and writable arrays are
copied, so that changing ``m.params`` or an array of ``m.extra_poses`` in place, or any state a
machine fills lazily on first use, never reaches the template or another caller's machine. The
immutable parts (the frozen ``model``, the machine's kind, its closed-form kernels' constants,
which no code writes) are shared, and so that no caller can write into them either, every
array reachable from them is made read-only when the template is kept (:func:`freeze_shared`:
``pkmkit.machine("x").model.leg_base[0] = 1`` raises ``ValueError`` instead of changing every
later ``pkmkit.machine("x")``; tests/machines/test_shared_state.py). Errors are not kept: a
file that fails is read again.
"""

from __future__ import annotations

import os
import sys
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import numpy as np

from pkmkit.numerics import jit

#: Templates kept (least recently used dropped first); a preset is a few kB to ~100 kB.
MAX_KEPT = 64

_kept: OrderedDict[tuple, Any] = OrderedDict()
_lock = threading.Lock()


def engine_key() -> tuple:
    """What of the process's engine choice a machine's build may read."""
    return (jit.mode(), os.environ.get("PKMKIT_NATIVE", "").strip(),
            jit.native_kernels() is not None, "numba" in sys.modules)


def built(key: tuple, build: Callable[[], Any]) -> Any:
    """A copy (:func:`handed_out`) of the machine kept under ``key`` (extended by
    :func:`engine_key`), built by ``build()`` and kept when absent."""
    key = (*key, engine_key())
    with _lock:
        template = _kept.get(key)
        if template is not None:
            _kept.move_to_end(key)
    if template is None:
        template = build()  # raises: nothing kept
        freeze_shared(template)
        with _lock:
            _kept[key] = template
            while len(_kept) > MAX_KEPT:
                _kept.popitem(last=False)
    return handed_out(template)


def forget() -> None:
    """Drop every kept machine (the next load of each file builds it again)."""
    with _lock:
        _kept.clear()


def handed_out(template: Any) -> Any:
    """A new machine equal to ``template``: the same attributes, with fresh copies of every
    dictionary, list, tuple and writable array among them (recursively); other objects
    shared."""
    machine = object.__new__(type(template))
    machine.__dict__.update({k: _fresh(v) for k, v in template.__dict__.items()})
    return machine


def _fresh(value: Any) -> Any:
    kind = type(value)
    if kind is np.ndarray:
        return value.copy() if value.flags.writeable else value
    if kind is dict:
        return {k: _fresh(v) for k, v in value.items()}
    if kind is list:
        return [_fresh(v) for v in value]
    if kind is tuple:
        return tuple(_fresh(v) for v in value)
    return value


def freeze_shared(template: Any) -> None:
    """Make read-only, in place, every NumPy array :func:`handed_out` shares between the
    copies of ``template``: the arrays reachable from its attributes that are neither arrays,
    dictionaries, lists nor tuples (those are copied), through their attributes, dictionaries,
    lists and tuples."""
    seen: set[int] = set()
    for value in template.__dict__.values():
        _freeze_parts(value, seen, False)


def _freeze_parts(value: Any, seen: set[int], shared: bool) -> None:
    """:func:`freeze_shared` below ``value``: ``shared`` once inside an object handed out as
    is (every array there is frozen), else only what the copies will share."""
    kind = type(value)
    if kind is np.ndarray:
        if shared and value.flags.writeable:
            value.flags.writeable = False
        return
    if id(value) in seen or kind in (str, bytes, int, float, bool, type(None)):
        return
    seen.add(id(value))
    if kind in (dict, list, tuple):
        for item in (value.values() if kind is dict else value):
            _freeze_parts(item, seen, shared)
        return
    if not kind.__module__.startswith("pkmkit."):
        return  # a function, a capsule, a NumPy scalar: nothing a caller writes into
    parts = getattr(value, "__dict__", {})
    slots = [getattr(value, name) for name in getattr(kind, "__slots__", ())
             if hasattr(value, name)]
    for item in (*parts.values(), *slots):
        _freeze_parts(item, seen, True)
