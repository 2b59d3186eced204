# Included by the compiled compiler phases (_memory.pyx, _queue_order.pyx): ``bisect_left`` on
# a C array of 64-bit integers sorted ascending.

ctypedef long long i64


cdef inline Py_ssize_t _bisect_left(i64 *a, Py_ssize_t n, i64 x):
    """The first index of ``a[:n]`` whose value is at least ``x`` (``n`` if none)."""
    cdef Py_ssize_t lo = 0, hi = n, mid
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo
