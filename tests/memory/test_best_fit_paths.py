"""Best fit's ways of visiting a block's placed neighbours (their union; the sorted list of
every placed block; where blocks overlap 90% of the others, the union's gaps and the bytes
only its placed non-neighbours hold, ``greedy._Cover``; its own neighbours sorted) give the
offsets of the plain algorithm: sort the placed neighbours by (offset, top), take the
smallest fitting gap. ``dense`` 0.6 gives about 70% overlapping pairs, 0.9 about 92%."""

from __future__ import annotations

import random

from hypothesis import given, settings
from hypothesis import strategies as st

from rgraph.memory.greedy import best_fit, orderings
from rgraph.memory.instance import Instance
from rgraph.memory.model import Block


def plain_best_fit(inst: Instance, order: list[int]) -> list[int]:
    offsets = [-1] * inst.n
    for i in order:
        need, a = inst.size[i], inst.align[i]
        taken = sorted((offsets[j], offsets[j] + inst.size[j]) for j in inst.neighbors[i] if offsets[j] >= 0)
        best_off, best_gap, cursor = -1, -1, 0
        for lo, hi in taken:
            aligned = -(-cursor // a) * a
            if lo > cursor and aligned + need <= lo and (best_gap < 0 or lo - cursor < best_gap):
                best_off, best_gap = aligned, lo - cursor
            cursor = max(cursor, hi)
        offsets[i] = best_off if best_off >= 0 else -(-cursor // a) * a
    return offsets


def instance(seed: int, count: int, dense: float, sizes: tuple[int, ...] = (1, 2, 3, 5, 8)) -> Instance:
    """Random lifetimes, sizes (``sizes`` times 256) and alignments; ``dense``: the share of
    pairs apart in time that conflict anyway (as cross-queue pairs do)."""
    rng = random.Random(seed)
    blocks = []
    for i in range(count):
        start = rng.randrange(40)
        blocks.append(Block(f"b{i}", start, start + rng.randrange(12), rng.choice(sizes) * 256,
                            rng.choice([1, 256, 512]), "c"))
    conflicts: dict[str, set[str]] = {}
    for i in range(count):
        for j in range(i):
            if rng.random() < dense:
                conflicts.setdefault(f"b{i}", set()).add(f"b{j}")
                conflicts.setdefault(f"b{j}", set()).add(f"b{i}")
    return Instance.build(blocks, conflicts)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10**6), count=st.integers(1, 120), dense=st.sampled_from([0.0, 0.3, 0.6, 0.9, 1.0]))
def test_best_fit_equals_the_plain_algorithm(seed: int, count: int, dense: float) -> None:
    inst = instance(seed, count, dense)
    for _, order in orderings(inst):
        assert best_fit(inst, order) == plain_best_fit(inst, order)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10**6), count=st.integers(1, 120), dense=st.sampled_from([0.6, 0.9]),
       sizes=st.sampled_from([(0, 1, 2, 7, 16), (1, 2, 7, 16)]))
def test_dense_best_fit_with_empty_and_mixed_blocks(seed: int, count: int, dense: float, sizes: tuple[int, ...]) -> None:
    """Blocks of no bytes (the dense path leaves them to the sorted lists: one would split a
    gap) and sizes spanning others' ranges (a block over several segments of ``_Cover``)."""
    inst = instance(seed, count, dense, sizes)
    rng = random.Random(seed)
    for order in [o for _, o in orderings(inst)] + [rng.sample(range(inst.n), inst.n)]:
        assert best_fit(inst, order) == plain_best_fit(inst, order)


def test_give_up_at_stops_once_the_peak_reaches_it() -> None:
    inst = instance(3, 80, 0.9)
    order = next(orderings(inst))[1]
    peak = inst.peak(best_fit(inst, order))
    assert best_fit(inst, order, peak) is None
    assert best_fit(inst, order, peak + 1) == plain_best_fit(inst, order)
