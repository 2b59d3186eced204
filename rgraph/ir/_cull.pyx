# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""Compiled mirror of ``rgraph.ir.cull._alive_python`` (the backwards walk)
and of ``rgraph.ir.cull._split`` (and ``_has_optional_python``): the same sets, with typed locals and the set tests of a write's
few cells done cell by cell. Any change to the Python code must be made here too
(tests/compile/test_native_phases.py compares the plans of both)."""


include "../plan/_slots.pxi"
include "../plan/_spec_slots.pxi"

cdef Slots CULLED = None


cdef inline bint _all_in(set s, tuple cells):
    for c in cells:
        if c not in s:
            return False
    return True


cdef inline bint _any_in(set s, tuple cells):
    for c in cells:
        if c in s:
            return True
    return False


def alive(spec, list kept, frozenset rw):
    """``_alive_python(spec, kept)``; ``rw``: ``READ_WRITE_USAGES``."""
    cdef set keep = set(), single = set(), wanted = set(), claimed = set(), alive = set()
    cdef bint live
    cdef tuple cs
    for n, r in spec.resources.items():
        if r.lifetime in ("persistent", "imported", "output"):
            keep.add(n)
        if r.kind != "image" or r.mips * r.layers == 1:
            single.add(n)
    keep.update(spec.outputs)
    for k in range(len(kept) - 1, -1, -1):
        p = kept[k]
        live = pass_field(p, 6, "side_effects")
        accesses = <tuple> pass_field(p, 7, "accesses")
        for access in accesses:
            if access_field(access, 2, "write"):
                name = access_field(access, 0, "resource")
                if name in single:
                    if name in keep:
                        if not live and (name not in claimed or name in wanted):
                            live = True
                        claimed.add(name)
                    elif not live and name in wanted:
                        live = True
                    continue
                cs = access_field(access, 9, "cells")
                if name in keep:
                    if not live and (not _all_in(claimed, cs) or _any_in(wanted, cs)):
                        live = True
                    for c in cs:
                        claimed.add(c)
                elif not live and _any_in(wanted, cs):
                    live = True
        if not live:
            continue
        alive.add(pass_field(p, 0, "name"))
        for access in accesses:
            name = access_field(access, 0, "resource")
            if name in single:
                if access_field(access, 2, "write") and access_field(access, 1, "usage") not in rw:
                    wanted.discard(name)
                else:
                    wanted.add(name)
            elif access_field(access, 2, "write") and access_field(access, 1, "usage") not in rw:
                for c in <tuple> access_field(access, 9, "cells"):
                    wanted.discard(c)
            else:  # ``reads(access)``
                for c in <tuple> access_field(access, 9, "cells"):
                    wanted.add(c)
    return alive


def split(list kept, set alive, culled_class):
    """``_split(kept, alive)``; ``culled_class``: ``rgraph.ir.cull.Culled``."""
    global CULLED
    if CULLED is None or CULLED.cls is not culled_class:
        CULLED = Slots(culled_class, ("pass_name", "reason"))
    cdef list final = [], unreached = []
    for p in kept:
        name = p.name
        if name in alive:
            final.append(p)
        else:
            value = new_slots(CULLED)
            put(value, CULLED, 0, name)
            put(value, CULLED, 1, "reaches no output")
            unreached.append(value)
    return final, unreached


def has_optional(passes):
    """``cull._has_optional(passes)``: whether any access of ``passes`` is optional (fields
    read from the slots)."""
    for p in passes:
        for a in <tuple> pass_field(p, 7, "accesses"):
            if access_field(a, 6, "optional"):
                return True
    return False


# ---- cull._plain: the walk and the split in one, with the cells numbered -------------------

from libc.stdlib cimport malloc, calloc, free
from libc.string cimport memset
from cpython.dict cimport PyDict_GetItem
from cpython.exc cimport PyErr_Clear, PyErr_Occurred
from cpython.long cimport PyLong_AsSsize_t


cdef enum:
    _KEEP = 1  # resource flags
    _SINGLE = 2
    _WANTED = 1  # cell states
    _CLAIMED = 2
    _MAX_CELLS = 1 << 22  # more cells in all: the general path (sets)
    _MAX_SIDE = 1 << 20  # more mips or layers in a resource: the same


cdef extern from "Python.h":
    PyObject *_list_item "PyList_GET_ITEM" (PyObject *l, Py_ssize_t k)  # borrowed
    PyObject *_tuple_item "PyTuple_GET_ITEM" (PyObject *t, Py_ssize_t k)  # borrowed
    Py_ssize_t _tuple_size "PyTuple_GET_SIZE" (PyObject *t)
    PyObject *_type "(PyObject *) Py_TYPE" (PyObject *o)
    void _prefetch "__builtin_prefetch" (const void *p)


cdef inline PyObject *_accesses_of(list passes, Py_ssize_t x):
    """Pass ``x``'s accesses tuple (borrowed), NULL where not an exact ``PassSpec``'s tuple."""
    cdef PyObject *o = _list_item(<PyObject *> passes, x)
    if _type(o) != <PyObject *> PASS_SPEC:
        return NULL
    o = borrowed_field(o, PASS, 7)
    if o == NULL or _type(o) != <PyObject *> tuple:
        return NULL
    return o


cdef void _ahead(list passes, Py_ssize_t x):
    """Prefetch what the backwards walk reads of the passes before ``x``: the chain pass ->
    accesses tuple -> accesses -> their cells tuples -> cells, a step further back each pass
    ahead, so that each pointer read was prefetched a pass earlier (the spec's objects are cold
    when a compile starts)."""
    cdef PyObject *o
    cdef PyObject *a
    cdef Py_ssize_t k, j
    if x >= 5:
        _prefetch(_list_item(<PyObject *> passes, x - 5))
    if x >= 4:
        o = _list_item(<PyObject *> passes, x - 4)
        if _type(o) == <PyObject *> PASS_SPEC:
            _prefetch(borrowed_field(o, PASS, 7))
    if x >= 3:
        o = _accesses_of(passes, x - 3)
        if o != NULL:
            for k in range(_tuple_size(o)):
                _prefetch(_tuple_item(o, k))
    if x >= 2:
        o = _accesses_of(passes, x - 2)
        if o != NULL:
            for k in range(_tuple_size(o)):
                a = _tuple_item(o, k)
                if _type(a) == <PyObject *> ACCESS_SPEC and borrowed_field(a, SPEC, 9) != NULL:
                    _prefetch(borrowed_field(a, SPEC, 9))
    if x >= 1:
        o = _accesses_of(passes, x - 1)
        if o != NULL:
            for k in range(_tuple_size(o)):
                a = _tuple_item(o, k)
                if _type(a) == <PyObject *> ACCESS_SPEC:
                    a = borrowed_field(a, SPEC, 9)
                    if a != NULL and _type(a) == <PyObject *> tuple:
                        for j in range(_tuple_size(a)):
                            _prefetch(_tuple_item(a, j))


cdef struct _Acc:
    Py_ssize_t res  # resource number
    bint write
    PyObject *cells  # borrowed: the access's cells tuple (the pass holds its accesses)


cdef struct _Tables:
    Py_ssize_t *base  # per resource: its first cell's number
    Py_ssize_t *mips  # per resource: its mips (cells of resources of several cells)
    Py_ssize_t *layers  # and layers
    unsigned char *flags  # per resource: _KEEP, _SINGLE
    unsigned char *state  # per cell: _WANTED, _CLAIMED
    unsigned char *alive  # per pass
    _Acc *accs  # the current pass's accesses
    Py_ssize_t accs_cap


cdef void _free_tables(_Tables *t):
    free(t.base)
    free(t.mips)
    free(t.layers)
    free(t.flags)
    free(t.state)
    free(t.alive)
    free(t.accs)


cdef inline Py_ssize_t _cell(_Tables *t, Py_ssize_t res, object name, object c) except -2:
    """The number of cell ``c`` of resource ``res`` (of several cells), or -1 where it is not one
    of its cells (the caller falls back)."""
    cdef tuple cell = <tuple> c
    cdef Py_ssize_t m, l
    if len(cell) != 3:
        return -1
    first, mo, lo = cell[0], cell[1], cell[2]
    if (first is not name and first != name) or type(mo) is not int or type(lo) is not int:
        return -1
    m, l = PyLong_AsSsize_t(mo), PyLong_AsSsize_t(lo)
    if (m == -1 or l == -1) and PyErr_Occurred():  # past 63 bits
        PyErr_Clear()
        return -1
    if m < 0 or m >= t.mips[res] or l < 0 or l >= t.layers[res]:
        return -1
    return t.base[res] + m * t.layers[res] + l


def plain(spec, list passes, frozenset rw, culled_class):
    """``cull._plain(spec, passes)``: ``_split(passes, _alive_python(spec, passes))`` where no
    access is optional, else None; ``rw``: ``READ_WRITE_USAGES``, ``culled_class``: ``Culled``.
    The walk of ``alive`` with each resource numbered (``index``) and each cell too (a
    resource of one cell: its number; else its first cell's number + mip * layers + layer),
    the sets ``wanted`` and ``claimed`` as bits per cell; None also where a resource or an
    access does not fit those (the caller takes the general path, which gives the same)."""
    global CULLED
    if CULLED is None or CULLED.cls is not culled_class:
        CULLED = Slots(culled_class, ("pass_name", "reason"))
    cdef dict resources = spec.resources
    cdef dict index = {}
    cdef list held = []  # the cells of other access objects, while their pass is walked
    cdef Py_ssize_t n = len(resources), k = 0, total = 0, npasses = len(passes), na, x, slot, res
    cdef Py_ssize_t mm, ll
    cdef _Tables t
    cdef PyObject *found
    cdef bint live, failed = False
    cdef unsigned char fl, st
    cdef _Acc *acc
    cdef tuple accesses
    memset(&t, 0, sizeof(t))
    t.base = <Py_ssize_t *> malloc((n + 1) * sizeof(Py_ssize_t))
    t.mips = <Py_ssize_t *> malloc((n + 1) * sizeof(Py_ssize_t))
    t.layers = <Py_ssize_t *> malloc((n + 1) * sizeof(Py_ssize_t))
    t.flags = <unsigned char *> calloc(n + 1, 1)
    t.alive = <unsigned char *> calloc(npasses + 1, 1)
    t.accs_cap = 16
    t.accs = <_Acc *> malloc(t.accs_cap * sizeof(_Acc))
    try:
        if t.base == NULL or t.mips == NULL or t.layers == NULL or t.flags == NULL or t.alive == NULL or t.accs == NULL:
            raise MemoryError()
        for name, r in resources.items():
            index[name] = k
            lifetime = resource_field(r, 2)
            if lifetime == "persistent" or lifetime == "imported" or lifetime == "output":
                t.flags[k] = _KEEP
            mips, layers = resource_field(r, 6), resource_field(r, 5)
            t.base[k] = total
            if resource_field(r, 1) != "image" or mips * layers == 1:
                t.flags[k] |= _SINGLE
                t.mips[k] = t.layers[k] = 1
                total += 1
            elif type(mips) is int and type(layers) is int and 0 <= mips <= _MAX_SIDE and 0 <= layers <= _MAX_SIDE:
                mm, ll = mips, layers
                t.mips[k], t.layers[k] = mm, ll
                total += mm * ll
                if total > _MAX_CELLS:
                    return None
            else:
                return None
            k += 1
        for name in spec.outputs:
            found = PyDict_GetItem(index, name)
            if found == NULL:
                return None  # an output that is no resource: the sets tell it apart
            t.flags[<Py_ssize_t> <object> found] |= _KEEP
        t.state = <unsigned char *> calloc(total + 1, 1)
        if t.state == NULL:
            raise MemoryError()
        for x in range(npasses - 1, -1, -1):
            _ahead(passes, x)
            p = passes[x]
            live = pass_field(p, 6, "side_effects")
            accesses = <tuple> pass_field(p, 7, "accesses")
            na = len(accesses)
            if held:
                held.clear()
            if na > t.accs_cap:
                free(t.accs)
                t.accs_cap = na
                t.accs = <_Acc *> malloc(na * sizeof(_Acc))
                if t.accs == NULL:
                    raise MemoryError()
            for k in range(na):
                a = accesses[k]
                if access_field(a, 6, "optional"):
                    return None
                name = access_field(a, 0, "resource")
                found = PyDict_GetItem(index, name)
                if found == NULL:
                    return None
                res = <Py_ssize_t> <object> found
                acc = &t.accs[k]
                acc.res = res
                acc.write = access_field(a, 2, "write")
                fl = t.flags[res]
                if fl & _SINGLE:  # (its cells are not read: a cold tuple)
                    if not acc.write:
                        continue
                    st = t.state[t.base[res]]
                    if fl & _KEEP:
                        if not live and (not (st & _CLAIMED) or (st & _WANTED)):
                            live = True
                        t.state[t.base[res]] = st | _CLAIMED
                    elif not live and (st & _WANTED):
                        live = True
                    continue
                cells = access_field(a, 9, "cells")
                acc.cells = <PyObject *> cells
                if type(a) is not ACCESS_SPEC:  # (an AccessSpec's stays in its slot)
                    held.append(cells)
                for c in <tuple> cells:  # checked here once: the second loop trusts them
                    slot = _cell(&t, res, name, c)
                    if slot < 0:
                        return None
                    if not acc.write:
                        continue
                    st = t.state[slot]
                    if fl & _KEEP:
                        if not live and (not (st & _CLAIMED) or (st & _WANTED)):
                            live = True
                        t.state[slot] = st | _CLAIMED
                    elif not live and (st & _WANTED):
                        live = True
            if not live:
                continue
            t.alive[x] = 1
            for k in range(na):
                acc = &t.accs[k]
                # ``reads(access)``: not a plain write
                if acc.write and access_field(accesses[k], 1, "usage") not in rw:
                    if t.flags[acc.res] & _SINGLE:
                        t.state[t.base[acc.res]] &= ~_WANTED
                    else:
                        for c in <tuple> acc.cells:
                            t.state[_cell(&t, acc.res, (<tuple> c)[0], c)] &= ~_WANTED
                elif t.flags[acc.res] & _SINGLE:
                    t.state[t.base[acc.res]] |= _WANTED
                else:
                    for c in <tuple> acc.cells:
                        t.state[_cell(&t, acc.res, (<tuple> c)[0], c)] |= _WANTED
        final, unreached = [], []
        for x in range(npasses):
            p = passes[x]
            if t.alive[x]:
                final.append(p)
            else:
                value = new_slots(CULLED)
                put(value, CULLED, 0, pass_field(p, 0, "name"))
                put(value, CULLED, 1, "reaches no output")
                unreached.append(value)
        return final, unreached
    finally:
        _free_tables(&t)
