"""Exact placement search in the style of MiniMalloc (Moffitt, ASPLOS 2023).

Decides whether the blocks fit under a capacity ``C`` by depth-first search over
*canonical* solutions: blocks are placed in non-decreasing (offset, preorder rank) order,
each at its lowest feasible offset (the highest top of the placed blocks it overlaps in
time). At each node the candidates are the unplaced blocks whose minimum offset is below
the lowest top any unplaced block could reach (placing anything higher would leave a gap
that block could fill: dominated). A partial solution is pruned when some section's floor
plus the bytes still to place in it exceeds ``C``.

The search is cut off after a fixed number of nodes, so results never depend on machine
speed.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import numpy as np

from rgraph.memory.instance import Instance

#: Static preorderings (MiniMalloc's defaults): W = lifetime width, A = area,
#: T = the largest live total among the block's sections. All descending.
PREORDERINGS = ("WAT", "TAW", "TWA")


_HUGE = np.iinfo(np.int64).max // 4


class _OutOfNodes(Exception):
    pass


def preorder(inst: Instance, heuristic: str) -> list[int]:
    totals = inst.section_totals()
    width = [inst.end[i] - inst.start[i] + 1 for i in range(inst.n)]
    area = [inst.size[i] * width[i] for i in range(inst.n)]
    total = [max(totals[inst.sec_lo[i] : inst.sec_hi[i]], default=0) for i in range(inst.n)]
    fields = {"W": width, "A": area, "T": total, "Z": inst.size}

    def key(i: int) -> tuple:
        return tuple(-fields[c][i] for c in heuristic) + (i,)

    return sorted(range(inst.n), key=key)


class CapacitySearch:
    """One decision search: place all blocks of ``inst`` within ``capacity`` bytes."""

    def __init__(self, inst: Instance, order: Sequence[int], capacity: int, node_limit: int):
        self.inst = inst
        self.capacity = capacity
        self.nodes_left = node_limit
        self.nodes = 0
        self.rank = [0] * inst.n
        for r, i in enumerate(order):
            self.rank[i] = r
        # Zero-size blocks occupy nothing: they go at offset 0 outside the search.
        self.unplaced = [i for i in order if inst.size[i] > 0]
        self.offsets = [0 if inst.size[i] == 0 else -1 for i in range(inst.n)]
        self.min_off = [0] * inst.n
        self.floor = np.zeros(inst.section_count, dtype=np.int64)
        self.total = np.asarray(inst.section_totals(), dtype=np.int64)
        self.members = inst.members
        self.pending_min = np.zeros(inst.n, dtype=np.int64)  # min_off, or a huge value once placed
        for i in range(inst.n):
            if inst.size[i] == 0:
                self.pending_min[i] = _HUGE
        # Lowest minimum offset of the unplaced blocks in each section (0 when none).
        self.pending_floor = np.zeros(inst.section_count, dtype=np.int64)

    def run(self) -> list[int] | None:
        """Offsets if a placement within capacity was found; None if none exists or the
        node limit ran out (see ``exhausted``)."""
        self.exhausted = False
        start_budget = self.nodes_left
        if self.total.size and int(self.total.max()) > self.capacity:
            return None
        limit = sys.getrecursionlimit()
        sys.setrecursionlimit(max(limit, 4 * self.inst.n + 1000))
        try:
            found = self._dfs(0, -1)
        except _OutOfNodes:
            self.exhausted = True
            return None
        finally:
            sys.setrecursionlimit(limit)
            self.work = start_budget - self.nodes_left
        return list(self.offsets) if found else None

    def _dfs(self, last_off: int, last_rank: int) -> bool:
        if self.nodes_left <= 0:
            raise _OutOfNodes
        self.nodes += 1
        unplaced = self.unplaced
        if not unplaced:
            return True
        inst, min_off, rank = self.inst, self.min_off, self.rank
        size, align, neighbors, offsets = inst.size, inst.align, inst.neighbors, self.offsets
        min_height = min(min_off[i] + size[i] for i in unplaced)
        candidates = sorted(
            (min_off[i], rank[i], i)
            for i in unplaced
            if min_off[i] < min_height and (min_off[i] > last_off or (min_off[i] == last_off and rank[i] > last_rank))
        )
        floor, total, capacity = self.floor, self.total, self.capacity
        for off, r, i in candidates:
            top = off + size[i]
            offsets[i] = off
            position = unplaced.index(i)
            del unplaced[position]
            changed = []
            for j in neighbors[i]:
                if offsets[j] < 0 and min_off[j] < top:
                    changed.append((j, min_off[j]))
                    a = align[j]
                    min_off[j] = top if top % a == 0 else top + a - top % a
            lo, hi = inst.sec_lo[i], inst.sec_hi[i]
            saved_floor = floor[lo:hi].copy()
            floor[lo:hi] = top
            total[lo:hi] -= size[i]
            pending = self.pending_min
            pending[i] = _HUGE
            rows_lo, rows_hi = lo, hi
            for j, _ in changed:
                pending[j] = min_off[j]
                rows_lo = min(rows_lo, inst.sec_lo[j])
                rows_hi = max(rows_hi, inst.sec_hi[j])
            pending_floor = self.pending_floor
            saved_pending_floor = pending_floor[rows_lo:rows_hi].copy()
            lowest = np.where(self.members[rows_lo:rows_hi], pending, _HUGE).min(axis=1)
            lowest[lowest == _HUGE] = 0
            pending_floor[rows_lo:rows_hi] = lowest
            bottom = np.maximum(np.maximum(floor, pending_floor), off)
            ok = not (bottom + total > capacity).any()
            self.nodes_left -= 1
            if ok and self._dfs(off, r):
                return True
            floor[lo:hi] = saved_floor
            pending_floor[rows_lo:rows_hi] = saved_pending_floor
            total[lo:hi] += size[i]
            for j, old in reversed(changed):
                min_off[j] = old
                pending[j] = old
            pending[i] = min_off[i]
            unplaced.insert(position, i)
            offsets[i] = -1
        return False
