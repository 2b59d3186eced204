"""Time neighbours and overlap counts: the fast paths agree with the definition."""

from __future__ import annotations

import random

import pytest

from rgraph.memory import instance
from rgraph.memory.aliased import overlapping_pairs
from rgraph.memory.instance import time_neighbors
from rgraph.memory.model import Block


def _lifetimes(seed: int) -> tuple[list[int], list[int]]:
    rng = random.Random(seed)
    n = rng.randint(0, 60)
    start = [rng.randint(0, 30) for _ in range(n)]
    return start, [s + rng.randint(0, 10) for s in start]


def _by_definition(start: list[int], end: list[int]) -> list[list[int]]:
    n = len(start)
    return [[j for j in range(n) if j != i and start[j] <= end[i] and start[i] <= end[j]] for i in range(n)]


@pytest.mark.parametrize("sweep_from", [0, 10**9], ids=["sweep", "numpy"])
def test_time_neighbors_match_the_definition(monkeypatch: pytest.MonkeyPatch, sweep_from: int) -> None:
    monkeypatch.setattr(instance, "SWEEP_FROM", sweep_from)
    for seed in range(150):
        start, end = _lifetimes(seed)
        assert time_neighbors(start, end) == _by_definition(start, end), seed


def test_overlapping_pairs_match_the_neighbour_lists() -> None:
    for seed in range(150):
        start, end = _lifetimes(seed)
        blocks = [Block(f"b{k}", s, e, 256, 256, "c") for k, (s, e) in enumerate(zip(start, end, strict=True))]
        assert overlapping_pairs(blocks) == sum(len(row) for row in _by_definition(start, end)), seed
