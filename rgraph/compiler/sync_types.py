"""The values the sync phase derives (``rgraph.compiler.sync``) and hands to emit."""

from __future__ import annotations

from dataclasses import dataclass

from rgraph.plan import model as pm

EMPTY: frozenset[str] = frozenset()

#: Where a cell stands: (stages, access, layout, queue) of the last accesses that later ones
#: must wait for (access: writes only), stages and access frozensets; a plain tuple, hashed and
#: compared in C (``rgraph.compiler.plan_values.plan_state`` gives the plan's ``State``).
StateKey = tuple


@dataclass
class SyncResult:
    barriers: list[tuple[pm.Barrier, ...]]  # per pass: before it
    releases: list[tuple[pm.Barrier, ...]]  # per pass: queue-family releases after it
    waits: list[tuple[pm.Wait, ...]]  # per pass, by queue
    signals: list[bool]  # per pass: a later pass waits for it
    signal_values: list[int]  # per pass: the timeline value it signals on its queue (1, 2, ...; 0: none)
    final: dict[str, pm.EndState]  # per resource: its end-of-frame state as the plan has it
    initial: dict[str, pm.EndState]
