"""Fast constructors for the plan's frozen slots dataclasses (``rgraph.plan.model``).

A frozen dataclass's ``__init__`` sets every field through ``object.__setattr__``; the emit
phase builds thousands of ``Access``, ``Barrier`` and ``PlanPass`` values per compile. A
builder has the same signature (fields, defaults) and returns an equal object of the same
class, built as an instance of a plain (mutable) twin class with the same slots, its fields
set by ordinary attribute stores in the twin's ``__init__``, and then given the frozen class (``__class__``
assignment: CPython allows it between classes of one object layout, and checks it). That is
about half the cost of the ``__init__``'s, or of setting each slot through its descriptor
(the fallback, for a class whose slots are spread over several bases). Only for classes
without ``__post_init__`` (none of the plan's have one).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, TypeVar

from rgraph.native import load

T = TypeVar("T")

#: The compiled builder (None where not built or ``RGRAPH_NATIVE=0``).
_NATIVE = load("rgraph.plan._builders")


def _twin(cls: type) -> type | None:
    """A plain class with ``cls``'s object layout (its slots, in one class), or None."""
    with_slots = [k for k in cls.__mro__ if vars(k).get("__slots__")]
    if len(with_slots) != 1:
        return None
    twin = type(f"_Mutable{cls.__name__}", (), {"__slots__": tuple(with_slots[0].__slots__)})
    probe = object.__new__(twin)
    try:
        probe.__class__ = cls
    except TypeError:
        return None
    return twin


def builder(cls: type[T]) -> Callable[..., T]:
    """``builder_python(cls)``, or where it is built its compiled twin (``rgraph/plan/_builders.pyx``:
    the object allocated and its slots stored from C, about a fifth of the twin class's cost)."""
    if _NATIVE is not None and dataclasses.is_dataclass(cls):
        try:
            return _NATIVE.FastBuilder(cls)
        except TypeError:  # not a plain slots dataclass: the Python builder says why
            pass
    return builder_python(cls)


def builder_python(cls: type[T]) -> Callable[..., T]:
    """A function ``f(*fields)`` (keywords and defaults as the class's ``__init__``) that
    returns ``cls(*fields)``. With a twin it is the twin class itself, whose ``__init__`` sets
    the fields and then gives the object the frozen class (a class call runs ``__init__``
    with less overhead than a function that creates the object: about 25 ns of 200 here)."""
    if not dataclasses.is_dataclass(cls) or hasattr(cls, "__post_init__") or "__slots__" not in vars(cls):
        raise TypeError(f"{cls.__name__}: a slots dataclass without __post_init__ expected")
    fields = dataclasses.fields(cls)
    twin = _twin(cls)
    scope: dict[str, Any] = {"_new": object.__new__, "_cls": cls}
    params = []
    for k, f in enumerate(fields):
        if f.default_factory is not dataclasses.MISSING:
            raise TypeError(f"{cls.__name__}.{f.name}: default_factory is not supported")
        if f.default is dataclasses.MISSING:
            params.append(f.name)
        else:
            scope[f"_d{k}"] = f.default
            params.append(f"{f.name}=_d{k}")
    if twin is not None:
        body = [f"    self.{f.name} = {f.name}" for f in fields] + ["    self.__class__ = _cls"]
        exec(f"def __init__(self, {', '.join(params)}):\n" + "\n".join(body) + "\n", scope)  # noqa: S102
        made = type(f"build_{cls.__name__}", (), {"__slots__": twin.__slots__, "__init__": scope["__init__"],
                                                  "__doc__": f"``{cls.__name__}(...)``, built through a mutable twin."})
        return made
    body = ["    o = _new(_cls)"]
    for k, f in enumerate(fields):
        scope[f"_s{k}"] = getattr(cls, f.name).__set__
        body.append(f"    _s{k}(o, {f.name})")
    source = f"def build({', '.join(params)}):\n" + "\n".join(body) + "\n    return o\n"
    exec(source, scope)  # noqa: S102 - generated from the dataclass's own field names
    fn = scope["build"]
    fn.__name__ = fn.__qualname__ = f"build_{cls.__name__}"
    fn.__doc__ = f"``{cls.__name__}(...)`` without the frozen ``__init__``'s per-field ``object.__setattr__``."
    return fn
