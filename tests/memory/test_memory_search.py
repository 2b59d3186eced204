"""Capacity search, MiniMalloc's round robin and the search phase of ``aliased``."""

from __future__ import annotations

import random

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rgraph.memory import Block, place
from rgraph.memory.aliased import place_class
from rgraph.memory.instance import Instance
from rgraph.memory.search import PREORDERINGS, CapacitySearch, preorder, solve_capacity
from rgraph.memory.verify import overlaps

# Every pass has exactly 4 units live; the blocks must interlock to reach it.
INTERLOCKING = [
    Block("a", 0, 1, 2, 1, "c"), Block("b", 2, 3, 2, 1, "c"),
    Block("c", 0, 0, 2, 1, "c"), Block("d", 1, 2, 2, 1, "c"), Block("e", 3, 3, 2, 1, "c"),
]


def hard_trace(count: int, seed: int) -> list[Block]:
    """Random lifetimes with mixed sizes and alignments: greedy rarely reaches the bound."""
    rng = random.Random(seed)
    blocks = []
    for i in range(count):
        start = rng.randrange(60)
        end = start + rng.randrange(1, 25)
        align = rng.choice([1, 64, 256])
        blocks.append(Block(f"b{i}", start, end, rng.randrange(1, 5000), align, "c"))
    return blocks


def assert_valid(inst: Instance, offsets: list[int], capacity: int) -> None:
    for i in range(inst.n):
        assert offsets[i] >= 0 and offsets[i] % inst.align[i] == 0
        assert offsets[i] + inst.size[i] <= capacity
        for j in inst.neighbors[i]:
            disjoint = offsets[i] + inst.size[i] <= offsets[j] or offsets[j] + inst.size[j] <= offsets[i]
            assert disjoint or inst.size[i] == 0 or inst.size[j] == 0, (i, j)


def test_search_finds_the_interlocking_optimum():
    inst = Instance.build(INTERLOCKING)
    run = CapacitySearch(inst, preorder(inst, "TWA"), 4, 1000)
    found = run.run()
    assert found is not None
    assert_valid(inst, found, 4)


def test_search_proves_a_capacity_below_the_bound_infeasible():
    inst = Instance.build(INTERLOCKING)
    run = CapacitySearch(inst, preorder(inst, "WAT"), 3, 1000)
    assert run.run() is None and not run.exhausted


def test_search_reports_running_out_of_nodes():
    inst = Instance.build(hard_trace(60, 3))
    run = CapacitySearch(inst, preorder(inst, "WAT"), inst.lower_bound(), 5)
    assert run.run() is None and run.exhausted and run.work == 5


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), count=st.integers(1, 40), slack=st.floats(1.0, 1.5))
def test_search_placements_fit_their_capacity(seed, count, slack):
    inst = Instance.build(hard_trace(count, seed))
    capacity = int(inst.lower_bound() * slack)
    run = CapacitySearch(inst, preorder(inst, "TAW"), capacity, 20 * count)
    found = run.run()
    if found is not None:
        assert_valid(inst, found, capacity)


def test_preorders_are_permutations_sorted_by_their_keys():
    inst = Instance.build(hard_trace(50, 1))
    for h in PREORDERINGS:
        order = preorder(inst, h)
        assert sorted(order) == list(range(inst.n))
    widths = [inst.end[i] - inst.start[i] for i in preorder(inst, "WAT")]
    assert widths == sorted(widths, reverse=True)
    subset = [3, 1, 2]
    assert sorted(preorder(inst, "TWA", subset)) == sorted(subset)


def test_round_robin_proves_below_the_bound_and_finds_above_it():
    inst = Instance.build(hard_trace(40, 2))
    lb = inst.lower_bound()
    found, spent, proven = solve_capacity(inst, lb - 1, 10**9)
    assert found is None and proven and spent >= 1
    found, _, proven = solve_capacity(inst, 2 * lb, 10**9)
    assert found is not None and not proven
    assert_valid(inst, found, 2 * lb)


def test_round_robin_stops_at_its_budget():
    inst = Instance.build(hard_trace(120, 5))
    found, spent, proven = solve_capacity(inst, inst.lower_bound(), 500)
    assert found is None and not proven and spent <= 500 + 2 * inst.n


def test_search_phase_improves_on_greedy_and_stays_valid_and_deterministic():
    blocks = hard_trace(120, 5)
    inst = Instance.build(blocks)
    with_search = place_class(inst, 0.5)
    greedy_only = place_class(inst, 0.0)
    assert with_search.how.startswith(("search:", "elastic:")), with_search.how
    assert with_search.peak < greedy_only.peak
    assert_valid(inst, with_search.offsets, with_search.peak)
    again = place_class(Instance.build(list(blocks)), 0.5)
    assert again.offsets == with_search.offsets
    placement = place(blocks, "aliased", time_budget_s=0.5)
    assert overlaps(blocks, placement) == []
    assert placement.stats.peak_bytes == with_search.peak
