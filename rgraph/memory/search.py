"""Exact placement search in the style of MiniMalloc (Moffitt, ASPLOS 2023).

Decides whether the blocks fit under a capacity ``C`` by depth-first search over
*canonical* solutions: blocks are placed in non-decreasing (offset, preorder rank) order,
each at its lowest feasible offset (the highest top of the placed blocks it overlaps in
time). At each node the candidates are the unplaced blocks whose minimum offset is below
the lowest top any unplaced block could reach (placing anything higher would leave a gap
that block could fill: dominated). Inference prunes a partial solution when

- some section touched by the block just placed has its new floor plus the bytes still to
  place in it above ``C``;
- the current offset plus the most bytes still to place in any one section is above ``C``
  (everything left goes at or above the current offset);
- a block pushed up by the block just placed no longer fits under ``C``.

A node is plain Python over lists (no per-node array allocation), so its cost grows with
the number of unplaced blocks and the neighbours of the block placed. The search is cut
off after a fixed number of nodes, so results never depend on machine speed.
"""

from __future__ import annotations

import sys
from bisect import bisect_right
from collections.abc import Sequence

from rgraph.memory.instance import Instance

#: Static preorderings (MiniMalloc's defaults): W = lifetime width, A = area,
#: T = the largest live total among the block's sections. All descending.
PREORDERINGS = ("WAT", "TAW", "TWA")


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
        self.work = 0
        self.exhausted = False
        self.rank = [0] * inst.n
        for r, i in enumerate(order):
            self.rank[i] = r
        # Zero-size blocks occupy nothing: they go at offset 0 outside the search.
        self.order = [i for i in order if inst.size[i] > 0]
        self.offsets = [0 if inst.size[i] == 0 else -1 for i in range(inst.n)]
        self.min_off = [0] * inst.n
        self.floor = [0] * inst.section_count
        self.total = inst.section_totals()
        # cuts[s]: unplaced blocks living in both section s and s + 1.
        self.cuts = [0] * max(inst.section_count - 1, 0)
        for i in self.order:
            for s in range(inst.sec_lo[i], inst.sec_hi[i] - 1):
                self.cuts[s] += 1

    def run(self) -> list[int] | None:
        """Offsets if a placement within capacity was found; None if none exists or the
        node limit ran out (see ``exhausted``)."""
        self.exhausted = False
        start_budget = self.nodes_left
        if max(self.total, default=0) > self.capacity:
            return None
        limit = sys.getrecursionlimit()
        sys.setrecursionlimit(max(limit, 8 * self.inst.n + 1000))
        try:
            found = self._split(self.order, 0, self.inst.section_count)
        except _OutOfNodes:
            self.exhausted = True
            return None
        finally:
            sys.setrecursionlimit(limit)
            self.work = start_budget - self.nodes_left
        return list(self.offsets) if found else None

    def _split(self, unplaced: list[int], lo: int, hi: int) -> bool:
        """Solve the blocks ``unplaced`` (preorder) living in sections ``lo..hi-1``, one
        independent part per run of sections joined by a block still to place (MiniMalloc's
        dynamic temporal decomposition). On failure, every part is undone."""
        if not unplaced:
            return True
        cuts, sec_lo = self.cuts, self.inst.sec_lo
        points = [s + 1 for s in range(lo, hi - 1) if cuts[s] == 0] if self.inst.separable else []
        if not points:
            return self._dfs(unplaced, lo, hi, 0, -1)
        bounds = [lo, *points, hi]
        parts: list[list[int]] = [[] for _ in range(len(bounds) - 1)]
        for i in unplaced:
            parts[bisect_right(bounds, sec_lo[i]) - 1].append(i)
        saved = (list(self.offsets), list(self.min_off), list(self.floor), list(self.total))
        for k, part in enumerate(parts):
            if part and not self._dfs(part, bounds[k], bounds[k + 1], 0, -1):
                self.offsets[:], self.min_off[:], self.floor[:], self.total[:] = saved
                return False
        return True

    def _dfs(self, unplaced: list[int], plo: int, phi: int, last_off: int, last_rank: int) -> bool:
        if not unplaced:
            return True
        if self.nodes_left <= 0:
            raise _OutOfNodes
        inst, mins, rank, offsets = self.inst, self.min_off, self.rank, self.offsets
        size, align, neighbors = inst.size, inst.align, inst.neighbors
        floor, total, capacity, cuts = self.floor, self.total, self.capacity, self.cuts
        min_height = min([mins[i] + size[i] for i in unplaced])
        candidates = [
            i
            for i in unplaced
            if last_off <= mins[i] < min_height and (mins[i] > last_off or rank[i] > last_rank)
        ]
        candidates.sort(key=mins.__getitem__)  # stable: ties keep preorder rank
        headroom = capacity - max(total[plo:phi])
        for i in candidates:
            off = mins[i]
            if off > headroom:
                break  # everything left goes at or above off; later candidates are higher
            top = off + size[i]
            self.nodes_left -= 1
            offsets[i] = off
            position = unplaced.index(i)
            del unplaced[position]
            ok = True
            changed = []
            for j in neighbors[i]:
                old = mins[j]
                if old < top and offsets[j] < 0:
                    a = align[j]
                    new = top if top % a == 0 else top + a - top % a
                    mins[j] = new
                    changed.append((j, old))
                    if new + size[j] > capacity:
                        ok = False
            lo, hi = inst.sec_lo[i], inst.sec_hi[i]
            if ok and changed:
                ok = self._pending_ok(changed, lo, hi)
            saved = floor[lo:hi]
            z = size[i]
            split = False
            for s in range(lo, hi):
                floor[s] = top
                left = total[s] - z
                total[s] = left
                if top + left > capacity:
                    ok = False
            for s in range(lo, hi - 1):
                cuts[s] -= 1
                if not cuts[s]:
                    split = inst.separable
            if ok and (self._split(unplaced, plo, phi) if split else self._dfs(unplaced, plo, phi, off, rank[i])):
                return True
            for s in range(lo, hi - 1):
                cuts[s] += 1
            floor[lo:hi] = saved
            for s in range(lo, hi):
                total[s] += z
            for j, old in changed:
                mins[j] = old
            unplaced.insert(position, i)
            offsets[i] = -1
        return False

    def _pending_ok(self, changed: list[tuple[int, int]], lo: int, hi: int) -> bool:
        """Sections outside ``lo..hi`` that a pushed-up block lives in: the lowest minimum
        offset of their unplaced blocks plus their bytes still to place must fit."""
        inst, mins, offsets = self.inst, self.min_off, self.offsets
        first = min(inst.sec_lo[j] for j, _ in changed)
        last = max(inst.sec_hi[j] for j, _ in changed)
        rows, total, capacity = inst.section_blocks, self.total, self.capacity
        for s in (*range(first, lo), *range(hi, last)):
            left = total[s]
            if not left:
                continue
            threshold = capacity - left
            for j in rows[s]:
                if mins[j] <= threshold and offsets[j] < 0:
                    break
            else:
                return False
        return True
