"""Record classes whose fields are computed when read: the lazy subclass of a frozen record
dataclass, each field a property served from an *evaluation* object (``evaluation.field(name)``,
cached per record); fields given at construction are served as given. Used by the full-pose
velocity models of one pose and of a batch (:mod:`pkmkit.machines.full_pose_velocity_one`,
:mod:`pkmkit.machines.full_pose_velocity_batch`)."""

from __future__ import annotations

import _thread
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

_T = TypeVar("_T")


def read_only(value: Any) -> Any:
    """``value`` as a record hands it out: a writeable NumPy array becomes a read-only *view*
    of it (no copy; the array the record keeps, and any array of the caller's it may share
    memory with, stay as they were), anything else is returned as is. A record's field is
    what every later read, and every field derived from it afterwards, sees: writing into it
    in place (``rec.J[...] = 0``) raises ``ValueError`` instead of changing them
    (docs/kinematics.md, "Records are read-only"). Every record whose fields are computed when
    read serves them through here (:func:`lazy_record_class`,
    :class:`pkmkit.machines.velocity.LazyJacobians` and its one-pose subclass)."""
    if type(value) is np.ndarray and value.flags.writeable:
        value = value.view()
        value.setflags(write=False)  # half the cost of value.flags.writeable = False
    return value


class ReadOnlyFields:
    """Base of the frozen record dataclasses (:mod:`pkmkit.machines.results`): each array field
    given at construction is kept as a read-only view (:func:`read_only`), so that no record
    hands out an array a caller may write into; unpickled or copied, likewise. The lazy
    subclasses (:func:`lazy_record_class`) serve their fields through :func:`read_only` when
    read instead."""

    __slots__ = ()

    def __post_init__(self) -> None:
        fields = self.__dict__
        for name, value in fields.items():
            if type(value) is np.ndarray and value.flags.writeable:
                fields[name] = read_only(value)

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update({name: read_only(value) for name, value in state.items()})


def lazy_record_class(base: type, prefix: str, describe: Callable[[Any], str],
                      doc: str) -> type:
    """The subclass ``{prefix}{base.__name__}`` of the record dataclass ``base`` whose every
    field is a property read from the evaluation given to its constructor
    (``cls(evaluation, **given_fields)``); ``describe(record)`` is the text inside its repr.
    Equality is identity (comparing would compute every field); pickled, it becomes the plain
    ``base`` record with every field computed."""
    names = tuple(base.__dataclass_fields__)

    def __init__(self, evaluation: Any = None, **fields: Any) -> None:
        object.__setattr__(self, "_evaluation", evaluation)
        object.__setattr__(self, "_cache", dict(fields))

    def _get(self, name: str) -> Any:
        cache = self._cache
        value = cache[name] if name in cache else self._evaluation.field(name)
        value = cache[name] = read_only(value)  # kept read-only: every later read sees it
        return value

    def known_fields(self) -> dict[str, Any]:
        """The fields given at construction or computed so far, by name: the record's own
        mapping (live: a later read adds to it), where its evaluation finds a field already
        computed (a ``pose`` from the ``direct`` record read before it) and may put one it
        computed along."""
        return self._cache

    def __eq__(self, other: object) -> bool:
        return self is other

    def __repr__(self) -> str:
        return f"{base.__name__}({describe(self)})"

    def __reduce__(self):  # pickled as the plain record, every field computed
        return base, tuple(getattr(self, name) for name in names)

    def prop(name: str) -> property:
        return property(lambda self: self._get(name), doc=f"``{name}`` (computed when read)")

    namespace = {"__init__": __init__, "_get": _get, "known_fields": known_fields,
                 "__eq__": __eq__,
                 "__hash__": object.__hash__, "__repr__": __repr__, "__reduce__": __reduce__,
                 "__doc__": doc}
    namespace.update({name: prop(name) for name in names})
    return type(f"{prefix}{base.__name__}", (base,), namespace)


def lazy_parts(record: Any) -> tuple[Any, dict[str, Any]] | None:
    """``(evaluation, fields given or computed so far)`` of a record made by a
    :func:`lazy_record_class` class, None for any other object (joining the chunks of a batch
    call keeps a lazy record lazy: :mod:`pkmkit.machines.chunks`)."""
    given = record.__dict__.get("_cache") if hasattr(record, "__dict__") else None
    if not isinstance(given, dict) or "_evaluation" not in record.__dict__:
        return None
    return record.__dict__["_evaluation"], given



def built_once(build: Callable[[], _T]) -> Callable[[], _T]:
    """A function returning ``build()``, run once on first use under a lock and handed out
    only when complete: threads making their first calls at once get the same object (one
    record class, its ``__reduce__`` already set), not one each (docs/testing.md, "Audit of
    threads, session 35"). Lazy so that importing the module builds nothing."""
    lock = _thread.allocate_lock()  # _thread: built in, no import cost (threading's is)
    built: list[_T] = []

    def get() -> _T:
        if not built:
            with lock:
                if not built:
                    built.append(build())
        return built[0]

    get.__doc__ = build.__doc__
    return get
