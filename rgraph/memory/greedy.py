"""Offline greedy placement: best-fit in a given order (TFLite / XLA heap-simulator style).

Each block, in turn, goes into the smallest gap between already placed blocks that overlap
it in time and can hold it (aligned); when no gap fits it goes on top of them.

``best_fit`` runs compiled (``rgraph/memory/_fit.pyx``: the same offsets, the same give-up)
where built; ``best_fit_python`` is the reference and the fallback (``RGRAPH_NATIVE=0``).
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right, insort
from collections.abc import Collection, Iterable, Iterator, Sequence
from itertools import repeat
from types import ModuleType
from typing import Any

import numpy as np

from rgraph.memory.instance import Instance
from rgraph.native import load

#: The compiled best fit (``rgraph/memory/_fit.pyx``), None where it is not built or
#: ``RGRAPH_NATIVE=0``: then :func:`best_fit` runs :func:`best_fit_python`.
NATIVE = load("rgraph.memory._fit")

#: ``_cover_best_fit`` is used where blocks overlap all but one in this many of the others
#: (on average): it visits a block's placed non-neighbours, each about ten times dearer
#: than an entry of ``_dense_best_fit``'s scan of every placed block (random conflict graphs:
#: break-even at 88-90% overlapping pairs; 3x slower at 50-80%, 1.5x faster at 93%).
NEARLY_ALL = 10


def best_fit(inst: Instance, order: Sequence[int], give_up_at: int | None = None) -> list[int] | None:
    """Offsets for every block, placing blocks in ``order``; None as soon as a block's top
    reaches ``give_up_at`` (the peak could then only be at least that). Compiled
    (:data:`NATIVE`) where built, else :func:`best_fit_python`: the same results."""
    if NATIVE is not None:
        flat = native_flat(NATIVE, inst)
        if flat is not None:
            return NATIVE.best_fit(flat, order, give_up_at)  # type: ignore[no-any-return]
    return best_fit_python(inst, order, give_up_at)


def native_flat(module: ModuleType, inst: Instance) -> Any:
    """``module.Flat`` (``rgraph.memory._fit``) of ``inst``, made once and kept on the
    instance; None where sizes or alignments pass 64 bits (the Python code then runs)."""
    flat = inst.accelerated.get("fit")
    if flat is None:
        try:
            matrix = None if inst.adjacency is None else np.ascontiguousarray(inst.adjacency).view(np.uint8)
            flat = module.Flat(inst.size, inst.align, matrix, inst.neighbors if matrix is None else None)
        except OverflowError:
            flat = False
        inst.accelerated["fit"] = flat
    return flat or None


def best_fit_python(inst: Instance, order: Sequence[int], give_up_at: int | None = None) -> list[int] | None:
    """:func:`best_fit` in Python (``rgraph/memory/_fit.pyx`` gives the same offsets).

    Each block's placed neighbours are visited in offset order (the gap scan depends only
    on the first of equal offsets and on the highest top so far): sorted per block, or, on
    instances where blocks overlap a quarter of the others or more (cross-queue conflicts),
    by ``_dense_best_fit``, or ``_cover_best_fit`` where they overlap all but one in
    :data:`NEARLY_ALL` of the others and none is empty."""
    n2 = inst.n * inst.n
    if 4 * inst.pair_count >= n2:
        if NEARLY_ALL * inst.pair_count >= (NEARLY_ALL - 1) * n2 and 0 not in inst.size:
            return _cover_best_fit(inst, order, give_up_at)
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


def _cover_best_fit(inst: Instance, order: Sequence[int], give_up_at: int | None) -> list[int] | None:
    """``_dense_best_fit`` for blocks that overlap nearly all others (every size above zero:
    a block of no bytes would split a gap at its offset, which ``_Cover`` does not keep): a
    block with placed non-neighbours fits among the union's gaps and the bytes only those
    non-neighbours hold (``_Cover.free``: a few per block), not among a scan of every
    placed block."""
    n = inst.n
    offsets = [-1] * n
    placed: list[tuple[int, int, int] | None] = [None] * n  # (offset, top, block) once placed
    size, align, degree, far = inst.size, inst.align, inst.degree, inst.far
    get = placed.__getitem__
    count = 0  # blocks placed so far
    placed_set: set[int] = set()
    cover = _Cover(n)
    cut, holders, alone = cover.cut, cover.holders, cover.alone
    union_lo: list[int] = []  # the union of the placed blocks' byte ranges: disjoint, sorted
    union_hi: list[int] = []
    limit = give_up_at if give_up_at is not None else -1
    for i in order:
        need, a = size[i], align[i]
        if count >= 2 * degree[i] + 16:
            off = _fit(sorted(filter(None, map(get, inst.neighbor_row(i)))), need, a)
        else:
            others = far[i].intersection(placed_set)  # placed blocks it may share bytes with
            if others:
                off = _fit_runs(cover.free(others, placed, far[i], union_lo, union_hi), cut[-1], need, a)
            elif len(union_lo) == 1 and union_lo[0] == 0:  # every placed block a neighbour, no gap: on top
                top = union_hi[0]
                off = top if top % a == 0 else top + a - top % a
            else:  # every placed block a neighbour: their union's gaps
                off = _fit(zip(union_lo, union_hi, repeat(-1)), need, a)
        top = off + need
        if 0 <= limit <= top:
            return None
        offsets[i] = off
        placed[i] = (off, top, i)
        count += 1
        placed_set.add(i)
        if off == cut[-1] and union_hi:  # right on top of every placed block, the usual case
            cut.append(top)  # _Cover.add's first case, inline
            holders.append((i,))
            alone[i] = (off, top)
            union_hi[-1] = top
            continue
        cover.add(off, top, i)
        if len(union_lo) == 1 and off <= union_hi[0] and union_lo[0] <= top:  # joins the one range
            if off < union_lo[0]:
                union_lo[0] = off
            if top > union_hi[0]:
                union_hi[0] = top
        else:
            _merge(union_lo, union_hi, off, top)
    return offsets


class _Cover:
    """The placed blocks' byte ranges, cut at every offset and top: segment ``k`` is
    ``[cut[k], cut[k+1])`` and ``holders[k]`` the blocks whose range holds it (none: a gap
    between them); ``cut[-1]`` is the highest top. Blocks of a dense class mostly conflict,
    so their ranges seldom overlap: a block's range spans few segments. Per block, so that
    ``free`` seldom has to look its segments up: ``alone`` (its range ``(offset, top)``
    while that is one segment held by it only, else None) and ``inside`` (blocks whose
    range holds all of its range, as found when it was placed inside one segment)."""

    __slots__ = ("cut", "holders", "alone", "inside")

    def __init__(self, n: int) -> None:
        self.cut: list[int] = [0]
        self.holders: list[tuple[int, ...]] = []
        self.alone: list[tuple[int, int] | None] = [None] * n
        self.inside: list[tuple[int, ...]] = [()] * n

    def add(self, lo: int, hi: int, block: int) -> None:
        """Add ``block``'s range ``[lo, hi)`` (``lo < hi``)."""
        cut, holders, alone = self.cut, self.holders, self.alone
        top = cut[-1]
        if lo >= top:  # on top: no segment to split
            if lo > top:
                cut.append(lo)
                holders.append(())
            cut.append(hi)
            holders.append((block,))
            alone[block] = (lo, hi)
            return
        k = bisect_right(cut, lo) - 1  # the segment holding lo
        if cut[k] < lo:
            k += 1
            cut.insert(k, lo)
            holders.insert(k, holders[k - 1])
        if hi > top:
            cut.append(hi)
            holders.append(())
        end = bisect_left(cut, hi, k)
        if cut[end] > hi:
            cut.insert(end, hi)
            holders.insert(end, holders[end - 1])
        if end == k + 1:  # within one segment: its holders hold all of the range
            if holders[k]:
                self.inside[block] = holders[k]
            else:
                alone[block] = (lo, hi)
        for m in range(k, end):
            held = holders[m]
            for h in held:
                alone[h] = None
            holders[m] = held + (block,)

    def free(self, others: Iterable[int], placed: Sequence[tuple[int, int, int] | None], allowed: set[int],
             union_lo: list[int], union_hi: list[int]) -> list[tuple[int, int]]:
        """The byte ranges below the highest top that no block outside ``allowed`` holds,
        as sorted pieces (they may touch or overlap): the gaps of the placed ranges' union
        ``union_lo``/``union_hi`` and, within the ranges of ``others`` (placed blocks in
        ``allowed``; ``placed[f]``: ``(offset, top, f)``), the segments that only blocks in
        ``allowed`` hold."""
        cut, holders, alone, inside = self.cut, self.holders, self.alone, self.inside
        pieces = list(zip(union_hi[:-1], union_lo[1:], strict=True)) if len(union_lo) > 1 else []
        if union_lo[0] > 0:
            pieces.append((0, union_lo[0]))
        is_allowed = allowed.issuperset
        for f in others:
            if alone[f] is not None:
                pieces.append(alone[f])
                continue
            if inside[f] and not is_allowed(inside[f]):
                continue  # a block outside ``allowed`` holds all of its range
            lo, hi, _ = placed[f]  # type: ignore[misc]
            k = bisect_left(cut, lo)
            if cut[k + 1] >= hi:  # one segment
                if is_allowed(holders[k]):
                    pieces.append((lo, hi))
                continue
            run = -1  # start of the current run of free segments
            while cut[k] < hi:
                if is_allowed(holders[k]):
                    if run < 0:
                        run = cut[k]
                elif run >= 0:
                    pieces.append((run, cut[k]))
                    run = -1
                k += 1
            if run >= 0:
                pieces.append((run, hi))
        pieces.sort()
        return pieces


def _fit_runs(pieces: list[tuple[int, int]], top: int, need: int, a: int) -> int:
    """``_fit`` from the free side: ``pieces`` (sorted by start; touching or overlapping
    ones join) are the free bytes below ``top``, the highest placed top. The start of the
    smallest joined run that holds ``need`` bytes aligned to ``a``, else the top of the
    bytes held (the start of a run that reaches ``top``)."""
    best_off, best_gap = -1, -1
    run_lo = run_hi = -1
    for lo, hi in pieces:
        if lo <= run_hi:
            if hi > run_hi:
                run_hi = hi
            continue
        if run_hi >= 0:
            aligned = run_lo if run_lo % a == 0 else run_lo + a - run_lo % a
            if aligned + need <= run_hi and (best_gap < 0 or run_hi - run_lo < best_gap):
                best_off, best_gap = aligned, run_hi - run_lo
        run_lo, run_hi = lo, hi
    if run_hi == top:  # the last run reaches the top: what lies below it is held
        top = run_lo
    elif run_hi >= 0:
        aligned = run_lo if run_lo % a == 0 else run_lo + a - run_lo % a
        if aligned + need <= run_hi and (best_gap < 0 or run_hi - run_lo < best_gap):
            best_off, best_gap = aligned, run_hi - run_lo
    if best_off < 0:
        best_off = top if top % a == 0 else top + a - top % a
    return best_off


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
    return _range_max(values, lo, hi).tolist()  # type: ignore[no-any-return]


def _range_max(values: Sequence[int], lo: Sequence[int], hi: Sequence[int]) -> np.ndarray:
    """``range_max`` as an int64 array (OverflowError past 64 bits)."""
    if not lo:
        return np.zeros(0, dtype=np.int64)
    padded = np.append(np.asarray(values, dtype=np.int64), 0)  # hi may be len(values)
    bounds = np.empty(2 * len(lo), dtype=np.int64)
    bounds[0::2], bounds[1::2] = lo, hi
    return np.maximum.reduceat(padded, bounds)[0::2]


def _sorted_by(*columns: Sequence[int]) -> list[int]:
    """Indices sorted by ``columns`` (the first most significant), ties by index."""
    try:
        keys = [np.asarray(c, dtype=np.int64) for c in reversed(columns)]
    except OverflowError:  # keys past 64 bits: Python's sort
        return [i for *_, i in sorted(zip(*columns, range(len(columns[0])), strict=True))]
    return np.lexsort(keys).tolist()  # stable: ties keep index order


#: The names of :func:`orderings`' orders, in turn.
ORDERINGS = ("size", "area", "length", "start", "contention", "contention_size")


def orderings(inst: Instance) -> Iterator[tuple[str, list[int]]]:
    """The static orderings tried by the heuristic, in turn (all deterministic, ties by
    index); each is sorted only when asked for, so a caller that stops early pays less.
    Compiled where built (``_fit.orderings``: all six at once, cheaper than one numpy sort)."""
    if NATIVE is not None and inst.n:
        try:
            orders = NATIVE.orderings(inst.start, inst.end, inst.size, inst.sec_lo, inst.sec_hi, inst._totals)
        except OverflowError:  # keys past 62 bits
            pass
        else:
            yield from zip(ORDERINGS, orders, strict=True)
            return
    keys = inst.order_keys
    if keys is None:  # keys past 63 bits
        yield from _orderings_python(inst)
        return
    start, neg_size, neg_area, neg_width = keys  # np.lexsort: the last key most significant
    yield "size", np.lexsort((start, neg_size)).tolist()
    yield "area", np.lexsort((neg_area,)).tolist()
    yield "length", np.lexsort((neg_size, neg_width)).tolist()
    yield "start", np.lexsort((neg_size, start)).tolist()
    totals = inst.section_totals()
    try:
        neg_contention = -_range_max(totals, inst.sec_lo, inst.sec_hi)
    except OverflowError:  # totals past 64 bits
        neg_peaks = [-max(totals[lo:hi]) for lo, hi in zip(inst.sec_lo, inst.sec_hi, strict=True)]
        yield "contention", _sorted_by(neg_peaks, inst.neg_area)
        yield "contention_size", _sorted_by(neg_peaks, inst.neg_size)
        return
    yield "contention", np.lexsort((neg_area, neg_contention)).tolist()
    yield "contention_size", np.lexsort((neg_size, neg_contention)).tolist()


def _orderings_python(inst: Instance) -> Iterator[tuple[str, list[int]]]:
    """``orderings`` where a key passes 63 bits (Python's sort where numpy's would overflow)."""
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
