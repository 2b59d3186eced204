"""Lower bounds: the most aligned bytes alive at any one time."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rgraph.memory import greedy
from rgraph.memory.instance import Instance
from rgraph.memory.model import Block, by_class


def live_profile(blocks: Sequence[Block]) -> tuple[list[int], list[int]]:
    """Live aligned bytes as a step function: ``(times, bytes)`` where ``bytes[k]`` holds
    from ``times[k]`` (inclusive) until ``times[k+1]``."""
    deltas: dict[int, int] = {}
    for b in blocks:
        deltas[b.start] = deltas.get(b.start, 0) + b.aligned_size
        deltas[b.end + 1] = deltas.get(b.end + 1, 0) - b.aligned_size
    times = sorted(deltas)
    live = np.cumsum([deltas[t] for t in times], dtype=np.int64).tolist() if times else []
    return times, live


def class_lower_bound(blocks: Sequence[Block]) -> int:
    """Max over time of live aligned bytes (no placement in one heap can beat it)."""
    _, live = live_profile(blocks)
    return max(live, default=0)


def lower_bound(blocks: Sequence[Block]) -> int:
    """Per class lower bound, summed over classes."""
    return sum(class_lower_bound(group) for group in by_class(blocks).values())


def clique_bound(inst: Instance) -> int:
    """The weight of a clique of ``inst``'s conflict graph (blocks that pairwise may not
    share bytes: all stacked in any placement): the blocks live in the busiest section,
    then, heaviest first, every block in conflict with all chosen so far. At least the time
    bound; above it only where conflicts join blocks apart in time (cross-queue pairs).
    Instances without the conflict matrix (:data:`rgraph.memory.instance.SWEEP_FROM` blocks
    and more) get the time bound."""
    totals = inst.section_totals()
    if not totals or inst.adjacency is None or inst.separable:
        return max(totals, default=0)
    busiest = totals.index(max(totals))  # the first busiest
    weight = totals[busiest]
    flat = None if greedy.NATIVE is None else greedy.native_flat(greedy.NATIVE, inst)
    if flat is not None:  # the same members and growth, compiled (rgraph/memory/_fit.pyx)
        members = greedy.NATIVE.live_at(inst.sec_lo, inst.sec_hi, busiest)
        return weight + greedy.NATIVE.clique_extra(flat, members)  # type: ignore[no-any-return]
    members = [i for i, (lo, hi) in enumerate(zip(inst.sec_lo, inst.sec_hi, strict=True)) if lo <= busiest < hi]
    return weight + _clique_extra(inst, members)


def _clique_extra(inst: Instance, members: list[int]) -> int:
    """``clique_bound``'s growth from the blocks in conflict with all ``members``: the
    heaviest joinable one in turn (``_fit.clique_extra`` mirrors it)."""
    assert inst.adjacency is not None
    weight = 0
    joinable = inst.adjacency[:, members].all(axis=1)
    sizes = np.asarray(inst.size, dtype=np.float64)  # ranks only: exact weights come from inst.size
    while joinable.any():
        k = int(np.argmax(np.where(joinable, sizes, -1.0)))
        weight += inst.size[k]
        joinable &= inst.adjacency[:, k]
    return weight
