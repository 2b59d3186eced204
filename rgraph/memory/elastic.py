"""Elastic dives: MiniMalloc's search without backtracking, raising the capacity instead.

One dive places the blocks in canonical order, as the first path of MiniMalloc's depth-first
search (``rgraph.memory.search``) would: at each step the candidates are the unplaced blocks
by (lowest offset, preorder rank), none at or above the lowest top an unplaced block could
reach (dominance); a candidate is accepted when the section inference passes at the current
capacity ``C`` (no block pushed above ``C``; in every section whose data changed, the lowest
offset an unplaced block could take plus the bytes still to place there fits in ``C``).
Where the search would backtrack (no candidate passes), the dive raises ``C`` to the least
capacity that one of the first :data:`CANDIDATES` candidates needs and places that one.
A candidate placed above lower ones lifts them to its offset (monotonic floor), so the dive
never dead-ends. Started at the lower bound, the capacity only rises where the packing
needs it, so the peak lands close to what the packing of the lower sections allows.

``improve`` repeats dives, each time moving the blocks that were still to place in the
sections that forced a raise to the front of the preorder (squeaky wheel: they get the
low offsets next time), round robin over chains started from different preorders.

Work is counted in operations (weighted: :data:`STEP_OPS`), so results do not depend on the
machine. The dives run compiled (``rgraph/memory/_dive.pyx``, same results and operations)
where built; their operations are granted at ``aliased.DIVE_OPS_PER_SECOND``, the search's at
``aliased.OPS_PER_SECOND``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType

from rgraph.memory.instance import Instance
from rgraph.native import load

#: The compiled mirror of :func:`dive_python` (``rgraph/memory/_dive.pyx``), None where it is
#: not built or ``RGRAPH_NATIVE=0``: then :func:`dive` runs the Python code.
NATIVE = load("rgraph.memory._dive")

#: Candidates tried per step (by lowest offset, then preorder rank); also the ones whose
#: needed capacity is compared when none fits.
CANDIDATES = 8

#: Operations charged: per step, plus half an operation per unplaced block scanned; per
#: candidate tried, plus half per neighbour and per section visited; one per ``ROW_SHARE``
#: blocks of a section scanned for its floor. Fitted (session 10) to CPU times of the Python
#: dives on the MiniMalloc traces (about 4 M a second); the compiled dive does the same
#: operations about 40 times faster (``aliased.DIVE_OPS_PER_SECOND``, session 13).
STEP_OPS = 20
TRY_OPS = 25
ROW_SHARE = 8


@dataclass
class Dive:
    offsets: list[int] | None  # None: given up (the peak would reach ``give_up_at``)
    peak: int  # of the placement; when given up, the capacity reached
    #: Blocks still to place, at a raise, in the sections that set the new capacity, in the
    #: order met (duplicates possible): the squeaky wheel's input.
    blamed: list[int]
    ops: int


def dive(inst: Instance, order: Sequence[int], capacity: int, ops_limit: int | None = None,
         give_up_at: int | None = None) -> Dive | None:
    """One elastic dive over ``order`` (a preorder of all blocks) starting at ``capacity``;
    None if it would spend more than ``ops_limit`` operations. When the capacity reaches
    ``give_up_at`` the dive stops (``offsets`` None) with what it blamed so far.
    The compiled dive (:data:`NATIVE`) where built, else :func:`dive_python`: same results."""
    if NATIVE is None:
        return dive_python(inst, order, capacity, ops_limit, give_up_at)
    return native_dive(NATIVE, inst, order, capacity, ops_limit, give_up_at)


def native_dive(module: ModuleType, inst: Instance, order: Sequence[int], capacity: int,
                ops_limit: int | None = None, give_up_at: int | None = None) -> Dive | None:
    """:func:`dive_python` run by the compiled ``module`` (``rgraph.memory._dive``); its flat
    copy of ``inst`` is made once and kept on the instance."""
    flat = inst.accelerated.get("dive")
    if flat is None:
        flat = inst.accelerated["dive"] = module.Flat(
            inst.size, inst.align, inst.neighbors, inst.sec_lo, inst.sec_hi, inst.section_blocks,
            inst.section_totals())
    found = module.dive(flat, order, capacity, ops_limit, give_up_at, CANDIDATES, STEP_OPS, TRY_OPS, ROW_SHARE)
    return None if found is None else Dive(*found)


def dive_python(inst: Instance, order: Sequence[int], capacity: int, ops_limit: int | None = None,
                give_up_at: int | None = None) -> Dive | None:
    """:func:`dive` in Python (``rgraph/memory/_dive.pyx`` mirrors it: change both)."""
    n = inst.n
    size, align, neighbors = inst.size, inst.align, inst.neighbors
    sec_lo, sec_hi, rows = inst.sec_lo, inst.sec_hi, inst.section_blocks
    mins = [0] * n
    offsets = [0 if size[i] == 0 else -1 for i in range(n)]
    total = inst.section_totals()
    witness = [-1] * inst.section_count  # an unplaced block that passed the section's check last
    unplaced = [i for i in order if size[i] > 0]
    cap = max(capacity, max(total, default=0))
    limit = ops_limit if ops_limit is not None else 1 << 62
    ops = 0
    blamed: list[int] = []

    def apply(c: int, cands: list[int]) -> tuple[list[int], list[int], int, int]:
        """Place ``c`` at its lowest offset: pushes its unplaced neighbours above it and
        lifts the candidates below it to its offset. Returns what changed and the range of
        sections whose data changed."""
        off = mins[c]
        top = off + size[c]
        offsets[c] = off
        changed: list[int] = []
        olds: list[int] = []
        first, last = sec_lo[c], sec_hi[c]
        for j in neighbors[c]:
            if offsets[j] < 0:
                old = mins[j]
                if old < top:
                    a = align[j]
                    mins[j] = top if top % a == 0 else top + a - top % a
                    changed.append(j)
                    olds.append(old)
                    if sec_lo[j] < first:
                        first = sec_lo[j]
                    if sec_hi[j] > last:
                        last = sec_hi[j]
        for j in cands:  # the candidates before c, at or below its offset
            if j == c:
                break
            old = mins[j]
            if old < off:  # not pushed by c: lifted to its offset
                a = align[j]
                mins[j] = off if off % a == 0 else off + a - off % a
                changed.append(j)
                olds.append(old)
                if sec_lo[j] < first:
                    first = sec_lo[j]
                if sec_hi[j] > last:
                    last = sec_hi[j]
        z = size[c]
        for s in range(sec_lo[c], sec_hi[c]):
            total[s] -= z
        return changed, olds, first, last

    def undo(c: int, changed: list[int], olds: list[int]) -> None:
        for k in range(len(changed) - 1, -1, -1):
            mins[changed[k]] = olds[k]
        z = size[c]
        for s in range(sec_lo[c], sec_hi[c]):
            total[s] += z
        offsets[c] = -1

    def passes(changed: list[int], first: int, last: int, within: int) -> bool:
        """Whether the section inference holds at capacity ``within``."""
        nonlocal ops
        for j in changed:
            if mins[j] + size[j] > within:
                return False
        for s in range(first, last):
            left = total[s]
            if left:
                threshold = within - left
                w = witness[s]
                if w >= 0 and offsets[w] < 0 and mins[w] <= threshold:
                    continue
                row = rows[s]
                ops += len(row) // ROW_SHARE
                for j in row:
                    if offsets[j] < 0 and mins[j] <= threshold:
                        witness[s] = j
                        break
                else:
                    return False
        return True

    def floor_above(s: int, within: int) -> int:
        """The lowest offset an unplaced block of section ``s`` can take, if it is above
        ``within`` less the bytes left there (else -1: the section fits in ``within``)."""
        nonlocal ops
        threshold = within - total[s]
        w = witness[s]
        if w >= 0 and offsets[w] < 0 and mins[w] <= threshold:
            return -1
        row = rows[s]
        ops += len(row) // ROW_SHARE
        floor = min([mins[j] for j in row if offsets[j] < 0])
        return floor if floor > threshold else -1

    def needed(changed: list[int], first: int, last: int, top: int, stop: int) -> int:
        """The least capacity above ``cap`` at which the inference holds (at least
        ``top``), or some value at or above ``stop`` once it is known to reach it."""
        need = top
        for j in changed:
            if mins[j] + size[j] > need:
                need = mins[j] + size[j]
        for s in range(first, last):
            left = total[s]
            if left:
                floor = floor_above(s, cap)
                if floor >= 0 and floor + left > need:
                    need = floor + left
                    if need >= stop:
                        return need
        return need

    while unplaced:
        ops += STEP_OPS + len(unplaced) // 2
        if ops > limit:
            return None
        lowest_top = min([mins[i] + size[i] for i in unplaced])
        cands = [i for i in unplaced if mins[i] < lowest_top]
        cands.sort(key=mins.__getitem__)  # stable: ties keep preorder rank
        del cands[CANDIDATES:]
        chosen = -1
        for c in cands:
            changed, olds, first, last = apply(c, cands)
            ops += TRY_OPS + (len(neighbors[c]) + last - first) // 2
            if passes(changed, first, last, cap):
                chosen = c
                break
            undo(c, changed, olds)
        if chosen < 0:  # raise the capacity to the least one of the candidates needs
            best, best_need = -1, 0
            for c in cands:
                changed, olds, first, last = apply(c, cands)
                ops += TRY_OPS + (len(neighbors[c]) + last - first) // 2
                if best < 0 or passes(changed, first, last, best_need - 1):
                    need = needed(changed, first, last, mins[c] + size[c], best_need if best >= 0 else 1 << 62)
                    if best < 0 or need < best_need:
                        best, best_need = c, need
                undo(c, changed, olds)
            cap = best_need
            chosen = best
            changed, olds, first, last = apply(chosen, cands)
            for s in range(first, last):
                left = total[s]
                if left:
                    floor = floor_above(s, cap - 1)
                    if floor >= 0:  # the section sets the new capacity
                        blamed.extend(j for j in rows[s] if offsets[j] < 0)
            if give_up_at is not None and cap >= give_up_at:
                return Dive(None, cap, blamed, ops)
        unplaced.remove(chosen)
    peak = max((offsets[i] + size[i] for i in range(n)), default=0)
    return Dive(offsets, peak, blamed, ops)


def squeak(order: Sequence[int], blamed: Sequence[int]) -> list[int]:
    """``order`` with the ``blamed`` blocks moved to the front, keeping their relative order."""
    front = set(blamed)
    return [i for i in order if i in front] + [i for i in order if i not in front]


#: ``improve`` stops after this many dives per chain in a row that did not lower the best
#: peak (the chains go round in circles on small instances, where the search can prove).
STALL_PER_CHAIN = 25


@dataclass
class Improved:
    offsets: list[int] | None  # None: nothing below the incumbent's peak was found
    peak: int
    ops: int  # operations spent
    dives: int


def improve(inst: Instance, orders: Sequence[Sequence[int]], incumbent: int, ops_budget: int) -> Improved:
    """Elastic dives from the lower bound, round robin over ``orders`` (one squeaky-wheel
    chain each), until ``ops_budget`` dive operations are spent, the bound is reached or the
    chains stall (:data:`STALL_PER_CHAIN`; a chain whose order comes back is dropped).
    Dives give up once their capacity reaches the best peak so far (``incumbent`` at first)."""
    bound = inst.lower_bound()
    chains = [list(o) for o in orders]
    blamed: list[list[int] | None] = [None] * len(chains)
    seen: list[set[int]] = [set() for _ in chains]
    best: list[int] | None = None
    peak, spent, dives, stall = incumbent, 0, 0, 0
    k = 0
    while spent < ops_budget and peak > bound and chains and stall < STALL_PER_CHAIN * len(orders):
        c = k % len(chains)
        if blamed[c] is not None:
            chains[c] = squeak(chains[c], blamed[c])  # type: ignore[arg-type]
        key = hash(tuple(chains[c]))
        if key in seen[c]:  # back to an order already dived: the chain is done
            del chains[c], blamed[c], seen[c]
            continue
        seen[c].add(key)
        k += 1
        found = dive(inst, chains[c], bound, ops_budget - spent, give_up_at=peak)
        if found is None:  # out of operations: they were spent
            spent = ops_budget
            break
        spent += found.ops
        dives += 1
        blamed[c] = found.blamed
        if found.offsets is not None and found.peak < peak:
            best, peak, stall = found.offsets, found.peak, 0
        else:
            stall += 1
    return Improved(best, peak, spent, dives)
