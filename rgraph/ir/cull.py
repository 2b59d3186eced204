"""Remove what the frame does not need, each removal with a reason.

1. Passes whose ``requires`` the scene lacks (decided in specialization).
2. Reads whose producers were removed: optional reads are dropped; a pass with a required
   read of a transient whose every producer was removed is removed too (the effect it
   feeds is absent).
3. Passes that reach no output: not an ancestor, through read-after-write edges, of the last
   writer of an output, of a persistent or imported resource, or of a ``side_effects`` pass.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import networkx as nx

from rgraph.ir.graph import Cell, build_graph, last_writers, reads
from rgraph.spec.specialize import PassSpec, Spec


@dataclass(frozen=True)
class Culled:
    pass_name: str
    reason: str


@dataclass(frozen=True)
class DroppedRead:
    pass_name: str
    resource: str
    reason: str


@dataclass
class Culling:
    passes: list[PassSpec]  # kept, declaration order, with dropped reads removed
    culled: list[Culled]
    dropped_reads: list[DroppedRead]

    @cached_property
    def graph(self) -> nx.DiGraph:
        """The dependency graph of the kept passes (built on first use)."""
        return build_graph(self.passes)


def cull(spec: Spec) -> Culling:
    removed_reason = dict(spec.removed)
    culled = [Culled(name, reason) for name, reason in spec.removed]
    kept, dropped, cascade = _drop_unproduced_reads(spec, removed_reason)
    culled += cascade
    alive = _alive(spec, kept)
    final = [p for p in kept if p.name in alive]
    culled += [Culled(p.name, "reaches no output") for p in kept if p.name not in alive]
    order = {p.name: p.order for p in spec.passes}
    culled.sort(key=lambda c: order[c.pass_name])
    return Culling(final, culled, dropped)


def _alive(spec: Spec, kept: list[PassSpec]) -> set[str]:
    """``raw_ancestors(dependencies(kept), _roots(spec, kept))`` as one backwards walk:
    ``wanted`` holds the cells that live passes read and whose producer is not met yet,
    ``claimed`` the cells of kept resources that a later pass writes last."""
    keep = {n for n, r in spec.resources.items() if r.lifetime in ("persistent", "imported", "output")}
    keep.update(spec.outputs)
    wanted: set[Cell] = set()
    claimed: set[Cell] = set()
    alive: set[str] = set()
    for p in reversed(kept):
        live = p.side_effects
        for access in p.accesses:
            if access.write:
                cs = access.cells
                if not live and (not wanted.isdisjoint(cs) or (access.resource in keep and not claimed.issuperset(cs))):
                    live = True
                if access.resource in keep:
                    claimed.update(cs)
        if not live:
            continue
        alive.add(p.name)
        for access in p.accesses:
            if access.write:
                wanted.difference_update(access.cells)
        for access in p.accesses:
            if reads(access):
                wanted.update(access.cells)
    return alive


def _roots(spec: Spec, kept: list[PassSpec]) -> set[str]:
    keep_written = {n for n, r in spec.resources.items() if r.lifetime in ("persistent", "imported", "output")}
    keep_written |= set(spec.outputs)
    roots = last_writers(kept, keep_written)
    roots |= {p.name for p in kept if p.side_effects}
    return roots


def _drop_unproduced_reads(
    spec: Spec, removed_reason: dict[str, str]
) -> tuple[list[PassSpec], list[DroppedRead], list[Culled]]:
    """Forward walk in program order: who produced each cell, given the removals so far."""
    producer: dict[tuple[str, int, int], str | None] = {}
    lost: dict[tuple[str, int, int], str] = {}  # cell -> removed pass that would have written it
    kept: list[PassSpec] = []
    dropped: list[DroppedRead] = []
    cascade: list[Culled] = []
    for p in spec.passes:
        removed = p.name in removed_reason
        new_accesses = []
        cascade_reason = None
        for access in p.accesses:
            persistent = spec.resources[access.resource].lifetime in ("persistent", "imported")
            needs_input = reads(access) and not access.write and not persistent
            if not removed and needs_input and not all(producer.get(c) for c in access.cells):
                culprit = next((lost[c] for c in access.cells if c in lost), None)
                if access.optional:
                    why = "optional read with no producer"
                    if culprit:
                        why += f" ('{culprit}' was removed: {removed_reason[culprit]})"
                    dropped.append(DroppedRead(p.name, access.resource, why))
                    continue
                if culprit:
                    cascade_reason = f"reads '{access.resource}', whose producer '{culprit}' was removed ({removed_reason[culprit]})"
            new_accesses.append(access)
        if cascade_reason and not removed:
            removed_reason[p.name] = cascade_reason
            cascade.append(Culled(p.name, cascade_reason))
            removed = True
        for access in p.accesses:
            if access.write:
                for c in access.cells:
                    if removed:
                        lost[c] = p.name
                    else:
                        producer[c] = p.name
                        lost.pop(c, None)
        if not removed:
            kept.append(replace(p, accesses=tuple(new_accesses)) if len(new_accesses) != len(p.accesses) else p)
    return kept, dropped, cascade
