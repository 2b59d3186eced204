"""MiniMalloc's solver (``rgraph.memory.search``) against brute force on small instances:
it finds a placement exactly when one exists, and ``optimal`` reaches the true optimum."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_memory_search import assert_valid

from rgraph.memory import Block, place
from rgraph.memory.aliased import place_class
from rgraph.memory.instance import Instance
from rgraph.memory.search import PREORDERINGS, CapacitySearch, preorder, solve_capacity
from rgraph.memory.verify import overlaps


def brute_force_fits(inst: Instance, capacity: int) -> bool:
    """Whether every block fits under ``capacity``: backtracking over every aligned offset
    of every block (no canonical form, no inference)."""
    offsets = [-1] * inst.n

    def place_from(k: int) -> bool:
        if k == inst.n:
            return True
        z, a = inst.size[k], inst.align[k]
        for off in range(0, capacity - z + 1, a):
            if all(offsets[j] < 0 or inst.size[j] == 0 or z == 0
                   or off + z <= offsets[j] or offsets[j] + inst.size[j] <= off
                   for j in inst.neighbors[k]):
                offsets[k] = off
                if place_from(k + 1):
                    return True
                offsets[k] = -1
        return False

    return place_from(0)


def brute_force_optimum(inst: Instance) -> int:
    capacity = inst.lower_bound()
    while not brute_force_fits(inst, capacity):
        capacity += 1
    return capacity


@st.composite
def block_lists(draw, count: int, last_start: int, longest: int, sizes: int, alignments: list[int], classes: str):
    """1..count blocks starting at 0..last_start, lasting 0..longest passes, 0..sizes bytes."""
    blocks = []
    for i in range(draw(st.integers(1, count))):
        start = draw(st.integers(0, last_start))
        end = start + draw(st.integers(0, longest))
        blocks.append(Block(f"b{i}", start, end, draw(st.integers(0, sizes)), draw(st.sampled_from(alignments)),
                            draw(st.sampled_from(classes))))
    return blocks


def tiny_instances():
    """Up to 6 blocks over 6 passes, sizes 0..4, alignments 1 or 2: brute force is cheap."""
    return block_lists(6, 5, 3, 4, [1, 1, 2], "c")


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blocks=tiny_instances(), heuristic=st.sampled_from(PREORDERINGS), slack=st.integers(-1, 3))
def test_decision_matches_brute_force(blocks, heuristic, slack):
    inst = Instance.build(blocks)
    optimum = brute_force_optimum(inst)
    capacity = max(optimum + slack, 0)
    run = CapacitySearch(inst, preorder(inst, heuristic), capacity, 10**6, heuristic)
    found = run.run()
    assert not run.exhausted
    assert (found is not None) == (capacity >= optimum), (capacity, optimum)
    if found is not None:
        assert_valid(inst, found, capacity)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blocks=tiny_instances())
def test_round_robin_and_optimal_policy_reach_the_brute_force_optimum(blocks):
    inst = Instance.build(blocks)
    optimum = brute_force_optimum(inst)
    found, _, proven = solve_capacity(inst, optimum - 1, 10**8)
    assert found is None and proven
    found, _, _ = solve_capacity(inst, optimum, 10**8)
    assert found is not None and inst.peak(found) <= optimum
    placement = place(blocks, "optimal")
    assert placement.stats.peak_bytes == optimum
    result = place_class(inst, 1.0, exact=True)
    assert result.peak == optimum and result.proven  # at the bound, or the peak - 1 proven too small
    assert overlaps(blocks, placement) == []


def traces():
    """Up to 40 blocks with gaps in time (so decomposition splits), mixed alignments."""
    return block_lists(40, 40, 12, 5000, [1, 16, 256], "xy")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blocks=traces(), policy=st.sampled_from(["aliased", "optimal"]), budget=st.sampled_from([0.001, 0.01, 0.05]))
def test_placements_never_overlap_in_time_and_memory(blocks, policy, budget):
    placement = place(blocks, policy, time_budget_s=budget)
    assert overlaps(blocks, placement) == []
    assert placement.stats.peak_bytes >= placement.stats.lower_bound_bytes
    again = place(blocks, policy, time_budget_s=budget)
    assert again.offsets == placement.offsets and again.heaps == placement.heaps


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blocks=traces(), slack=st.floats(1.0, 1.3))
def test_search_results_fit_their_capacity(blocks, slack):
    inst = Instance.build([b for b in blocks if b.memory_class == "x"] or blocks[:1])
    capacity = int(inst.lower_bound() * slack)
    found, _, proven = solve_capacity(inst, capacity, 200_000)
    assert not (found is not None and proven)
    if found is not None:
        assert_valid(inst, found, capacity)


def test_hatless_pruning_and_decomposition_keep_completeness():
    # Two time-disjoint groups, each needing interlocking; a lone block overhead of nothing.
    blocks = [
        Block("a", 0, 1, 2, 1, "c"), Block("b", 2, 3, 2, 1, "c"), Block("c", 0, 0, 2, 1, "c"),
        Block("d", 1, 2, 2, 1, "c"), Block("e", 3, 3, 2, 1, "c"),
        Block("f", 5, 6, 3, 1, "c"), Block("g", 5, 5, 1, 1, "c"), Block("h", 6, 6, 1, 1, "c"),
    ]
    inst = Instance.build(blocks)
    assert brute_force_optimum(inst) == 4 == inst.lower_bound()
    for h in PREORDERINGS:
        run = CapacitySearch(inst, preorder(inst, h), 4, 10**6, h)
        found = run.run()
        assert found is not None
        assert_valid(inst, found, 4)
        run = CapacitySearch(inst, preorder(inst, h), 3, 10**6, h)
        assert run.run() is None and not run.exhausted


def test_easy_instances_stop_at_the_bound_without_searching(monkeypatch):
    from rgraph.memory import aliased
    from rgraph.memory.model import by_class
    from rgraph.memory.random_instances import random_blocks

    def no_search(*args, **kwargs):
        raise AssertionError("the search ran although greedy reached the bound")

    monkeypatch.setattr(aliased, "solve_capacity", no_search)
    for blocks in by_class(random_blocks(200, 1)).values():
        result = aliased.place_class(Instance.build(blocks), 1.0, exact=True)
        assert result.proven and result.peak == result.lower_bound

