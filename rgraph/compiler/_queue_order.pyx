# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""Compiled mirror of ``rgraph.compiler.queue_order.cross_queue_conflicts_python``: the same
pairs, found with typed locals and, per queue, C arrays of the sorted (last use, resource's
last pass) rows. Any change to the Python code must be made here too
(tests/compile/test_native_phases.py compares the plans of both)."""

from libc.stdlib cimport free, malloc

include "_bisect.pxi"


cdef Py_ssize_t _bisect_right(i64 *a, Py_ssize_t n, i64 x):
    cdef Py_ssize_t lo = 0, hi = n, mid
    while lo < hi:
        mid = (lo + hi) >> 1
        if x < a[mid]:
            hi = mid
        else:
            lo = mid + 1
    return lo


cdef inline void _pair(dict out, r, p):
    found = out.get(r)
    if found is None:
        out[r] = {p}
    else:
        (<set> found).add(p)


def cross_queue_conflicts(passes, trace, candidates):
    """``cross_queue_conflicts_python(passes, trace, candidates)``."""
    cdef set queues = set()
    cdef dict firsts = {}, by_queue = {}, per, out = {}, none = {}, waits, resources
    cdef list rows, cells, uses, names, qs
    cdef tuple first, end
    cdef Py_ssize_t n, k, lo, hi, total = 0, nq, qi
    cdef i64 r_first, low, have
    cdef bint any_low
    cdef i64 *keys
    cdef i64 *lasts
    cdef Py_ssize_t *start
    for p in passes:
        queues.add(p.queue)
    if len(queues) < 2:
        return {}
    waits = trace.waits
    resources = trace.resources
    for name in candidates:
        cells = resources[name].cells
        if len(cells) == 1:  # most resources
            uses = (<tuple> cells[0])[1]
            first, end = uses[0], uses[len(uses) - 1]
            firsts[name] = ((first[0], first[3]),)
            q = end[3]
            found = by_queue.get(q)
            if found is None:
                by_queue[q] = [(end[0], name)]
            else:
                (<list> found).append((end[0], name))
            continue
        starts = set()
        per = {}  # queue -> last pass of a cell ending there
        for cell in cells:
            uses = (<tuple> cell)[1]
            first, end = uses[0], uses[len(uses) - 1]
            starts.add((first[0], first[3]))
            q = end[3]
            if per.get(q, -1) < end[0]:
                per[q] = end[0]
        firsts[name] = starts
        for q, j in per.items():
            found = by_queue.get(q)
            if found is None:
                by_queue[q] = [(j, name)]
            else:
                (<list> found).append((j, name))
    qs = list(by_queue)
    nq = len(qs)
    for rows in by_queue.values():
        rows.sort()
        total += len(rows)
    # per queue qi: rows start[qi] .. start[qi + 1] of keys (last use on the queue) and lasts
    # (the resource's last pass), names in the same order
    keys = <i64 *> malloc((2 * total + 1) * sizeof(i64))
    start = <Py_ssize_t *> malloc((nq + 1) * sizeof(Py_ssize_t))
    if keys == NULL or start == NULL:
        free(keys)
        free(start)
        raise MemoryError()
    lasts = keys + total
    names = []
    try:
        k = 0
        for qi in range(nq):
            start[qi] = k
            for row in <list> by_queue[qs[qi]]:
                j, p = row
                keys[k] = j
                lasts[k] = resources[p].last
                names.append(p)
                k += 1
        start[nq] = k
        for r in sorted(candidates):
            r_first = resources[r].first
            r_firsts = firsts[r]
            for qi in range(nq):
                q = qs[qi]
                any_low = False  # the earliest pass on q that a cell of r first used elsewhere already waits for
                low = 0
                for v, qv in r_firsts:
                    if qv != q:
                        have = (<dict> waits.get(v, none)).get(q, -1)
                        if not any_low or have < low:
                            low = have
                            any_low = True
                if not any_low:
                    continue  # r starts on q only: a pipeline barrier orders it
                n = start[qi + 1] - start[qi]
                lo = start[qi] + _bisect_right(keys + start[qi], n, low)
                hi = start[qi] + _bisect_left(keys + start[qi], n, r_first)
                for k in range(lo, hi):
                    if lasts[k] < r_first:
                        p = names[k]
                        _pair(out, r, p)
                        _pair(out, p, r)
    finally:
        free(keys)
        free(start)
    return out
