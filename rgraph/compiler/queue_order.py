"""Which transients may share memory without a new cross-queue wait.

Work on different queues that the graph does not order overlaps in time, whatever the
pass indices say. The synchronisation phase makes a resource that reuses another's memory
wait, at the first use of each of its cells, for the last use of each cell of the earlier
occupant on every other queue. That wait costs nothing only where the pass already waits
for that queue at that point or later (a data hand-off between the queues): the semaphore
wait is then the same one, its stage mask widened. ``cross_queue_conflicts`` lists the
pairs of transients, disjoint in pass index, where it would not be: the placement treats
them as overlapping in time, so aliasing never adds a semaphore wait the ``dedicated``
policy lacks (tests/compile/test_alias_queues.py checks it on random multi-queue graphs).

The dedicated plan's waits come from the trace (``rgraph.compiler.trace``), derived the way
``sync`` derives them: a cell whose previous use was on another queue waits for that use.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from collections.abc import Collection, Sequence

from rgraph.compiler.trace import Trace
from rgraph.native import load
from rgraph.spec.specialize import PassSpec

#: The compiled mirror of :func:`cross_queue_conflicts_python` (``rgraph/compiler/_queue_order.pyx``),
#: None where it is not built or ``RGRAPH_NATIVE=0``.
NATIVE = load("rgraph.compiler._queue_order")


def cross_queue_conflicts(passes: Sequence[PassSpec], trace: Trace, candidates: Collection[str]) -> dict[str, set[str]]:
    """:func:`cross_queue_conflicts_python`, compiled where built."""
    if NATIVE is None:
        return cross_queue_conflicts_python(passes, trace, candidates)
    return NATIVE.cross_queue_conflicts(passes, trace, candidates)


def cross_queue_conflicts_python(passes: Sequence[PassSpec], trace: Trace, candidates: Collection[str]
                                 ) -> dict[str, set[str]]:
    """Pairs of ``candidates`` (symmetric) that may not share memory although one ends before
    the other starts: sharing would add a cross-queue wait. Empty for one-queue graphs.
    ``trace``: the passes' (``rgraph.compiler.trace``), whose ``waits`` are the dedicated plan's."""
    if len({p.queue for p in passes}) < 2:
        return {}
    waits = trace.waits
    firsts: dict[str, Collection[tuple[int, str]]] = {}  # resource -> (first pass of a cell, its queue)
    # Per queue q: the resources with a cell last used on q, by that last use. Sharing with a
    # later r adds a wait iff some cell of r first used on another queue does not already
    # wait for q at or after it: a range of this order, found by bisection.
    by_queue: dict[str, list[tuple[int, str]]] = {}
    resources = trace.resources
    for name in candidates:
        cells = resources[name].cells
        if len(cells) == 1:  # most resources
            uses = cells[0][1]
            first, end = uses[0], uses[-1]
            firsts[name] = ((first[0], first[3]),)
            q = end[3]
            if q in by_queue:
                by_queue[q].append((end[0], name))
            else:
                by_queue[q] = [(end[0], name)]
            continue
        starts: set[tuple[int, str]] = set()
        per: dict[str, int] = {}  # queue -> last pass of a cell ending there
        for _, uses in cells:
            first, end = uses[0], uses[-1]
            starts.add((first[0], first[3]))
            q = end[3]
            if per.get(q, -1) < end[0]:
                per[q] = end[0]
        firsts[name] = starts
        for q, j in per.items():
            if q in by_queue:
                by_queue[q].append((j, name))
            else:
                by_queue[q] = [(j, name)]
    for rows in by_queue.values():
        rows.sort()
    keys = {q: [j for j, _ in rows] for q, rows in by_queue.items()}
    out: dict[str, set[str]] = {}
    none: dict[str, int] = {}
    for r in sorted(candidates):
        r_first = resources[r].first
        r_firsts = firsts[r]
        for q, rows in by_queue.items():
            low = None  # the earliest pass on q that a cell of r first used elsewhere already waits for
            for v, qv in r_firsts:
                if qv != q:
                    have = waits.get(v, none).get(q, -1)
                    if low is None or have < low:
                        low = have
            if low is None:
                continue  # r starts on q only: a pipeline barrier orders it
            key = keys[q]
            lo, hi = bisect_right(key, low), bisect_left(key, r_first)
            for _, p in rows[lo:hi]:
                if resources[p].last < r_first:
                    if r in out:
                        out[r].add(p)
                    else:
                        out[r] = {p}
                    if p in out:
                        out[p].add(r)
                    else:
                        out[p] = {r}
    return out
