"""Offline greedy placement: best-fit in a given order (TFLite / XLA heap-simulator style).

Each block, in turn, goes into the smallest gap between already placed blocks that overlap
it in time and can hold it (aligned); when no gap fits it goes on top of them.
"""

from __future__ import annotations

from bisect import bisect_left, insort
from collections.abc import Collection, Iterable, Iterator, Sequence
from itertools import repeat

import numpy as np

from rgraph.memory.instance import Instance


def best_fit(inst: Instance, order: Sequence[int], give_up_at: int | None = None) -> list[int] | None:
    """Offsets for every block, placing blocks in ``order``; None as soon as a block's top
    reaches ``give_up_at`` (the peak could then only be at least that).

    Each block's placed neighbours are visited in offset order (the gap scan depends only
    on the first of equal offsets and on the highest top so far): sorted per block, or, on
    instances where blocks overlap a quarter of the others or more (cross-queue conflicts),
    by ``_dense_best_fit``."""
    if 4 * inst.pair_count >= inst.n * inst.n:
        return _dense_best_fit(inst, order, give_up_at)
    offsets = [-1] * inst.n
    placed: list[tuple[int, int, int] | None] = [None] * inst.n  # (offset, top, block) once placed
    size, align, neighbors = inst.size, inst.align, inst.neighbors
    get = placed.__getitem__
    limit = give_up_at if give_up_at is not None else -1
    for i in order:
        need = size[i]
        off = _fit(sorted(filter(None, map(get, neighbors[i]))), need, align[i])
        if 0 <= limit <= off + need:
            return None
        offsets[i] = off
        placed[i] = (off, off + need, i)
    return offsets


def _fit(taken: Iterable[tuple[int, int, int]], need: int, a: int, skip: Collection[int] = frozenset()) -> int:
    """The offset best fit gives a block of ``need`` bytes aligned to ``a`` among the
    ``(start, end, block)`` byte ranges ``taken`` (ascending by start) of the blocks not in
    ``skip``: the start of the smallest gap that holds it, else the top of them all."""
    best_off, best_gap = -1, -1
    cursor = 0
    for lo, hi, j in taken:
        if j in skip:
            continue
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
    return best_off


def _dense_best_fit(inst: Instance, order: Sequence[int], give_up_at: int | None) -> list[int] | None:
    """``best_fit`` for blocks that overlap most others. A block that overlaps about half
    of the placed blocks or more scans the union of their byte ranges when all of them are
    its neighbours (the same gaps; one range from 0, the usual case, needs no scan), else
    the sorted list of every placed block, skipping its non-neighbours; one with fewer
    neighbours sorts its placed ones."""
    n = inst.n
    offsets = [-1] * n
    placed: list[tuple[int, int, int] | None] = [None] * n  # (offset, top, block) once placed
    size, align, degree, far = inst.size, inst.align, inst.degree, inst.far
    get = placed.__getitem__
    every: list[tuple[int, int, int]] = []  # (offset, top, block) of the placed blocks, sorted
    placed_set: set[int] = set()
    union_lo: list[int] = []  # the union of the placed blocks' byte ranges: disjoint, sorted
    union_hi: list[int] = []
    limit = give_up_at if give_up_at is not None else -1
    for i in order:
        need, a = size[i], align[i]
        if len(every) >= 2 * degree[i] + 16:
            off = _fit(sorted(filter(None, map(get, inst.neighbor_row(i)))), need, a)
        elif far[i].isdisjoint(placed_set):  # every placed block is a neighbour: their union's gaps
            if len(union_lo) == 1 and union_lo[0] == 0:  # no gap: on top
                top = union_hi[0]
                off = top if top % a == 0 else top + a - top % a
            else:
                off = _fit(zip(union_lo, union_hi, repeat(-1)), need, a)
        else:
            off = _fit(every, need, a, far[i])
        top = off + need
        if 0 <= limit <= top:
            return None
        offsets[i] = off
        placed[i] = entry = (off, top, i)
        insort(every, entry)
        placed_set.add(i)
        if len(union_lo) == 1 and off <= union_hi[0] and union_lo[0] <= top:  # joins the one range
            if off < union_lo[0]:
                union_lo[0] = off
            if top > union_hi[0]:
                union_hi[0] = top
        else:
            _merge(union_lo, union_hi, off, top)
    return offsets


def _merge(los: list[int], his: list[int], lo: int, hi: int) -> None:
    """Add ``[lo, hi)`` to the union ``los``/``his`` (sorted, disjoint, not touching)."""
    k = bisect_left(his, lo)  # first interval ending at or after lo: touches or follows it
    end = k
    while end < len(los) and los[end] <= hi:
        end += 1
    if end > k:
        lo, hi = min(lo, los[k]), max(hi, his[end - 1])
    los[k:end] = [lo]
    his[k:end] = [hi]


def range_max(values: Sequence[int], lo: Sequence[int], hi: Sequence[int]) -> list[int]:
    """``max(values[lo[k]:hi[k]])`` for each ``k`` (every range non-empty)."""
    if not lo:
        return []
    padded = np.append(np.asarray(values, dtype=np.int64), 0)  # hi may be len(values)
    bounds = np.empty(2 * len(lo), dtype=np.int64)
    bounds[0::2], bounds[1::2] = lo, hi
    return np.maximum.reduceat(padded, bounds)[0::2].tolist()


def _sorted_by(*columns: Sequence[int]) -> list[int]:
    """Indices sorted by ``columns`` (the first most significant), ties by index."""
    try:
        keys = [np.asarray(c, dtype=np.int64) for c in reversed(columns)]
    except OverflowError:  # keys past 64 bits: Python's sort
        return [i for *_, i in sorted(zip(*columns, range(len(columns[0])), strict=True))]
    return np.lexsort(keys).tolist()  # stable: ties keep index order


def orderings(inst: Instance) -> Iterator[tuple[str, list[int]]]:
    """The static orderings tried by the heuristic, in turn (all deterministic, ties by
    index); each is sorted only when asked for, so a caller that stops early pays less."""
    s = inst.start
    neg_size, neg_area, neg_width = inst.neg_size, inst.neg_area, inst.neg_width
    yield "size", _sorted_by(neg_size, s)
    yield "area", _sorted_by(neg_area)
    yield "length", _sorted_by(neg_width, neg_size)  # width - 1 = end - start: the same order
    yield "start", _sorted_by(s, neg_size)
    totals = inst.section_totals()
    try:
        peaks = range_max(totals, inst.sec_lo, inst.sec_hi)
    except OverflowError:
        peaks = [max(totals[lo:hi]) for lo, hi in zip(inst.sec_lo, inst.sec_hi, strict=True)]
    neg_contention = [-p for p in peaks]
    yield "contention", _sorted_by(neg_contention, neg_area)
    yield "contention_size", _sorted_by(neg_contention, neg_size)
