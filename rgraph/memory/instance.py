"""One memory class's blocks as flat arrays, with time overlaps and sections precomputed."""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from heapq import heappop, heappush

import numpy as np

from rgraph.memory.model import Block

#: From this many blocks, neighbours come from a sweep over start times (cost in the pairs
#: found) instead of one numpy row per block (cost n**2, cheap per element).
SWEEP_FROM = 1500


def time_neighbors(start: Sequence[int], end: Sequence[int]) -> list[list[int]]:
    """For each block, the other blocks whose closed lifetime ``[start, end]`` overlaps
    its own, ascending by index."""
    n = len(start)
    if n < SWEEP_FROM:
        starts = np.asarray(start, dtype=np.int64)
        ends = np.asarray(end, dtype=np.int64)
        overlap = (starts[:, None] <= ends[None, :]) & (ends[:, None] >= starts[None, :])
        np.fill_diagonal(overlap, False)
        columns = np.nonzero(overlap)[1].tolist()  # row by row, ascending within a row
        bounds = np.concatenate(([0], np.cumsum(overlap.sum(axis=1)))).tolist()
        return [columns[bounds[i] : bounds[i + 1]] for i in range(n)]
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


@dataclass
class Instance:
    """Blocks of one memory class, indexed 0..n-1 in input order.

    Sections are the maximal time ranges in which the set of live blocks does not change;
    block ``i`` lives in sections ``sec_lo[i] .. sec_hi[i]-1``.
    """

    blocks: list[Block]
    start: list[int]
    end: list[int]
    size: list[int]  # aligned sizes
    align: list[int]
    neighbors: list[list[int]]  # blocks overlapping in time, ascending index
    sec_lo: list[int]
    sec_hi: list[int]
    section_count: int
    separable: bool = True  # no overlaps beyond the time ones: parts split in time are independent

    @property
    def n(self) -> int:
        return len(self.blocks)

    @classmethod
    def build(cls, blocks: Sequence[Block], conflicts: Mapping[str, Collection[str]] | None = None) -> Instance:
        """``conflicts``: pairs of block names that may not share bytes although they are
        apart in time (symmetric), added to ``neighbors``."""
        blocks = list(blocks)
        start = [b.start for b in blocks]
        end = [b.end for b in blocks]
        neighbors = time_neighbors(start, end)
        separable = True
        if conflicts:
            index = {b.name: k for k, b in enumerate(blocks)}
            for k, b in enumerate(blocks):
                names = conflicts.get(b.name)
                if not names:
                    continue
                s, e = start[k], end[k]
                # conflicts apart in time (those overlapping it are neighbours already)
                extra = {j for j in map(index.get, names) if j is not None and (start[j] > e or end[j] < s)}
                if extra:
                    neighbors[k] = sorted(neighbors[k] + list(extra))
                    separable = False
        coords = sorted(set(start) | {e + 1 for e in end})
        sec_lo = [bisect_left(coords, s) for s in start]
        sec_hi = [bisect_left(coords, e + 1) for e in end]
        return cls(
            blocks=blocks,
            start=start,
            end=end,
            size=[b.aligned_size for b in blocks],
            align=[b.alignment for b in blocks],
            neighbors=neighbors,
            sec_lo=sec_lo,
            sec_hi=sec_hi,
            section_count=max(len(coords) - 1, 0),
            separable=separable,
        )

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
        """Aligned bytes alive in each section."""
        diff = [0] * (self.section_count + 1)
        for i in range(self.n):
            diff[self.sec_lo[i]] += self.size[i]
            diff[self.sec_hi[i]] -= self.size[i]
        totals, running = [], 0
        for k in range(self.section_count):
            running += diff[k]
            totals.append(running)
        return totals

    @cached_property
    def pair_count(self) -> int:
        """Ordered pairs of blocks that may not share bytes (the neighbour lists' total)."""
        return sum(map(len, self.neighbors))

    def non_neighbors(self, i: int) -> set[int]:
        """The blocks, ``i`` included, that ``i`` may share bytes with (cached)."""
        cache = self.__dict__.setdefault("_non_neighbors", {})
        far = cache.get(i)
        if far is None:
            far = cache[i] = set(range(self.n)).difference(self.neighbors[i])
        return far

    def lower_bound(self) -> int:
        return max(self.section_totals(), default=0)

    def peak(self, offsets: Sequence[int]) -> int:
        return max((offsets[i] + self.size[i] for i in range(self.n)), default=0)
