"""Exact placement search: MiniMalloc's solver (Moffitt, ASPLOS 2023) in plain Python.

Decides whether the blocks fit under a capacity ``C`` by depth-first search over
*canonical* solutions: blocks are placed in non-decreasing (offset, preorder rank) order,
each at its lowest feasible offset (the highest top of the placed blocks it overlaps in
time). As in MiniMalloc's ``solver.cc`` (``SearchSolutions``):

- dynamic ordering: the candidates are the unplaced blocks of the current partition by
  (minimum offset, preorder rank); canonical: none below the offset (and rank) placed last;
- dominance: none at or above the lowest top any unplaced block could reach (that would
  leave a gap the block could fill);
- section inference (``Check``): every section of the partition must hold its floor plus
  the bytes still to place in it within ``C``; the floor is the highest of the current
  offset (monotonic floor), the top of the block just placed in its sections, and the
  lowest minimum offset of the section's unplaced blocks (unallocated floor) in the
  sections of blocks pushed up. Only sections whose data changed are re-checked; the rest
  passed at the parent and only got looser;
- hatless pruning: when the block placed has no unplaced block overlapping it in time and
  its subtree fails, no sibling is tried (any completion places it exactly there);
- dynamic temporal decomposition: each section boundary counts the unplaced blocks living
  on both sides; when a placement drops counts to zero, the blocks still to place split
  into independent partitions, each preordered afresh (with the section totals of the
  moment) and solved in turn; one failing fails the node.

A node is plain Python over integer lists (no per-node objects beyond small lists); the
search is cut off after a fixed number of nodes (counted, as in MiniMalloc, per
``SearchSolutions`` call), so results never depend on machine speed.
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


def preorder(inst: Instance, heuristic: str, blocks: Sequence[int] | None = None,
             totals: Sequence[int] | None = None) -> list[int]:
    """``blocks`` (default: all) sorted by ``heuristic`` (letters of W, A, T, Z; all
    descending, ties by index) with section totals ``totals`` (default: all blocks')."""
    totals = inst.section_totals() if totals is None else totals
    blocks = range(inst.n) if blocks is None else blocks
    lo, hi = inst.sec_lo, inst.sec_hi
    columns = []
    for c in heuristic:
        if c == "T":
            columns.append([-max(totals[lo[i] : hi[i]]) for i in blocks])  # every block spans a section
        else:
            field = {"W": inst.neg_width, "A": inst.neg_area, "Z": inst.neg_size}[c]
            columns.append([field[i] for i in blocks])
    return [i for *_, i in sorted(zip(*columns, blocks, strict=True))]


class CapacitySearch:
    """One decision search: place all blocks of ``inst`` within ``capacity`` bytes.

    ``order`` is the static preorder; with ``heuristic`` set, every partition made by
    decomposition is preordered again by it (MiniMalloc's ``SubSolve``)."""

    def __init__(self, inst: Instance, order: Sequence[int], capacity: int, node_limit: int,
                 heuristic: str | None = None, work_limit: int | None = None):
        self.inst = inst
        self.capacity = capacity
        self.heuristic = heuristic
        self.nodes_left = node_limit
        self.work = 0  # nodes visited by the last run
        #: Operations spent (unplaced blocks scanned per node, neighbours and sections per
        #: candidate): a machine-independent measure of time, capped by ``work_limit``.
        self.ops = 0
        self.ops_limit = work_limit if work_limit is not None else 1 << 62
        self.exhausted = False
        self.rank = [0] * inst.n
        for r, i in enumerate(order):
            self.rank[i] = r
        # Zero-size blocks occupy nothing: they go at offset 0 outside the search.
        self.order = [i for i in order if inst.size[i] > 0]
        self.offsets = [0 if inst.size[i] == 0 else -1 for i in range(inst.n)]
        self.min_off = [0] * inst.n
        self.total = inst.section_totals()
        # witness[s]: a block of section s that passed its floor check last (a hint only).
        self.witness = [row[0] if row else 0 for row in inst.section_blocks]
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
            points = [s + 1 for s, c in enumerate(self.cuts) if c == 0] if self.inst.separable else []
            found = self._split(self.order, 0, self.inst.section_count, points, static=True)
        except _OutOfNodes:
            self.exhausted = True
            return None
        finally:
            sys.setrecursionlimit(limit)
            self.work = start_budget - self.nodes_left
        return list(self.offsets) if found else None

    def _split(self, unplaced: list[int], lo: int, hi: int, points: list[int], static: bool = False) -> bool:
        """Solve the blocks ``unplaced`` living in sections ``lo..hi-1``, one partition per
        run of sections between the cut ``points``, in turn. On failure, all is undone."""
        if not unplaced:
            return True
        bounds = [lo, *points, hi]
        sec_lo = self.inst.sec_lo
        parts: list[list[int]] = [[] for _ in range(len(bounds) - 1)]
        for i in unplaced:
            parts[bisect_right(bounds, sec_lo[i]) - 1].append(i)
        reorder = self.heuristic is not None and not static
        saved = (list(self.offsets), list(self.min_off), list(self.total), list(self.cuts),
                 list(self.rank) if reorder else None)
        for k, part in enumerate(parts):
            if not part:
                continue
            if reorder:
                if len(part) > 1:
                    part = preorder(self.inst, self.heuristic, part, self.total)  # type: ignore[arg-type]
                for r, i in enumerate(part):
                    self.rank[i] = r
            if not self._dfs(part, bounds[k], bounds[k + 1], 0, -1):
                self.offsets[:], self.min_off[:], self.total[:], self.cuts[:] = saved[:4]
                if saved[4] is not None:
                    self.rank[:] = saved[4]
                return False
        return True

    def _dfs(self, unplaced: list[int], plo: int, phi: int, last_off: int, last_rank: int) -> bool:
        if self.nodes_left <= 0 or self.ops >= self.ops_limit:
            raise _OutOfNodes
        self.nodes_left -= 1
        if not unplaced:
            return True
        ops = len(unplaced)
        inst, mins, rank, offsets = self.inst, self.min_off, self.rank, self.offsets
        size, align, neighbors, sec_lo, sec_hi = inst.size, inst.align, inst.neighbors, inst.sec_lo, inst.sec_hi
        total, capacity, cuts = self.total, self.capacity, self.cuts
        min_height = min([mins[i] + size[i] for i in unplaced])
        candidates = [
            i
            for i in unplaced
            if last_off <= mins[i] < min_height and (mins[i] > last_off or rank[i] > last_rank)
        ]
        candidates.sort(key=mins.__getitem__)  # stable: ties keep preorder rank
        # Monotonic floor: everything left goes at or above the offset placed next.
        headroom = capacity - max(total[plo:phi])
        rows, witness = inst.section_blocks, self.witness
        for i in candidates:
            off = mins[i]
            if off > headroom:
                break  # later candidates are no lower
            top = off + size[i]
            offsets[i] = off
            position = unplaced.index(i)
            del unplaced[position]
            ok = True
            hat = False
            changed: list[int] = []
            olds: list[int] = []
            first, last = sec_lo[i], sec_hi[i]
            for j in neighbors[i]:
                if offsets[j] >= 0:
                    continue
                hat = True
                old = mins[j]
                if old < top:
                    a = align[j]
                    new = top if top % a == 0 else top + a - top % a
                    mins[j] = new
                    changed.append(j)
                    olds.append(old)
                    if new + size[j] > capacity:
                        ok = False
                    if sec_lo[j] < first:
                        first = sec_lo[j]
                    if sec_hi[j] > last:
                        last = sec_hi[j]
            lo, hi = sec_lo[i], sec_hi[i]
            ops += len(neighbors[i]) + last - first
            z = size[i]
            for s in range(lo, hi):
                total[s] -= z
            if ok and changed:
                # Unallocated floor: in the sections of the blocks pushed up, the lowest
                # minimum offset of an unplaced block plus the bytes left must fit.
                for s in range(first, last):
                    left = total[s]
                    if left:
                        threshold = capacity - left
                        w = witness[s]  # the block that passed this section last, if still low enough
                        if offsets[w] < 0 and mins[w] <= threshold:
                            continue
                        for j in rows[s]:
                            if offsets[j] < 0 and mins[j] <= threshold:
                                witness[s] = j
                                break
                        else:
                            ok = False
                            break
            split: list[int] = []
            for s in range(lo, hi - 1):
                cuts[s] -= 1
                if not cuts[s]:
                    split.append(s + 1)
            if ok:
                self.ops += ops
                ops = 0
                if split and inst.separable:
                    ok = self._split(unplaced, plo, phi, split)
                else:
                    ok = self._dfs(unplaced, plo, phi, off, rank[i])
                if ok:
                    return True
            for s in range(lo, hi - 1):
                cuts[s] += 1
            for s in range(lo, hi):
                total[s] += z
            for j, old in zip(changed, olds, strict=True):
                mins[j] = old
            unplaced.insert(position, i)
            offsets[i] = -1
            if not hat:
                break  # hatless: any completion would place this block here too
        self.ops += ops
        return False


def solve_capacity(inst: Instance, capacity: int, ops_budget: int, rounds: int | None = None,
                   orders: Sequence[Sequence[int]] | None = None,
                   heuristics: Sequence[str] = PREORDERINGS,
                   first_limit: float = 2.0) -> tuple[list[int] | None, int, bool]:
    """MiniMalloc's round robin (``RoundRobin`` in solver.cc): each heuristic in turn with
    a node limit that starts at ``2 n`` and doubles each round, until one finds a placement
    or proves there is none, ``rounds`` rounds are done or ``ops_budget`` operations are
    spent. ``orders``: the heuristics' static preorders, if already computed.
    Returns (offsets or None, operations spent, proven infeasible)."""
    orders = [preorder(inst, h) for h in heuristics] if orders is None else orders
    limit, spent, done = first_limit * max(inst.n, 1) / 2, 0, 0
    while spent < ops_budget and (rounds is None or done < rounds):
        limit *= 2
        done += 1
        for h, order in zip(heuristics, orders, strict=True):
            if spent >= ops_budget:
                break
            run = CapacitySearch(inst, order, capacity, int(limit), h, ops_budget - spent)
            found = run.run()
            spent += max(run.ops, 1)
            if found is not None:
                return found, spent, False
            if not run.exhausted:
                return None, spent, True
    return None, spent, False
