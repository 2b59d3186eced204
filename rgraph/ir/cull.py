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

from rgraph.ir.graph import READ_WRITE_USAGES, Cell, build_graph, last_writers
from rgraph.native import load
from rgraph.plan.builders import builder
from rgraph.spec.specialize import PassSpec, Spec, check_empty


@dataclass(frozen=True, slots=True)
class Culled:
    pass_name: str
    reason: str


_new_culled = builder(Culled)

#: The compiled mirror of :func:`_alive_python` and :func:`_split` (``rgraph/ir/_cull.pyx``),
#: None where it is not built or ``RGRAPH_NATIVE=0``.
NATIVE = load("rgraph.ir._cull")


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
    if not spec.removed:  # the common case in one walk, unless a read is optional
        found = _plain(spec, spec.passes)
        if found is not None:
            final, unreached = found
            check_empty(spec, final)
            return Culling(final, unreached, [])
    removed_reason = dict(spec.removed)
    culled = [Culled(name, reason) for name, reason in spec.removed]
    kept, dropped, cascade = _drop_unproduced_reads(spec, removed_reason)
    culled += cascade
    alive = _alive(spec, kept)
    final, unreached = _split(kept, alive) if NATIVE is None else NATIVE.split(kept, alive, Culled)
    check_empty(spec, final)
    if not culled:  # kept is in declaration order
        return Culling(final, unreached, dropped)
    culled += unreached
    order = {p.name: p.order for p in spec.passes}
    culled.sort(key=lambda c: order[c.pass_name])
    return Culling(final, culled, dropped)


def _alive(spec: Spec, kept: list[PassSpec]) -> set[str]:
    """The passes of ``kept`` that reach an output: :func:`_alive_python`, compiled where built."""
    if NATIVE is None:
        return _alive_python(spec, kept)
    return NATIVE.alive(spec, kept, READ_WRITE_USAGES)


def _plain(spec: Spec, passes: list[PassSpec]) -> tuple[list[PassSpec], list[Culled]] | None:
    """``_split(passes, _alive(spec, passes))`` where no access of ``passes`` is optional (so,
    with no pass removed by the scene, ``_drop_unproduced_reads`` keeps ``passes`` as they are),
    else None. Compiled where built (``NATIVE.plain``: one backwards walk that also looks for
    an optional access, the cells of each resource numbered in C arrays instead of sets; None
    also where a resource or a cell does not fit those, and the general path runs)."""
    if NATIVE is not None:
        return NATIVE.plain(spec, passes, READ_WRITE_USAGES, Culled)
    if _has_optional_python(passes):
        return None
    return _split(passes, _alive_python(spec, passes))


def _split(kept: list[PassSpec], alive: set[str]) -> tuple[list[PassSpec], list[Culled]]:
    """The passes of ``kept`` in ``alive``, and the others as culled ("reaches no output")."""
    final = []
    unreached = []
    for p in kept:
        if p.name in alive:
            final.append(p)
        else:
            unreached.append(_new_culled(p.name, "reaches no output"))
    return final, unreached


def _has_optional(passes: list[PassSpec]) -> bool:
    """Whether any access of ``passes`` is optional (compiled where built: ``NATIVE``; it scans
    every access of a graph without optional reads)."""
    if NATIVE is not None:
        return NATIVE.has_optional(passes)
    return _has_optional_python(passes)


def _has_optional_python(passes: list[PassSpec]) -> bool:
    for p in passes:
        for a in p.accesses:
            if a.optional:
                return True
    return False


def _alive_python(spec: Spec, kept: list[PassSpec]) -> set[str]:
    """``raw_ancestors(dependencies(kept), _roots(spec, kept))`` as one backwards walk:
    ``wanted`` holds the cells that live passes read and whose producer is not met yet,
    ``claimed`` the cells of kept resources that a later pass writes last. (Within a pass,
    a write's cells overlap no other access's: ``specialize`` checks it. So a live pass's
    writes and reads update ``wanted`` in one loop, a read-write access as a read.) A
    resource of one cell (every buffer) stands in both sets as its name, whose hash is
    cached (a cell tuple's is computed at each lookup); names and cells never compare equal."""
    keep = {n for n, r in spec.resources.items() if r.lifetime in ("persistent", "imported", "output")}
    keep.update(spec.outputs)
    single = {n for n, r in spec.resources.items() if r.kind != "image" or r.mips * r.layers == 1}
    wanted: set[Cell | str] = set()
    claimed: set[Cell | str] = set()
    alive: set[str] = set()
    rw = READ_WRITE_USAGES
    for p in reversed(kept):
        live = p.side_effects
        accesses = p.accesses
        for access in accesses:
            if access.write:
                name = access.resource
                if name in single:
                    if name in keep:
                        if not live and (name not in claimed or name in wanted):
                            live = True
                        claimed.add(name)
                    elif not live and name in wanted:
                        live = True
                    continue
                cs = access.cells
                if name in keep:
                    if not live and (not claimed.issuperset(cs) or not wanted.isdisjoint(cs)):
                        live = True
                    claimed.update(cs)
                elif not live and not wanted.isdisjoint(cs):
                    live = True
        if not live:
            continue
        alive.add(p.name)
        for access in accesses:
            name = access.resource
            if name in single:
                if access.write and access.usage not in rw:
                    wanted.discard(name)
                else:
                    wanted.add(name)
            elif access.write and access.usage not in rw:
                wanted.difference_update(access.cells)
            else:  # ``reads(access)``
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
    if not removed_reason:
        return _drop_optional_reads(spec)
    producer: dict[tuple[str, int, int], str | None] = {}
    lost: dict[tuple[str, int, int], str] = {}  # cell -> removed pass that would have written it
    kept: list[PassSpec] = []
    dropped: list[DroppedRead] = []
    cascade: list[Culled] = []
    persistent = {n for n, r in spec.resources.items() if r.lifetime in ("persistent", "imported")}
    get = producer.get
    for p in spec.passes:
        removed = p.name in removed_reason
        new_accesses = None  # the accesses kept once one is dropped
        cascade_reason = None
        for k, access in enumerate(p.accesses):
            # a plain read (not a read-write) of a transient needs its producer
            if removed or access.write or access.resource in persistent:
                if new_accesses is not None:
                    new_accesses.append(access)
                continue
            cells = access.cells
            if get(cells[0]) if len(cells) == 1 else all(get(c) for c in cells):
                if new_accesses is not None:
                    new_accesses.append(access)
                continue
            culprit = next((lost[c] for c in cells if c in lost), None) if lost else None
            if access.optional:
                why = "optional read with no producer"
                if culprit:
                    why += f" ('{culprit}' was removed: {removed_reason[culprit]})"
                dropped.append(DroppedRead(p.name, access.resource, why))
                if new_accesses is None:
                    new_accesses = list(p.accesses[:k])
                continue
            if culprit:
                cascade_reason = f"reads '{access.resource}', whose producer '{culprit}' was removed ({removed_reason[culprit]})"
            if new_accesses is not None:
                new_accesses.append(access)
        if cascade_reason and not removed:
            removed_reason[p.name] = cascade_reason
            cascade.append(Culled(p.name, cascade_reason))
            removed = True
        name = p.name
        for access in p.accesses:
            if access.write:
                if removed:
                    for c in access.cells:
                        lost[c] = name
                else:
                    for c in access.cells:
                        producer[c] = name
                    if lost:
                        for c in access.cells:
                            lost.pop(c, None)
        if not removed:
            kept.append(replace(p, accesses=tuple(new_accesses)) if new_accesses is not None else p)
    return kept, dropped, cascade


def _drop_optional_reads(spec: Spec) -> tuple[list[PassSpec], list[DroppedRead], list[Culled]]:
    """``_drop_unproduced_reads`` when the scene removed no pass: no producer is lost, so no
    pass is removed and only optional reads of cells nothing wrote are dropped. A pass's
    writes are noted as they come (they overlap none of its reads: ``specialize`` checks it).
    Without optional reads (one scan finds them) nothing is dropped: no walk."""
    if not _has_optional(spec.passes):
        return list(spec.passes), [], []
    produced: set[tuple[str, int, int]] = set()
    kept: list[PassSpec] = []
    dropped: list[DroppedRead] = []
    persistent = {n for n, r in spec.resources.items() if r.lifetime in ("persistent", "imported")}
    for p in spec.passes:
        new_accesses = None  # the accesses kept once one is dropped
        for k, access in enumerate(p.accesses):
            if access.write:
                produced.update(access.cells)
            elif access.optional and access.resource not in persistent and not produced.issuperset(access.cells):
                dropped.append(DroppedRead(p.name, access.resource, "optional read with no producer"))
                if new_accesses is None:
                    new_accesses = list(p.accesses[:k])
                continue
            if new_accesses is not None:
                new_accesses.append(access)
        kept.append(replace(p, accesses=tuple(new_accesses)) if new_accesses is not None else p)
    return kept, dropped, []
