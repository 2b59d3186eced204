"""The values the sync phase derives (``rgraph.compiler.sync``) and hands to emit."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

from rgraph.compiler.usages import Sync
from rgraph.ir.graph import Cell

EMPTY: frozenset[str] = frozenset()


class State(NamedTuple):
    """Where a cell stands: stages/access of the last accesses that later ones must wait for.
    (A named tuple: hashed and compared in C, as barrier group keys are many.)"""

    stages: frozenset[str]
    access: frozenset[str]  # writes only
    layout: str | None
    queue: str | None


class BarrierKey(NamedTuple):
    src: State
    dst: State
    aliases: tuple[str, ...] = ()


class Barrier(NamedTuple):
    resource: str
    mips: tuple[int, int] | None
    layers: tuple[int, int] | None
    key: BarrierKey


class Wait(NamedTuple):
    queue: str
    signal_pass: int  # executed index of the pass whose signal is waited for
    stages: frozenset[str]


@dataclass(slots=True)
class PassSync:
    barriers: list[Barrier] = field(default_factory=list)
    releases: list[Barrier] = field(default_factory=list)
    waits: list[Wait] = field(default_factory=list)
    signal: bool = False


@dataclass
class SyncResult:
    passes: list[PassSync]
    access_sync: list[list[Sync]]  # per pass, per declared access
    final: dict[str, dict[Cell, State]]  # per resource: end-of-frame state per cell
    initial: dict[str, dict[Cell, State]]
