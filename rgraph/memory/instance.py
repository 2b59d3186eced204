"""One memory class's blocks as flat arrays, with time overlaps and sections precomputed."""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from heapq import heappop, heappush
from itertools import accumulate
from operator import add
from typing import Any

import numpy as np

from rgraph.memory.model import Block
from rgraph.native import load

#: ``rgraph/memory/_fit.pyx`` (its ``conflict_matrix``), None where not built or ``RGRAPH_NATIVE=0``.
_NATIVE = load("rgraph.memory._fit")

#: From this many blocks, neighbours come from a sweep over start times (cost in the pairs
#: found) instead of one numpy row per block (cost n**2, cheap per element).
SWEEP_FROM = 1500


def time_overlaps(start: Sequence[int], end: Sequence[int]) -> np.ndarray:
    """``m[i, j]``: blocks ``i != j`` overlap in (closed) time."""
    starts = np.asarray(start, dtype=np.int64)
    ends = np.asarray(end, dtype=np.int64)
    overlap = (starts[:, None] <= ends[None, :]) & (ends[:, None] >= starts[None, :])
    np.fill_diagonal(overlap, False)
    return overlap


def _rows(matrix: np.ndarray, make: Callable[[list[int]], Any] = list) -> list[Any]:
    """``make`` of the column indices of each row's true entries, ascending (a square
    matrix)."""
    n = len(matrix)
    flat = np.flatnonzero(matrix)  # row by row, ascending within a row (2-D nonzero: 7x slower)
    columns = (flat % n).tolist() if n else []
    bounds = np.searchsorted(flat, np.arange(0, n * n + 1, max(n, 1))).tolist()
    return [make(columns[bounds[i] : bounds[i + 1]]) for i in range(n)]


def time_neighbors(start: Sequence[int], end: Sequence[int]) -> list[list[int]]:
    """For each block, the other blocks whose closed lifetime ``[start, end]`` overlaps
    its own, ascending by index."""
    n = len(start)
    if n < SWEEP_FROM:
        return _rows(time_overlaps(start, end))
    neighbors: list[list[int]] = [[] for _ in range(n)]
    active: list[tuple[int, int]] = []  # heap of (end, block) of blocks begun so far
    live: set[int] = set()
    for i in sorted(range(n), key=start.__getitem__):
        s = start[i]
        while active and active[0][0] < s:
            live.discard(heappop(active)[1])
        row = neighbors[i]
        for j in live:
            row.append(j)
            neighbors[j].append(i)
        live.add(i)
        heappush(active, (end[i], i))
    for row in neighbors:
        row.sort()
    return neighbors


def sections(start: Sequence[int], end: Sequence[int]) -> tuple[list[int], list[int], int]:
    """``(sec_lo, sec_hi, count)``: the sections (time ranges between consecutive starts
    and ends + 1 of any block) that each closed lifetime ``[start, end]`` covers,
    ``sec_lo[i] .. sec_hi[i]-1``, and how many sections there are."""
    starts = np.asarray(start, dtype=np.int64)
    after = np.asarray(end, dtype=np.int64) + 1
    coords = np.concatenate((starts, after))
    coords.sort()
    if len(coords):
        coords = coords[np.concatenate(([True], coords[1:] != coords[:-1]))]  # distinct (np.unique: slower)
    return (np.searchsorted(coords, starts).tolist(), np.searchsorted(coords, after).tolist(),
            max(len(coords) - 1, 0))


def _conflict_graph(blocks: Sequence[Block], start: list[int], end: list[int],
                    conflicts: Mapping[str, Collection[str]] | None) -> tuple[np.ndarray | None, list[list[int]] | None, bool]:
    """``Instance.build``'s ``(adjacency, rows, separable)``: the conflict matrix below
    :data:`SWEEP_FROM` blocks (``rgraph/memory/_fit.pyx``'s ``conflict_matrix`` makes the
    same), else the neighbour lists; ``separable``: every conflicting pair overlaps in time."""
    ks: list[int] = []  # conflicting pairs (k, j), some of them overlapping in time as well
    js: list[int] = []
    if conflicts:
        index = {b.name: k for k, b in enumerate(blocks)}
        here = set(index)
        at = index.__getitem__
        for name in here.intersection(conflicts):  # any order: only the set of pairs counts
            found = here.intersection(conflicts[name])  # the conflicting blocks of this class
            found.discard(name)
            ks.extend([at(name)] * len(found))
            js.extend(map(at, found))
    separable = True
    adjacency, rows = None, None
    if len(blocks) < SWEEP_FROM:
        adjacency = time_overlaps(start, end)
        if ks:  # pairs apart in time (not overlapping): beyond what the time sections see
            pairs = (np.array(ks, dtype=np.intp), np.array(js, dtype=np.intp))
            separable = bool(adjacency[pairs].all())
            if not separable:
                adjacency[pairs] = True  # those overlapping in time are already
    else:
        if ks:  # pairs apart in time: beyond what the time sections see
            starts, ends = np.asarray(start, dtype=np.int64), np.asarray(end, dtype=np.int64)
            apart = (starts[js] > ends[ks]) | (ends[js] < starts[ks])
            separable = not apart.any()
        rows = time_neighbors(start, end)
        if not separable:
            by_block: dict[int, set[int]] = {}
            for k, j, far in zip(ks, js, apart.tolist(), strict=True):
                if far:
                    by_block.setdefault(k, set()).add(j)
            for k, extra in by_block.items():
                rows[k] = sorted(rows[k] + list(extra))
    return adjacency, rows, separable


@dataclass
class Instance:
    """Blocks of one memory class, indexed 0..n-1 in input order.

    Sections are the maximal time ranges in which the set of live blocks does not change;
    block ``i`` lives in sections ``sec_lo[i] .. sec_hi[i]-1``. Pairs that may not share
    bytes are kept as a boolean matrix below :data:`SWEEP_FROM` blocks (``neighbors``, the
    lists, are then made when first asked for: dense conflict graphs need only the few
    non-neighbours), as lists from a sweep above.
    """

    blocks: list[Block]
    start: list[int]
    end: list[int]
    size: list[int]  # aligned sizes
    align: list[int]
    sec_lo: list[int]
    sec_hi: list[int]
    section_count: int
    separable: bool = True  # no overlaps beyond the time ones: parts split in time are independent
    adjacency: np.ndarray | None = field(default=None, compare=False, repr=False)  # ``[i, j]``: i and j may not share bytes (None: lists only)
    rows: list[list[int]] | None = field(default=None, compare=False, repr=False)  # the neighbour lists, when built by the sweep

    @property
    def n(self) -> int:
        return len(self.blocks)

    @classmethod
    def build(cls, blocks: Sequence[Block], conflicts: Mapping[str, Collection[str]] | None = None) -> Instance:
        """``conflicts``: pairs of block names that may not share bytes although they are
        apart in time (symmetric), added to ``neighbors``."""
        blocks = list(blocks)
        arrays = None
        if _NATIVE is not None:
            try:  # the lists, the sections and their totals, compiled
                arrays = _NATIVE.class_arrays(blocks)
            except OverflowError:  # past 62 bits
                pass
        if arrays is None:
            start = [b.start for b in blocks]
            end = [b.end for b in blocks]
        else:
            start, end = arrays[0], arrays[1]
        adjacency, rows, separable = None, None, True
        if len(blocks) < SWEEP_FROM and _NATIVE is not None:
            try:  # the same matrix, compiled
                adjacency, separable = _NATIVE.conflict_matrix(start, end, [b.name for b in blocks], conflicts)
            except OverflowError:  # times past 64 bits
                pass
        if adjacency is None:
            adjacency, rows, separable = _conflict_graph(blocks, start, end, conflicts)
        if arrays is not None:
            _, _, size, align, sec_lo, sec_hi, section_count, totals = arrays
            inst = cls(blocks=blocks, start=start, end=end, size=size, align=align, sec_lo=sec_lo,
                       sec_hi=sec_hi, section_count=section_count, separable=separable,
                       adjacency=adjacency, rows=rows)
            inst.__dict__["_totals"] = totals  # the cached property, already computed
            return inst
        sec_lo, sec_hi, section_count = sections(start, end)
        return cls(
            blocks=blocks,
            start=start,
            end=end,
            size=[b.aligned_size for b in blocks],
            align=[b.alignment for b in blocks],
            sec_lo=sec_lo,
            sec_hi=sec_hi,
            section_count=section_count,
            separable=separable,
            adjacency=adjacency,
            rows=rows,
        )

    @cached_property
    def neighbors(self) -> list[list[int]]:
        """For each block, the blocks it may not share bytes with (overlapping in time or
        conflicting), ascending index."""
        if self.rows is not None:
            return self.rows
        assert self.adjacency is not None
        return _rows(self.adjacency)

    def neighbor_row(self, i: int) -> list[int]:
        """``neighbors[i]`` without building every list."""
        if "neighbors" in self.__dict__ or self.adjacency is None:
            return self.neighbors[i]
        return np.flatnonzero(self.adjacency[i]).tolist()

    @cached_property
    def degree(self) -> list[int]:
        """How many neighbours each block has."""
        if self.adjacency is not None:
            return self.adjacency.sum(axis=1).tolist()
        return [len(row) for row in self.neighbors]

    @cached_property
    def neg_width(self) -> list[int]:
        """Minus each block's lifetime in passes (preorder sort keys, descending)."""
        return [s - e - 1 for s, e in zip(self.start, self.end, strict=True)]

    @cached_property
    def neg_area(self) -> list[int]:
        return [w * z for w, z in zip(self.neg_width, self.size, strict=True)]

    @cached_property
    def neg_size(self) -> list[int]:
        return [-z for z in self.size]

    @cached_property
    def order_keys(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """``start``, ``neg_size``, ``neg_area`` and ``neg_width`` as int64 arrays (the greedy
        orderings' sort keys), or None where one of them passes 63 bits."""
        if not self.n:
            return None
        try:
            start = np.asarray(self.start, dtype=np.int64)
            end = np.asarray(self.end, dtype=np.int64)
            size = np.asarray(self.size, dtype=np.int64)
        except OverflowError:
            return None
        width = int(end.max()) - int(start.min()) + 1  # at least every lifetime's
        if width * max(int(size.max()), 1) >= 1 << 62:
            return None
        neg_width = start - end - 1
        return start, -size, neg_width * size, neg_width

    @cached_property
    def members(self) -> np.ndarray:
        """``members[s, i]``: block ``i`` lives in section ``s``."""
        matrix = np.zeros((self.section_count, self.n), dtype=bool)
        for i in range(self.n):
            matrix[self.sec_lo[i] : self.sec_hi[i], i] = True
        return matrix

    @cached_property
    def section_blocks(self) -> list[list[int]]:
        """``section_blocks[s]``: the blocks live in section ``s``, ascending."""
        rows: list[list[int]] = [[] for _ in range(self.section_count)]
        for i in range(self.n):
            for s in range(self.sec_lo[i], self.sec_hi[i]):
                rows[s].append(i)
        return rows

    def section_totals(self) -> list[int]:
        """Aligned bytes alive in each section (a new list: the searches update theirs)."""
        return list(self._totals)

    @cached_property
    def _totals(self) -> tuple[int, ...]:
        """``section_totals``, computed once (the greedy orderings, the bounds and the
        searches each ask)."""
        diff = [0] * (self.section_count + 1)
        for lo, hi, z in zip(self.sec_lo, self.sec_hi, self.size, strict=True):
            diff[lo] += z
            diff[hi] -= z
        return tuple(accumulate(diff[: self.section_count]))

    @cached_property
    def pair_count(self) -> int:
        """Ordered pairs of blocks that may not share bytes (the neighbour lists' total)."""
        return sum(self.degree)

    @cached_property
    def far(self) -> list[set[int]]:
        """For each block, the blocks, itself included, that it may share bytes with."""
        if self.adjacency is not None:
            return _rows(~self.adjacency, set)
        everything = range(self.n)
        return [set(everything).difference(row) for row in self.neighbors]

    def non_neighbors(self, i: int) -> set[int]:
        """The blocks, ``i`` included, that ``i`` may share bytes with."""
        return self.far[i]

    @cached_property
    def accelerated(self) -> dict[str, Any]:
        """Flat copies of this instance made by the compiled accelerators (``rgraph.native``),
        by use (e.g. ``"dive"``: ``rgraph.memory._dive.Flat``), kept for the next call."""
        return {}

    def lower_bound(self) -> int:
        return max(self.section_totals(), default=0)

    def peak(self, offsets: Sequence[int]) -> int:
        """The highest top of ``offsets`` (one per block); compiled where built."""
        if _NATIVE is not None and len(offsets) == self.n:
            try:
                return _NATIVE.peak(offsets, self.size)  # type: ignore[no-any-return]
            except OverflowError:  # past 62 bits
                pass
        return max(map(add, offsets, self.size), default=0)
