# Included by the compiled placement and compiler helpers (rgraph/memory/_fit.pyx,
# rgraph/compiler/_memory.pyx, rgraph/compiler/_queue_order.pyx): merge sorts (runs of 8 by
# insertion) with the comparison inlined, for the few hundred keys a compile sorts at a time
# (``qsort``'s call per comparison, and its copy through a byte buffer, cost more than the rest).


cdef struct Triple:
    long long a  # most significant
    long long b
    long long c


cdef inline bint triple_less(const Triple *p, const Triple *q) noexcept nogil:
    if p.a != q.a:
        return p.a < q.a
    if p.b != q.b:
        return p.b < q.b
    return p.c < q.c


ctypedef fused Sortable:
    Triple
    long long


cdef inline bint _less(Sortable *p, Sortable *q) noexcept nogil:
    if Sortable is Triple:
        return triple_less(p, q)
    else:
        return p[0] < q[0]


cdef Sortable *merge_sort(Sortable *src, Sortable *dst, Py_ssize_t n) noexcept nogil:
    """Sort ``src[:n]`` (triples by (a, b, c), numbers ascending), ``dst`` (as long) the spare
    buffer: returns the one holding the sorted items."""
    cdef Py_ssize_t k, j, width, lo, mid, hi, x, y, o
    cdef Sortable item
    cdef Sortable *swap
    lo = 0
    while lo < n:
        hi = lo + 8 if lo + 8 < n else n
        for k in range(lo + 1, hi):
            item = src[k]
            j = k
            while j > lo and _less(&item, &src[j - 1]):
                src[j] = src[j - 1]
                j -= 1
            src[j] = item
        lo = hi
    width = 8
    while width < n:
        lo = 0
        while lo < n:
            mid = lo + width if lo + width < n else n
            hi = lo + 2 * width if lo + 2 * width < n else n
            x, y, o = lo, mid, lo
            while x < mid and y < hi:
                if _less(&src[y], &src[x]):
                    dst[o] = src[y]
                    y += 1
                else:
                    dst[o] = src[x]
                    x += 1
                o += 1
            while x < mid:
                dst[o] = src[x]
                x += 1
                o += 1
            while y < hi:
                dst[o] = src[y]
                y += 1
                o += 1
            lo = hi
        swap = src
        src = dst
        dst = swap
        width *= 2
    return src


cdef inline Triple *sort_triples(Triple *src, Triple *dst, Py_ssize_t n) noexcept nogil:
    """``merge_sort`` of triples, by (a, b, c)."""
    return merge_sort(src, dst, n)


cdef inline long long *sort_i64(long long *src, long long *dst, Py_ssize_t n) noexcept nogil:
    """``merge_sort`` of numbers, ascending."""
    return merge_sort(src, dst, n)
