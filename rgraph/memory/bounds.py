"""Lower bounds: the most aligned bytes alive at any one time."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

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
