"""Transient memory placement: lifetimes in, heaps and offsets out.

``place(blocks, policy)`` is what the compiler calls; see ``docs/memory.md`` for the
policies. Pure Python and numpy (no Vulkan): sizes and alignments come in with the blocks.
"""

from __future__ import annotations

import time
from collections.abc import Collection, Mapping, Sequence

from rgraph.memory.aliased import (
    MIN_GREEDY_PAIRS,
    OPS_PER_SECOND,
    PAIRS_PER_SECOND,
    dive_ops,
    overlapping_pairs,
    place_class,
    too_dense_pairs,
)
from rgraph.memory.bounds import class_lower_bound
from rgraph.memory.instance import SWEEP_FROM, Instance
from rgraph.memory.model import Block, Heap, Placement, PlacementStats, by_class, check_blocks
from rgraph.memory.online import place_blocks, place_tlsf
from rgraph.memory.policy import Policy, parse_policy
from rgraph.native import load

#: ``rgraph/memory/_fit.pyx`` (its ``class_groups``: the checks, the classes and their
#: overlapping pairs in one pass; ``Columns``: blocks as arrays, each class's greedy on them),
#: None where not built or ``RGRAPH_NATIVE=0``.
_NATIVE = load("rgraph.memory._fit")

__all__ = ["Block", "Heap", "Placement", "PlacementStats", "Policy", "parse_policy", "parse_place_args", "place"]

#: Budget of the ``optimal`` policy when the caller leaves the default: MiniMalloc's own
#: solver takes 0.6-5 s on the challenging traces on the 2-core machine (docs/memory.md).
OPTIMAL_BUDGET_S = 10.0
#: The compiler's budget per memory class: it runs on every compile, so 1,000 resources
#: must place in well under 100 ms (a graph's greedy placement is usually at the bound and
#: the search never starts).
DEFAULT_BUDGET_S = 0.05
#: ``rgraph place``'s default for ``aliased``: an offline tool for lifetime traces, where a
#: second buys the search enough dives on the hard MiniMalloc instances (benchmarks/placement.py).
TRACE_BUDGET_S = 1.0
#: The largest budget a user may ask for (``--budget inf`` would never end).
MAX_BUDGET_S = 3600.0


def parse_place_args(policy: str, budget: float | None, source: str = "<command line>") -> tuple[Policy, float | None]:
    """Validate a policy name and budget given by a user; bad ones raise RGraphError."""
    from rgraph.errors import RGraphError

    try:
        chosen = parse_policy(policy)
    except ValueError as exc:
        raise RGraphError.in_file(source, str(exc)) from None
    if budget is not None and not 0 < budget <= MAX_BUDGET_S:
        raise RGraphError.in_file("<command line>", f"--budget must be in (0, {MAX_BUDGET_S:g}] seconds, got {budget}")
    return chosen, budget


def class_groups(blocks: Sequence[Block]) -> dict[str, tuple[list[Block], int, int, int]]:
    """Check ``blocks`` (``check_blocks``: ValueError for blocks no policy can place), then
    per memory class (sorted): its blocks in input order, their highest alignment, their
    ordered pairs overlapping in time (``aliased.overlapping_pairs``) and their aligned
    bytes. Compiled where built (``_fit.class_groups``), else :func:`class_groups_python`."""
    if _NATIVE is not None and isinstance(blocks, list):
        found = _NATIVE.class_groups(blocks)
        if found is not None:
            return found  # type: ignore[no-any-return]
    return class_groups_python(blocks)


def class_groups_python(blocks: Sequence[Block]) -> dict[str, tuple[list[Block], int, int, int]]:
    check_blocks(blocks)
    return {cls: (group, max(b.alignment for b in group), overlapping_pairs(group),
                  sum(b.aligned_size for b in group))
            for cls, group in by_class(blocks).items()}


def place(
    blocks: Sequence[Block], policy: str | Policy = "aliased", *, time_budget_s: float = DEFAULT_BUDGET_S,
    conflicts: Mapping[str, Collection[str]] | None = None,
) -> Placement:
    """Place ``blocks`` under ``policy``. Heap ids go by memory class (sorted), then by
    creation order within a class. Deterministic: the same input gives the same output.
    ``conflicts`` (``aliased`` and ``optimal``): pairs of names that may not share bytes
    although apart in time. ``blocks`` may be ``Columns`` (compiled: the same placement,
    each class's greedy run on its arrays, no ``Block`` made unless a class needs the search)."""
    began = time.perf_counter()
    chosen = parse_policy(policy)
    columns = blocks if _NATIVE is not None and type(blocks) is _NATIVE.Columns else None
    if columns is not None and not (columns.valid and chosen.kind in ("aliased", "optimal")):
        blocks, columns = columns.blocks(), None
    grouped = class_groups(blocks) if columns is None else None
    if chosen.kind == "optimal" and time_budget_s == DEFAULT_BUDGET_S:
        time_budget_s = OPTIMAL_BUDGET_S
    offsets: dict[str, tuple[int, int]] = {}
    heaps: list[Heap] = []
    bound = 0  # the time bound summed over classes
    unaliased = 0

    def new_heap(size: int, memory_class: str, alignment: int) -> int:
        heaps.append(Heap(len(heaps), size, memory_class, alignment))
        return len(heaps) - 1

    def place_group(memory_class: str, group: list[Block], max_align: int, pairs: int, group_bytes: int) -> None:
        nonlocal bound, unaliased
        unaliased += group_bytes
        searched = chosen.kind in ("aliased", "optimal") and not too_dense_pairs(pairs, time_budget_s)
        if not searched:  # place_class gives it otherwise
            bound += class_lower_bound(group)
        if chosen.kind == "dedicated":
            for b in group:
                offsets[b.name] = (new_heap(b.aligned_size, memory_class, b.alignment), 0)
        elif chosen.kind in ("aliased", "optimal") and not searched:
            tlsf_offsets, high_water = place_tlsf(group)  # bounded time on very dense lifetimes
            heap_id = new_heap(high_water, memory_class, max_align)
            for b, offset in zip(group, tlsf_offsets, strict=True):
                offsets[b.name] = (heap_id, offset)
        elif searched:
            result = place_class(Instance.build(group, conflicts), time_budget_s, exact=chosen.kind == "optimal")
            bound += result.lower_bound
            heap_id = new_heap(result.peak, memory_class, max_align)
            for b, offset in zip(group, result.offsets, strict=True):
                offsets[b.name] = (heap_id, offset)
        elif chosen.kind == "tlsf":
            tlsf_offsets, high_water = place_tlsf(group)
            heap_id = new_heap(high_water, memory_class, max_align)
            for b, offset in zip(group, tlsf_offsets, strict=True):
                offsets[b.name] = (heap_id, offset)
        else:
            where, sizes = place_blocks(group, chosen.block_bytes)
            first = len(heaps)
            for k, size in enumerate(sizes):
                members = [b.alignment for b, (alloc, _) in zip(group, where, strict=True) if alloc == k]
                new_heap(size, memory_class, max(members, default=1))
            for b, (alloc, offset) in zip(group, where, strict=True):
                offsets[b.name] = (first + alloc, offset)

    if columns is None:
        assert grouped is not None
        for memory_class, found in grouped.items():
            place_group(memory_class, *found)
    else:
        dense = max(MIN_GREEDY_PAIRS, time_budget_s * PAIRS_PER_SECOND)  # too_dense_pairs's limit
        dives = dive_ops(int(time_budget_s * OPS_PER_SECOND))
        for k, memory_class in enumerate(columns.classes):
            done = columns.greedy(k, conflicts, dense, dives, SWEEP_FROM, len(heaps), offsets)
            if done is None:  # TLSF or the search: on the blocks
                place_group(memory_class, *class_groups_python(columns.group(k))[memory_class])
                continue
            max_align, group_bytes, time_bound, peak = done
            unaliased += group_bytes
            bound += time_bound
            new_heap(peak, memory_class, max_align)
    stats = PlacementStats(
        policy=str(chosen),
        peak_bytes=sum(h.bytes for h in heaps),
        lower_bound_bytes=bound,
        unaliased_bytes=unaliased,
        allocations=len(heaps),
        seconds=time.perf_counter() - began,
    )
    return Placement(offsets=offsets, heaps=heaps, stats=stats)
