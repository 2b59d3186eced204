"""Elastic dives (``rgraph.memory.elastic``): valid, deterministic, better than greedy."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from test_memory_search import INTERLOCKING, assert_valid, hard_trace
from test_minimalloc_exact import block_lists

from rgraph.memory import Placement, PlacementStats, place
from rgraph.memory.aliased import ELASTIC_ORDERS
from rgraph.memory.elastic import dive, improve, squeak
from rgraph.memory.greedy import best_fit, orderings
from rgraph.memory.instance import Instance
from rgraph.memory.model import Heap
from rgraph.memory.search import preorder
from rgraph.memory.verify import overlaps


def as_placement(inst: Instance, offsets: list[int], peak: int) -> Placement:
    stats = PlacementStats("elastic", peak, inst.lower_bound(), sum(inst.size), 1, 0.0)
    return Placement({b.name: (0, o) for b, o in zip(inst.blocks, offsets, strict=True)},
                     [Heap(0, peak, "c", max(inst.align, default=1))], stats)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blocks=block_lists(40, 40, 12, 5000, [1, 16, 256], "c"))
def test_dives_are_valid_placements_at_their_peak(blocks):
    inst = Instance.build(blocks)
    for h in ELASTIC_ORDERS:
        found = dive(inst, preorder(inst, h), inst.lower_bound())
        assert found is not None and found.offsets is not None
        assert found.peak >= inst.lower_bound()
        assert_valid(inst, found.offsets, found.peak)
        assert overlaps(blocks, as_placement(inst, found.offsets, found.peak)) == []


def test_a_dive_needs_no_raise_where_the_packing_interlocks():
    inst = Instance.build(INTERLOCKING)
    best = min(dive(inst, preorder(inst, h), inst.lower_bound()).peak for h in ELASTIC_ORDERS)  # type: ignore[union-attr]
    assert best == inst.lower_bound() == 4


def test_dives_are_deterministic_and_stop_at_their_limits():
    blocks = hard_trace(120, 5)
    inst = Instance.build(blocks)
    order = preorder(inst, "TAW")
    first, again = dive(inst, order, inst.lower_bound()), dive(Instance.build(blocks), order, inst.lower_bound())
    assert first is not None and again is not None
    assert first.offsets == again.offsets and first.blamed == again.blamed and first.ops == again.ops
    assert dive(inst, order, inst.lower_bound(), ops_limit=first.ops // 2) is None
    stopped = dive(inst, order, inst.lower_bound(), give_up_at=first.peak)
    assert stopped is not None and stopped.offsets is None and stopped.peak >= first.peak
    assert stopped.ops <= first.ops


def test_squeak_moves_the_blamed_blocks_to_the_front_in_order():
    assert squeak([4, 3, 2, 1, 0], [1, 3, 1]) == [3, 1, 4, 2, 0]
    assert squeak([2, 0, 1], []) == [2, 0, 1]


def test_improve_beats_every_greedy_ordering():
    blocks = hard_trace(120, 5)
    inst = Instance.build(blocks)
    greedy = min(inst.peak(best_fit(inst, order)) for _, order in orderings(inst))  # type: ignore[arg-type]
    found = improve(inst, [preorder(inst, h) for h in ELASTIC_ORDERS], greedy, 2_000_000)
    assert found.offsets is not None and found.peak < greedy
    assert found.peak == inst.peak(found.offsets)
    assert_valid(inst, found.offsets, found.peak)
    assert found.ops <= 2_000_000 and found.dives >= 3
    again = improve(Instance.build(blocks), [preorder(inst, h) for h in ELASTIC_ORDERS], greedy, 2_000_000)
    assert again.offsets == found.offsets


def test_improve_stops_at_the_bound_and_on_budget():
    inst = Instance.build(INTERLOCKING)
    found = improve(inst, [preorder(inst, h) for h in ELASTIC_ORDERS], 10, 10**6)
    assert found.peak == 4 and found.dives <= 3
    blocks = hard_trace(120, 5)
    inst = Instance.build(blocks)
    nothing = improve(inst, [preorder(inst, h) for h in ELASTIC_ORDERS], 10**9, 10)
    assert nothing.offsets is None and nothing.dives == 0


def test_aliased_uses_the_dives_and_stays_valid():
    blocks = hard_trace(120, 5)
    placement = place(blocks, "aliased", time_budget_s=0.2)
    assert overlaps(blocks, placement) == []
    inst = Instance.build(blocks)
    greedy = min(inst.peak(best_fit(inst, order)) for _, order in orderings(inst))  # type: ignore[arg-type]
    assert placement.stats.peak_bytes < greedy
