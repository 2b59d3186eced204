"""Offline placement of one memory class into one heap.

1. Greedy best fit under several orderings (size, area, lifetime, start, contention), keep
   the lowest peak: fast and already within a few percent on typical render graphs.
2. If the peak is above the lower bound, the MiniMalloc-style exact search
   (``rgraph.memory.search``) looks for a placement under a series of capacities, from the
   lower bound up, with a node budget derived from the time budget. Any placement it finds
   replaces the greedy one.

The time budget is turned into a node count (``NODES_PER_SECOND``) so that results are
the same on every machine; the real time taken varies with the machine.
"""

from __future__ import annotations

from dataclasses import dataclass

from rgraph.memory.greedy import best_fit, orderings
from rgraph.memory.instance import Instance
from rgraph.memory.search import PREORDERINGS, CapacitySearch, preorder

#: Search nodes granted per second of budget (about what a 2-core laptop visits on a
#: 200-block instance); node cost grows with sections x blocks, which scales it down.
NODES_PER_SECOND = 20000


@dataclass
class ClassResult:
    offsets: list[int]
    peak: int
    lower_bound: int
    how: str  # which method produced the offsets


def place_class(inst: Instance, time_budget_s: float) -> ClassResult:
    lb = inst.lower_bound()
    best: ClassResult | None = None
    for name, order in orderings(inst).items():
        offsets = best_fit(inst, order)
        peak = inst.peak(offsets)
        if best is None or peak < best.peak:
            best = ClassResult(offsets, peak, lb, f"greedy:{name}")
    assert best is not None
    if best.peak <= lb or inst.n == 0:
        return best
    budget = node_budget_for(inst, time_budget_s)
    if budget < 2 * inst.n:
        return best  # too little to finish even one dive of the search
    orders = [preorder(inst, h) for h in PREORDERINGS]
    # First the lower bound itself (often reachable), then bisection between the highest
    # capacity that failed and the best peak found, each try with a share of what is left.
    low, tries = lb, 0
    while budget > 0 and best.peak - low > max(best.peak // 1000, 1):
        capacity = lb if tries == 0 else (low + best.peak) // 2
        share = budget // 3 if tries == 0 else max(budget // 2, 1)
        found, spent = search_capacity(inst, orders, capacity, share)
        budget -= spent
        tries += 1
        if found is None:
            low = capacity
            continue
        peak = inst.peak(found)
        if peak < best.peak:
            best = ClassResult(found, peak, lb, f"search:{capacity}")
    return best


def node_budget_for(inst: Instance, time_budget_s: float) -> int:
    work_per_node = max(1.0, inst.section_count * inst.n / 40_000)
    return int(time_budget_s * NODES_PER_SECOND / work_per_node)


def search_capacity(
    inst: Instance, orders: list[list[int]], capacity: int, node_budget: int
) -> tuple[list[int] | None, int]:
    """Round robin over the preorderings with doubling node limits (as MiniMalloc does),
    until a placement within ``capacity`` is found, one is proven impossible, or the node
    budget is spent. Returns the offsets (or None) and the nodes spent."""
    limit = 2 * max(inst.n, 1)
    remaining = node_budget
    while remaining > 0:
        for order in orders:
            run = CapacitySearch(inst, order, capacity, min(limit, remaining))
            found = run.run()
            remaining -= max(run.work, 1)
            if found is not None or not run.exhausted or remaining <= 0:
                # found, or proven that nothing fits under this capacity, or out of nodes
                return found, node_budget - remaining
        limit *= 2
    return None, node_budget - remaining
