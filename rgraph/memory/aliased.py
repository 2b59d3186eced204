"""Offline placement of one memory class into one heap.

1. Greedy best fit under several orderings (size, area, lifetime, start, contention), keep
   the lowest peak: fast and already within a few percent on typical render graphs.
2. If the peak is above the lower bound: elastic dives (``rgraph.memory.elastic``:
   MiniMalloc's search from the bound, raising the capacity where it would backtrack,
   squeaky-wheel chains over three preorders) until the bound, the budget, or they stall.
3. With what the dives left, MiniMalloc's solver (``rgraph.memory.search``) decides
   capacities by bisection between the bound (tried first) and the best peak found, each
   with MiniMalloc's round robin over its three preorderings; when the bisection closes it
   starts again with one more (doubled) round. Any placement it finds replaces the best
   one; it stops at the bound or when a capacity just below the peak is proven infeasible.
   ``optimal`` runs the dives first, then MiniMalloc's own run at the bound, then this.

The time budget is turned into an operation count (``OPS_PER_SECOND``) so that results are
the same on every machine; the real time taken varies with the machine.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rgraph.memory.bounds import clique_bound
from rgraph.memory.elastic import improve
from rgraph.memory.greedy import best_fit, orderings
from rgraph.memory.instance import Instance
from rgraph.memory.model import Block
from rgraph.memory.search import PREORDERINGS, preorder, solve_capacity

#: Search operations (blocks scanned per node, neighbours and sections per placement:
#: ``CapacitySearch.ops``) granted per second of budget, about what this 2-core machine does
#: (search 2.3-6 M/s measured on the MiniMalloc traces; the elastic dives' operations have
#: their own rate, ``DIVE_OPS_PER_SECOND``).
#: The budget is counted in operations, so results are the same on every machine; the real
#: time taken varies with the machine.
OPS_PER_SECOND = 4_000_000

#: Elastic dive operations (``rgraph.memory.elastic.STEP_OPS``) granted per second of the
#: budget the dives take (session 13): what the compiled dive (``rgraph/memory/_dive.pyx``)
#: does on the MiniMalloc traces, fitted to the minimum CPU times of whole ``improve`` runs
#: on the 2-core development machine (124 and 166 M a second in two runs) and rounded down.
#: The same count with or without the compiled dive, so plans do not depend on it; the
#: pure-Python dives (4-8 M a second) take 15-30 times longer than charged.
DIVE_OPS_PER_SECOND = 120_000_000


def dive_ops(ops: int) -> int:
    """The elastic dive operations that ``ops`` search operations of budget buy."""
    return ops * DIVE_OPS_PER_SECOND // OPS_PER_SECOND


def search_ops(dive: int) -> int:
    """The search operations of budget that ``dive`` elastic dive operations use (rounded up)."""
    return -(-dive * OPS_PER_SECOND // DIVE_OPS_PER_SECOND)

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
    return too_dense_pairs(overlapping_pairs(blocks), time_budget_s)


def too_dense_pairs(pairs: int, time_budget_s: float) -> bool:
    """``too_dense`` of blocks with ``pairs`` overlapping pairs (``overlapping_pairs``)."""
    return pairs > max(MIN_GREEDY_PAIRS, time_budget_s * PAIRS_PER_SECOND)


#: Bisection closes when the best peak is within this fraction of the highest capacity
#: given up on; it then starts again from the highest one proven infeasible with one more
#: round-robin round per capacity (MiniMalloc's doubling node limit).
CLOSE = 1 / 1000


@dataclass
class ClassResult:
    offsets: list[int]
    peak: int
    lower_bound: int
    how: str  # which method produced the offsets
    proven: bool = False  # no placement under ``peak`` exists (the bound, or proven by search)


def place_class(inst: Instance, time_budget_s: float, exact: bool = False) -> ClassResult:
    """Greedy, then (above the bound) elastic dives and the search within
    ``time_budget_s``. ``exact`` (the ``optimal`` policy): after a first share of elastic
    dives, most of the budget goes to MiniMalloc's own run at the bound (round robin with no
    round limit), the rest to more dives and the bisection."""
    lb = inst.lower_bound()
    bound, cliqued = lb, inst.separable  # non-separable: the clique bound once greedy misses lb
    best: ClassResult | None = None
    tried: list[list[int]] = []
    for name, order in orderings(inst):
        if order in tried:
            continue  # the same placement again (orderings often coincide on small classes)
        tried.append(order)
        offsets = best_fit(inst, order, None if best is None else best.peak)  # None: not lower
        if offsets is None:
            continue
        peak = inst.peak(offsets)
        if best is None or peak < best.peak:
            best = ClassResult(offsets, peak, lb, f"greedy:{name}")
        if best.peak > bound and not cliqued:
            bound, cliqued = clique_bound(inst), True
        if best.peak <= bound:
            break  # proven optimal: no later ordering can be strictly better
    assert best is not None
    if best.peak <= bound:
        best.proven = True
        return best
    if inst.n == 0 or not inst.separable:
        # Conflicts beyond time overlaps (cross-queue pairs) leave the time bound out of
        # reach: the search could only burn its budget proving nothing, so greedy it is.
        return best
    budget = int(time_budget_s * OPS_PER_SECOND)
    if dive_ops(budget) < inst.n * inst.n // 2 + inst.pair_count:
        return best  # not even one dive (each step scans the blocks left) would finish
    search = _Bisection(inst, best)
    if exact:
        first = min(budget // EXACT_ELASTIC_SHARE, int(EXACT_ELASTIC_S * OPS_PER_SECOND))
        left = search.elastic(first) + budget - first
        at_bound = int(budget * EXACT_BOUND_SHARE)
        left = search.attempt(lb, None, min(at_bound, left)) + max(left - at_bound, 0)
        search.run(search.elastic(left // 2) + left - left // 2)
    else:
        search.run(search.elastic(budget))
    return search.best


#: The order of the elastic dives' squeaky-wheel chains (the first preorders dived first).
ELASTIC_ORDERS = ("TAW", "TWA", "WAT")


#: Where the bisection tries next, as a fraction of the way from the best peak down to the
#: highest capacity given up on: short steps succeed far more often than halving.
STEP = 0.25

#: The first round's node limit per heuristic, in blocks (MiniMalloc: 2).
FIRST_LIMIT = 2.0

#: ``optimal``: one part in this many of the budget, at most ``EXACT_ELASTIC_S``, goes
#: to elastic dives first (a good placement early; often the bound itself), then up to
#: ``EXACT_BOUND_SHARE`` of it to MiniMalloc's run at the bound, the rest half to more
#: dives, half to the bisection (where the bound is out of reach, as on MiniMalloc D and J).
EXACT_ELASTIC_SHARE = 5
EXACT_ELASTIC_S = 0.5
EXACT_BOUND_SHARE = 0.85


class _Bisection:
    """Capacities by bisection between the highest one given up on (``low``) and the best
    peak, each tried with MiniMalloc's round robin for ``rounds`` rounds; once the
    bisection closes, ``rounds`` grows by one and it starts again from the highest capacity
    proven infeasible, the bound first. A placement found lowers the peak to its height
    (often well below the capacity tried)."""

    def __init__(self, inst: Instance, best: ClassResult):
        self.inst, self.best, self.lb = inst, best, best.lower_bound
        self.orders = [preorder(inst, h) for h in PREORDERINGS]
        self.low = self.infeasible = self.lb - 1  # infeasible: the highest proven too small
        self.rounds = 1

    def elastic(self, budget: int) -> int:
        """Elastic dives (``rgraph.memory.elastic.improve``) for up to ``budget`` operations;
        returns what is left."""
        if self.best.proven or budget <= 0:
            return max(budget, 0)
        orders = {h: o for h, o in zip(PREORDERINGS, self.orders, strict=True)}
        found = improve(self.inst, [orders.get(h) or preorder(self.inst, h) for h in ELASTIC_ORDERS],
                        self.best.peak, dive_ops(budget))
        if found.offsets is not None:
            self.best = ClassResult(found.offsets, found.peak, self.lb, f"elastic:{found.dives}")
            if found.peak <= self.lb:
                self.best.proven = True
        return budget - search_ops(found.ops)

    def attempt(self, capacity: int, rounds: int | None, budget: int) -> int:
        """Try one capacity; returns the budget left."""
        if self.best.proven or budget <= 0:
            return budget
        found, spent, proven = solve_capacity(self.inst, capacity, budget, rounds, self.orders, first_limit=FIRST_LIMIT)
        if found is not None:
            peak = self.inst.peak(found)
            if peak < self.best.peak:
                self.best = ClassResult(found, peak, self.lb, f"search:{capacity}")
        elif proven or spent < budget:  # cut short by the budget: not given up, tried again later
            self.low = max(self.low, capacity)
            if proven:
                self.infeasible = max(self.infeasible, capacity)
        if self.best.peak - 1 <= self.infeasible:
            self.best.proven = True
        return budget - spent

    def run(self, budget: int) -> int:
        """Bisect until proven or ``budget`` operations are spent; returns what is left."""
        while budget > 0 and not self.best.proven:
            peak = self.best.peak
            if peak - self.low <= max(int(peak * CLOSE), 1):
                self.low, self.rounds = self.infeasible, self.rounds + 1
                capacity = self.infeasible + 1
            else:
                capacity = peak - max(int((peak - self.low - 1) * STEP), 1)
            budget = self.attempt(capacity, self.rounds, budget)
        return max(budget, 0)
