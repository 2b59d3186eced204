# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled greedy best fit: ``rgraph.memory.greedy.best_fit_python``'s offsets on C arrays.

Not a line-by-line mirror: the Python module has four ways of visiting a block's placed
neighbours (for speed in Python); all give the offsets of the plain algorithm, which this
module runs (tests/memory/test_best_fit_paths.py and test_best_fit_native.py compare them):
each block, in turn, goes to the start (aligned) of the smallest gap, between its placed
neighbours sorted by offset, that holds it (the first of equal gaps), else on top of them;
as soon as a block's top reaches ``give_up_at`` the placement is given up (None).

A block's placed neighbours come in offset order either from a scan of every placed block
(kept sorted by offset; on dense instances, when the block overlaps a good share of them)
or by sorting its own placed neighbours. Which way is used changes the time only: the gap
scan depends only on the first of equal offsets and the highest top so far. ``Flat`` is
one instance's arrays, made once per ``Instance`` (``greedy.native_flat``)."""

from libc.stdlib cimport calloc, free, malloc, qsort, realloc
from libc.string cimport memcmp, memcpy, memmove

include "_sort.pxi"
from cpython.object cimport PyObject


cdef Py_ssize_t *_push_pair(Py_ssize_t *pairs, Py_ssize_t *room, Py_ssize_t count, Py_ssize_t i,
                            Py_ssize_t j) except NULL:
    """``pairs`` (``count`` pairs, room for ``room``) with (i, j) appended: the array itself, or a
    grown copy (``room`` doubled; the old one is freed by realloc). MemoryError leaves it as it was."""
    cdef Py_ssize_t *grown
    if count == room[0]:
        grown = <Py_ssize_t *> realloc(pairs, 4 * room[0] * sizeof(Py_ssize_t))
        if not grown:
            raise MemoryError()
        room[0] *= 2
        pairs = grown
    pairs[2 * count], pairs[2 * count + 1] = i, j
    return pairs


cdef extern from "Python.h":
    PyObject *PyDict_GetItemWithError(object d, object key) except? NULL
    object PyObject_GenericGetDict(object o, void *context)

from rgraph.memory.model import Block


cdef inline object block_dict(b):
    """The ``__dict__`` of ``b`` where it is exactly a ``Block`` (its fields are read from it
    directly: ``Block`` has no data descriptor, so that is what ``getattr`` finds), else None."""
    if type(b) is Block:
        return PyObject_GenericGetDict(b, NULL)
    return None


cdef inline object field(b, d, str key):
    """``getattr(b, key)``, read from ``d`` (``block_dict(b)``) where it holds ``key``."""
    cdef PyObject *v
    if d is not None:
        v = PyDict_GetItemWithError(d, key)
        if v != NULL:
            return <object> v
    return getattr(b, key)

ctypedef long long i64

#: Sizes plus alignments must stay below this (offsets and tops then fit in 64 bits).
cdef i64 LIMIT = (<i64> 1) << 62


cdef struct Range:
    i64 lo
    i64 hi


cdef int by_lo(const void *a, const void *b) noexcept nogil:
    cdef i64 x = (<const Range *> a).lo, y = (<const Range *> b).lo
    return (x > y) - (x < y)


cdef struct Graph:
    # One instance's sizes, alignments and conflicts: the matrix (``adj``, n by n, may be
    # NULL) and/or the neighbour lists (CSR: ``nbr_ptr``, ``nbr_idx``; empty rows where
    # ``dense`` with the matrix: every placed block is then scanned against its row).
    int n
    bint dense
    i64 *size
    i64 *align
    int *nbr_ptr
    int *nbr_idx
    const unsigned char *adj


cdef Py_ssize_t graph_from_matrix(Graph *g) except -1:
    """``g.dense`` and, where not dense, ``g.nbr_idx`` from ``g.adj`` (``g.nbr_ptr``: n + 1
    entries, allocated by the caller): dense where a quarter of all pairs or more may not
    share bytes (as in ``greedy.best_fit_python``). Returns the (ordered) pairs."""
    cdef int n = g.n, i, j, k = 0
    cdef Py_ssize_t pairs = 0
    with nogil:
        for i in range(n):
            for j in range(n):
                pairs += g.adj[<Py_ssize_t> i * n + j] != 0
    g.dense = 4 * pairs >= <Py_ssize_t> n * n
    if g.dense:
        for i in range(n + 1):
            g.nbr_ptr[i] = 0
        return pairs
    g.nbr_idx = <int *> malloc(max(pairs, 1) * sizeof(int))
    if not g.nbr_idx:
        raise MemoryError()
    with nogil:
        for i in range(n):
            g.nbr_ptr[i] = k
            for j in range(n):
                if g.adj[<Py_ssize_t> i * n + j]:
                    g.nbr_idx[k] = j
                    k += 1
        g.nbr_ptr[n] = k
    return pairs


cdef class Flat:
    """An ``Instance``'s ``Graph``, from its conflict matrix (``adjacency``, uint8, kept for
    membership tests) or its neighbour lists (``neighbors``, used when ``adjacency`` is None)."""

    cdef Graph g
    cdef object matrix  # owns g.adj

    def __cinit__(self, size, align, adjacency, neighbors):
        cdef int n = len(size), i, j, k
        cdef Py_ssize_t pairs = 0
        cdef i64 total = 0
        cdef const unsigned char[:, ::1] m
        cdef Graph *g = &self.g
        g.n, g.adj, g.nbr_idx = n, NULL, NULL
        if len(align) != n:
            raise ValueError("inconsistent instance arrays")
        g.size = <i64 *> malloc(max(n, 1) * sizeof(i64))
        g.align = <i64 *> malloc(max(n, 1) * sizeof(i64))
        g.nbr_ptr = <int *> malloc((n + 1) * sizeof(int))
        if not (g.size and g.align and g.nbr_ptr):
            raise MemoryError()
        for i in range(n):
            g.size[i] = size[i]  # OverflowError past 64 bits
            g.align[i] = align[i]
            if not (0 <= g.size[i] < LIMIT and 1 <= g.align[i] < LIMIT):
                raise OverflowError("sizes and alignments must be in [0, 2**62), alignments positive")
            total += g.size[i] + g.align[i]
            if total >= LIMIT:
                raise OverflowError("sizes and alignments sum past 2**62")
        if adjacency is not None:
            m = adjacency
            if m.shape[0] != n or m.shape[1] != n:
                raise ValueError("adjacency must be n by n")
            self.matrix = adjacency
            g.adj = &m[0, 0] if n else NULL
            graph_from_matrix(g)
            return
        if len(neighbors) != n:
            raise ValueError("inconsistent instance arrays")
        for row in neighbors:
            pairs += len(row)
        g.nbr_idx = <int *> malloc(max(pairs, 1) * sizeof(int))
        if not g.nbr_idx:
            raise MemoryError()
        k = 0
        for i in range(n):
            g.nbr_ptr[i] = k
            for x in neighbors[i]:
                j = x
                if not (0 <= j < n):
                    raise ValueError("neighbour out of range")
                g.nbr_idx[k] = j
                k += 1
        g.nbr_ptr[n] = k
        g.dense = 4 * k >= <Py_ssize_t> n * n

    def __dealloc__(self):
        free(self.g.size)
        free(self.g.align)
        free(self.g.nbr_ptr)
        free(self.g.nbr_idx)


cdef inline i64 align_up(i64 x, i64 a) noexcept nogil:
    return x if x % a == 0 else x + a - x % a


cdef int place(const Graph *flat, const int *order, int count, i64 limit, i64 *offsets) noexcept nogil:
    """Best fit of ``order[:count]`` into ``offsets`` (all -1 on entry); 1 if given up at
    ``limit`` (negative: never), -1 out of memory, else 0."""
    cdef int n = flat.n, i, j, k, e, placed = 0, lo_k, deg, found
    cdef const i64 *size = flat.size
    cdef const i64 *align = flat.align
    cdef const int *ptr = flat.nbr_ptr
    cdef const int *idx = flat.nbr_idx
    cdef const unsigned char *row = NULL
    cdef i64 need, a, cursor, best_off, best_gap, lo, hi, aligned, off, top
    cdef bint dense = flat.dense, scan
    # every placed block by offset (dense instances): starts, tops, blocks
    cdef i64 *e_lo = NULL
    cdef i64 *e_hi = NULL
    cdef int *e_blk = NULL
    cdef int *stamp = NULL  # stamp[j] == i + 1: j is a neighbour of i (no matrix)
    cdef Range *taken = <Range *> malloc(max(n, 1) * sizeof(Range))
    cdef int code = 0
    if dense:
        e_lo = <i64 *> malloc(max(n, 1) * sizeof(i64))
        e_hi = <i64 *> malloc(max(n, 1) * sizeof(i64))
        e_blk = <int *> malloc(max(n, 1) * sizeof(int))
        if flat.adj == NULL:
            stamp = <int *> malloc(max(n, 1) * sizeof(int))
    if not taken or (dense and not (e_lo and e_hi and e_blk and (flat.adj != NULL or stamp))):
        code = -1
    else:
        if stamp:
            for j in range(n):
                stamp[j] = 0
        for k in range(count):
            i = order[k]
            need, a = size[i], align[i]
            deg = ptr[i + 1] - ptr[i]
            scan = dense and (flat.adj != NULL or placed <= 2 * deg + 16)
            best_off, best_gap, cursor = -1, -1, 0
            if scan:  # every placed block in offset order, skipping non-neighbours
                if flat.adj != NULL:
                    row = flat.adj + <Py_ssize_t> i * n
                else:
                    for e in range(ptr[i], ptr[i + 1]):
                        stamp[idx[e]] = i + 1
                for e in range(placed):
                    j = e_blk[e]
                    if (row[j] == 0) if flat.adj != NULL else (stamp[j] != i + 1):
                        continue
                    lo = e_lo[e]
                    if lo > cursor:
                        aligned = align_up(cursor, a)
                        if aligned + need <= lo and (best_gap < 0 or lo - cursor < best_gap):
                            best_off, best_gap = aligned, lo - cursor
                    if e_hi[e] > cursor:
                        cursor = e_hi[e]
            else:  # its placed neighbours, sorted
                found = 0
                for e in range(ptr[i], ptr[i + 1]):
                    j = idx[e]
                    if offsets[j] >= 0:
                        taken[found].lo = offsets[j]
                        taken[found].hi = offsets[j] + size[j]
                        found += 1
                qsort(taken, found, sizeof(Range), by_lo)
                for e in range(found):
                    lo = taken[e].lo
                    if lo > cursor:
                        aligned = align_up(cursor, a)
                        if aligned + need <= lo and (best_gap < 0 or lo - cursor < best_gap):
                            best_off, best_gap = aligned, lo - cursor
                    if taken[e].hi > cursor:
                        cursor = taken[e].hi
            off = best_off if best_off >= 0 else align_up(cursor, a)
            top = off + need
            if 0 <= limit <= top:
                code = 1
                break
            offsets[i] = off
            if dense:  # insert after the last entry at or below off
                lo_k = upper_bound(e_lo, placed, off)
                memmove(e_lo + lo_k + 1, e_lo + lo_k, (placed - lo_k) * sizeof(i64))
                memmove(e_hi + lo_k + 1, e_hi + lo_k, (placed - lo_k) * sizeof(i64))
                memmove(e_blk + lo_k + 1, e_blk + lo_k, (placed - lo_k) * sizeof(int))
                e_lo[lo_k], e_hi[lo_k], e_blk[lo_k] = off, top, i
            placed += 1
    free(taken)
    free(e_lo)
    free(e_hi)
    free(e_blk)
    free(stamp)
    return code


def best_fit(Flat flat, order, give_up_at):
    """``greedy.best_fit_python(inst, order, give_up_at)``: the offsets (-1 for blocks not in
    ``order``), or None once a block's top reaches ``give_up_at``."""
    cdef int n = flat.g.n, count = len(order), i, k, code
    cdef i64 limit
    cdef int *blocks
    cdef i64 *offsets
    if give_up_at is None or give_up_at < 0 or give_up_at >= LIMIT:
        limit = -1  # never reached: every top stays below 2**62
    else:
        limit = give_up_at
    blocks = <int *> malloc(max(count, 1) * sizeof(int))
    offsets = <i64 *> malloc(max(n, 1) * sizeof(i64))
    try:
        if not (blocks and offsets):
            raise MemoryError()
        for i in range(n):
            offsets[i] = -1
        k = 0
        for x in order:
            i = x
            if not (0 <= i < n) or offsets[i] != -1:
                raise ValueError("order must hold distinct blocks of the instance")
            offsets[i] = -2  # seen
            blocks[k] = i
            k += 1
        for i in range(n):
            offsets[i] = -1
        with nogil:
            code = place(&flat.g, blocks, count, limit, offsets)
        if code < 0:
            raise MemoryError()
        if code == 1:
            return None
        return [offsets[i] for i in range(n)]
    finally:
        free(blocks)
        free(offsets)


cdef i64 clique_core(const Graph *g, const int *chosen, int count, unsigned char *joinable) noexcept nogil:
    """``clique_extra`` of the members ``chosen[:count]`` (``joinable``: n bytes of scratch)."""
    cdef int n = g.n, i, j, k
    cdef Py_ssize_t n_ = n
    cdef const unsigned char *adj = g.adj
    cdef i64 extra = 0
    cdef double best
    for i in range(n):
        joinable[i] = 1
        for k in range(count):
            if not adj[i * n_ + chosen[k]]:
                joinable[i] = 0
                break
    while True:
        j, best = -1, -1.0
        for i in range(n):
            if joinable[i] and <double> g.size[i] > best:
                j, best = i, <double> g.size[i]
        if j < 0:
            break
        extra += g.size[j]
        for i in range(n):
            joinable[i] = joinable[i] and adj[i * n_ + j]
    return extra


def clique_extra(Flat flat, members):
    """``bounds.clique_bound``'s greedy growth on the conflict matrix: starting from the
    blocks that may not share bytes with every one of ``members``, add the heaviest (by
    size as a float, the first of equal ones), keep those in conflict with it, until none
    is left; the sizes added. Needs the matrix (``adjacency``)."""
    cdef int n = flat.g.n, k, m, count = len(members)
    cdef i64 extra
    cdef unsigned char *joinable
    cdef int *chosen
    if flat.g.adj == NULL and n:
        raise ValueError("clique_extra needs the conflict matrix")
    joinable = <unsigned char *> malloc(max(n, 1))
    chosen = <int *> malloc(max(count, 1) * sizeof(int))
    try:
        if not (joinable and chosen):
            raise MemoryError()
        k = 0
        for x in members:
            m = x
            if not (0 <= m < n):
                raise IndexError("member out of range")
            chosen[k] = m
            k += 1
        with nogil:
            extra = clique_core(&flat.g, chosen, count, joinable)
        return extra
    finally:
        free(joinable)
        free(chosen)


cdef bint matrix_core(Py_ssize_t n, const i64 *s, const i64 *e, const Py_ssize_t *pairs, Py_ssize_t count,
                      unsigned char *adj) noexcept nogil:
    """``conflict_matrix``'s matrix into ``adj`` (n by n) from the closed lifetimes ``s``/``e``
    and the conflicting pairs ``pairs[:2 * count]``; whether every pair overlaps in time."""
    cdef Py_ssize_t i, j, k
    cdef i64 si, ei
    cdef bint separable = True
    for i in range(n):  # (bitwise, not short-circuit: no branch to mispredict)
        si, ei = s[i], e[i]
        for j in range(n):
            adj[i * n + j] = (si <= e[j]) & (ei >= s[j])
        adj[i * n + i] = 0
    for k in range(count):
        if not adj[pairs[2 * k] * n + pairs[2 * k + 1]]:
            separable = False
            break
    if not separable:
        for k in range(count):
            adj[pairs[2 * k] * n + pairs[2 * k + 1]] = 1
    return separable


def conflict_matrix(start, end, names, conflicts):
    """``instance.time_overlaps(start, end)`` with the ``conflicts`` among ``names`` (a
    mapping from a name to names it may not share bytes with; names of other classes are
    skipped) added where some pair is apart in time, as ``Instance.build`` does:
    ``(adjacency, separable)``, ``separable`` when every conflicting pair overlaps in time
    (the matrix then holds the time overlaps only). OverflowError where a time passes
    64 bits."""
    import numpy as np

    cdef Py_ssize_t n = len(start), i, j, count = 0, room = 64
    cdef i64 *s = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *e = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef Py_ssize_t *pairs = <Py_ssize_t *> malloc(2 * room * sizeof(Py_ssize_t))
    cdef unsigned char[:, ::1] m
    cdef bint separable = True
    cdef dict index
    try:
        if not (s and e and pairs):
            raise MemoryError()
        if len(end) != n or len(names) != n:
            raise ValueError("inconsistent instance arrays")
        for i in range(n):
            s[i] = start[i]
            e[i] = end[i]
        if conflicts:
            index = {name: i for i, name in enumerate(names)}
            get = conflicts.get
            for i in range(n):
                row = get(names[i])
                if not row:
                    continue
                for other in row:
                    found = index.get(other)
                    if found is None:
                        continue
                    j = found
                    if j == i:
                        continue
                    pairs = _push_pair(pairs, &room, count, i, j)
                    count += 1
        matrix = np.empty((n, n), dtype=np.uint8)
        if n:
            m = matrix
            with nogil:
                separable = matrix_core(n, s, e, pairs, count, &m[0, 0])
        return matrix.view(np.bool_), separable
    finally:
        free(s)
        free(e)
        free(pairs)


cdef Py_ssize_t lower_bound(const i64 *a, Py_ssize_t n, i64 x) noexcept nogil:
    """The first index of ``a`` (ascending) holding ``x`` or more."""
    cdef Py_ssize_t lo = 0, hi = n, mid
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


cdef Py_ssize_t upper_bound(const i64 *a, Py_ssize_t n, i64 x) noexcept nogil:
    """The first index of ``a`` (ascending) holding more than ``x``."""
    cdef Py_ssize_t lo = 0, hi = n, mid
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return lo


cdef Py_ssize_t sections_core(Py_ssize_t n, const i64 *s, const i64 *e, const i64 *z, i64 *buf, Py_ssize_t *lo,
                              Py_ssize_t *hi, i64 **totals) noexcept nogil:
    """``instance.sections`` of the closed lifetimes ``s``/``e`` (n of them, n > 0): each
    block's sections ``lo[i] .. hi[i]-1``, and ``*totals`` (within ``buf``, 4 n entries)
    the aligned bytes ``z`` alive in each section; returns how many sections there are."""
    cdef Py_ssize_t i, m = 1, count
    cdef i64 *coords
    cdef i64 *diff
    cdef i64 run = 0
    for i in range(n):
        buf[2 * i], buf[2 * i + 1] = s[i], e[i] + 1
    coords = sort_i64(buf, buf + 2 * n, 2 * n)
    diff = buf + 2 * n if coords == buf else buf  # the other half
    for i in range(1, 2 * n):
        if coords[i] != coords[m - 1]:
            coords[m] = coords[i]
            m += 1
    count = m - 1
    for i in range(count + 1):
        diff[i] = 0
    for i in range(n):
        lo[i] = lower_bound(coords, m, s[i])
        hi[i] = lower_bound(coords, m, e[i] + 1)
        diff[lo[i]] += z[i]
        diff[hi[i]] -= z[i]
    for i in range(count):
        run += diff[i]
        diff[i] = run
    totals[0] = diff
    return count


def class_arrays(list blocks):
    """``Instance.build``'s per-block lists and sections, and ``Instance._totals``, for the
    blocks of one class: ``(start, end, size, align, sec_lo, sec_hi, section_count, totals)``
    (``size``: the aligned sizes), the values ``instance.sections`` and the Python lists
    give. OverflowError where a time or a size passes 62 bits (the Python code then runs)."""
    cdef Py_ssize_t n = len(blocks), i, count = 0
    cdef i64 *s = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *e = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *z = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *buf = <i64 *> malloc(4 * max(n, 1) * sizeof(i64))
    cdef i64 *tot = NULL
    cdef i64 total = 0
    cdef Py_ssize_t *lo = <Py_ssize_t *> malloc(max(n, 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t *hi = <Py_ssize_t *> malloc(max(n, 1) * sizeof(Py_ssize_t))
    cdef list start = [], end = [], size = [], align = [], sec_lo = [], sec_hi = []
    try:
        if not (s and e and z and buf and lo and hi):
            raise MemoryError()
        for i in range(n):
            b = blocks[i]
            d = block_dict(b)
            x, y, w = field(b, d, "start"), field(b, d, "end"), field(b, d, "aligned_size")
            start.append(x)
            end.append(y)
            size.append(w)
            align.append(field(b, d, "alignment"))
            s[i], e[i], z[i] = x, y, w  # OverflowError past 64 bits
            if not (-LIMIT < s[i] < LIMIT and -LIMIT < e[i] < LIMIT and 0 <= z[i] < LIMIT):
                raise OverflowError("times and sizes must be within 2**62")
            total += z[i]
            if total >= LIMIT:
                raise OverflowError("sizes sum past 2**62")
        if n:
            count = sections_core(n, s, e, z, buf, lo, hi, &tot)
        for i in range(n):
            sec_lo.append(lo[i])
            sec_hi.append(hi[i])
        return start, end, size, align, sec_lo, sec_hi, count, tuple([tot[i] for i in range(count)])
    finally:
        free(s)
        free(e)
        free(z)
        free(buf)
        free(lo)
        free(hi)


def class_groups(list blocks):
    """``place``'s checks and grouping in one pass: ``{class: (blocks, max alignment,
    overlapping pairs, sum of aligned sizes)}``, classes sorted, blocks in input order, the
    pairs as ``aliased.overlapping_pairs`` counts them. None where ``model.check_blocks``
    would raise (the caller then runs it) or a time passes 62 bits."""
    cdef Py_ssize_t n = len(blocks), i, k, g
    cdef i64 *s = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *e = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *ss_buf = <i64 *> malloc(2 * max(n, 1) * sizeof(i64))  # starts and a spare
    cdef i64 *es_buf = <i64 *> malloc(2 * max(n, 1) * sizeof(i64))
    cdef i64 *ss = ss_buf
    cdef i64 *es = es_buf
    cdef i64 pairs
    cdef set seen = set()
    cdef dict groups = {}, at = {}, out = {}
    cdef list members, where
    try:
        if not (s and e and ss_buf and es_buf):
            raise MemoryError()
        for i in range(n):
            b = blocks[i]
            d = block_dict(b)
            name = field(b, d, "name")
            if name in seen:
                return None
            seen.add(name)
            x, y = field(b, d, "start"), field(b, d, "end")
            if x > y or field(b, d, "size") < 0 or field(b, d, "alignment") < 1:
                return None
            try:
                s[i], e[i] = x, y
            except OverflowError:
                return None
            if not (-LIMIT < s[i] < LIMIT and -LIMIT < e[i] < LIMIT):
                return None
            cls = field(b, d, "memory_class")
            members = groups.get(cls)
            if members is None:
                members = groups[cls] = []
                at[cls] = []
            members.append(b)
            (<list> at[cls]).append(i)
        for cls in sorted(groups):
            members, where = groups[cls], at[cls]
            g = len(where)
            top = None
            bytes_ = 0
            for k in range(g):
                i = where[k]
                ss_buf[k], es_buf[k] = s[i], e[i]
                b = members[k]
                d = block_dict(b)
                a = field(b, d, "alignment")
                if top is None or a > top:
                    top = a
                bytes_ += field(b, d, "aligned_size")
            ss = sort_i64(ss_buf, ss_buf + max(n, 1), g)
            es = sort_i64(es_buf, es_buf + max(n, 1), g)
            pairs = 0
            for k in range(g):  # j overlaps i: start_j <= end_i, less those with end_j < start_i
                i = where[k]
                pairs += upper_bound(ss, g, e[i]) - lower_bound(es, g, s[i])
            out[cls] = (members, top, pairs - g, bytes_)
        return out
    finally:
        free(s)
        free(e)
        free(ss_buf)
        free(es_buf)


cdef void orders_core(Py_ssize_t n, const i64 *s, const i64 *z, const i64 *w, const i64 *area, const i64 *peak,
                      Triple *keys, int *out) noexcept nogil:
    """``orderings``' six orders into ``out`` (n each, in turn) from the starts ``s``, aligned
    sizes ``z``, minus the widths ``w``, areas ``area`` and contentions ``peak``; each sorted
    by (a, b, index), as np.lexsort's stable sort has them (``keys``: 2 n of scratch)."""
    cdef Py_ssize_t i, o
    cdef Triple *done
    for o in range(6):
        for i in range(n):
            keys[i].c = i
            if o == 0:  # size
                keys[i].a, keys[i].b = -z[i], s[i]
            elif o == 1:  # area
                keys[i].a, keys[i].b = area[i], 0
            elif o == 2:  # length
                keys[i].a, keys[i].b = w[i], -z[i]
            elif o == 3:  # start
                keys[i].a, keys[i].b = s[i], -z[i]
            elif o == 4:  # contention
                keys[i].a, keys[i].b = peak[i], area[i]
            else:  # contention_size
                keys[i].a, keys[i].b = peak[i], -z[i]
        done = sort_triples(keys, keys + n, n)
        for i in range(n):
            out[o * n + i] = <int> done[i].c


def orderings(start, end, size, sec_lo, sec_hi, totals):
    """``greedy.orderings``' six orders (size, area, length, start, contention,
    contention_size), all at once, as a list: ``start``, ``end``, ``size`` (aligned),
    ``sec_lo``, ``sec_hi`` and the section ``totals`` of an ``Instance``. OverflowError
    where a key passes 62 bits (``greedy.orderings`` then sorts in Python)."""
    cdef Py_ssize_t n = len(start), i, k, s
    cdef i64 *s_ = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *z = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *w = <i64 *> malloc(max(n, 1) * sizeof(i64))  # minus the width
    cdef i64 *area = <i64 *> malloc(max(n, 1) * sizeof(i64))  # minus the area
    cdef i64 *peak = <i64 *> malloc(max(n, 1) * sizeof(i64))  # minus the contention
    cdef Triple *keys = <Triple *> malloc(2 * max(n, 1) * sizeof(Triple))
    cdef int *order = <int *> malloc(6 * max(n, 1) * sizeof(int))
    cdef i64 e, top, width
    cdef Py_ssize_t lo, hi, count = len(totals)
    cdef i64 *tot = <i64 *> malloc(max(count, 1) * sizeof(i64))
    cdef list out = []
    try:
        if not (s_ and z and w and area and peak and keys and tot and order):
            raise MemoryError()
        for s in range(count):
            tot[s] = totals[s]
            if not (-LIMIT < tot[s] < LIMIT):
                raise OverflowError("totals past 62 bits")
        if len(end) != n or len(size) != n or len(sec_lo) != n or len(sec_hi) != n:
            raise ValueError("inconsistent instance arrays")
        for i in range(n):
            s_[i], e, z[i] = start[i], end[i], size[i]  # OverflowError past 64 bits
            if not (-LIMIT < s_[i] < LIMIT and -LIMIT < e < LIMIT and 0 <= z[i] < LIMIT):
                raise OverflowError("keys past 62 bits")
            width = e - s_[i] + 1
            if width > 0 and z[i] > LIMIT // width:
                raise OverflowError("area past 62 bits")
            w[i], area[i] = -width, -width * z[i]
            lo, hi = sec_lo[i], sec_hi[i]
            if not (0 <= lo < hi <= count):
                raise ValueError("a block outside the sections")
            top = tot[lo]
            for s in range(lo + 1, hi):
                if tot[s] > top:
                    top = tot[s]
            peak[i] = -top
        with nogil:
            orders_core(n, s_, z, w, area, peak, keys, order)
        for i in range(6):
            out.append([order[i * n + k] for k in range(n)])
        return out
    finally:
        free(s_)
        free(z)
        free(w)
        free(area)
        free(peak)
        free(keys)
        free(order)
        free(tot)


def peak(offsets, size):
    """``Instance.peak``: ``max(map(add, offsets, size), default=0)``. OverflowError where a
    value passes 62 bits (the Python code then runs)."""
    cdef Py_ssize_t n = len(offsets), i
    cdef i64 top = 0, o, z
    if len(size) != n:
        raise ValueError("inconsistent instance arrays")
    for i in range(n):
        o, z = offsets[i], size[i]
        if not (-LIMIT < o < LIMIT and -LIMIT < z < LIMIT):
            raise OverflowError("values past 62 bits")
        if i == 0 or o + z > top:
            top = o + z
    return top


def live_at(sec_lo, sec_hi, Py_ssize_t section):
    """The blocks living in ``section``, ascending: ``[i for i, (lo, hi) in
    enumerate(zip(sec_lo, sec_hi)) if lo <= section < hi]`` (``bounds.clique_bound``)."""
    cdef Py_ssize_t n = len(sec_lo), i, lo, hi
    cdef list out = []
    if len(sec_hi) != n:
        raise ValueError("inconsistent instance arrays")
    for i in range(n):
        lo, hi = sec_lo[i], sec_hi[i]
        if lo <= section < hi:
            out.append(i)
    return out


cdef class Columns:
    """Blocks as columns: ``rgraph.memory.place`` takes them as it takes a list of ``Block``
    (a sequence of them, made when first asked for), without a ``Block`` per resource where
    ``valid``: ``model.check_blocks`` passes and every value fits the C arrays (62 bits,
    areas included). Each class's greedy placement then runs here (:meth:`greedy`)."""

    cdef readonly list names
    cdef readonly list classes  # the memory classes, sorted
    cdef readonly bint valid
    cdef list start, end, size, alignment, memory_class, made
    cdef dict index  # name -> position
    cdef Py_ssize_t n
    cdef i64 *s
    cdef i64 *e
    cdef i64 *z  # aligned sizes
    cdef i64 *a
    cdef int *cls  # the class's place in ``classes``

    def __cinit__(self, list names, list start, list end, list size, list alignment, list memory_class):
        cdef Py_ssize_t n = len(names), i
        cdef i64 width, sum_za = 0
        cdef dict rank = {}
        self.names, self.start, self.end, self.size = names, start, end, size
        self.alignment, self.memory_class, self.n, self.made = alignment, memory_class, n, None
        if not (len(start) == len(end) == len(size) == len(alignment) == len(memory_class) == n):
            raise ValueError("inconsistent columns")
        self.s = <i64 *> malloc(max(n, 1) * sizeof(i64))
        self.e = <i64 *> malloc(max(n, 1) * sizeof(i64))
        self.z = <i64 *> malloc(max(n, 1) * sizeof(i64))
        self.a = <i64 *> malloc(max(n, 1) * sizeof(i64))
        self.cls = <int *> malloc(max(n, 1) * sizeof(int))
        if not (self.s and self.e and self.z and self.a and self.cls):
            raise MemoryError()
        self.index = {}
        self.valid = False
        for i in range(n):
            name, x, y, w, al, c = names[i], start[i], end[i], size[i], alignment[i], memory_class[i]
            if not (type(name) is str and type(x) is int and type(y) is int and type(w) is int
                    and type(al) is int and type(c) is str) or name in self.index:
                return
            self.index[name] = i
            if not (-LIMIT < x < LIMIT and -LIMIT < y < LIMIT and 0 <= w < LIMIT and 1 <= al < LIMIT and x <= y):
                return
            self.s[i], self.e[i], self.a[i] = x, y, al
            self.z[i] = align_up(w, al)
            sum_za += self.z[i] + self.a[i]
            width = self.e[i] - self.s[i] + 1
            if sum_za >= LIMIT or self.z[i] > LIMIT // width:
                return
            found = rank.get(c)
            if found is None:
                found = rank[c] = len(rank)
            self.cls[i] = found
        self.classes = sorted(rank)
        where = [rank[c] for c in self.classes]  # old place -> new
        order = [0] * len(where)
        for i, k in enumerate(where):
            order[k] = i
        for i in range(n):
            self.cls[i] = order[self.cls[i]]
        self.valid = True

    def __dealloc__(self):
        free(self.s)
        free(self.e)
        free(self.z)
        free(self.a)
        free(self.cls)

    def blocks(self) -> list:
        """The ``Block`` of each entry (made once)."""
        if self.made is None:
            self.made = [Block(*row) for row in zip(self.names, self.start, self.end, self.size, self.alignment,
                                                  self.memory_class)]
        return self.made

    def __len__(self):
        return self.n

    def __getitem__(self, k):
        return self.blocks()[k]

    def __iter__(self):
        return iter(self.blocks())

    def group(self, int k) -> list:
        """The blocks of the class ``classes[k]``, in input order."""
        made = self.blocks()
        return [made[i] for i in range(self.n) if self.cls[i] == k]

    def greedy(self, int k, conflicts, double dense_limit, i64 dive_budget, Py_ssize_t max_blocks, heap_id,
               dict offsets):
        """``place``'s loop body for the class ``classes[k]`` (``valid`` columns) where it ends
        with ``aliased.place_class``'s greedy: its offsets written to ``offsets`` as ``(heap_id,
        offset)`` in input order, and ``(max alignment, aligned bytes, time bound, peak)``
        returned. None where ``place`` must run it on the blocks: ``max_blocks``
        (``instance.SWEEP_FROM``) blocks or more, overlapping pairs past ``dense_limit``
        (``aliased.too_dense_pairs``: TLSF), or the search to run (separable, above the bound,
        ``dive_budget``, ``aliased.dive_ops`` of the budget, enough for one dive)."""
        cdef Py_ssize_t n = self.n, g = 0, i, j, t, o, q, count, npairs = 0, room = 64, cut
        cdef Py_ssize_t overlapping = 0, pair_count, chosen_n
        cdef i64 lb = 0, bound, best_peak = -1, top, group_bytes = 0
        cdef bint separable, cliqued, duplicate
        cdef int code = 0
        cdef Graph gr
        # one buffer of i64 (``g`` each unless said): s, e, z, a, offsets, best, minus width,
        # minus area, minus contention, sorted starts and ends (2 g each: a spare), sections (4 g)
        cdef i64 *mem = NULL
        cdef i64 *s
        cdef i64 *e
        cdef i64 *z
        cdef i64 *a
        cdef i64 *off
        cdef i64 *best
        cdef i64 *w
        cdef i64 *area
        cdef i64 *peak
        cdef i64 *ss
        cdef i64 *es
        cdef i64 *buf
        cdef i64 *sorted_s
        cdef i64 *sorted_e
        cdef i64 *tot
        cdef int *ints = NULL  # members (g), local place (n), orders (6 g), chosen (g)
        cdef int *at
        cdef int *local
        cdef int *orders
        cdef int *chosen
        cdef Py_ssize_t *lo = NULL
        cdef Py_ssize_t *hi
        cdef Py_ssize_t *pairs = NULL
        cdef Triple *keys = NULL
        cdef unsigned char *adj = NULL
        cdef unsigned char *joinable = NULL
        if not self.valid:
            raise ValueError("greedy needs valid columns")
        for i in range(n):
            g += self.cls[i] == k
        if g == 0 or g >= max_blocks:
            return None
        gr.nbr_ptr = gr.nbr_idx = NULL
        try:
            mem = <i64 *> malloc(17 * g * sizeof(i64))
            ints = <int *> malloc((9 * g + n) * sizeof(int))
            lo = <Py_ssize_t *> malloc(2 * g * sizeof(Py_ssize_t))
            pairs = <Py_ssize_t *> malloc(2 * room * sizeof(Py_ssize_t))
            keys = <Triple *> malloc(2 * g * sizeof(Triple))
            adj = <unsigned char *> malloc(g * g + g)
            gr.nbr_ptr = <int *> malloc((g + 1) * sizeof(int))
            if not (mem and ints and lo and pairs and keys and adj and gr.nbr_ptr):
                raise MemoryError()
            joinable = adj + g * g
            s, e, z, a, off, best = mem, mem + g, mem + 2 * g, mem + 3 * g, mem + 4 * g, mem + 5 * g
            w, area, peak, ss, es, buf = mem + 6 * g, mem + 7 * g, mem + 8 * g, mem + 9 * g, mem + 11 * g, mem + 13 * g
            at, local, orders, chosen = ints, ints + g, ints + g + n, ints + 7 * g + n
            hi = lo + g
            t = 0
            for i in range(n):
                local[i] = -1
                if self.cls[i] == k:
                    at[t], local[i] = i, t
                    s[t], e[t], z[t], a[t] = self.s[i], self.e[i], self.z[i], self.a[i]
                    ss[t], es[t] = s[t], e[t]
                    group_bytes += z[t]
                    t += 1
            # ``aliased.overlapping_pairs``, as ``class_groups`` counts them
            sorted_s = sort_i64(ss, ss + g, g)
            sorted_e = sort_i64(es, es + g, g)
            for t in range(g):
                overlapping += upper_bound(sorted_s, g, e[t]) - lower_bound(sorted_e, g, s[t])
            if <double> (overlapping - g) > dense_limit:
                return None
            count = sections_core(g, s, e, z, buf, lo, hi, &tot)
            for q in range(count):
                if tot[q] > lb:
                    lb = tot[q]
            if conflicts:  # ``conflict_matrix``'s pairs
                get = conflicts.get
                for t in range(g):
                    row = get(self.names[at[t]])
                    if not row:
                        continue
                    for other in row:
                        found = self.index.get(other)
                        if found is None:
                            continue
                        j = local[<Py_ssize_t> found]
                        if j < 0 or j == t:
                            continue
                        pairs = _push_pair(pairs, &room, npairs, t, j)
                        npairs += 1
            with nogil:
                separable = matrix_core(g, s, e, pairs, npairs, adj)
            gr.n, gr.size, gr.align, gr.adj = <int> g, z, a, adj
            pair_count = graph_from_matrix(&gr)
            with nogil:
                for t in range(g):  # ``orderings``' keys
                    w[t] = -(e[t] - s[t] + 1)
                    area[t] = w[t] * z[t]
                    top = tot[lo[t]]
                    for q in range(lo[t] + 1, hi[t]):
                        if tot[q] > top:
                            top = tot[q]
                    peak[t] = -top
                orders_core(g, s, z, w, area, peak, keys, orders)
                # ``aliased.place_class``'s greedy loop
                bound, cliqued = lb, separable
                for o in range(6):
                    duplicate = False
                    for q in range(o):
                        if memcmp(orders + q * g, orders + o * g, g * sizeof(int)) == 0:
                            duplicate = True
                            break
                    if duplicate:
                        continue
                    for t in range(g):
                        off[t] = -1
                    code = place(&gr, orders + o * g, <int> g, best_peak, off)
                    if code < 0:
                        break
                    if code == 1:
                        continue
                    top = off[0] + z[0]
                    for t in range(1, g):
                        if off[t] + z[t] > top:
                            top = off[t] + z[t]
                    if best_peak < 0 or top < best_peak:
                        best_peak = top
                        memcpy(best, off, g * sizeof(i64))
                    if best_peak > bound and not cliqued:  # ``bounds.clique_bound``
                        cut = 0
                        for q in range(1, count):
                            if tot[q] > tot[cut]:
                                cut = q
                        chosen_n = 0
                        for t in range(g):
                            if lo[t] <= cut < hi[t]:
                                chosen[chosen_n] = <int> t
                                chosen_n += 1
                        bound, cliqued = tot[cut] + clique_core(&gr, chosen, <int> chosen_n, joinable), True
                    if best_peak <= bound:
                        break
            if code < 0:
                raise MemoryError()
            if best_peak > bound and separable and dive_budget >= g * g // 2 + pair_count:
                return None  # the search runs
            for t in range(g):
                offsets[self.names[at[t]]] = (heap_id, best[t])
            top_align = None
            for t in range(g):
                x = self.alignment[at[t]]
                if top_align is None or x > top_align:
                    top_align = x
            return top_align, group_bytes, lb, best_peak
        finally:
            free(mem)
            free(ints)
            free(lo)
            free(pairs)
            free(keys)
            free(adj)
            free(gr.nbr_ptr)
            free(gr.nbr_idx)
