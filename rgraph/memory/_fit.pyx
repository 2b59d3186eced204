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
from libc.string cimport memmove

include "_sort.pxi"
from cpython.object cimport PyObject

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


cdef class Flat:
    """An ``Instance``'s sizes, alignments and neighbour lists (CSR) as C arrays, from its
    conflict matrix (``adjacency``, uint8, kept for membership tests) or its neighbour lists
    (``neighbors``, used when ``adjacency`` is None). Dense (a quarter of all pairs or more
    may not share bytes, as in ``greedy.best_fit_python``): every placed block is kept sorted."""

    cdef int n
    cdef bint dense
    cdef i64 *size
    cdef i64 *align
    cdef int *nbr_ptr
    cdef int *nbr_idx
    cdef const unsigned char *adj
    cdef object matrix  # owns adj

    def __cinit__(self, size, align, adjacency, neighbors):
        cdef int n = len(size), i, j, k
        cdef Py_ssize_t pairs = 0
        cdef i64 total = 0
        cdef const unsigned char[:, ::1] m
        self.n, self.adj, self.nbr_idx = n, NULL, NULL
        if len(align) != n:
            raise ValueError("inconsistent instance arrays")
        self.size = <i64 *> malloc(max(n, 1) * sizeof(i64))
        self.align = <i64 *> malloc(max(n, 1) * sizeof(i64))
        self.nbr_ptr = <int *> malloc((n + 1) * sizeof(int))
        if not (self.size and self.align and self.nbr_ptr):
            raise MemoryError()
        for i in range(n):
            self.size[i] = size[i]  # OverflowError past 64 bits
            self.align[i] = align[i]
            if not (0 <= self.size[i] < LIMIT and 1 <= self.align[i] < LIMIT):
                raise OverflowError("sizes and alignments must be in [0, 2**62), alignments positive")
            total += self.size[i] + self.align[i]
            if total >= LIMIT:
                raise OverflowError("sizes and alignments sum past 2**62")
        if adjacency is not None:
            m = adjacency
            if m.shape[0] != n or m.shape[1] != n:
                raise ValueError("adjacency must be n by n")
            self.matrix = adjacency
            self.adj = &m[0, 0] if n else NULL
            with nogil:
                for i in range(n):
                    for j in range(n):
                        pairs += self.adj[<Py_ssize_t> i * n + j] != 0
            self.dense = 4 * pairs >= <Py_ssize_t> n * n
            if self.dense:  # every block scans the placed ones against its row: no lists
                self.nbr_idx = NULL
                for i in range(n + 1):
                    self.nbr_ptr[i] = 0
                return
            self.nbr_idx = <int *> malloc(max(pairs, 1) * sizeof(int))
            if not self.nbr_idx:
                raise MemoryError()
            k = 0
            with nogil:
                for i in range(n):
                    self.nbr_ptr[i] = k
                    for j in range(n):
                        if self.adj[<Py_ssize_t> i * n + j]:
                            self.nbr_idx[k] = j
                            k += 1
        else:
            if len(neighbors) != n:
                raise ValueError("inconsistent instance arrays")
            for row in neighbors:
                pairs += len(row)
            self.nbr_idx = <int *> malloc(max(pairs, 1) * sizeof(int))
            if not self.nbr_idx:
                raise MemoryError()
            k = 0
            for i in range(n):
                self.nbr_ptr[i] = k
                for x in neighbors[i]:
                    j = x
                    if not (0 <= j < n):
                        raise ValueError("neighbour out of range")
                    self.nbr_idx[k] = j
                    k += 1
        self.nbr_ptr[n] = k
        self.dense = 4 * k >= <Py_ssize_t> n * n

    def __dealloc__(self):
        free(self.size)
        free(self.align)
        free(self.nbr_ptr)
        free(self.nbr_idx)


cdef inline i64 align_up(i64 x, i64 a) noexcept nogil:
    return x if x % a == 0 else x + a - x % a


cdef int place(Flat flat, const int *order, int count, i64 limit, i64 *offsets) noexcept nogil:
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
    cdef int n = flat.n, count = len(order), i, k, code
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
            code = place(flat, blocks, count, limit, offsets)
        if code < 0:
            raise MemoryError()
        if code == 1:
            return None
        return [offsets[i] for i in range(n)]
    finally:
        free(blocks)
        free(offsets)


def clique_extra(Flat flat, members):
    """``bounds.clique_bound``'s greedy growth on the conflict matrix: starting from the
    blocks that may not share bytes with every one of ``members``, add the heaviest (by
    size as a float, the first of equal ones), keep those in conflict with it, until none
    is left; the sizes added. Needs the matrix (``adjacency``)."""
    cdef int n = flat.n, i, j, k, m, count = len(members)
    cdef Py_ssize_t n_ = n
    cdef const unsigned char *adj = flat.adj
    cdef i64 extra = 0
    cdef double best
    cdef unsigned char *joinable
    cdef int *chosen
    if adj == NULL and n:
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
            for i in range(n):
                joinable[i] = 1
                for k in range(count):
                    if not adj[i * n_ + chosen[k]]:
                        joinable[i] = 0
                        break
            while True:
                j, best = -1, -1.0
                for i in range(n):
                    if joinable[i] and <double> flat.size[i] > best:
                        j, best = i, <double> flat.size[i]
                if j < 0:
                    break
                extra += flat.size[j]
                for i in range(n):
                    joinable[i] = joinable[i] and adj[i * n_ + j]
        return extra
    finally:
        free(joinable)
        free(chosen)


def conflict_matrix(start, end, names, conflicts):
    """``instance.time_overlaps(start, end)`` with the ``conflicts`` among ``names`` (a
    mapping from a name to names it may not share bytes with; names of other classes are
    skipped) added where some pair is apart in time, as ``Instance.build`` does:
    ``(adjacency, separable)``, ``separable`` when every conflicting pair overlaps in time
    (the matrix then holds the time overlaps only). OverflowError where a time passes
    64 bits."""
    import numpy as np

    cdef Py_ssize_t n = len(start), i, j, k, count = 0, room = 64
    cdef i64 si, ei
    cdef i64 *s = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *e = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef Py_ssize_t *pairs = <Py_ssize_t *> malloc(2 * room * sizeof(Py_ssize_t))
    cdef Py_ssize_t *grown
    cdef unsigned char[:, ::1] m
    cdef unsigned char *adj
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
                    if count == room:
                        room *= 2
                        grown = <Py_ssize_t *> realloc(pairs, 2 * room * sizeof(Py_ssize_t))
                        if not grown:
                            raise MemoryError()
                        pairs = grown
                    pairs[2 * count], pairs[2 * count + 1] = i, j
                    count += 1
        matrix = np.empty((n, n), dtype=np.uint8)
        if n:
            m = matrix
            adj = &m[0, 0]
            with nogil:
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


def class_arrays(list blocks):
    """``Instance.build``'s per-block lists and sections, and ``Instance._totals``, for the
    blocks of one class: ``(start, end, size, align, sec_lo, sec_hi, section_count, totals)``
    (``size``: the aligned sizes), the values ``instance.sections`` and the Python lists
    give. OverflowError where a time or a size passes 62 bits (the Python code then runs)."""
    cdef Py_ssize_t n = len(blocks), i, m = 0, count
    cdef i64 *s = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *e = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *z = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *coords_buf = <i64 *> malloc(2 * max(2 * n, 1) * sizeof(i64))  # the coordinates and a spare
    cdef i64 *coords = coords_buf
    cdef i64 *diff = NULL
    cdef i64 total = 0, run = 0
    cdef Py_ssize_t *lo = <Py_ssize_t *> malloc(max(n, 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t *hi = <Py_ssize_t *> malloc(max(n, 1) * sizeof(Py_ssize_t))
    cdef list start = [], end = [], size = [], align = [], sec_lo = [], sec_hi = [], totals = []
    try:
        if not (s and e and z and coords_buf and lo and hi):
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
            coords[2 * i], coords[2 * i + 1] = s[i], e[i] + 1
        if n:
            coords = sort_i64(coords_buf, coords_buf + max(2 * n, 1), 2 * n)
            m = 1
            for i in range(1, 2 * n):
                if coords[i] != coords[m - 1]:
                    coords[m] = coords[i]
                    m += 1
        count = m - 1 if m > 1 else 0
        diff = <i64 *> calloc(count + 1, sizeof(i64))
        if not diff:
            raise MemoryError()
        for i in range(n):
            lo[i] = lower_bound(coords, m, s[i])
            hi[i] = lower_bound(coords, m, e[i] + 1)
            sec_lo.append(lo[i])
            sec_hi.append(hi[i])
            diff[lo[i]] += z[i]
            diff[hi[i]] -= z[i]
        for i in range(count):
            run += diff[i]
            totals.append(run)
        return start, end, size, align, sec_lo, sec_hi, count, tuple(totals)
    finally:
        free(s)
        free(e)
        free(z)
        free(coords_buf)
        free(diff)
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


cdef list sorted_by(Triple *keys, Triple *spare, Py_ssize_t n):
    """The indices ``c`` of ``keys`` sorted by (a, b, c): ``sort_triples`` (``c``: the index,
    so ties go by index, as np.lexsort's stable sort has them)."""
    cdef Triple *done
    with nogil:
        done = sort_triples(keys, spare, n)
    return [done[k].c for k in range(n)]


def orderings(start, end, size, sec_lo, sec_hi, totals):
    """``greedy.orderings``' six orders (size, area, length, start, contention,
    contention_size), all at once, as a list: ``start``, ``end``, ``size`` (aligned),
    ``sec_lo``, ``sec_hi`` and the section ``totals`` of an ``Instance``. OverflowError
    where a key passes 62 bits (``greedy.orderings`` then sorts in Python)."""
    cdef Py_ssize_t n = len(start), i, s
    cdef i64 *s_ = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *z = <i64 *> malloc(max(n, 1) * sizeof(i64))
    cdef i64 *w = <i64 *> malloc(max(n, 1) * sizeof(i64))  # minus the width
    cdef i64 *area = <i64 *> malloc(max(n, 1) * sizeof(i64))  # minus the area
    cdef i64 *peak = <i64 *> malloc(max(n, 1) * sizeof(i64))  # minus the contention
    cdef Triple *keys = <Triple *> malloc(2 * max(n, 1) * sizeof(Triple))
    cdef Triple *spare = keys + max(n, 1)
    cdef i64 e, top, width
    cdef Py_ssize_t lo, hi, count = len(totals)
    cdef i64 *tot = <i64 *> malloc(max(count, 1) * sizeof(i64))
    cdef list out = []
    try:
        if not (s_ and z and w and area and peak and keys and tot):
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
        for i in range(n):
            keys[i].a, keys[i].b, keys[i].c = -z[i], s_[i], i
        out.append(sorted_by(keys, spare, n))  # size
        for i in range(n):
            keys[i].a, keys[i].b, keys[i].c = area[i], 0, i
        out.append(sorted_by(keys, spare, n))  # area
        for i in range(n):
            keys[i].a, keys[i].b, keys[i].c = w[i], -z[i], i
        out.append(sorted_by(keys, spare, n))  # length
        for i in range(n):
            keys[i].a, keys[i].b, keys[i].c = s_[i], -z[i], i
        out.append(sorted_by(keys, spare, n))  # start
        for i in range(n):
            keys[i].a, keys[i].b, keys[i].c = peak[i], area[i], i
        out.append(sorted_by(keys, spare, n))  # contention
        for i in range(n):
            keys[i].a, keys[i].b, keys[i].c = peak[i], -z[i], i
        out.append(sorted_by(keys, spare, n))  # contention_size
        return out
    finally:
        free(s_)
        free(z)
        free(w)
        free(area)
        free(peak)
        free(keys)
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
