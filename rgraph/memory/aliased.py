"""Offline placement of one memory class into one heap.

1. Greedy best fit under several orderings (size, area, lifetime, start, contention), keep
   the lowest peak: fast and already within a few percent on typical render graphs.
2. If the peak is above the lower bound, the MiniMalloc-style search
   (``rgraph.memory.search``) looks for placements under tighter and tighter capacities
   (bisection between the lower bound and the best peak found), each capacity tried with a
   few short dives under different block preorderings (``restarts.py``). Any placement it
   finds replaces the greedy one.

The time budget is turned into a node count (``NODES_PER_SECOND``) so that results are
the same on every machine; the real time taken varies with the machine.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rgraph.memory.greedy import best_fit, orderings
from rgraph.memory.instance import Instance
from rgraph.memory.model import Block
from rgraph.memory.restarts import Preorders
from rgraph.memory.search import CapacitySearch

#: Search nodes granted per second of budget for a 100-block instance (about what a 2-core
#: laptop visits); a node costs about linearly in the block count, which scales it down.
NODES_PER_SECOND = 100000

#: Nodes per dive, in blocks: a little backtracking beyond one full dive.
DIVE_NODES = 2

#: Dives (each under another preordering) before a capacity is given up as too tight.
DIVES_PER_CAPACITY = 3

#: The greedy orderings cost about linearly in the pairs of blocks alive at the same time
#: (each block is fitted among its neighbours). Past this many (ordered) pairs per second of
#: budget, and past :data:`MIN_GREEDY_PAIRS` whatever the budget, the class is placed online
#: (TLSF in time order, n log n) instead: 10,000 blocks alive at once are 10**8 pairs, 450 are 200,000.
PAIRS_PER_SECOND = 300_000
MIN_GREEDY_PAIRS = 200_000


def overlapping_pairs(blocks: Sequence[Block]) -> int:
    """Ordered pairs (i, j), i != j, of blocks whose lifetimes overlap: n log n, no pair lists."""
    if not blocks:
        return 0
    starts = np.fromiter((b.start for b in blocks), dtype=np.int64, count=len(blocks))
    ends = np.fromiter((b.end for b in blocks), dtype=np.int64, count=len(blocks))
    # j overlaps i iff start_j <= end_i and end_j >= start_i (no j ends before it starts)
    began = np.searchsorted(np.sort(starts), ends, side="right")
    ended = np.searchsorted(np.sort(ends), starts, side="left")
    return int(began.sum() - ended.sum()) - len(blocks)


def too_dense(blocks: Sequence[Block], time_budget_s: float) -> bool:
    """Whether the offline greedy would overrun ``time_budget_s`` on ``blocks``."""
    return overlapping_pairs(blocks) > max(MIN_GREEDY_PAIRS, time_budget_s * PAIRS_PER_SECOND)


#: Budget, in dives, from which the bound itself is tried first (about half of it then
#: remains for the bisection).
LB_FIRST_DIVES = 6


@dataclass
class ClassResult:
    offsets: list[int]
    peak: int
    lower_bound: int
    how: str  # which method produced the offsets


def place_class(inst: Instance, time_budget_s: float) -> ClassResult:
    lb = inst.lower_bound()
    best: ClassResult | None = None
    for name, order in orderings(inst):
        offsets = best_fit(inst, order, None if best is None else best.peak)  # None: not lower
        if offsets is None:
            continue
        peak = inst.peak(offsets)
        if best is None or peak < best.peak:
            best = ClassResult(offsets, peak, lb, f"greedy:{name}")
        if best.peak <= lb:
            break  # proven optimal: no later ordering can be strictly better
    assert best is not None
    if best.peak <= lb or inst.n == 0 or not inst.separable:
        # Conflicts beyond time overlaps (cross-queue pairs) leave the time bound out of
        # reach: the search could only burn its budget proving nothing, so greedy it is.
        return best
    budget = node_budget_for(inst, time_budget_s)
    if budget < inst.n:
        return best  # too little to finish even one dive of the search
    preorders = Preorders(inst)
    # The bound first when the budget affords it: tight capacities prune hardest and, once
    # a block splits the rest in time, the search solves the parts one by one, so the bound
    # is often reached in a few dives (MiniMalloc C and F in under 6,000 nodes).
    proven = False
    if budget >= LB_FIRST_DIVES * DIVE_NODES * inst.n:
        found, spent, proven = search_capacity(inst, preorders, lb, budget, DIVES_PER_CAPACITY)
        budget -= spent
        if found is not None:
            return ClassResult(found, inst.peak(found), lb, f"search:{lb}")
    # Bisection between the highest capacity given up on and the best peak found; once it
    # closes, start again from the lower bound with twice the dives per capacity.
    low, dives, infeasible = lb, DIVES_PER_CAPACITY, lb if proven else lb - 1  # infeasible: proven too small
    while budget >= inst.n:
        if best.peak - low <= max(best.peak // 1000, 1):
            if best.peak - infeasible <= max(best.peak // 1000, 1):
                break
            low, dives = max(lb, infeasible), 2 * dives
        capacity = (low + best.peak) // 2
        found, spent, proven = search_capacity(inst, preorders, capacity, budget, dives)
        budget -= spent
        if found is None:
            low = capacity
            if proven:
                infeasible = max(infeasible, capacity)
            continue
        peak = inst.peak(found)
        if peak < best.peak:
            best = ClassResult(found, peak, lb, f"search:{capacity}")
    return best


def node_budget_for(inst: Instance, time_budget_s: float) -> int:
    work_per_node = max(1.0, inst.n / 100)
    return int(time_budget_s * NODES_PER_SECOND / work_per_node)


def search_capacity(
    inst: Instance, preorders: Preorders, capacity: int, node_budget: int, dives: int
) -> tuple[list[int] | None, int, bool]:
    """Up to ``dives`` dives of ``DIVE_NODES * n`` nodes, each under the next
    preordering, until a placement within ``capacity`` is found or one dive proves that
    none exists. Returns the offsets (or None), the nodes spent and whether it is proven."""
    limit = int(DIVE_NODES * max(inst.n, 1))
    spent = 0
    for _ in range(dives):
        if node_budget - spent <= 0:
            break
        run = CapacitySearch(inst, preorders.next(), capacity, min(limit, node_budget - spent))
        found = run.run()
        spent += max(run.work, 1)
        if found is not None:
            return found, spent, False
        if not run.exhausted:
            return None, spent, True
    return None, spent, False
