"""What the sync simulation walks: each access's sync2 scope, each pass's cells, each cell's timeline.

One walk over the executed passes gives every access its ``Sync`` (``usages.sync_of``, read
groups moved to GENERAL by ``read_layouts``) and every cell the ordered list of its uses
(``Use``: accesses of one pass to one cell merged into one).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import lru_cache

from rgraph.compiler.read_layouts import ReadGroups
from rgraph.compiler.usages import Sync, merge, sync_of
from rgraph.ir.graph import Cell
from rgraph.spec.specialize import PassSpec, ResourceSpec

#: One pass's use of a cell: (executed pass index, merged sync, written, queue, position of the
#: cell in the pass's cell list); a plain tuple (one per cell per pass: a named tuple costs twice
#: as much to build).
Use = tuple[int, Sync, bool, str, int]


@dataclass
class SyncInputs:
    syncs: list[list[Sync]]  # per pass, per declared access
    timeline: dict[Cell, list[Use]]  # first touch order
    touched: dict[str, int]  # cells per resource
    first_pass: dict[str, int]  # first executed pass of each resource


@lru_cache(maxsize=4096)
def _sync(usage: str, kind: str, stages: tuple[str, ...] | None, image: bool, depth: bool, stencil: bool,
          refit: bool) -> Sync:
    """``sync_of`` by position (a positional cache key is cheaper to build than keywords)."""
    return sync_of(usage, kind, explicit_stages=stages, is_image=image, depth_format=depth, stencil_format=stencil,
                   refit=refit)


def format_flags(resources: Mapping[str, ResourceSpec]) -> dict[str, tuple[bool, bool, bool]]:
    """Per resource: (image, depth format, stencil format), the format part of ``sync_of``'s key."""
    out = {}
    for name, res in resources.items():
        fmt = res.format
        out[name] = (res.is_image, bool(fmt and fmt.has_depth), bool(fmt and fmt.has_stencil))
    return out


def sync_inputs(passes: Sequence[PassSpec], resources: Mapping[str, ResourceSpec]) -> SyncInputs:
    """Scopes and timelines in one walk; the reads ``read_layouts`` moves to GENERAL are
    patched in afterwards (a few per graph)."""
    flags = format_flags(resources)
    groups = ReadGroups(resources)
    candidates = groups.candidates
    syncs: list[list[Sync]] = []
    timeline: dict[Cell, list[Use]] = {}
    touched: dict[str, int] = {}
    first_pass: dict[str, int] = {}
    for i, p in enumerate(passes):
        queue, kind = p.queue, p.kind
        accesses = p.accesses
        row: list[Sync] = []
        index: dict[Cell, tuple[int, Sync, bool]] | None = {} if len(accesses) > 1 else None  # this pass's cells
        pos = 0
        for j, a in enumerate(accesses):
            name = a.resource
            s = _sync(a.usage, kind, a.stages, *flags[name], a.refit)
            row.append(s)
            if name in candidates:
                groups.note(i, j, a)
            w = a.write
            for c in a.cells:
                if index is not None:
                    prev = index.get(c)
                    if prev is not None:  # a second access to the cell in this pass: one merged use
                        k, ps, pw = prev
                        s2, w2 = merge(ps, s), pw or w
                        index[c] = (k, s2, w2)
                        timeline[c][-1] = (i, s2, w2, queue, k)
                        continue
                    index[c] = (pos, s, w)
                uses = timeline.get(c)
                if uses is None:
                    timeline[c] = [(i, s, w, queue, pos)]
                    if name in touched:
                        touched[name] += 1
                    else:
                        touched[name] = 1
                        first_pass[name] = i
                else:
                    uses.append((i, s, w, queue, pos))
                pos += 1
        syncs.append(row)
    moved = groups.to_general(syncs)
    for i, j in moved:
        syncs[i][j] = replace(syncs[i][j], layout="GENERAL")
    for i, j in moved:
        _repatch(passes[i], i, passes[i].accesses[j].cells, syncs[i], timeline)
    return SyncInputs(syncs, timeline, touched, first_pass)


def _repatch(p: PassSpec, i: int, cells: Sequence[Cell], row: Sequence[Sync], timeline: dict[Cell, list[Use]]) -> None:
    """Pass ``i``'s use of ``cells`` with its accesses' (changed) syncs merged again."""
    for c in cells:
        merged = None
        for a, s in zip(p.accesses, row, strict=True):
            if c in a.cells:
                merged = s if merged is None else merge(merged, s)
        uses = timeline[c]
        for k in range(len(uses) - 1, -1, -1):
            if uses[k][0] == i:
                _, _, w, queue, pos = uses[k]
                uses[k] = (i, merged, w, queue, pos)
                break
