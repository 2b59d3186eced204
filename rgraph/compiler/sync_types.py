"""The values the sync phase derives (``rgraph.compiler.sync``) and hands to emit."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from rgraph.compiler.usages import Sync
from rgraph.ir.graph import Cell
from rgraph.plan import model as pm

EMPTY: frozenset[str] = frozenset()

#: Where a cell stands: (stages, access, layout, queue) of the last accesses that later ones
#: must wait for (access: writes only), stages and access frozensets; a plain tuple, hashed and
#: compared in C (``rgraph.compiler.plan_values.plan_state`` gives the plan's ``State``).
StateKey = tuple


class Wait(NamedTuple):
    queue: str
    signal_pass: int  # executed index of the pass whose signal is waited for
    stages: frozenset[str]


@dataclass
class SyncResult:
    barriers: list[tuple[pm.Barrier, ...]]  # per pass: before it
    releases: list[tuple[pm.Barrier, ...]]  # per pass: queue-family releases after it
    waits: list[tuple[Wait, ...]]  # per pass, by queue
    signals: list[bool]  # per pass: a later pass waits for it
    access_sync: list[list[Sync]]  # per pass, per declared access
    final: dict[str, dict[Cell, StateKey]]  # per resource: end-of-frame state per cell
    initial: dict[str, dict[Cell, StateKey]]
