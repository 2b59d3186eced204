"""Instance.build with cross-queue conflicts: neighbour lists, non-neighbours and the clique
bound agree with their definitions, on the matrix path and the sweep path."""

from __future__ import annotations

import random

import pytest

from rgraph.memory import instance
from rgraph.memory.bounds import clique_bound
from rgraph.memory.greedy import best_fit, orderings
from rgraph.memory.instance import Instance
from rgraph.memory.model import Block


def _case(seed: int) -> tuple[list[Block], dict[str, set[str]]]:
    rng = random.Random(seed)
    count = rng.randint(0, 50)
    blocks = []
    for k in range(count):
        start = rng.randrange(30)
        blocks.append(Block(f"b{k}", start, start + rng.randrange(8), rng.randrange(6) * 256, 256, "c"))
    conflicts: dict[str, set[str]] = {}
    dense = rng.choice([0.0, 0.1, 0.5])
    for k in range(count):
        for j in range(k):
            if rng.random() < dense:
                conflicts.setdefault(f"b{k}", set()).add(f"b{j}")
                conflicts.setdefault(f"b{j}", set()).add(f"b{k}")
        if rng.random() < 0.1:
            conflicts.setdefault(f"b{k}", set()).update({f"b{k}", "not-a-block"})  # ignored
    return blocks, conflicts


@pytest.mark.parametrize("sweep_from", [0, 10**9], ids=["sweep", "matrix"])
def test_neighbours_are_time_overlaps_plus_conflicts(monkeypatch: pytest.MonkeyPatch, sweep_from: int) -> None:
    monkeypatch.setattr(instance, "SWEEP_FROM", sweep_from)
    for seed in range(120):
        blocks, conflicts = _case(seed)
        inst = Instance.build(blocks, conflicts)
        n = len(blocks)
        apart_conflict = False
        for k, b in enumerate(blocks):
            want = []
            for j, c in enumerate(blocks):
                conflict = c.name in conflicts.get(b.name, ()) and j != k
                if j != k and (b.overlaps_in_time(c) or conflict):
                    want.append(j)
                apart_conflict |= conflict and not b.overlaps_in_time(c)
            assert inst.neighbors[k] == want, seed
            assert inst.neighbor_row(k) == want and inst.degree[k] == len(want), seed
            assert inst.non_neighbors(k) == set(range(n)) - set(want), seed
        assert inst.separable == (not apart_conflict), seed


def test_clique_bound_counts_blocks_apart_in_time_that_conflict() -> None:
    blocks = [Block(f"b{k}", 2 * k, 2 * k, 256 * (k + 1), 256, "c") for k in range(3)]
    pairs = {"b0": {"b1", "b2"}, "b1": {"b0", "b2"}, "b2": {"b0", "b1"}}
    inst = Instance.build(blocks, pairs)
    assert inst.lower_bound() == 768
    assert clique_bound(inst) == 256 + 512 + 768


def test_clique_bound_is_a_lower_bound() -> None:
    """No placement (greedy's, under every ordering) is below it; it is at least the time bound."""
    for seed in range(150):
        blocks, conflicts = _case(seed)
        inst = Instance.build(blocks, conflicts)
        bound = clique_bound(inst)
        assert bound >= inst.lower_bound(), seed
        for _, order in orderings(inst):
            assert inst.peak(best_fit(inst, order)) >= bound, seed
