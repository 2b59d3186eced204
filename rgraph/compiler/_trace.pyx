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


# ---- each pass's accesses, by the pass's identity --------------------------------------------
# A ``PassSpec`` is frozen, and so are its ``AccessSpec``s: its queue, kind and accesses, and
# each access's fields, scope (``trace._SCOPES`` by (usage, kind, stages, code, refit)) and
# plan value (``pm.Access``, frozen: of its fields, the scope and the subresource by (mips,
# layers)) depend only on it and on its resource's format code. The walk meets the same passes
# at every compile of a graph: this table finds them by the pass's pointer, one probe per pass.
# A pass's first walk only notes it (``_pass_mark``: a spec compiled once pays nothing more);
# its second lists it, with each access's fields read into a C array (``_Acc``); later walks
# read those instead of the cold ``AccessSpec``s, look up no scope and build no plan value: the
# pass's tuple of them is the listing walk's (shared by the plans; ``patch`` copies a tuple it
# changes). So are its uses of its cells (``Use``: the pass's index and queue, the access's
# scope and write, and the position, which depends only on the pass's accesses) where the pass
# has the listing walk's index. A listed pass and what its slot points at are kept alive
# (``_table_keep``), so no pointer is reused; a scope, value or use is used only where its
# resource's format code is the one it was found for (else found again). The values are the
# ones the lookups give (equal ones, where those tables were cleared since): the walk's results
# do not change. The table is emptied at a walk's start once half full, and only when no other
# walk (another thread's) is under way: while one is, what the table points at stays.

from libc.stdlib cimport malloc, free
from cpython.exc cimport PyErr_Clear, PyErr_Occurred
from cpython.long cimport PyLong_AsLong

cdef enum:
    _TABLE_CAP = 4096  # table slots (power of two): at most half used
    _MAX_CACHED = 64  # passes of more accesses are not listed

cdef struct _Acc:
    PyObject *name
    PyObject *usage
    PyObject *write
    PyObject *cells  # tuple
    PyObject *mips
    PyObject *layers
    PyObject *scope  # tuple: trace._SCOPES' value, for ``code``
    PyObject *value  # pm.Access, for ``code``
    PyObject *uses  # the uses of its cells (all appended, none merged), for ``code`` and the pass's ``i``: the
    # use (a tuple) where it has one cell (``one``), else a tuple of them; or NULL
    long code
    bint one
    bint w  # ``write``'s truth
    bint ranges  # mips and layers are pairs of ints, (mlo, mhi) and (llo, lhi)
    long mlo, mhi, llo, lhi

cdef struct PassSlot:
    PyObject *pass_
    PyObject *queue
    PyObject *kind
    PyObject *accesses  # tuple
    PyObject *values  # tuple: the accesses' ``value``s
    PyObject *oi  # int: the pass's index at its listing walk, ``i``
    Py_ssize_t i
    Py_ssize_t n
    _Acc *accs  # NULL: noted, not listed (only ``pass_`` is set)

cdef PassSlot _passes[_TABLE_CAP]
cdef Py_ssize_t _pass_count = 0
cdef Py_ssize_t _walking = 0  # walks under way (threads)
cdef list _table_keep = []  # what the table points at


cdef inline PassSlot *_pass_find(object p):
    """The table's slot of pass ``p``, or NULL."""
    cdef size_t h = (<size_t> <PyObject *> p >> 4) & (_TABLE_CAP - 1)
    while _passes[h].pass_ != NULL:
        if _passes[h].pass_ == <PyObject *> p:
            return &_passes[h]
        h = (h + 1) & (_TABLE_CAP - 1)
    return NULL


cdef void _pass_mark(object p):
    """Note pass ``p`` as walked once (a slot without accesses; not kept alive: a later pass at its
    address is then listed at its first walk); not once the table is half full."""
    global _pass_count
    if _pass_count >= _TABLE_CAP // 2:
        return
    cdef size_t h = (<size_t> <PyObject *> p >> 4) & (_TABLE_CAP - 1)
    while _passes[h].pass_ != NULL:
        h = (h + 1) & (_TABLE_CAP - 1)
    _passes[h].pass_ = <PyObject *> p
    _pass_count += 1


cdef void _pass_add(PassSlot *slot, object p, object queue, object kind, object accesses, tuple values, object oi,
                    Py_ssize_t i, Py_ssize_t n, _Acc *accs, list held):
    """List pass ``p`` in its ``slot`` (``_pass_mark``'s) with its index ``i`` (``oi``), its plan
    ``values`` and a copy of its accesses' ``accs`` (``held``: their scopes and uses); not where
    it is listed already (another thread's walk may have listed it meanwhile)."""
    cdef Py_ssize_t k
    if slot.pass_ != <PyObject *> p or slot.accs != NULL:
        return
    cdef _Acc *copy = <_Acc *> malloc(n * sizeof(_Acc) + 1)
    if copy == NULL:
        return
    _table_keep.append(p)  # holds its queue, kind, accesses and their fields
    _table_keep.append(values)  # and the values their subresources
    _table_keep.append(oi)
    _table_keep.extend(held)
    for k in range(n):
        copy[k] = accs[k]
    slot.queue = <PyObject *> queue
    slot.kind = <PyObject *> kind
    slot.accesses = <PyObject *> accesses
    slot.values = <PyObject *> values
    slot.oi = <PyObject *> oi
    slot.i = i
    slot.n = n
    slot.accs = copy


cdef void _table_reset():
    global _pass_count
    cdef Py_ssize_t h
    for h in range(_TABLE_CAP):
        if _passes[h].pass_ != NULL:
            free(_passes[h].accs)
    memset(_passes, 0, sizeof(_passes))
    _pass_count = 0
    _table_keep.clear()


def reset_access_table():
    """Empty the table (tests: a walk that fills it afresh gives the same results)."""
    if _walking == 0:
        _table_reset()


# ---- scopes by their key's objects ---------------------------------------------------------
# ``trace._SCOPES`` is keyed by a tuple (usage, kind, stages, code, refit): a tuple to build and
# hash for every access of a pass the pass table has not listed. Accesses of no explicit stages
# (most) find their scope here instead, by the pointers of their usage, their pass's kind and
# their refit, and the format code: the spec's usage and kind strings are interned, so few
# entries serve every spec. The objects are kept alive while listed (``_scope_keep``); the
# table is emptied once half full (a scope is held by whatever uses it).

cdef struct _ScopeSlot:
    PyObject *usage
    PyObject *kind
    PyObject *refit
    long code
    PyObject *scope

cdef enum:
    _SCOPE_CAP = 512  # slots (power of two): at most half used

cdef _ScopeSlot _scope_slots[_SCOPE_CAP]
cdef Py_ssize_t _scope_count = 0
cdef list _scope_keep = []


cdef inline size_t _scope_hash(object usage, object kind, long code, object refit):
    """The first slot to probe for these objects and code."""
    return ((<size_t> <PyObject *> usage >> 4) * 3 + (<size_t> <PyObject *> kind >> 4) * 5
            + (<size_t> <PyObject *> refit >> 4) + <size_t> code * 7) & (_SCOPE_CAP - 1)


cdef inline object _scope_find(object usage, object kind, long code, object refit):
    """The scope listed for these objects and code, or None."""
    cdef size_t h = _scope_hash(usage, kind, code, refit)
    while _scope_slots[h].usage != NULL:
        if (_scope_slots[h].usage == <PyObject *> usage and _scope_slots[h].kind == <PyObject *> kind
                and _scope_slots[h].code == code and _scope_slots[h].refit == <PyObject *> refit):
            return <object> _scope_slots[h].scope
        h = (h + 1) & (_SCOPE_CAP - 1)
    return None


cdef void _scope_add(object usage, object kind, long code, object refit, object scope):
    """List ``scope`` for these objects and code (emptying the table first where half full)."""
    global _scope_count
    if _scope_find(usage, kind, code, refit) is not None:
        return
    if _scope_count >= _SCOPE_CAP // 2:
        memset(_scope_slots, 0, sizeof(_scope_slots))
        _scope_count = 0
        _scope_keep.clear()
    cdef size_t h = _scope_hash(usage, kind, code, refit)
    while _scope_slots[h].usage != NULL:
        h = (h + 1) & (_SCOPE_CAP - 1)
    _scope_keep.append((usage, kind, refit, scope))
    _scope_slots[h].usage = <PyObject *> usage
    _scope_slots[h].kind = <PyObject *> kind
    _scope_slots[h].refit = <PyObject *> refit
    _scope_slots[h].code = code
    _scope_slots[h].scope = <PyObject *> scope
    _scope_count += 1


cdef inline bint _pair(object t, long *lo, long *hi):
    """Whether ``t`` is a pair of ints (within a C long): then ``lo``, ``hi``."""
    if type(t) is not tuple or len(<tuple> t) != 2:
        return False
    a, b = (<tuple> t)[0], (<tuple> t)[1]
    if type(a) is not int or type(b) is not int:
        return False
    lo[0] = PyLong_AsLong(a)
    hi[0] = PyLong_AsLong(b)
    if (lo[0] == -1 or hi[0] == -1) and PyErr_Occurred():
        PyErr_Clear()
        return False
    return True


# ---- subresources by their ranges ------------------------------------------------------------
# ``plan_values``' table of them is keyed by ((mips), (layers)): two tuples to hash and compare
# for every image access of an unlisted pass. Ranges of C longs find them here instead (the
# objects that table gives, kept alive while listed: ``_sub_keep``); emptied once half full.

cdef struct _SubSlot:
    long mlo, mhi, llo, lhi
    PyObject *sub  # NULL: an empty slot

cdef enum:
    _SUB_CAP = 512  # slots (power of two): at most half used

cdef _SubSlot _sub_slots[_SUB_CAP]
cdef Py_ssize_t _sub_count = 0
cdef list _sub_keep = []


cdef inline _SubSlot *_sub_slot(long mlo, long mhi, long llo, long lhi):
    """The slot of these ranges, or the empty one to list them in."""
    cdef size_t h = <size_t> (mlo * 7 + mhi * 31 + llo * 127 + lhi * 257) & (_SUB_CAP - 1)
    while _sub_slots[h].sub != NULL and not (_sub_slots[h].mlo == mlo and _sub_slots[h].mhi == mhi
                                             and _sub_slots[h].llo == llo and _sub_slots[h].lhi == lhi):
        h = (h + 1) & (_SUB_CAP - 1)
    return &_sub_slots[h]


cdef object _sub_of(object mips, object layers):
    """``plan_values.subresource(mips, layers)``."""
    global _sub_count
    cdef long mlo, mhi, llo, lhi
    cdef _SubSlot *slot
    if _pair(mips, &mlo, &mhi) and _pair(layers, &llo, &lhi):
        slot = _sub_slot(mlo, mhi, llo, lhi)
        if slot.sub != NULL:
            return <object> slot.sub
    else:
        slot = NULL
    sub = SUBRESOURCES.get((mips, layers))
    if sub is None:
        sub = subresource(mips, layers)
    if slot == NULL:
        return sub
    if _sub_count >= _SUB_CAP // 2:
        memset(_sub_slots, 0, sizeof(_sub_slots))
        _sub_count = 0
        _sub_keep.clear()
    slot = _sub_slot(mlo, mhi, llo, lhi)  # again: ``subresource`` may have let another thread list some
    if slot.sub == NULL:
        _sub_keep.append(sub)
        slot.mlo, slot.mhi, slot.llo, slot.lhi, slot.sub = mlo, mhi, llo, lhi, <PyObject *> sub
        _sub_count += 1
    return sub


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
    cdef bint cranges  # and those as C longs: (0, cm), (0, cl)
    cdef long cm, cl
    cdef object last_usage  # the usage added last to ``usages``


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
    cdef bint image = resource_field(res, 1) == "image", depth = False, stencil = False
    cdef long lo
    fmt = resource_field(res, 3)
    if fmt is not None:
        depth, stencil = bool(fmt.has_depth), bool(fmt.has_stencil)
    r.usages = {usage}
    r.last_usage = usage
    r.first = r.last = i
    r.cells = []
    r.icode = image + 2 * depth + 4 * stencil
    r.code = r.icode
    mips = layers = None  # (read for images only, as trace._start does)
    if image:
        mips, layers = resource_field(res, 6), resource_field(res, 5)
    if image and resource_field(res, 2) == "transient" and fmt is not None and not depth and not stencil:
        r.group = []
        r.candidate = True
        r.mips, r.layers = (0, mips), (0, layers)
        r.cranges = _pair(r.mips, &lo, &r.cm) and _pair(r.layers, &lo, &r.cl)
    else:
        r.group = None
        r.candidate = False
    r.single = not image or mips * layers == 1
    return r


cdef inline tuple _add_use(list uses, Py_ssize_t i, object oi, object s, object w, object queue, Py_ssize_t pos,
                           dict waits, object use):
    """Pass ``i``'s use of a cell that has ``uses`` already: the use appended (at ``pos``; ``use``
    where given: the same values), or None where a second access of the pass to the cell merged
    into its last use."""
    cdef tuple prev = <tuple> uses[len(uses) - 1]
    if <Py_ssize_t> prev[0] == i:  # a second access to the cell in this pass: one merged use
        uses[len(uses) - 1] = (oi, merge(prev[1], s), prev[2] or w, queue, prev[4])
        return None
    q = prev[3]
    if q is not queue and q != queue:  # the dedicated plan waits for that use
        _wait(waits, oi, prev, q)
    if use is None:
        use = (oi, s, w, queue, pos)
    uses.append(use)
    return <tuple> use


cdef inline void _wait(dict waits, object i, tuple prev, object q):
    """The dedicated plan's wait of pass ``i`` for ``prev`` (a use on queue ``q``)."""
    cdef dict found = waits.get(i)
    if found is None:
        waits[i] = {q: prev[0]}
    elif found.get(q, -1) < prev[0]:
        found[q] = prev[0]


cdef inline void _set(tuple t, Py_ssize_t k, object value):
    """Item ``k`` of a new tuple ``t`` (each once)."""
    Py_INCREF(value)
    PyTuple_SET_ITEM(t, k, value)


cdef tuple _prefix(tuple values, Py_ssize_t j):
    """A new tuple as long as ``values``, with its first ``j`` items (the others to set)."""
    cdef tuple out = PyTuple_New(len(values))
    cdef Py_ssize_t k
    for k in range(j):
        _set(out, k, values[k])
    return out


def walk(passes, resources, dict scopes, scope_of, list moved=None):
    """``walk_python(passes, resources)``; ``scopes``: ``trace._SCOPES``, ``scope_of``: its
    filler (``trace._scope``). With a list ``moved``: no read-group candidates in the traces
    (``group`` None); ``moved`` gets ``read_layouts.to_general`` of them instead, found during
    the walk (no tuple per candidate access)."""
    global _walking
    if _pass_count >= _TABLE_CAP // 2 and _walking == 0:
        _table_reset()
    _walking += 1
    try:
        return _walk(passes, resources, scopes, scope_of, moved)
    finally:
        _walking -= 1


cdef tuple _walk(passes, resources, dict scopes, scope_of, list moved):
    cdef bint keep_groups = moved is None
    cdef list plan_accesses = [], uses, cells
    cdef tuple values, accs
    cdef dict info = {}, timeline = {}, waits = {}
    cdef list held = []  # the scopes and uses of ``fresh`` (the caches may drop the scopes before it is listed)
    cdef Py_ssize_t i = -1, j, n, m, pos
    cdef bint raytrace, whole, listing, shared, same, reuse, keep
    cdef PassSlot *slot
    cdef _Acc *known  # the listed pass's accesses
    cdef _Acc fresh[_MAX_CACHED]  # an unlisted pass's, to list it
    cdef _Acc spare  # an unlisted pass's access, not to list
    cdef _Acc *cur
    cdef _Res r
    cdef tuple scope, prev, cs
    cdef object oi, queue, kind, name, usage, w, s, sub, mips, layers, stages, refit, c, q, value, a, use, given, made
    for p in passes:
        i += 1
        slot = _pass_find(p) if type(p) is PASS_SPEC else NULL
        if slot != NULL and slot.accs != NULL:
            queue, kind, accs = <object> slot.queue, <object> slot.kind, <tuple> slot.accesses
            known = slot.accs
            listing = False
            values = <tuple> slot.values  # shared: copied (``_prefix``) where a value differs
            shared = True
            same = slot.i == i  # the listed uses hold (their index)
            oi = <object> slot.oi if same else i
        else:
            queue, kind = pass_field(p, 3, "queue"), pass_field(p, 2, "kind")
            accs = <tuple> pass_field(p, 7, "accesses")
            known = NULL
            listing = slot != NULL and len(accs) <= _MAX_CACHED  # walked before: listed now
            if slot == NULL and type(p) is PASS_SPEC:
                _pass_mark(p)
            if held:
                held.clear()
            values = PyTuple_New(len(accs))  # the plan's tuple (emit keeps it)
            shared = same = False
            oi = i
        raytrace = kind == "raytrace"
        n = len(accs)
        pos = 0
        for j in range(n):
            if known != NULL:
                cur = &known[j]
                name, usage, w = <object> cur.name, <object> cur.usage, <object> cur.write
            else:
                a = accs[j]
                if listing and type(a) is not ACCESS_SPEC:  # only AccessSpecs are frozen
                    listing = False
                cur = &fresh[j] if listing else &spare
                name, usage, w = access_field(a, 0, "resource"), access_field(a, 1, "usage"), access_field(a, 2, "write")
                cur.name, cur.usage, cur.write = <PyObject *> name, <PyObject *> usage, <PyObject *> w
                cur.w = w
                cur.scope = NULL
            found = info.get(name)
            if found is None:
                r = _start(resources[name], i, usage)
                info[name] = r
            else:
                r = <_Res> found
                if usage is not r.last_usage:
                    r.usages.add(usage)
                    r.last_usage = usage
                r.last = i
            if raytrace and usage == "indirect":  # vkCmdTraceRaysIndirectKHR: a device address
                r.usages.add("trace_indirect")
                r.last_usage = None
            reuse = cur.scope != NULL and cur.code == r.icode  # listed, for this format code
            if reuse:
                scope = <tuple> cur.scope
                if not shared:
                    _set(values, j, <object> cur.value)
            else:
                a = accs[j]
                stages, refit = access_field(a, 5, "stages"), access_field(a, 8, "refit")
                found = _scope_find(usage, kind, r.icode, refit) if stages is None else None
                if found is None:
                    key = (usage, kind, stages, r.code, refit)
                    found = scopes.get(key)
                    if found is None:
                        found = scope_of(key)
                    if stages is None:
                        _scope_add(usage, kind, r.icode, refit, found)
                scope = <tuple> found
                mips, layers = access_field(a, 3, "mips"), access_field(a, 4, "layers")
                sub = None if mips is None else _sub_of(mips, layers)  # (None: buffers and accels)
                value = new_slots(ACCESS)
                put(value, ACCESS, 0, name)
                put(value, ACCESS, 1, sub)
                put(value, ACCESS, 2, usage)
                put(value, ACCESS, 3, scope[1])
                put(value, ACCESS, 4, scope[2])
                put(value, ACCESS, 5, scope[3])
                put(value, ACCESS, 6, w)
                if shared:  # the listed tuple holds another value here
                    values = _prefix(values, j)
                    shared = False
                _set(values, j, value)
                if listing:
                    c = access_field(a, 9, "cells")
                    cur.cells, cur.mips, cur.layers = <PyObject *> c, <PyObject *> mips, <PyObject *> layers
                    cur.ranges = _pair(mips, &cur.mlo, &cur.mhi) and _pair(layers, &cur.llo, &cur.lhi)
                    cur.scope, cur.value, cur.code = <PyObject *> scope, <PyObject *> value, r.icode
                    cur.uses = NULL
                    cur.one = len(<tuple> c) == 1
                    held.append(scope)
            s = scope[0]
            layout = scope[3]
            if r.candidate:
                if known != NULL and cur.ranges and r.cranges:
                    whole = cur.mlo == 0 and cur.mhi == r.cm and cur.llo == 0 and cur.lhi == r.cl
                elif known != NULL:
                    whole = not (<object> cur.mips != r.mips or <object> cur.layers != r.layers)
                else:
                    a = accs[j]
                    whole = not (access_field(a, 3, "mips") != r.mips or access_field(a, 4, "layers") != r.layers)
                if not whole:  # not the whole image: never unified
                    r.group = None
                    r.candidate = False
                elif keep_groups:
                    r.group.append((oi, j, w, usage, layout))
                elif cur.w:
                    _close(r)
                elif usage in GENERAL_READS:
                    if r.cur is None:
                        r.cur = [(oi, j)]
                        r.lay0 = layout
                    else:
                        r.cur.append((oi, j))
                        if not r.mixed and layout is not r.lay0 and layout != r.lay0:
                            r.mixed = True
            # the uses: the listed ones (``given``), else new ones, which a listing pass keeps (``made``)
            given = <object> cur.uses if reuse and same and cur.uses != NULL else None
            made = None
            if r.single:  # most resources: the one cell's uses without a lookup by cell
                if given is not None and not cur.one:
                    given = (<tuple> given)[0]
                cells = r.cells
                if cells:
                    use = _add_use(<list> (<tuple> cells[0])[1], i, oi, s, w, queue, pos, waits, given)
                else:  # (the cells tuple is read only here: it is cold)
                    use = (oi, s, w, queue, pos) if given is None else given
                    cs = <tuple> cur.cells if known != NULL else access_field(accs[j], 9, "cells")
                    cells.append((cs[0], [use]))
                if use is not None:
                    pos += 1
                    if listing and cur.one:
                        made = use
            else:
                cs = <tuple> cur.cells if known != NULL else access_field(accs[j], 9, "cells")
                keep = listing
                if keep and not cur.one:
                    made = PyTuple_New(len(cs))
                m = -1
                for c in cs:
                    m += 1
                    use = given if given is None or cur.one else (<tuple> given)[m]
                    found = timeline.get(c)
                    if found is None:
                        if use is None:
                            use = (oi, s, w, queue, pos)
                        uses = [use]
                        timeline[c] = uses
                        r.cells.append((c, uses))
                    else:
                        use = _add_use(<list> found, i, oi, s, w, queue, pos, waits, use)
                    if use is None:  # merged: the positions after it are others
                        given = made = None
                        keep = False
                        continue
                    pos += 1
                    if keep:
                        if cur.one:
                            made = use
                        else:
                            _set(<tuple> made, m, use)
            if made is not None:
                cur.uses = <PyObject *> made
                held.append(made)
        if listing:
            _pass_add(slot, p, queue, kind, accs, values, oi, i, n, fresh, held)
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
    """``trace._row``: the scope of each access of ``p`` (from the pass table where listed;
    counted as a walk meanwhile, so no other thread empties the table)."""
    global _walking
    cdef list out = []
    cdef PassSlot *slot
    cdef Py_ssize_t j = -1
    cdef long code
    _walking += 1
    try:
        slot = _pass_find(p) if type(p) is PASS_SPEC else NULL
        if slot != NULL and slot.accs == NULL:  # walked once, not listed
            slot = NULL
        kind = pass_field(p, 2, "kind")
        for a in <tuple> pass_field(p, 7, "accesses"):
            j += 1
            code_obj = info[access_field(a, 0, "resource")].code
            if slot != NULL:
                code = code_obj
                if slot.accs[j].code == code:
                    out.append((<tuple> slot.accs[j].scope)[0])
                    continue
            key = (access_field(a, 1, "usage"), kind, access_field(a, 5, "stages"), code_obj,
                   access_field(a, 8, "refit"))
            found = scopes.get(key)
            out.append((<tuple> (scope_of(key) if found is None else found))[0])
        return out
    finally:
        _walking -= 1


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
