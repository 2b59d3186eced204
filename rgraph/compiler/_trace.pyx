# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""Compiled mirror of ``rgraph.compiler.trace.walk_python``: the same walk over the executed
passes' accesses, with the same results (plan accesses, resource traces, timelines, waits),
built with typed locals. A resource's trace is kept in a C struct (``_Res``) during the walk
and becomes a ``ResourceTrace`` at the end; plan values are stored slot by slot
(``rgraph/plan/_slots.pxi``). Any change to the Python walk must be made here too
(tests/compile/test_native_phases.py compares the plans of both)."""

from rgraph.compiler.plan_values import get_subresource, subresource
from rgraph.compiler.read_layouts import GENERAL_READS
from rgraph.compiler.usages import merge
from rgraph.plan import model as pm

from libc.string cimport memset
from cpython.ref cimport PyObject
from cpython.tuple cimport PyTuple_New, PyTuple_SET_ITEM

include "../plan/_slots.pxi"
include "../plan/_spec_slots.pxi"

from rgraph.compiler.trace import ResourceTrace

cdef Slots ACCESS = Slots(pm.Access, ("resource", "subresource", "usage", "stages", "access", "layout", "write"))
cdef Slots TRACE = Slots(ResourceTrace, ("usages", "first", "last", "cells", "code", "group", "single"))
cdef dict SUBRESOURCES = get_subresource.__self__  # plan_values' cache (cleared, never replaced)


# ---- each access's scope and subresource, by the access's identity ------------------------
# An ``AccessSpec`` is frozen: its scope (``trace._SCOPES`` by (usage, kind, stages, code,
# refit)) and its subresource (by (mips, layers)) depend only on it, its pass's kind and its
# resource's format code. Those lookups hash nested tuples at every access of every compile;
# this table finds them by pointers instead (each object kept alive while listed, so no
# pointer is reused). The values are the ones the lookups give (equal ones, where those
# tables were cleared since): the walk's results do not change.

cdef enum:
    _ACCESS_CAP = 8192  # table slots (power of two); at most half used, then emptied at a walk's start

cdef struct AccessSlot:
    PyObject *access
    PyObject *kind
    long code
    PyObject *scope  # tuple: trace._SCOPES' value
    PyObject *sub  # pm.Subresource or None

cdef AccessSlot _accesses[_ACCESS_CAP]
cdef Py_ssize_t _access_count = 0
cdef list _access_keep = []  # what the table points at


cdef inline size_t _access_home(PyObject *a, PyObject *kind, long code):
    return ((<size_t> a >> 4) ^ ((<size_t> kind >> 4) * 31) ^ (<size_t> code * 0x9E37)) & (_ACCESS_CAP - 1)


cdef inline AccessSlot *_access_find(object a, object kind, long code):
    """The table's slot of (``a``, ``kind``, ``code``), or NULL."""
    cdef size_t h = _access_home(<PyObject *> a, <PyObject *> kind, code)
    while _accesses[h].access != NULL:
        if (_accesses[h].access == <PyObject *> a and _accesses[h].kind == <PyObject *> kind
                and _accesses[h].code == code):
            return &_accesses[h]
        h = (h + 1) & (_ACCESS_CAP - 1)
    return NULL


cdef inline void _access_add(object a, object kind, long code, tuple scope, object sub):
    """Remember ``a``'s scope and subresource (not once the table is half full)."""
    global _access_count
    if _access_count >= _ACCESS_CAP // 2:
        return
    cdef size_t h = _access_home(<PyObject *> a, <PyObject *> kind, code)
    while _accesses[h].access != NULL:
        h = (h + 1) & (_ACCESS_CAP - 1)
    _access_keep.append(a)
    _access_keep.append(kind)
    _access_keep.append(scope)
    _access_keep.append(sub)
    _accesses[h].access = <PyObject *> a
    _accesses[h].kind = <PyObject *> kind
    _accesses[h].code = code
    _accesses[h].scope = <PyObject *> scope
    _accesses[h].sub = <PyObject *> sub
    _access_count += 1


cdef void _access_reset():
    global _access_count
    memset(_accesses, 0, sizeof(_accesses))
    _access_count = 0
    _access_keep.clear()


def reset_access_table():
    """Empty the table (tests: a walk that fills it afresh gives the same results)."""
    _access_reset()


cdef class _Res:
    """A resource's ``ResourceTrace`` fields during the walk, and its whole-image ranges."""

    cdef set usages
    cdef Py_ssize_t first, last
    cdef list cells
    cdef object code  # int
    cdef long icode  # the same, for the access table
    cdef list group  # or None
    # ``walk(..., moved=[])``: read_layouts.to_general's groups kept as they go, not as ``group``
    cdef bint candidate  # still a read-group candidate (every access so far the whole image)
    cdef list closed  # the movable reads of the groups closed so far that move to GENERAL
    cdef list cur  # the movable reads since the last write (None: none)
    cdef object lay0  # the layout of the first of them
    cdef bint mixed  # another layout among them
    cdef bint single
    cdef object mips, layers  # read-group candidates: (0, mips), (0, layers)


cdef inline void _close(_Res r):
    """``to_general`` at a write (or the end): the reads since the last write move to GENERAL
    where there are several and their layouts differ."""
    if r.cur is not None:
        if len(r.cur) > 1 and r.mixed:
            if r.closed is None:
                r.closed = r.cur
            else:
                r.closed += r.cur
        r.cur = None
        r.mixed = False


cdef _Res _start(res, Py_ssize_t i, usage):
    """``trace._start``: a resource's trace at its first use."""
    cdef _Res r = _Res.__new__(_Res)
    cdef bint image = res.kind == "image", depth = False, stencil = False
    fmt = res.format
    if fmt is not None:
        depth, stencil = bool(fmt.has_depth), bool(fmt.has_stencil)
    r.usages = {usage}
    r.first = r.last = i
    r.cells = []
    r.icode = image + 2 * depth + 4 * stencil
    r.code = r.icode
    if image and res.lifetime == "transient" and fmt is not None and not depth and not stencil:
        r.group = []
        r.candidate = True
        r.mips, r.layers = (0, res.mips), (0, res.layers)
    else:
        r.group = None
        r.candidate = False
    r.single = not image or res.mips * res.layers == 1
    return r


cdef inline int _add_use(list uses, Py_ssize_t i, object oi, object s, object w, object queue, Py_ssize_t pos,
                         dict waits) except -1:
    """Pass ``i``'s use of a cell that has ``uses`` already: 1 where appended (at ``pos``), 0 where a
    second access of the pass to the cell merged into its last use."""
    cdef tuple prev = <tuple> uses[len(uses) - 1]
    if <Py_ssize_t> prev[0] == i:  # a second access to the cell in this pass: one merged use
        uses[len(uses) - 1] = (oi, merge(prev[1], s), prev[2] or w, queue, prev[4])
        return 0
    q = prev[3]
    if q is not queue and q != queue:  # the dedicated plan waits for that use
        _wait(waits, oi, prev, q)
    uses.append((oi, s, w, queue, pos))
    return 1


cdef inline void _wait(dict waits, object i, tuple prev, object q):
    """The dedicated plan's wait of pass ``i`` for ``prev`` (a use on queue ``q``)."""
    cdef dict found = waits.get(i)
    if found is None:
        waits[i] = {q: prev[0]}
    elif found.get(q, -1) < prev[0]:
        found[q] = prev[0]


def walk(passes, resources, dict scopes, scope_of, list moved=None):
    """``walk_python(passes, resources)``; ``scopes``: ``trace._SCOPES``, ``scope_of``: its
    filler (``trace._scope``). With a list ``moved``: no read-group candidates in the traces
    (``group`` None); ``moved`` gets ``read_layouts.to_general`` of them instead, found during
    the walk (no tuple per candidate access)."""
    cdef bint keep_groups = moved is None
    cdef list plan_accesses = [], uses, cells
    cdef tuple values, accs
    cdef dict info = {}, timeline = {}, waits = {}
    cdef Py_ssize_t i = -1, j, pos
    cdef bint raytrace, exact
    cdef AccessSlot *slot
    cdef _Res r
    cdef tuple scope, prev, cs
    cdef object oi, queue, kind, name, usage, w, s, sub, mips, layers, c, q, value
    if _access_count >= _ACCESS_CAP // 2:
        _access_reset()
    for p in passes:
        i += 1
        oi = i
        queue, kind = pass_field(p, 3, "queue"), pass_field(p, 2, "kind")
        raytrace = kind == "raytrace"
        accs = <tuple> pass_field(p, 7, "accesses")
        values = PyTuple_New(len(accs))  # the plan's tuple (emit keeps it)
        pos = 0
        j = -1
        for a in accs:
            j += 1
            exact = type(a) is ACCESS_SPEC  # frozen: its scope and subresource are in the table
            # (the other fields are read where needed: each read touches its object)
            name, usage, w = access_field(a, 0, "resource"), access_field(a, 1, "usage"), access_field(a, 2, "write")
            found = info.get(name)
            if found is None:
                r = _start(resources[name], i, usage)
                info[name] = r
            else:
                r = <_Res> found
                r.usages.add(usage)
                r.last = i
            if raytrace and usage == "indirect":  # vkCmdTraceRaysIndirectKHR: a device address
                r.usages.add("trace_indirect")
            slot = _access_find(a, kind, r.icode) if exact else NULL
            if slot != NULL:
                scope = <tuple> slot.scope
                sub = <object> slot.sub
            else:
                key = (usage, kind, access_field(a, 5, "stages"), r.code, access_field(a, 8, "refit"))
                found = scopes.get(key)
                scope = <tuple> (scope_of(key) if found is None else found)
                mips, layers = access_field(a, 3, "mips"), access_field(a, 4, "layers")
                if mips is None:  # buffers and accels
                    sub = None
                else:
                    sub = SUBRESOURCES.get((mips, layers))
                    if sub is None:
                        sub = subresource(mips, layers)
                if exact:
                    _access_add(a, kind, r.icode, scope, sub)
            s = scope[0]
            layout = scope[3]
            value = new_slots(ACCESS)
            put(value, ACCESS, 0, name)
            put(value, ACCESS, 1, sub)
            put(value, ACCESS, 2, usage)
            put(value, ACCESS, 3, scope[1])
            put(value, ACCESS, 4, scope[2])
            put(value, ACCESS, 5, layout)
            put(value, ACCESS, 6, w)
            Py_INCREF(value)
            PyTuple_SET_ITEM(values, j, value)
            if r.candidate:
                if access_field(a, 3, "mips") != r.mips or access_field(a, 4, "layers") != r.layers:
                    # not the whole image: never unified
                    r.group = None
                    r.candidate = False
                elif keep_groups:
                    r.group.append((oi, j, w, usage, layout))
                elif w:
                    _close(r)
                elif usage in GENERAL_READS:
                    if r.cur is None:
                        r.cur = [(oi, j)]
                        r.lay0 = layout
                    else:
                        r.cur.append((oi, j))
                        if not r.mixed and layout is not r.lay0 and layout != r.lay0:
                            r.mixed = True
            if r.single:  # most resources: the one cell's uses without a lookup by cell
                cells = r.cells
                if not cells:
                    cells.append(((<tuple> access_field(a, 9, "cells"))[0], [(oi, s, w, queue, pos)]))
                    pos += 1
                    continue
                pos += _add_use(<list> (<tuple> cells[0])[1], i, oi, s, w, queue, pos, waits)
                continue
            cs = access_field(a, 9, "cells")
            for c in cs:
                found = timeline.get(c)
                if found is None:
                    uses = [(oi, s, w, queue, pos)]
                    timeline[c] = uses
                    r.cells.append((c, uses))
                    pos += 1
                    continue
                pos += _add_use(<list> found, i, oi, s, w, queue, pos, waits)
        plan_accesses.append(values)
    traced = {}
    for name, found in info.items():
        r = <_Res> found
        if not keep_groups and r.candidate:
            _close(r)
            if r.closed is not None:
                moved += r.closed
        value = new_slots(TRACE)
        put(value, TRACE, 0, r.usages)
        put(value, TRACE, 1, r.first)
        put(value, TRACE, 2, r.last)
        put(value, TRACE, 3, r.cells)
        put(value, TRACE, 4, r.code)
        put(value, TRACE, 5, r.group if keep_groups else None)
        put(value, TRACE, 6, r.single)
        traced[name] = value
    return plan_accesses, traced, timeline, waits


# ---- trace._finish: the reads read_layouts moves to GENERAL ---------------------------------

from dataclasses import replace as _replace


cdef list _row(p, dict info, dict scopes, scope_of):
    """``trace._row``: the scope of each access of ``p`` (from the access table where listed)."""
    cdef list out = []
    cdef AccessSlot *slot
    cdef long code
    kind = pass_field(p, 2, "kind")
    for a in <tuple> pass_field(p, 7, "accesses"):
        code_obj = info[access_field(a, 0, "resource")].code
        slot = NULL
        if type(a) is ACCESS_SPEC:
            code = code_obj
            slot = _access_find(a, kind, code)
        if slot != NULL:
            out.append((<tuple> slot.scope)[0])
            continue
        key = (access_field(a, 1, "usage"), kind, access_field(a, 5, "stages"), code_obj, access_field(a, 8, "refit"))
        found = scopes.get(key)
        out.append((<tuple> (scope_of(key) if found is None else found))[0])
    return out


def patch(passes, list plan_accesses, dict info, dict timeline, list moved, dict scopes, scope_of):
    """``trace._finish``'s patching of the ``moved`` reads (their plan accesses and their
    passes' uses of their cells), in place."""
    cdef dict general = {}, rows = {}
    cdef list row, uses
    cdef tuple found, u
    cdef Py_ssize_t i, j, lo, hi, mid
    for pair in moved:
        i, j = pair
        row = rows.get(i)
        if row is None:
            row = rows[i] = _row(passes[i], info, scopes, scope_of)
        scope = row[j]
        found = general.get(id(scope))
        if found is None:
            found = general[id(scope)] = (scope, _replace(scope, layout="GENERAL"))
        row[j] = found[1]
        values = plan_accesses[i]
        if type(values) is tuple:  # the walk's: a list while patched, a tuple again below
            values = plan_accesses[i] = list(values)
        v = values[j]
        value = new_slots(ACCESS)
        put(value, ACCESS, 0, v.resource)
        put(value, ACCESS, 1, v.subresource)
        put(value, ACCESS, 2, v.usage)
        put(value, ACCESS, 3, v.stages)
        put(value, ACCESS, 4, v.access)
        put(value, ACCESS, 5, "GENERAL")
        put(value, ACCESS, 6, v.write)
        values[j] = value
    for i in rows:
        plan_accesses[i] = tuple(plan_accesses[i])
    for pair in moved:  # ``trace._repatch``
        i, j = pair
        p = passes[i]
        accesses = <tuple> pass_field(p, 7, "accesses")
        row = rows[i]
        for c in <tuple> access_field(accesses[j], 9, "cells"):
            merged = None
            for k in range(len(accesses)):
                if c in <tuple> access_field(accesses[k], 9, "cells"):
                    merged = row[k] if merged is None else merge(merged, row[k])
            uses = timeline.get(c)
            if uses is None:  # a resource of one cell
                uses = <list> (<tuple> (<list> info[c[0]].cells)[0])[1]
            lo, hi = 0, len(uses)  # uses are in pass order, one per pass: the use of pass i
            while lo < hi:
                mid = (lo + hi) >> 1
                if <Py_ssize_t> (<tuple> uses[mid])[0] < i:
                    lo = mid + 1
                else:
                    hi = mid
            u = <tuple> uses[lo]
            uses[lo] = (u[0], merged, u[2], u[3], u[4])
