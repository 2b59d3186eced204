"""Plan values that many accesses and barriers share, each built once per value (interned).

A plan holds thousands of states, subresources and sorted name tuples but few distinct ones;
all are immutable, so equal ones may be one object (a plan read from JSON has equal, not
identical, ones). The tables are bounded: cleared when they grow past a few thousand values.
"""

from __future__ import annotations

from rgraph.plan import model as pm
from rgraph.plan.builders import builder

#: A compiler-side state: (stages, write access, layout, queue), stages and access frozensets.
StateKey = tuple

_NAMES: dict[frozenset[str], tuple[str, ...]] = {}
_STATES: dict[StateKey, pm.State] = {}
_SUBRESOURCES: dict[tuple[tuple[int, int], tuple[int, int]], pm.Subresource] = {}
_LIMIT = 65536

#: ``pm.Barrier(...)`` without the frozen ``__init__``'s per-field ``object.__setattr__``.
make_barrier = builder(pm.Barrier)


def names(values: frozenset[str]) -> tuple[str, ...]:
    """A set of stage or access names as the plan's sorted tuple (frozensets cache their hash)."""
    found = _NAMES.get(values)
    if found is None:
        if len(_NAMES) > _LIMIT:
            _NAMES.clear()
        found = _NAMES[values] = tuple(sorted(values))
    return found


def plan_state(st: StateKey) -> pm.State:
    """The plan's ``State`` of a compiler state."""
    found = _STATES.get(st)
    if found is None:
        if len(_STATES) > _LIMIT:
            _STATES.clear()
        found = _STATES[st] = pm.State(names(st[0]), names(st[1]), st[2], st[3])
    return found


def subresource(mips: tuple[int, int], layers: tuple[int, int]) -> pm.Subresource:
    key = (mips, layers)
    found = _SUBRESOURCES.get(key)
    if found is None:
        if len(_SUBRESOURCES) > _LIMIT:
            _SUBRESOURCES.clear()
        found = _SUBRESOURCES[key] = pm.Subresource(mips, layers)
    return found


#: Lookups for the hot loops (``dict.get``: None when not built yet).
get_state = _STATES.get
get_subresource = _SUBRESOURCES.get
