"""Where aliased transients start: the last accesses of the resources whose memory they reuse.

``with_partial_handoffs`` widens the planner's alias sources through partial hand-offs;
``AliasStarts`` sets each aliased resource's cells, when its first pass comes, from its
predecessors' cells in the one simulation of the frame (``rgraph.compiler.sync``).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Mapping, Sequence
from typing import Any

from rgraph.compiler.sync_types import State
from rgraph.ir.graph import Cell
from rgraph.spec.specialize import ResourceSpec

PREVIOUS_FRAME = -1


class AliasStarts:
    """Transient cells whose memory an earlier resource used start from that resource's last
    accesses (``alias_state``). Every earlier occupant ends before the resource's first
    pass, so its cells already hold their end-of-frame state when that pass comes: the
    states are taken then, from the one simulation of the frame. (A transient's end state
    does not depend on where it started: its first access to each cell writes it or reads
    it, and either replaces what ``state()`` reports.)"""

    def __init__(self, alias_sources: Mapping[str, Sequence[str]], start: dict[Cell, Any],
                 first_pass: Mapping[str, int], initial: dict[Cell, State]) -> None:
        self.cells_of: dict[str, list[tuple[Cell, Any]]] = {}
        self.at: dict[int, list[str]] = defaultdict(list)  # pass -> resources that start there
        for name, preds in alias_sources.items():
            if preds and name in first_pass:
                self.at[first_pass[name]].append(name)
        if self.at:
            for c, st in start.items():
                self.cells_of.setdefault(c[0], []).append((c, st))
        self.sources = alias_sources
        self.initial = initial

    def apply(self, i: int) -> None:
        """Start the aliased resources whose first pass is ``i``."""
        for name in self.at.get(i, ()):
            stages, access, queue, last, names, waits = alias_state(
                self.sources[name], [st for pred in self.sources[name] for _, st in self.cells_of.get(pred, ())], i)
            for c, cell in self.cells_of[name]:
                cell.write = (PREVIOUS_FRAME, stages, access) if stages or access else None
                cell.queue = queue
                cell.last_pass = last
                cell.aliases = names
                cell.alias_waits = waits
                self.initial[c] = cell.state()


def with_partial_handoffs(
    alias_sources: Mapping[str, Sequence[str]], touched: Mapping[str, int], resources: Mapping[str, ResourceSpec],
    ranges: Mapping[str, tuple[int, int, int]] | None = None,
) -> dict[str, list[str]]:
    """``alias_sources`` plus, through every predecessor that touches only some of its
    subresources (``touched``: cells per resource), that predecessor's own predecessors
    (recursively).

    The memory planner leaves out an older occupant whose bytes a later one fully covers,
    counting on the later one's hand-off. But a resource hands over only the cells it
    touches: the bytes of its untouched subresources still hold the older occupant's last
    accesses, so the next resource must wait for those itself (random graph seed 32, 10
    passes, aliased: img2 used on one layer of two left img4's colour writes unordered
    before img3's first transition)."""

    def partial(name: str) -> bool:
        res = resources[name]
        return res.is_image and touched.get(name, 0) < res.mips * res.layers

    out: dict[str, list[str]] = {}
    for name, preds in alias_sources.items():
        found: list[str] = []
        stack = list(preds)
        while stack:
            pred = stack.pop(0)
            if pred in found:
                continue
            if ranges is not None and not _share_bytes(ranges, name, pred):
                continue
            found.append(pred)
            if partial(pred):
                stack.extend(alias_sources.get(pred, ()))
        out[name] = found
    return out


def _share_bytes(ranges: Mapping[str, tuple[int, int, int]], a: str, b: str) -> bool:
    (ha, lo_a, hi_a), (hb, lo_b, hi_b) = ranges[a], ranges[b]
    return ha == hb and lo_a < hi_b and lo_b < hi_a


def alias_state(preds: Sequence[str], pred_cells: Sequence[Any], at: int):
    """Union of the last accesses of an aliased resource's predecessors (their cells, each
    last used before pass ``at``)."""
    stages: set[str] = set()
    access: set[str] = set()
    last: tuple[int, str | None] = (-1, None)
    waits: set[tuple[str, int]] = set()
    for st in pred_cells:
        assert st.last_pass is None or st.last_pass < at, "an earlier occupant outlives its successor's start"
        s = st.state()
        stages |= s.stages
        access |= s.access
        if st.last_pass is not None and st.last_pass > last[0]:
            last = (st.last_pass, st.queue)
        if st.last_pass is not None and st.queue is not None:
            waits.add((st.queue, st.last_pass))
    return (
        frozenset(stages), frozenset(access), last[1], last[0] if last[0] >= 0 else None, tuple(sorted(preds)),
        tuple(sorted(waits)),
    )
