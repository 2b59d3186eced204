"""Offline greedy placement: best-fit in a given order (TFLite / XLA heap-simulator style).

Each block, in turn, goes into the smallest gap between already placed blocks that overlap
it in time and can hold it (aligned); when no gap fits it goes on top of them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from rgraph.memory.instance import Instance


def best_fit(inst: Instance, order: Sequence[int]) -> list[int]:
    """Offsets for every block, placing blocks in ``order``."""
    offsets = [-1] * inst.n
    tops = [0] * inst.n
    size, align, neighbors = inst.size, inst.align, inst.neighbors
    for i in order:
        need, a = size[i], align[i]
        taken = sorted((offsets[j], tops[j]) for j in neighbors[i] if offsets[j] >= 0)
        best_off, best_gap = -1, -1
        cursor = 0
        for lo, hi in taken:
            if lo > cursor:
                aligned = cursor if cursor % a == 0 else cursor + a - cursor % a
                if aligned + need <= lo:
                    gap = lo - cursor
                    if best_gap < 0 or gap < best_gap:
                        best_off, best_gap = aligned, gap
            if hi > cursor:
                cursor = hi
        if best_off < 0:
            best_off = cursor if cursor % a == 0 else cursor + a - cursor % a
        offsets[i] = best_off
        tops[i] = best_off + need
    return offsets


def orderings(inst: Instance) -> dict[str, list[int]]:
    """The static orderings tried by the heuristic (all deterministic, ties by index)."""
    n = range(inst.n)
    s, e, z = inst.start, inst.end, inst.size
    totals = inst.section_totals()
    contention = [max(totals[inst.sec_lo[i] : inst.sec_hi[i]], default=0) for i in n]
    keys: dict[str, Callable[[int], tuple]] = {
        "size": lambda i: (-z[i], s[i], i),
        "area": lambda i: (-z[i] * (e[i] - s[i] + 1), i),
        "length": lambda i: (-(e[i] - s[i]), -z[i], i),
        "start": lambda i: (s[i], -z[i], i),
        "contention": lambda i: (-contention[i], -z[i] * (e[i] - s[i] + 1), i),
        "contention_size": lambda i: (-contention[i], -z[i], i),
    }
    return {name: sorted(n, key=key) for name, key in keys.items()}
