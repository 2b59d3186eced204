"""Placement policies: soundness on random instances, stats, determinism, parsing."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rgraph.memory import Block, Heap, Placement, PlacementStats, parse_policy, place
from rgraph.memory.policy import MIB, Policy
from rgraph.memory.verify import overlaps

POLICIES = ["dedicated", "aliased", "optimal", "tlsf", "blocks:4MiB", "blocks:16MiB"]


@st.composite
def block_lists(draw):
    count = draw(st.integers(0, 24))
    blocks = []
    for i in range(count):
        start = draw(st.integers(0, 12))
        end = start + draw(st.integers(0, 6))
        alignment = draw(st.sampled_from([1, 4, 256, 4096, 65536]))
        size = draw(st.integers(0, 3 * MIB))
        cls = draw(st.sampled_from(["device_local_optimal", "device_local_linear"]))
        blocks.append(Block(f"b{i}", start, end, size, alignment, cls))
    return blocks


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blocks=block_lists(), policy=st.sampled_from(POLICIES))
def test_every_policy_is_sound(blocks, policy):
    placement = place(blocks, policy, time_budget_s=0.02)
    assert overlaps(blocks, placement) == []
    stats = placement.stats
    assert stats.peak_bytes >= stats.lower_bound_bytes
    assert stats.unaliased_bytes == sum(b.aligned_size for b in blocks)
    assert stats.allocations == len(placement.heaps)
    assert [h.id for h in placement.heaps] == list(range(len(placement.heaps)))
    classes = [h.memory_class for h in placement.heaps]
    assert classes == sorted(classes)
    if policy == "dedicated":
        assert stats.peak_bytes == stats.unaliased_bytes
        assert stats.allocations == len(blocks)


def test_aliasing_reuses_memory_of_dead_blocks():
    blocks = [Block(f"t{i}", i, i, 4 * MIB, 65536, "optimal") for i in range(5)]
    placement = place(blocks, "aliased")
    assert placement.stats.peak_bytes == 4 * MIB == placement.stats.lower_bound_bytes
    assert placement.stats.unaliased_bytes == 20 * MIB
    assert {placement.offsets[b.name] for b in blocks} == {(0, 0)}


def test_classes_never_share_a_heap():
    blocks = [Block("img", 0, 0, 100, 64, "optimal"), Block("buf", 1, 1, 100, 64, "linear")]
    placement = place(blocks, "aliased")
    assert placement.offsets["buf"][0] != placement.offsets["img"][0]
    assert [h.memory_class for h in placement.heaps] == ["linear", "optimal"]


def test_alignment_is_honoured_after_odd_sizes():
    blocks = [Block("odd", 0, 2, 1000, 1, "c"), Block("aligned", 1, 3, 4096, 4096, "c")]
    for policy in POLICIES:
        placement = place(blocks, policy)
        assert placement.offsets["aligned"][1] % 4096 == 0, policy
        assert overlaps(blocks, placement) == [], policy


def test_blocks_policy_counts_whole_blocks_and_dedicates_large_resources():
    small = [Block(f"s{i}", i, i + 1, 1 * MIB, 256, "c") for i in range(6)]
    large = Block("large", 0, 10, 3 * MIB, 256, "c")
    placement = place([*small, large], "blocks:4MiB")
    assert placement.stats.peak_bytes % MIB == 0
    heap_sizes = sorted(h.bytes for h in placement.heaps)
    assert 3 * MIB in heap_sizes  # the dedicated allocation
    assert all(size in (3 * MIB, 4 * MIB) for size in heap_sizes)


def test_tlsf_reuses_freed_ranges():
    blocks = [Block(f"t{i}", i, i, 1 << 20, 256, "c") for i in range(10)]
    assert place(blocks, "tlsf").stats.peak_bytes == 1 << 20


def test_results_are_deterministic():
    from rgraph.memory.random_instances import random_blocks

    blocks = random_blocks(120, 7)
    first = place(blocks, "aliased", time_budget_s=0.2)
    second = place(list(blocks), "aliased", time_budget_s=0.2)
    assert first.offsets == second.offsets and first.heaps == second.heaps


def test_aliased_reaches_the_bound_on_render_graph_sized_inputs():
    from rgraph.memory.random_instances import random_blocks

    for seed in range(5):
        stats = place(random_blocks(40, seed), "aliased").stats
        assert stats.peak_bytes <= 1.05 * stats.lower_bound_bytes, seed


def test_optimal_reaches_the_bound_on_an_interlocking_instance():
    # Every pass has exactly 4 units live; the blocks must interlock to reach it.
    blocks = [
        Block("a", 0, 1, 2, 1, "c"), Block("b", 2, 3, 2, 1, "c"),
        Block("c", 0, 0, 2, 1, "c"), Block("d", 1, 2, 2, 1, "c"), Block("e", 3, 3, 2, 1, "c"),
    ]
    placement = place(blocks, "optimal")
    assert overlaps(blocks, placement) == []
    assert placement.stats.peak_bytes == placement.stats.lower_bound_bytes == 4


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("aliased", Policy("aliased")),
        (" Dedicated ", Policy("dedicated")),
        ("tlsf", Policy("tlsf")),
        ("optimal", Policy("optimal")),
        ("blocks:16MiB", Policy("blocks", 16 * MIB)),
        ("blocks:16M", Policy("blocks", 16 * MIB)),
        ("blocks:256mb", Policy("blocks", 256 * MIB)),
        ("blocks:4", Policy("blocks", 4 * MIB)),
    ],
)
def test_parse_policy_accepts(text, expected):
    assert parse_policy(text) == expected


@pytest.mark.parametrize("text", ["", "alias", "blocks:", "blocks:3MiB", "blocks:16GiB", "tlsf2"])
def test_parse_policy_rejects_with_the_valid_choices(text):
    with pytest.raises(ValueError, match="dedicated|4MiB"):
        parse_policy(text)


def test_bad_blocks_raise_value_error():
    with pytest.raises(ValueError, match="duplicate"):
        place([Block("x", 0, 0, 1, 1, "c"), Block("x", 1, 1, 1, 1, "c")])
    with pytest.raises(ValueError, match="after end"):
        place([Block("x", 3, 2, 1, 1, "c")])


def test_verifier_reports_each_kind_of_problem():
    blocks = [Block("a", 0, 2, 100, 16, "c"), Block("b", 1, 3, 100, 16, "c")]
    heap = Heap(0, 150, "c", 16)
    stats = PlacementStats("test", 150, 200, 200, 1, 0.0)
    bad = Placement({"a": (0, 0), "b": (0, 64)}, [heap], stats)
    problems = overlaps(blocks, bad)
    assert any("share bytes" in p for p in problems)
    assert any("exceeds heap" in p for p in problems)
    misaligned = Placement({"a": (0, 0), "b": (0, 104)}, [Heap(0, 300, "c", 16)], stats)
    assert any("alignment" in p for p in overlaps(blocks, misaligned))
    wrong_class = Placement({"a": (0, 0), "b": (0, 112)}, [Heap(0, 300, "other", 16)], stats)
    assert any("class" in p for p in overlaps(blocks, wrong_class))
    disjoint_in_time = [Block("a", 0, 1, 100, 16, "c"), Block("b", 2, 3, 100, 16, "c")]
    good = Placement({"a": (0, 0), "b": (0, 0)}, [Heap(0, 100, "c", 16)], stats)
    assert overlaps(disjoint_in_time, good) == []
