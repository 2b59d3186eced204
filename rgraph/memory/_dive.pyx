# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled mirror of ``rgraph.memory.elastic.dive_python``: the same elastic dive (candidate
order, tie-breaks, capacity raises, blamed list, operations charged, cut-offs) on flat C
arrays. ``Flat`` is one instance's arrays (made once per ``Instance``, see
``rgraph.memory.elastic``); ``dive`` returns ``(offsets or None, peak, blamed, ops)`` or None,
the fields of ``elastic.Dive``. Any change to the Python dive must be made here too (the tests
compare the two on random instances and the MiniMalloc traces)."""

from libc.stdlib cimport free, malloc, realloc
from libc.string cimport memmove

ctypedef long long i64

cdef i64 NO_LIMIT = (<i64> 1) << 62


cdef class Flat:
    """An ``Instance``'s sizes, alignments, neighbour lists and section rows as C arrays
    (CSR for the lists) and its section totals."""

    cdef int n, sections, max_degree
    cdef i64 *size
    cdef i64 *align
    cdef i64 *totals
    cdef int *nbr_ptr
    cdef int *nbr_idx
    cdef int *sec_lo
    cdef int *sec_hi
    cdef int *row_ptr
    cdef int *row_idx

    def __cinit__(self, size, align, neighbors, sec_lo, sec_hi, rows, totals):
        cdef int n = len(size), s_count = len(rows), i, k
        cdef Py_ssize_t pairs = 0, members = 0
        self.n, self.sections, self.max_degree = n, s_count, 0
        for row in neighbors:
            pairs += len(row)
            if len(row) > self.max_degree:
                self.max_degree = len(row)
        for row in rows:
            members += len(row)
        self.size = <i64 *> malloc(max(n, 1) * sizeof(i64))
        self.align = <i64 *> malloc(max(n, 1) * sizeof(i64))
        self.totals = <i64 *> malloc(max(s_count, 1) * sizeof(i64))
        self.nbr_ptr = <int *> malloc((n + 1) * sizeof(int))
        self.nbr_idx = <int *> malloc(max(pairs, 1) * sizeof(int))
        self.sec_lo = <int *> malloc(max(n, 1) * sizeof(int))
        self.sec_hi = <int *> malloc(max(n, 1) * sizeof(int))
        self.row_ptr = <int *> malloc((s_count + 1) * sizeof(int))
        self.row_idx = <int *> malloc(max(members, 1) * sizeof(int))
        if not (self.size and self.align and self.totals and self.nbr_ptr and self.nbr_idx and self.sec_lo
                and self.sec_hi and self.row_ptr and self.row_idx):
            raise MemoryError()
        if len(align) != n or len(neighbors) != n or len(sec_lo) != n or len(sec_hi) != n or len(totals) != s_count:
            raise ValueError("inconsistent instance arrays")
        k = 0
        for i in range(n):
            self.size[i] = size[i]
            self.align[i] = align[i]
            if self.align[i] < 1 or self.size[i] < 0:
                raise ValueError("alignments must be positive, sizes non-negative")
            self.sec_lo[i] = sec_lo[i]
            self.sec_hi[i] = sec_hi[i]
            if not (0 <= self.sec_lo[i] <= self.sec_hi[i] <= s_count):
                raise ValueError("section range out of bounds")
            self.nbr_ptr[i] = k
            for j in neighbors[i]:
                if not (0 <= j < n):
                    raise ValueError("neighbour out of range")
                self.nbr_idx[k] = j
                k += 1
        self.nbr_ptr[n] = k
        k = 0
        for i in range(s_count):
            self.totals[i] = totals[i]
            self.row_ptr[i] = k
            for j in rows[i]:
                if not (0 <= j < n):
                    raise ValueError("section member out of range")
                self.row_idx[k] = j
                k += 1
        self.row_ptr[s_count] = k

    def __dealloc__(self):
        free(self.size)
        free(self.align)
        free(self.totals)
        free(self.nbr_ptr)
        free(self.nbr_idx)
        free(self.sec_lo)
        free(self.sec_hi)
        free(self.row_ptr)
        free(self.row_idx)


cdef struct State:
    # the instance (borrowed from Flat)
    const i64 *size
    const i64 *align
    const int *nbr_ptr
    const int *nbr_idx
    const int *sec_lo
    const int *sec_hi
    const int *row_ptr
    const int *row_idx
    # the dive
    i64 *mins
    i64 *offsets
    i64 *total
    int *witness
    i64 ops
    i64 cap
    int row_share
    # what the last apply changed
    int *changed
    i64 *olds
    int nchanged
    int first
    int last


cdef inline i64 align_up(i64 x, i64 a) noexcept nogil:
    cdef i64 r = x % a
    return x if r == 0 else x + a - r


cdef void apply(State *st, int c, const int *cands, int ncand) noexcept nogil:
    """Place ``c`` at its lowest offset (``elastic.dive_python``'s ``apply``)."""
    cdef i64 off = st.mins[c]
    cdef i64 top = off + st.size[c]
    cdef i64 old, z
    cdef int k, j, s, n = 0, first = st.sec_lo[c], last = st.sec_hi[c]
    st.offsets[c] = off
    for k in range(st.nbr_ptr[c], st.nbr_ptr[c + 1]):
        j = st.nbr_idx[k]
        if st.offsets[j] < 0:
            old = st.mins[j]
            if old < top:
                st.mins[j] = align_up(top, st.align[j])
                st.changed[n] = j
                st.olds[n] = old
                n += 1
                if st.sec_lo[j] < first:
                    first = st.sec_lo[j]
                if st.sec_hi[j] > last:
                    last = st.sec_hi[j]
    for k in range(ncand):
        j = cands[k]
        if j == c:
            break
        old = st.mins[j]
        if old < off:
            st.mins[j] = align_up(off, st.align[j])
            st.changed[n] = j
            st.olds[n] = old
            n += 1
            if st.sec_lo[j] < first:
                first = st.sec_lo[j]
            if st.sec_hi[j] > last:
                last = st.sec_hi[j]
    z = st.size[c]
    for s in range(st.sec_lo[c], st.sec_hi[c]):
        st.total[s] -= z
    st.nchanged, st.first, st.last = n, first, last


cdef void undo(State *st, int c) noexcept nogil:
    cdef int k, s
    cdef i64 z = st.size[c]
    for k in range(st.nchanged - 1, -1, -1):
        st.mins[st.changed[k]] = st.olds[k]
    for s in range(st.sec_lo[c], st.sec_hi[c]):
        st.total[s] += z
    st.offsets[c] = -1


cdef bint passes(State *st, i64 within) noexcept nogil:
    """Whether the section inference holds at capacity ``within``."""
    cdef int k, j, s, w, hi
    cdef i64 left, threshold
    cdef bint found
    for k in range(st.nchanged):
        j = st.changed[k]
        if st.mins[j] + st.size[j] > within:
            return False
    for s in range(st.first, st.last):
        left = st.total[s]
        if left:
            threshold = within - left
            w = st.witness[s]
            if w >= 0 and st.offsets[w] < 0 and st.mins[w] <= threshold:
                continue
            hi = st.row_ptr[s + 1]
            st.ops += (hi - st.row_ptr[s]) // st.row_share
            found = False
            for k in range(st.row_ptr[s], hi):
                j = st.row_idx[k]
                if st.offsets[j] < 0 and st.mins[j] <= threshold:
                    st.witness[s] = j
                    found = True
                    break
            if not found:
                return False
    return True


cdef i64 floor_above(State *st, int s, i64 within) noexcept nogil:
    """The lowest offset an unplaced block of section ``s`` can take if above ``within``
    less the bytes left there, else -1."""
    cdef i64 threshold = within - st.total[s]
    cdef int w = st.witness[s], k, j, hi
    cdef i64 floor = NO_LIMIT
    if w >= 0 and st.offsets[w] < 0 and st.mins[w] <= threshold:
        return -1
    hi = st.row_ptr[s + 1]
    st.ops += (hi - st.row_ptr[s]) // st.row_share
    for k in range(st.row_ptr[s], hi):
        j = st.row_idx[k]
        if st.offsets[j] < 0 and st.mins[j] < floor:
            floor = st.mins[j]
    return floor if floor > threshold else -1


cdef i64 needed(State *st, i64 top, i64 stop) noexcept nogil:
    """The least capacity above ``cap`` at which the inference holds (at least ``top``),
    or some value at or above ``stop`` once it is known to reach it."""
    cdef i64 need = top, left, floor
    cdef int k, j, s
    for k in range(st.nchanged):
        j = st.changed[k]
        if st.mins[j] + st.size[j] > need:
            need = st.mins[j] + st.size[j]
    for s in range(st.first, st.last):
        left = st.total[s]
        if left:
            floor = floor_above(st, s, st.cap)
            if floor >= 0 and floor + left > need:
                need = floor + left
                if need >= stop:
                    return need
    return need


cdef int run(State *st, int *unplaced, int count, int *cands, int ncandidates, i64 step_ops, i64 try_ops,
             i64 limit, bint stops, i64 give_up_at, int **blamed, Py_ssize_t *nblamed,
             Py_ssize_t *blamed_room) noexcept nogil:
    """The dive's loop: 0 placed everything, 1 out of operations, 2 given up, -1 no memory."""
    cdef i64 lowest_top, t, m, need, best_need, left, floor
    cdef int k, p, q, i, c, chosen, best, ncand, s, j, hi
    cdef int *grown
    while count > 0:
        st.ops += step_ops + count // 2
        if st.ops > limit:
            return 1
        lowest_top = NO_LIMIT
        for k in range(count):
            i = unplaced[k]
            t = st.mins[i] + st.size[i]
            if t < lowest_top:
                lowest_top = t
        ncand = 0  # the first ``ncandidates`` of the stable sort by lowest offset
        for k in range(count):
            i = unplaced[k]
            m = st.mins[i]
            if m < lowest_top:
                p = ncand
                while p > 0 and st.mins[cands[p - 1]] > m:
                    p -= 1
                if p < ncandidates:
                    q = ncand if ncand < ncandidates else ncandidates - 1
                    while q > p:
                        cands[q] = cands[q - 1]
                        q -= 1
                    cands[p] = i
                    if ncand < ncandidates:
                        ncand += 1
        chosen = -1
        for k in range(ncand):
            c = cands[k]
            apply(st, c, cands, ncand)
            st.ops += try_ops + (st.nbr_ptr[c + 1] - st.nbr_ptr[c] + st.last - st.first) // 2
            if passes(st, st.cap):
                chosen = c
                break
            undo(st, c)
        if chosen < 0:  # raise the capacity to the least one of the candidates needs
            best, best_need = -1, 0
            for k in range(ncand):
                c = cands[k]
                apply(st, c, cands, ncand)
                st.ops += try_ops + (st.nbr_ptr[c + 1] - st.nbr_ptr[c] + st.last - st.first) // 2
                if best < 0 or passes(st, best_need - 1):
                    need = needed(st, st.mins[c] + st.size[c], best_need if best >= 0 else NO_LIMIT)
                    if best < 0 or need < best_need:
                        best, best_need = c, need
                undo(st, c)
            st.cap = best_need
            chosen = best
            apply(st, chosen, cands, ncand)
            for s in range(st.first, st.last):
                left = st.total[s]
                if left:
                    floor = floor_above(st, s, st.cap - 1)
                    if floor >= 0:  # the section sets the new capacity
                        hi = st.row_ptr[s + 1]
                        if nblamed[0] + (hi - st.row_ptr[s]) > blamed_room[0]:
                            blamed_room[0] = 2 * blamed_room[0] + (hi - st.row_ptr[s])
                            grown = <int *> realloc(blamed[0], blamed_room[0] * sizeof(int))
                            if not grown:
                                return -1
                            blamed[0] = grown
                        for k in range(st.row_ptr[s], hi):
                            j = st.row_idx[k]
                            if st.offsets[j] < 0:
                                blamed[0][nblamed[0]] = j
                                nblamed[0] += 1
            if stops and st.cap >= give_up_at:
                return 2
        for k in range(count):  # unplaced.remove(chosen)
            if unplaced[k] == chosen:
                memmove(&unplaced[k], &unplaced[k + 1], (count - k - 1) * sizeof(int))
                break
        count -= 1
    return 0


def dive(Flat flat, order, i64 capacity, ops_limit, give_up_at, int candidates, i64 step_ops, i64 try_ops,
         int row_share):
    """``elastic.dive_python(inst, order, capacity, ops_limit, give_up_at)`` with its constants
    (``CANDIDATES``, ``STEP_OPS``, ``TRY_OPS``, ``ROW_SHARE``) given: ``(offsets or None, peak,
    blamed, ops)``, or None when out of operations."""
    cdef int n = flat.n, S = flat.sections, i, k, count = 0, code
    cdef i64 limit = NO_LIMIT if ops_limit is None else ops_limit
    cdef bint stops = give_up_at is not None
    cdef i64 give_up = give_up_at if stops else 0
    cdef i64 peak, total_max
    cdef State st
    cdef int *unplaced = NULL
    cdef int *cands = NULL
    cdef int *blamed = NULL
    cdef Py_ssize_t nblamed = 0, blamed_room = 64
    if candidates < 1 or row_share < 1:
        raise ValueError("candidates and row_share must be positive")
    st.size, st.align, st.nbr_ptr, st.nbr_idx = flat.size, flat.align, flat.nbr_ptr, flat.nbr_idx
    st.sec_lo, st.sec_hi, st.row_ptr, st.row_idx = flat.sec_lo, flat.sec_hi, flat.row_ptr, flat.row_idx
    st.ops, st.row_share, st.nchanged, st.first, st.last = 0, row_share, 0, 0, 0
    st.mins = <i64 *> malloc(max(n, 1) * sizeof(i64))
    st.offsets = <i64 *> malloc(max(n, 1) * sizeof(i64))
    st.total = <i64 *> malloc(max(S, 1) * sizeof(i64))
    st.witness = <int *> malloc(max(S, 1) * sizeof(int))
    st.changed = <int *> malloc((flat.max_degree + candidates) * sizeof(int))
    st.olds = <i64 *> malloc((flat.max_degree + candidates) * sizeof(i64))
    unplaced = <int *> malloc(max(len(order), 1) * sizeof(int))
    cands = <int *> malloc(candidates * sizeof(int))
    blamed = <int *> malloc(blamed_room * sizeof(int))
    try:
        if not (st.mins and st.offsets and st.total and st.witness and st.changed and st.olds and unplaced
                and cands and blamed):
            raise MemoryError()
        for i in range(n):
            st.mins[i] = 0
            st.offsets[i] = 0 if flat.size[i] == 0 else -1
        total_max = 0
        for k in range(S):
            st.total[k] = flat.totals[k]
            st.witness[k] = -1
            if st.total[k] > total_max:
                total_max = st.total[k]
        for x in order:
            i = x
            if not (0 <= i < n):
                raise IndexError("order holds a block out of range")
            if flat.size[i] > 0:
                unplaced[count] = i
                count += 1
        st.cap = capacity if capacity > total_max else total_max
        with nogil:
            code = run(&st, unplaced, count, cands, candidates, step_ops, try_ops, limit, stops, give_up,
                       &blamed, &nblamed, &blamed_room)
        if code < 0:
            raise MemoryError()
        if code == 1:
            return None
        blamed_list = [blamed[k] for k in range(nblamed)]
        if code == 2:
            return None, st.cap, blamed_list, st.ops
        peak = 0
        for i in range(n):
            if st.offsets[i] + flat.size[i] > peak:
                peak = st.offsets[i] + flat.size[i]
        return [st.offsets[i] for i in range(n)], peak, blamed_list, st.ops
    finally:
        free(st.mins)
        free(st.offsets)
        free(st.total)
        free(st.witness)
        free(st.changed)
        free(st.olds)
        free(unplaced)
        free(cands)
        free(blamed)
