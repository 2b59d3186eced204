# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""Compiled mirror of ``rgraph.compiler.queue_order.cross_queue_conflicts_python``: the same
pairs, inserted in the same order, found with C arrays: per candidate (by its rank in name
order) its first and last pass and the (first pass, queue) of its cells' first uses, each
with the waits of that pass; per queue the sorted (last use there, rank) rows; queues as
small indices (compared by address, then by value). Any change to the Python code must be
made here too (tests/compile/test_native_phases.py compares the plans of both,
tests/compile/test_memory_compiled.py the pairs)."""

from cpython.ref cimport PyObject
from libc.stdlib cimport free, malloc, realloc

include "_bisect.pxi"
include "../memory/_sort.pxi"
include "../plan/_slots.pxi"

#: Queues past this many: the Python code runs (the C arrays hold a few per candidate).
cdef enum:
    MAX_QUEUES = 64

cdef Slots TRACE = None, PASS = None
cdef object TRACE_T = None, PASS_T = None


cdef int _layouts() except -1:
    global TRACE, PASS, TRACE_T, PASS_T
    from rgraph.compiler.trace import ResourceTrace
    from rgraph.spec.specialize import PassSpec

    TRACE = Slots(ResourceTrace, ("usages", "first", "last", "cells", "code", "group"))
    PASS = Slots(PassSpec, ("name", "order", "kind", "queue", "impl", "requires", "side_effects", "accesses",
                            "params", "loc", "requires_any"))
    TRACE_T, PASS_T = ResourceTrace, PassSpec
    return 0


cdef Py_ssize_t _bisect_right(i64 *a, Py_ssize_t n, i64 x) noexcept:
    cdef Py_ssize_t lo = 0, hi = n, mid
    while lo < hi:
        mid = (lo + hi) >> 1
        if x < a[mid]:
            hi = mid
        else:
            lo = mid + 1
    return lo


cdef struct Row:
    i64 q  # the queue's place in ``by_queue``'s order
    i64 j  # the last use of a cell of the resource on that queue
    i64 k  # the resource's rank in name order


cdef void *_grown(void *p, size_t size) except NULL:
    """``p`` reallocated to ``size`` bytes (MemoryError where that fails: ``p`` is then still
    the caller's to free)."""
    cdef void *grown = realloc(p, size)
    if grown == NULL:
        raise MemoryError()
    return grown


cdef Py_ssize_t _queue(list qs, q) except -1:
    """The index of ``q`` in ``qs`` (by address, then by value), appended where absent."""
    cdef Py_ssize_t i, n = len(qs)
    for i in range(n):
        if qs[i] is q:
            return i
    for i in range(n):
        if qs[i] == q:
            return i
    qs.append(q)
    return n


cdef inline void _pair(dict out, list sets, list names, Py_ssize_t r, Py_ssize_t p) except *:
    found = sets[r]
    if found is None:
        found = {names[p]}
        sets[r] = found
        out[names[r]] = found
    else:
        (<set> found).add(names[p])


def cross_queue_conflicts(passes, trace, candidates):
    """``cross_queue_conflicts_python(passes, trace, candidates)``."""
    if TRACE is None:
        _layouts()
    q0 = None
    cdef bint several = False, started = False
    for p in passes:
        q = (<object> slot_get(p, PASS, 3)) if type(p) is PASS_T else p.queue
        if not started:
            q0, started = q, True
        elif q is not q0 and q != q0:
            several = True
            break
    if not several:
        return {}
    found = _conflicts(trace, candidates)
    if found is None:  # more queues than the arrays hold
        from rgraph.compiler.queue_order import cross_queue_conflicts_python

        return cross_queue_conflicts_python(passes, trace, candidates)
    return found


cdef inline PyObject *slot_get(object o, Slots layout, Py_ssize_t k) except NULL:
    """Field ``k`` of ``o`` (exactly ``layout.cls``), borrowed."""
    cdef PyObject *v = (<PyObject **> ((<char *> <PyObject *> o) + layout.off[k]))[0]
    if v == NULL:
        raise AttributeError(f"{type(o).__name__}: field {k} is not set")
    return v


cdef object _conflicts(trace, candidates):
    cdef list ranked = sorted(candidates), qs = [], row_queues = [], entry_waits = [], sets, cells, uses
    cdef Py_ssize_t n = len(ranked), k, i, e, qi, nq, nrows = 0, room, nentries = 0, eroom, c, ncells
    cdef Py_ssize_t lo, hi, count, start
    cdef dict rank = {}, out = {}, none = {}, resources = trace.resources, waits = trace.waits
    cdef tuple first, end
    cdef i64 r_first, have
    cdef i64 low[MAX_QUEUES]
    cdef bint low_set[MAX_QUEUES]
    cdef i64 permax[MAX_QUEUES]
    cdef Py_ssize_t perorder[MAX_QUEUES]
    cdef Py_ssize_t nper
    cdef Py_ssize_t qstart[MAX_QUEUES + 1]
    cdef Py_ssize_t row_of[MAX_QUEUES]  # a queue's place in by_queue's order, -1 before its first row
    cdef Py_ssize_t row_q[MAX_QUEUES]  # the index in qs of each queue in by_queue's order
    cdef i64 *first_pass = NULL
    cdef i64 *last_pass = NULL
    cdef Py_ssize_t *estart = NULL
    cdef i64 *entry_q = NULL
    cdef Row *rows = NULL
    cdef Row *spare = NULL
    cdef i64 *keys = NULL
    cdef void *grown
    for k in range(n):
        rank[ranked[k]] = k
    if len(rank) != n:
        return None  # a name twice: the Python code
    for qi in range(MAX_QUEUES):
        row_of[qi] = -1
    room = n + 16
    eroom = n + 16
    try:
        first_pass = <i64 *> malloc(2 * max(n, 1) * sizeof(i64))
        estart = <Py_ssize_t *> malloc(2 * max(n, 1) * sizeof(Py_ssize_t))
        entry_q = <i64 *> malloc(eroom * sizeof(i64))
        rows = <Row *> malloc(room * sizeof(Row))
        if not (first_pass and estart and entry_q and rows):
            raise MemoryError()
        last_pass = first_pass + n
        # per candidate (by rank): its first uses' (pass, queue) entries, its rows (queues
        # in by_queue's order: that of their first row, candidates in the given order)
        for name in candidates:
            k = rank[name]
            rt = resources[name]
            if type(rt) is TRACE_T:
                r_first = <object> slot_get(rt, TRACE, 1)
                have = <object> slot_get(rt, TRACE, 2)
                cells = <list> slot_get(rt, TRACE, 3)
            else:
                r_first, have, cells = rt.first, rt.last, rt.cells
            first_pass[k], last_pass[k] = r_first, have
            ncells = len(cells)
            start = nentries
            nper = 0
            for c in range(ncells):
                uses = <list> (<tuple> cells[c])[1]
                first, end = uses[0], uses[len(uses) - 1]
                if nentries == eroom:
                    eroom *= 2
                    entry_q = <i64 *> _grown(entry_q, eroom * sizeof(i64))
                qi = _queue(qs, first[3])
                if qi >= MAX_QUEUES:
                    return None
                entry_q[nentries] = qi
                entry_waits.append(waits.get(first[0], none))
                nentries += 1
                qi = _queue(qs, end[3])
                if qi >= MAX_QUEUES:
                    return None
                have = end[0]
                for i in range(nper):
                    if perorder[i] == qi:
                        if permax[i] < have:
                            permax[i] = have
                        break
                else:
                    perorder[nper] = qi
                    permax[nper] = have
                    nper += 1
            estart[2 * k], estart[2 * k + 1] = start, nentries
            for i in range(nper):
                qi = perorder[i]
                if row_of[qi] < 0:
                    row_of[qi] = len(row_queues)
                    row_q[len(row_queues)] = qi
                    row_queues.append(qs[qi])
                if nrows == room:
                    room *= 2
                    rows = <Row *> _grown(rows, room * sizeof(Row))
                rows[nrows].q, rows[nrows].j, rows[nrows].k = row_of[qi], permax[i], k
                nrows += 1
        nq = len(row_queues)
        spare = <Row *> malloc(max(nrows, 1) * sizeof(Row))
        if spare == NULL:
            raise MemoryError()
        if <Row *> sort_triples(<Triple *> rows, <Triple *> spare, nrows) == spare:  # by (q, j, k)
            grown = rows
            rows = spare
            spare = <Row *> grown
        keys = <i64 *> malloc(max(nrows, 1) * sizeof(i64))
        if keys == NULL:
            raise MemoryError()
        qi = 0
        qstart[0] = 0
        for i in range(nrows):
            keys[i] = rows[i].j
            while qi < rows[i].q:
                qi += 1
                qstart[qi] = i
        while qi < nq:
            qi += 1
            qstart[qi] = nrows
        sets = [None] * n
        for k in range(n):
            r_first = first_pass[k]

            for qi in range(nq):
                low_set[qi] = False
            for e in range(estart[2 * k], estart[2 * k + 1]):
                wv = entry_waits[e]
                for qi in range(nq):  # the queues in by_queue's order
                    if entry_q[e] != row_q[qi]:
                        have = (<dict> wv).get(row_queues[qi], -1) if wv else -1
                        if not low_set[qi] or have < low[qi]:
                            low[qi] = have
                            low_set[qi] = True
            for qi in range(nq):
                if not low_set[qi]:
                    continue  # r starts on q only: a pipeline barrier orders it
                count = qstart[qi + 1] - qstart[qi]
                lo = qstart[qi] + _bisect_right(keys + qstart[qi], count, low[qi])
                hi = qstart[qi] + _bisect_left(keys + qstart[qi], count, r_first)
                for i in range(lo, hi):
                    if last_pass[rows[i].k] < r_first:
                        _pair(out, sets, ranked, k, rows[i].k)
                        _pair(out, sets, ranked, rows[i].k, k)
    finally:
        free(first_pass)
        free(estart)
        free(entry_q)
        free(rows)
        free(spare)
        free(keys)
    return out
