"""Where aliased transients start: the last accesses of the resources whose memory they reuse.

``with_partial_handoffs`` widens the planner's alias sources through partial hand-offs;
``alias_state`` is the start of an aliased resource's cells, from the end states of its
predecessors' cells. Every earlier occupant ends before the resource's first pass, so those
are their end-of-frame states (``rgraph.compiler.sync`` walks them first). A transient's end
state does not depend on where it started: its first access to each cell writes it or reads
it, and either replaces what its state reports.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from rgraph.compiler.sync_types import StateKey
from rgraph.spec.specialize import ResourceSpec


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


def alias_state(preds: Sequence[str], ends: Sequence[tuple[StateKey, int | None]], at: int):
    """Union of the last accesses of an aliased resource's predecessors (``ends``: the end state
    and last pass of each of their cells, each last used before pass ``at``): (stages, write
    access, queue and pass of the latest, sorted names, sorted (queue, last pass) pairs)."""
    stages: set[str] = set()
    access: set[str] = set()
    last: tuple[int, str | None] = (-1, None)
    waits: set[tuple[str, int]] = set()
    for (s_stages, s_access, _, s_queue), last_pass in ends:
        assert last_pass is None or last_pass < at, "an earlier occupant outlives its successor's start"
        stages |= s_stages
        access |= s_access
        if last_pass is not None and last_pass > last[0]:
            last = (last_pass, s_queue)
        if last_pass is not None and s_queue is not None:
            waits.add((s_queue, last_pass))
    return (
        frozenset(stages), frozenset(access), last[1], last[0] if last[0] >= 0 else None, tuple(sorted(preds)),
        tuple(sorted(waits)),
    )
