# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""The sync phase compiled: ``sync.synchronize`` (``rgraph/compiler/sync.py``, the reference)
with a cell's state in a C struct, stage and access sets as 64-bit masks (one bit per name,
numbered as names are first seen), and the barrier groups, rectangles and per-pass sorting as C
records. The values it hands back are the Python phase's (frozensets, the plan's states from
``plan_values.plan_state``). ``phases.synchronize`` calls ``synchronize`` first; where it declines
(None: a name set past the masks, or another walk running) the twin ``_sync`` (sync.py compiled
as it is) runs. Changes to ``sync.py`` must be made here too (tests/compile/test_sync_compiled.py
and test_native_phases.py compare them)."""

from libc.stdint cimport uint64_t
from libc.stdlib cimport free, malloc, qsort, realloc
from libc.string cimport memset
from cpython.ref cimport Py_INCREF, PyObject
from cpython.list cimport PyList_CheckExact
from cpython.tuple cimport PyTuple_CheckExact, PyTuple_New, PyTuple_SET_ITEM
from cpython.unicode cimport PyUnicode_CheckExact, PyUnicode_Compare, PyUnicode_GET_LENGTH

from rgraph.compiler.plan_values import plan_state
from rgraph.compiler.usages import WRITE_ACCESS

ctypedef uint64_t u64

# ---- name sets as masks -------------------------------------------------------------------

cdef dict _STAGE_BITS = {}, _ACCESS_BITS = {}  # name -> its bit
cdef dict _SETS_STAGES = {}, _SETS_ACCESS = {}  # mask -> frozenset
cdef bint _overflow = False
#: A walk is running: its tables are in use. A phase started meanwhile (another thread, while
#: this one is in ``plan_state``; or reentered through it) declines (the twin runs instead),
#: so a reset of the tables never happens under a running walk's pointers.
cdef bint _busy = False


cdef u64 _mask(object names, dict bits):
    """The mask of a set of names (new names get the next free bit; past 64: ``_overflow``)."""
    global _overflow
    cdef u64 m = 0
    for name in names:
        b = bits.get(name)
        if b is None:
            if len(bits) >= 64:
                _overflow = True
                return 0
            b = bits[name] = len(bits)
        m |= (<u64> 1) << <int> b
    return m


cdef object _names(u64 m, dict bits, dict sets):
    """The frozenset of mask ``m`` (the same object for every equal mask)."""
    key = m
    found = sets.get(key)
    if found is None:
        if len(sets) > 4096:
            sets.clear()
        found = sets[key] = frozenset([name for name, b in bits.items() if (m >> <int> b) & 1])
    return found


cdef u64 _WRITES = _mask(WRITE_ACCESS, _ACCESS_BITS)  # the write accesses (a write's scope keeps only these)


# ---- per-Sync masks, by object identity (each kept alive while listed) ------------------

cdef enum:
    _SYNC_CAP = 4096  # table slots (power of two); at most half used
    _STATE_CAP = 8192

cdef struct SyncInfo:
    PyObject *obj
    u64 stages
    u64 access
    PyObject *layout

cdef SyncInfo _syncs[_SYNC_CAP]
cdef Py_ssize_t _sync_count = 0
cdef list _keep = []  # the Syncs, layouts and queues the tables point at


cdef SyncInfo *_sync(object s):
    """``s``'s masks (NULL where its names overflow the masks or the table is half full)."""
    global _sync_count
    cdef size_t h = (<size_t> <PyObject *> s >> 4) & (_SYNC_CAP - 1)
    while _syncs[h].obj != NULL:
        if _syncs[h].obj == <PyObject *> s:
            return &_syncs[h]
        h = (h + 1) & (_SYNC_CAP - 1)
    if _sync_count >= _SYNC_CAP // 2:
        return NULL
    stages = _mask(s.stages, _STAGE_BITS)
    access = _mask(s.access, _ACCESS_BITS)
    if _overflow:
        return NULL
    layout = s.layout
    _keep.append(s)
    _keep.append(layout)
    _syncs[h].obj = <PyObject *> s
    _syncs[h].stages = stages
    _syncs[h].access = access
    _syncs[h].layout = <PyObject *> layout
    _sync_count += 1
    return &_syncs[h]


# ---- plan states by (stages, access, layout, queue) --------------------------------------

cdef struct StateSlot:
    bint used
    u64 stages
    u64 access
    PyObject *layout
    PyObject *queue
    PyObject *state

cdef StateSlot _states[_STATE_CAP]
cdef Py_ssize_t _state_count = 0


cdef object _state(u64 stages, u64 access, object layout, object queue):
    """``plan_state((stages, access, layout, queue))`` of the masks."""
    global _state_count
    cdef size_t h = <size_t> ((stages * <u64> 0x9E3779B97F4A7C15) ^ (access * <u64> 0xC2B2AE3D27D4EB4F)
                              ^ (<size_t> <PyObject *> layout >> 4) ^ ((<size_t> <PyObject *> queue >> 4) * 31))
    h &= _STATE_CAP - 1
    while _states[h].used:
        if (_states[h].stages == stages and _states[h].access == access
                and _states[h].layout == <PyObject *> layout and _states[h].queue == <PyObject *> queue):
            return <object> _states[h].state
        h = (h + 1) & (_STATE_CAP - 1)
    st = plan_state((_names(stages, _STAGE_BITS, _SETS_STAGES), _names(access, _ACCESS_BITS, _SETS_ACCESS),
                     layout, queue))
    if _state_count >= _STATE_CAP // 2:  # full for this walk: not cached
        return st
    _keep.append(layout)
    _keep.append(queue)
    _keep.append(st)
    _states[h].used = True
    _states[h].stages = stages
    _states[h].access = access
    _states[h].layout = <PyObject *> layout
    _states[h].queue = <PyObject *> queue
    _states[h].state = <PyObject *> st
    _state_count += 1
    return st


cdef void _reset():
    global _sync_count, _state_count
    memset(_syncs, 0, sizeof(_syncs))
    memset(_states, 0, sizeof(_states))
    _sync_count = _state_count = 0
    _keep.clear()


cdef inline bint _differ(object a, object b) except -1:
    """``a != b`` for the walk's strings and None (identity first; strings without a rich compare)."""
    if a is b:
        return False
    if a is None or b is None:
        return True
    if PyUnicode_CheckExact(a) and PyUnicode_CheckExact(b):
        return PyUnicode_GET_LENGTH(a) != PyUnicode_GET_LENGTH(b) or PyUnicode_Compare(a, b) != 0
    return a != b


cdef inline object _fs_stages(u64 m):
    return _names(m, _STAGE_BITS, _SETS_STAGES)


cdef inline object _fs_access(u64 m):
    return _names(m, _ACCESS_BITS, _SETS_ACCESS)


cdef extern from "Python.h":
    # str order; called with the GIL held (qsort's comparators are declared nogil)
    int _str_cmp "PyUnicode_Compare" (PyObject *a, PyObject *b) nogil

from rgraph.compiler.alias_starts import with_partial_handoffs
from rgraph.compiler.plan_values import names as _sorted_names, subresource as _subresource
from rgraph.compiler.sync_types import SyncResult
from rgraph.compiler.trace import ResourceTrace
from rgraph.plan import model as pm
from rgraph.plan.builders import builder

include "../plan/_slots.pxi"
include "../plan/_spec_slots.pxi"

cdef Slots BARRIER = Slots(pm.Barrier, ("resource", "subresource", "src", "dst", "aliases"))
cdef Slots WAIT = Slots(pm.Wait, ("queue", "value", "stages"))  # ``device``: its default
_new_cell_state = builder(pm.CellState)


cdef struct CellState:
    PyObject *layout  # borrowed: a Sync's layout, "UNDEFINED" or None (alive through the trace)
    PyObject *cq  # borrowed: a use's queue or an earlier occupant's, or None
    bint has_write
    u64 w_st, w_ac
    bint has_reads
    u64 rd
    Py_ssize_t last_pass  # -1: None
    u64 vis_st, vis_ac


cdef struct BarRec:  # a barrier before pass ``at``: sorted by (res, m0, m1, l0, l1) within the pass
    Py_ssize_t at
    PyObject *res
    long m0, m1, l0, l1
    PyObject *barrier

cdef struct RelRec:  # releases after pass ``at``: sorted by (i, res, pos) within it
    Py_ssize_t at
    Py_ssize_t i
    PyObject *res
    Py_ssize_t pos
    PyObject *made  # tuple of barriers

cdef struct GroupRec:  # a multi-cell resource's cells of one pass with one key and release pass
    Py_ssize_t at
    PyObject *ps
    PyObject *pd
    PyObject *al
    # the key as the walk has it (equal keys <=> equal plan states): masks, layouts, queues
    u64 s_st, s_ac, d_st, d_ac
    PyObject *s_lay
    PyObject *s_q
    PyObject *d_lay
    PyObject *d_q
    Py_ssize_t rel  # -1: none
    Py_ssize_t first  # least cell position
    Py_ssize_t ncells, head, tail  # cells: a list through CellRec.next
    Py_ssize_t next  # the next group of the same pass (this resource), -1

cdef struct CellRec:
    long mip, layer
    Py_ssize_t next

cdef struct WaitRec:  # a pass's wait for another queue
    PyObject *queue  # borrowed: a use's queue or an earlier occupant's (alive through the phase)
    Py_ssize_t j  # the latest pass waited for
    u64 stages
    Py_ssize_t next  # the pass's next wait, -1


cdef class _Sink:
    """What the walks of one ``synchronize`` find (C records; the objects they point at are
    kept alive in ``keep`` or by the trace)."""

    cdef list keep
    cdef BarRec *bars
    cdef RelRec *rels
    cdef GroupRec *groups
    cdef CellRec *cells
    cdef WaitRec *waits
    cdef Py_ssize_t *head  # per pass: its first group of the resource being walked, -1
    cdef Py_ssize_t *whead  # per pass: its first wait, -1
    cdef Py_ssize_t nbars, cbars, nrels, crels, ngroups, cgroups, ncells, ccells, nwaits, cwaits, count

    def __cinit__(self, Py_ssize_t count):
        self.count = count
        self.keep = []
        self.head = <Py_ssize_t *> malloc(2 * (count + 1) * sizeof(Py_ssize_t))
        if self.head == NULL:
            raise MemoryError()
        self.whead = self.head + count + 1
        cdef Py_ssize_t k
        for k in range(2 * (count + 1)):
            self.head[k] = -1

    def __dealloc__(self):
        free(self.bars)
        free(self.rels)
        free(self.groups)
        free(self.cells)
        free(self.waits)
        free(self.head)

    cdef int wait(self, Py_ssize_t i, object queue, Py_ssize_t j, u64 stages) except -1:
        """Pass ``i`` waits for pass ``j`` on ``queue`` in ``stages`` (merged with its other
        wait for that queue: the latest pass, the union of the stages); a pass's waits are
        listed in queue order."""
        cdef Py_ssize_t g = self.whead[i], before = -1  # the wait it follows in the list
        cdef WaitRec *r
        while g >= 0:
            r = &self.waits[g]
            if _same(r.queue, queue):
                if j > r.j:
                    r.j = j
                r.stages |= stages
                return 0
            if <object> r.queue > queue:
                break
            before = g
            g = r.next
        if self.nwaits == self.cwaits:
            self.cwaits = 2 * self.cwaits + 64
            r = <WaitRec *> realloc(self.waits, self.cwaits * sizeof(WaitRec))
            if r == NULL:
                raise MemoryError()
            self.waits = r
        r = &self.waits[self.nwaits]
        r.queue, r.j, r.stages = <PyObject *> queue, j, stages
        if before < 0:
            r.next, self.whead[i] = self.whead[i], self.nwaits
        else:
            r.next, self.waits[before].next = self.waits[before].next, self.nwaits
        self.nwaits += 1
        return 0

    cdef BarRec *bar(self) except NULL:
        cdef BarRec *grown
        if self.nbars == self.cbars:
            self.cbars = 2 * self.cbars + 256
            grown = <BarRec *> realloc(self.bars, self.cbars * sizeof(BarRec))
            if grown == NULL:
                raise MemoryError()
            self.bars = grown
        self.nbars += 1
        return &self.bars[self.nbars - 1]

    cdef RelRec *rel(self) except NULL:
        cdef RelRec *grown
        if self.nrels == self.crels:
            self.crels = 2 * self.crels + 64
            grown = <RelRec *> realloc(self.rels, self.crels * sizeof(RelRec))
            if grown == NULL:
                raise MemoryError()
            self.rels = grown
        self.nrels += 1
        return &self.rels[self.nrels - 1]

    cdef Py_ssize_t group(self) except -1:
        cdef GroupRec *grown
        if self.ngroups == self.cgroups:
            self.cgroups = 2 * self.cgroups + 64
            grown = <GroupRec *> realloc(self.groups, self.cgroups * sizeof(GroupRec))
            if grown == NULL:
                raise MemoryError()
            self.groups = grown
        self.ngroups += 1
        return self.ngroups - 1

    cdef Py_ssize_t cell(self, long mip, long layer) except -1:
        cdef CellRec *grown
        if self.ncells == self.ccells:
            self.ccells = 2 * self.ccells + 256
            grown = <CellRec *> realloc(self.cells, self.ccells * sizeof(CellRec))
            if grown == NULL:
                raise MemoryError()
            self.cells = grown
        self.cells[self.ncells].mip = mip
        self.cells[self.ncells].layer = layer
        self.cells[self.ncells].next = -1
        self.ncells += 1
        return self.ncells - 1


# ---- subresources by (m0, m1, l0, l1) ------------------------------------------------------

cdef enum:
    _SUB_CAP = 1024

cdef struct SubSlot:
    bint used
    long m0, m1, l0, l1
    PyObject *sub

cdef SubSlot _subs[_SUB_CAP]
cdef Py_ssize_t _sub_count = 0
cdef list _sub_keep = []


cdef object _sub(long m0, long m1, long l0, long l1):
    """``plan_values.subresource((m0, m1), (l0, l1))``."""
    global _sub_count
    cdef size_t h = <size_t> ((m0 * 1000003) ^ (m1 * 10007) ^ (l0 * 131) ^ l1) & (_SUB_CAP - 1)
    while _subs[h].used:
        if _subs[h].m0 == m0 and _subs[h].m1 == m1 and _subs[h].l0 == l0 and _subs[h].l1 == l1:
            return <object> _subs[h].sub
        h = (h + 1) & (_SUB_CAP - 1)
    s = _subresource((m0, m1), (l0, l1))
    if _sub_count >= _SUB_CAP // 2:
        return s
    _sub_keep.append(s)
    _subs[h].used = True
    _subs[h].m0, _subs[h].m1, _subs[h].l0, _subs[h].l1 = m0, m1, l0, l1
    _subs[h].sub = <PyObject *> s
    _sub_count += 1
    return s


cdef void _sub_reset():
    global _sub_count
    memset(_subs, 0, sizeof(_subs))
    _sub_count = 0
    _sub_keep.clear()


# ---- barriers by (resource, subresource, src, dst, aliases) -------------------------------
# A plan's barriers are frozen values: an equal one made earlier (this compile, or an earlier
# compile of the same graph) is reused, which saves building it and freeing the old plan's.
# The barriers are listed in the order made; a compile of the same graph asks for them in that
# order again, so the one after the last found is tried before the hash index.

cdef enum:
    _BAR_CAP = 8192  # index slots (power of two)
    _BAR_MAX = 4096  # barriers listed: the index at most half used

cdef struct BarSlot:
    Py_hash_t res_hash
    PyObject *res  # the key: the barrier's own fields (it keeps them alive)
    PyObject *sub
    PyObject *src
    PyObject *dst
    PyObject *al
    PyObject *barrier
    PyObject *one  # (barrier,), a one-cell release's entry, once made; else NULL

cdef BarSlot _bars[_BAR_MAX]  # in the order made
cdef int _bar_index[_BAR_CAP]  # hash index: 1 + the barrier's place in ``_bars``; 0: free
cdef BarSlot _unlisted  # a barrier made while the list is full (kept by the sink)
cdef Py_ssize_t _bar_count = 0, _bar_next = 0  # listed barriers; the place to try first
cdef list _bar_keep = []  # the barriers and one-tuples listed


cdef inline bint _bar_is(BarSlot *slot, object res, object sub, object ps, object pd, object al) except -1:
    return (slot.sub == <PyObject *> sub and slot.src == <PyObject *> ps and slot.dst == <PyObject *> pd
            and _same(slot.res, res) and _same(slot.al, al))


cdef BarSlot *_barrier(_Sink sink, object res, object sub, object ps, object pd, object al) except NULL:
    """The slot of ``pm.Barrier(res, sub, ps, pd, al)``: ``sub``, ``ps`` and ``pd`` compared by
    identity (interned: ``_sub``, ``_state``), the resource name and aliases by value."""
    global _bar_count, _bar_next
    cdef BarSlot *slot
    cdef int found
    if _bar_next < _bar_count and _bar_is(&_bars[_bar_next], res, sub, ps, pd, al):
        _bar_next += 1
        return &_bars[_bar_next - 1]
    cdef Py_hash_t rh = hash(res)
    cdef size_t h = <size_t> (<u64> rh * <u64> 0x9E3779B97F4A7C15 ^ ((<size_t> <PyObject *> sub >> 4) * 31)
                              ^ ((<size_t> <PyObject *> ps >> 4) * 1000003) ^ (<size_t> <PyObject *> pd >> 4))
    h &= _BAR_CAP - 1
    while _bar_index[h]:
        found = _bar_index[h] - 1
        slot = &_bars[found]
        if slot.res_hash == rh and _bar_is(slot, res, sub, ps, pd, al):
            _bar_next = found + 1
            return slot
        h = (h + 1) & (_BAR_CAP - 1)
    barrier = new_slots(BARRIER)
    put(barrier, BARRIER, 0, res)
    put(barrier, BARRIER, 1, sub)
    put(barrier, BARRIER, 2, ps)
    put(barrier, BARRIER, 3, pd)
    put(barrier, BARRIER, 4, al)
    if _bar_count >= _BAR_MAX:
        sink.keep.append(barrier)
        slot = &_unlisted
    else:
        _bar_keep.append(barrier)
        slot = &_bars[_bar_count]
        _bar_count += 1
        _bar_index[h] = _bar_count
        _bar_next = _bar_count
    slot.res_hash = rh
    slot.res, slot.sub, slot.src, slot.dst, slot.al = (<PyObject *> res, <PyObject *> sub, <PyObject *> ps,
                                                       <PyObject *> pd, <PyObject *> al)
    slot.barrier = <PyObject *> barrier
    slot.one = NULL
    return slot


cdef PyObject *_one(_Sink sink, BarSlot *slot) except NULL:
    """``(barrier,)`` of ``slot``'s barrier (kept with it)."""
    if slot.one == NULL:
        one = (<object> slot.barrier,)
        if slot == &_unlisted:
            sink.keep.append(one)
        else:
            _bar_keep.append(one)
        slot.one = <PyObject *> one
    return slot.one


cdef void _bar_reset():
    global _bar_count, _bar_next
    memset(_bar_index, 0, sizeof(_bar_index))
    _bar_count = _bar_next = 0
    _bar_keep.clear()


# ---- the cell walk on a C state ------------------------------------------------------------

cdef inline object _end_state_of(CellState *st):
    """``plan_state(sync._state(end))``: what later accesses must wait for."""
    if st.has_reads:
        return _state(st.rd, 0, <object> st.layout, <object> st.cq)
    if st.has_write:
        return _state(st.w_st, st.w_ac, <object> st.layout, <object> st.cq)
    return _state(0, 0, <object> st.layout, <object> st.cq)


cdef inline void _end_masks(CellState *st, u64 *stages, u64 *access):
    if st.has_reads:
        stages[0], access[0] = st.rd, 0
    elif st.has_write:
        stages[0], access[0] = st.w_st, st.w_ac
    else:
        stages[0] = access[0] = 0


cdef Py_ssize_t _group_at(list uses, SyncInfo **infos, Py_ssize_t k, Py_ssize_t last, object layout, object queue,
                          u64 *stages, u64 *access):
    """``sync._group``: stages and accesses (into ``stages``, ``access``) of the read group starting
    at use ``k``, with the uses' masks in ``infos``; returns its last use."""
    cdef Py_ssize_t e = k
    cdef PyObject *u
    cdef SyncInfo *sj
    stages[0] = infos[k].stages
    access[0] = infos[k].access
    while e < last:
        u = _list_item(<PyObject *> uses, e + 1)
        sj = infos[e + 1]
        if (_truth(_tuple_item(u, 2)) or _differ(<object> sj.layout, layout)
                or _differ(<object> _tuple_item(u, 3), queue)):
            break
        stages[0] |= sj.stages
        access[0] |= sj.access
        e += 1
    return e


cdef enum:
    _INFOS_ON_STACK = 64
    _AHEAD = 4  # uses prefetched ahead


cdef extern from "Python.h":
    PyObject *_list_item "PyList_GET_ITEM" (PyObject *l, Py_ssize_t k)  # borrowed
    PyObject *_tuple_item "PyTuple_GET_ITEM" (PyObject *t, Py_ssize_t k)  # borrowed
    Py_ssize_t _as_ssize "PyLong_AsSsize_t" (PyObject *o) except? -1
    void _prefetch "__builtin_prefetch" (const void *p)
    ctypedef struct PyListObject:
        PyObject **ob_item
    Py_ssize_t _list_size "PyList_GET_SIZE" (PyObject *l)
    Py_ssize_t _tuple_size "PyTuple_GET_SIZE" (PyObject *t)
    PyObject *_type "(PyObject *) Py_TYPE" (PyObject *o)


cdef inline bint _truth(PyObject *o) except -1:
    """``bool(o)``, a bool without a call."""
    if o == <PyObject *> True:
        return True
    if o == <PyObject *> False:
        return False
    return bool(<object> o)


cdef inline bint _same(PyObject *a, object b) except -1:
    """``a == b`` (identity first) for a key's layouts, queues (str or None) and alias tuples."""
    if a == <PyObject *> b:
        return True
    return <object> a == b


cdef int _walk_c(list uses, bint image, CellState *st, tuple aliases, tuple alias_waits, bint last_prev,
                 _Sink sink, object res, long mip, long layer, object sub, bint multi) except -1:
    """``sync._walk`` from and into ``st`` (``sink`` None: the end state only). A barrier of a
    one-cell resource (``multi`` false) is built here (``sub``: its subresource); those of a
    resource of several cells join its groups of their pass (``sink.head``). Returns 1 (and
    writes nothing) where a use's names do not fit the masks or the table is half full."""
    cdef SyncInfo *on_stack[_INFOS_ON_STACK]
    cdef SyncInfo **infos = on_stack
    cdef Py_ssize_t n = len(uses), k
    cdef PyObject *u
    if n > _INFOS_ON_STACK:
        infos = <SyncInfo **> malloc(n * sizeof(SyncInfo *))
        if infos == NULL:
            raise MemoryError()
    try:
        for k in range(n):  # every scope's masks before anything is written
            if k + _AHEAD < n:  # (the trace's use tuples are cold by now)
                _prefetch(_list_item(<PyObject *> uses, k + _AHEAD))
            u = _list_item(<PyObject *> uses, k)
            _prefetch(_tuple_item(u, 0))  # its pass number, read by the walk
            infos[k] = _sync(<object> _tuple_item(u, 1))
            if infos[k] == NULL:
                return 1
        return _walk_infos(uses, infos, image, st, aliases, alias_waits, last_prev, sink, res, mip, layer, sub, multi)
    finally:
        if infos != on_stack:
            free(infos)


cdef int _walk_infos(list uses, SyncInfo **infos, bint image, CellState *st, tuple aliases, tuple alias_waits,
                     bint last_prev, _Sink sink, object res, long mip, long layer, object sub, bint multi) except -1:
    cdef Py_ssize_t n = len(uses), k, end = n - 1, covered_until = -1, i = 0, last_pass = st.last_pass
    cdef Py_ssize_t release_at, pos, g, cr
    cdef SyncInfo *si
    cdef bint w, has_write = st.has_write, has_reads = st.has_reads, transfer, has_key, changed, wait_prev
    cdef Py_ssize_t wait_j = 0
    cdef tuple wait_from
    cdef u64 w_st = st.w_st, w_ac = st.w_ac, rd = st.rd, vis_st = st.vis_st, vis_ac = st.vis_ac
    cdef u64 src_st = 0, src_ac = 0, dst_st = 0, dst_ac = 0, wait_st
    cdef dict found
    cdef PyObject *u
    cdef GroupRec *gr
    cdef BarRec *b
    cdef RelRec *rr
    cdef BarSlot *bs
    layout = <object> st.layout
    cq = <object> st.cq
    for k in range(n):
        u = _list_item(<PyObject *> uses, k)  # (i, sync, written, queue, position): read in place
        i = _as_ssize(_tuple_item(u, 0))
        w = _truth(_tuple_item(u, 2))
        queue = <object> _tuple_item(u, 3)
        pos = _as_ssize(_tuple_item(u, 4))
        si = infos[k]
        wait_from = ()  # aliased memory used on another queue: these (queue, last pass) to wait for
        wait_prev = False  # wait for (wait_q, wait_j), the cell's last use on another queue
        transfer = False
        release_at = -1
        if alias_waits or (cq is not None and _differ(cq, queue)):
            for q, j in alias_waits:
                if _differ(q, queue):
                    wait_from = alias_waits
                    break
            if cq is not None and _differ(cq, queue):
                if last_pass >= 0 and not last_prev:  # earlier frames: the runtime's frame-boundary waits
                    wait_prev, wait_q, wait_j = True, cq, last_pass
                if image:
                    transfer = layout is not None and _differ(layout, "UNDEFINED")
                else:
                    transfer = not aliases and (has_write or has_reads)
                if transfer:
                    release_at = last_pass
            src_queue = cq if transfer else queue
        else:  # the same queue as the cell's last use (or its first use), nothing to wait for
            src_queue = queue
        new_layout = <object> si.layout
        has_key = False
        changed = _differ(new_layout, layout)
        if w or changed:
            if has_reads:
                src_st, src_ac = rd, 0
            elif has_write:
                src_st, src_ac = w_st, w_ac
            else:
                src_st = src_ac = 0
            if src_st or src_ac or changed or transfer:
                if w:
                    dst_st, dst_ac = si.stages, si.access
                else:  # a transition for a read group: cover the whole group
                    covered_until = _group_at(uses, infos, k, end, new_layout, queue, &dst_st, &dst_ac)
                    vis_st, vis_ac = dst_st, dst_ac
                has_key = True
                key_src_layout = layout
                key_aliases = aliases
            if w:
                has_write = True
                w_st = si.stages
                w_ac = si.access & _WRITES
                has_reads = False
                rd = 0
                covered_until = k
                vis_st = vis_ac = 0
            else:  # a layout change: a transition is a write; from UNDEFINED it happens once, at creation
                if layout is None or _differ(layout, "UNDEFINED"):
                    has_write = True
                    w_st, w_ac = si.stages, 0
                else:
                    has_write = False
                    w_st = w_ac = 0
                has_reads = True
                rd = si.stages
        else:  # a read in the current layout
            if transfer or (has_write and k > covered_until
                            and not ((si.stages & ~vis_st) == 0 and (si.access & ~vis_ac) == 0)):
                if has_reads:  # the write is already available: chain through the reads
                    src_st, src_ac = rd, 0
                elif has_write:
                    src_st, src_ac = w_st, w_ac
                else:
                    src_st = src_ac = 0
                covered_until = _group_at(uses, infos, k, end, new_layout, queue, &dst_st, &dst_ac)
                vis_st, vis_ac = dst_st, dst_ac
                if transfer or src_st or src_ac:
                    has_key = True
                    key_src_layout = layout
                    key_aliases = aliases
            if has_reads:
                rd |= si.stages
            else:
                has_reads = True
                rd = si.stages
        layout = new_layout
        cq = queue
        last_pass = i
        if aliases or alias_waits or last_prev:
            aliases = ()
            alias_waits = ()
            last_prev = False
        if sink is None or (not has_key and not wait_from and not wait_prev):
            continue
        if wait_from or wait_prev:
            wait_st = si.stages
            if has_key and not _differ(src_queue, queue):
                # A semaphore wait orders only its own stages, and a barrier chains after it
                # only through its source stages: they must meet (the swapchain-acquire pattern).
                if not src_st:
                    src_st = si.stages
                wait_st = wait_st | src_st
            for q, j in wait_from:
                if _differ(q, queue):
                    sink.wait(i, q, j, wait_st)
            if wait_prev:
                sink.wait(i, wait_q, wait_j, wait_st)
        if not has_key:
            continue
        if multi:  # the pass's group of this key and release pass, else a new one
            g = sink.head[i]
            while g >= 0:
                gr = &sink.groups[g]
                if (gr.rel == release_at and gr.s_st == src_st and gr.s_ac == src_ac and gr.d_st == dst_st
                        and gr.d_ac == dst_ac and _same(gr.s_lay, key_src_layout) and _same(gr.s_q, src_queue)
                        and _same(gr.d_lay, new_layout) and _same(gr.d_q, queue) and _same(gr.al, key_aliases)):
                    break
                g = gr.next
            cr = sink.cell(mip, layer)
            if g < 0:
                ps = _state(src_st, src_ac, key_src_layout, src_queue)
                pd = _state(dst_st, dst_ac, new_layout, queue)
                g = sink.group()
                gr = &sink.groups[g]
                gr.s_st, gr.s_ac, gr.d_st, gr.d_ac = src_st, src_ac, dst_st, dst_ac
                gr.s_lay, gr.s_q = <PyObject *> key_src_layout, <PyObject *> src_queue
                gr.d_lay, gr.d_q = <PyObject *> new_layout, <PyObject *> queue
                sink.keep.append(ps)
                sink.keep.append(pd)
                sink.keep.append(key_aliases)
                gr.at, gr.ps, gr.pd, gr.al, gr.rel, gr.first = i, <PyObject *> ps, <PyObject *> pd, \
                    <PyObject *> key_aliases, release_at, pos
                gr.ncells, gr.head, gr.tail = 1, cr, cr
                gr.next = sink.head[i]
                sink.head[i] = g
            else:
                gr = &sink.groups[g]
                sink.cells[gr.tail].next = cr
                gr.tail = cr
                gr.ncells += 1
                if pos < gr.first:
                    gr.first = pos
            continue
        ps = _state(src_st, src_ac, key_src_layout, src_queue)
        pd = _state(dst_st, dst_ac, new_layout, queue)
        bs = _barrier(sink, res, sub, ps, pd, key_aliases)
        b = sink.bar()
        b.at, b.res, b.barrier = i, <PyObject *> res, bs.barrier
        b.m0 = b.m1 = b.l0 = b.l1 = 0
        if release_at >= 0:
            rr = sink.rel()
            rr.at, rr.i, rr.res, rr.pos, rr.made = release_at, i, <PyObject *> res, pos, _one(sink, bs)
    st.layout = <PyObject *> layout
    st.cq = <PyObject *> cq
    st.has_write, st.w_st, st.w_ac = has_write, w_st, w_ac
    st.has_reads, st.rd = has_reads, rd
    st.last_pass = last_pass
    st.vis_st, st.vis_ac = vis_st, vis_ac
    return 0


# ---- a multi-cell resource's groups -> rectangles -----------------------------------------

cdef int _rect_groups(_Sink sink, Py_ssize_t g0, object res, long mips, long layers) except -1:
    """``sync._rectangles`` of the groups ``g0`` on (one resource of ``mips`` x ``layers``): each
    group's cells as mip x layer rectangles (``rectangles.mip_layer_rectangles``), a barrier per
    rectangle, the releases' barriers in rectangle order; the pass heads reset."""
    cdef Py_ssize_t g, k, n, cr, a, b, nrows, nruns, start, e, r, maxc = 0
    cdef long count = mips * layers, tm, tl
    cdef GroupRec *gr
    cdef BarRec *br
    cdef RelRec *rr
    cdef long *cm
    cdef long *cl
    cdef long *row_mip
    cdef Py_ssize_t *row_first
    cdef Py_ssize_t *row_n
    cdef long *run_lo
    cdef long *run_hi
    cdef list made
    for g in range(g0, sink.ngroups):
        if sink.groups[g].ncells > maxc:
            maxc = sink.groups[g].ncells
    # scratch: cells (mip, layer), rows (mip, first run, runs), runs (lo, hi); each at most maxc
    cm = <long *> malloc((5 * maxc + 1) * sizeof(long))
    row_first = <Py_ssize_t *> malloc((2 * maxc + 1) * sizeof(Py_ssize_t))
    if cm == NULL or row_first == NULL:
        free(cm)
        free(row_first)
        raise MemoryError()
    cl, row_mip, run_lo, run_hi = cm + maxc, cm + 2 * maxc, cm + 3 * maxc, cm + 4 * maxc
    row_n = row_first + maxc
    try:
        for g in range(g0, sink.ngroups):
            gr = &sink.groups[g]
            sink.head[gr.at] = -1
            ps, pd, al = <object> gr.ps, <object> gr.pd, <object> gr.al
            made = [] if gr.rel >= 0 else None
            if gr.ncells == 1:
                a = gr.head
                tm, tl = sink.cells[a].mip, sink.cells[a].layer
                _rect(sink, gr, res, tm, tm + 1, tl, tl + 1, ps, pd, al, made)
            elif gr.ncells == count:  # every cell: the whole resource
                _rect(sink, gr, res, 0, mips, 0, layers, ps, pd, al, made)
            else:
                n = 0
                cr = gr.head
                while cr >= 0:  # insertion sort by (mip, layer)
                    tm, tl = sink.cells[cr].mip, sink.cells[cr].layer
                    k = n
                    while k > 0 and (cm[k - 1] > tm or (cm[k - 1] == tm and cl[k - 1] > tl)):
                        cm[k], cl[k] = cm[k - 1], cl[k - 1]
                        k -= 1
                    cm[k], cl[k] = tm, tl
                    n += 1
                    cr = sink.cells[cr].next
                nrows = nruns = 0
                for k in range(n):  # runs of layers per mip
                    if nrows == 0 or cm[k] != row_mip[nrows - 1]:
                        row_mip[nrows], row_first[nrows], row_n[nrows] = cm[k], nruns, 1
                        nrows += 1
                        run_lo[nruns], run_hi[nruns] = cl[k], cl[k] + 1
                        nruns += 1
                    elif run_hi[nruns - 1] == cl[k]:
                        run_hi[nruns - 1] = cl[k] + 1
                    else:
                        run_lo[nruns], run_hi[nruns] = cl[k], cl[k] + 1
                        nruns += 1
                        row_n[nrows - 1] += 1
                start = 0
                while start < nrows:  # consecutive mips of equal runs merged
                    e = start
                    while e + 1 < nrows and row_mip[e + 1] == row_mip[e] + 1 and _same_runs(
                            run_lo, run_hi, row_first[e + 1], row_n[e + 1], row_first[start], row_n[start]):
                        e += 1
                    for r in range(row_first[start], row_first[start] + row_n[start]):
                        _rect(sink, gr, res, row_mip[start], row_mip[e] + 1, run_lo[r], run_hi[r], ps, pd, al, made)
                    start = e + 1
            if made is not None:
                t = tuple(made)
                sink.keep.append(t)
                rr = sink.rel()
                rr.at, rr.i, rr.res, rr.pos, rr.made = gr.rel, gr.at, <PyObject *> res, gr.first, <PyObject *> t
    finally:
        free(cm)
        free(row_first)
    sink.ngroups = g0
    sink.ncells = 0
    return 0


cdef inline bint _same_runs(long *lo, long *hi, Py_ssize_t a, Py_ssize_t na, Py_ssize_t b, Py_ssize_t nb):
    cdef Py_ssize_t k
    if na != nb:
        return False
    for k in range(na):
        if lo[a + k] != lo[b + k] or hi[a + k] != hi[b + k]:
            return False
    return True


cdef int _rect(_Sink sink, GroupRec *gr, object res, long m0, long m1, long l0, long l1, ps, pd, al,
               list made) except -1:
    """The barrier of one rectangle of group ``gr``."""
    cdef Py_ssize_t at = gr.at
    barrier = <object> _barrier(sink, res, _sub(m0, m1, l0, l1), ps, pd, al).barrier
    cdef BarRec *b = sink.bar()  # (``gr`` may move when groups grow: none are added here)
    b.at, b.res, b.barrier = at, <PyObject *> res, <PyObject *> barrier
    b.m0, b.m1, b.l0, b.l1 = m0, m1, l0, l1
    if made is not None:
        made.append(barrier)
    return 0


# ---- start and end states -------------------------------------------------------------------

cdef tuple _alias_start(object preds, dict ends, Py_ssize_t at, CellState *st):
    """``alias_starts.alias_state`` of the earlier occupants ``preds`` (their cells' ends in
    ``ends``: (stage mask, access mask, queue, last pass or -1)) into ``st`` (layout set by the
    caller): returns (aliases, alias waits)."""
    cdef u64 stages = 0, access = 0
    cdef Py_ssize_t last = -1, lp
    cdef set waits = set()
    cdef tuple e
    last_queue = None
    for pred in preds:
        found = ends.get(pred)
        if found is None:
            continue
        for e in <list> found:
            lp = <Py_ssize_t> e[3]
            assert lp < at, "an earlier occupant outlives its successor's start"
            stages |= <u64> e[0]
            access |= <u64> e[1]
            if lp >= 0 and lp > last:
                last = lp
                last_queue = e[2]
            if lp >= 0 and e[2] is not None:
                waits.add((e[2], lp))
    st.cq = <PyObject *> last_queue  # alive in ``ends``
    st.has_write = stages != 0 or access != 0
    st.w_st, st.w_ac = stages, access
    st.has_reads, st.rd = False, 0
    st.last_pass = last
    st.vis_st = st.vis_ac = 0
    return tuple(sorted(preds)), tuple(sorted(waits))


cdef inline void _fresh(CellState *st, object layout):
    st.layout = <PyObject *> layout
    st.cq = <PyObject *> None
    st.has_write = st.has_reads = False
    st.w_st = st.w_ac = st.rd = st.vis_st = st.vis_ac = 0
    st.last_pass = -1


cdef bint _states_equal(a, b) except -1:
    """``a == b`` for two plan states, field by field (not the dataclass's ``__eq__``)."""
    if type(a) is not type(b):
        return a == b
    return a.stages == b.stages and a.access == b.access and a.layout == b.layout and a.queue == b.queue


cdef object _end_state_c(bint per_cell, list cells, list states):
    """``sync._end_state``: ``states`` the plan states of ``cells`` ((cell, uses) pairs), alike."""
    cdef Py_ssize_t n = len(states), k
    if n == 0:
        return None
    first = states[0]
    if n == 1:
        return first
    for k in range(1, n):
        other = states[k]
        if other is not first and not _states_equal(other, first):
            break
    else:
        return first
    if not per_cell:
        return None
    order = sorted([((<tuple> (<tuple> cells[k])[0])[1], (<tuple> (<tuple> cells[k])[0])[2], k) for k in range(n)])
    return tuple([_new_cell_state(_sub(m, m + 1, l, l + 1), states[k]) for m, l, k in order])


# ---- per pass: sorted barriers and releases, waits ------------------------------------------

cdef inline bint _bar_less(BarRec *a, BarRec *b) noexcept nogil:
    cdef int c
    if a.res != b.res:
        c = _str_cmp(a.res, b.res)
        if c != 0:
            return c < 0
    if a.m0 != b.m0:
        return a.m0 < b.m0
    if a.m1 != b.m1:
        return a.m1 < b.m1
    if a.l0 != b.l0:
        return a.l0 < b.l0
    return a.l1 < b.l1


cdef inline bint _rel_less(RelRec *a, RelRec *b) noexcept nogil:
    cdef int c
    if a.i != b.i:
        return a.i < b.i
    if a.res != b.res:
        c = _str_cmp(a.res, b.res)
        if c != 0:
            return c < 0
    return a.pos < b.pos


cdef int _bar_cmp(const void *a, const void *b) noexcept nogil:
    if _bar_less(<BarRec *> a, <BarRec *> b):
        return -1
    return 1 if _bar_less(<BarRec *> b, <BarRec *> a) else 0


cdef int _rel_cmp(const void *a, const void *b) noexcept nogil:
    if _rel_less(<RelRec *> a, <RelRec *> b):
        return -1
    return 1 if _rel_less(<RelRec *> b, <RelRec *> a) else 0


#: The last phase's barrier tuples per pass: a pass with the same barriers (the same objects:
#: ``_barrier``) gets its tuple again, which touches none of them.
cdef list _last_bars = []


cdef list _bars_by_pass(_Sink sink):
    """Each pass's barriers in (resource, mips, layers) order (``sync._gather``)."""
    global _last_bars
    cdef Py_ssize_t count = sink.count, n = sink.nbars, k, m, j, at, lo
    cdef list out = [()] * count, last = _last_bars
    cdef tuple made
    cdef Py_ssize_t *start = <Py_ssize_t *> malloc((count + 1) * sizeof(Py_ssize_t))
    cdef BarRec *order = <BarRec *> malloc((n + 1) * sizeof(BarRec))
    cdef BarRec t
    if start == NULL or order == NULL:
        free(start)
        free(order)
        raise MemoryError()
    try:
        for k in range(count + 1):
            start[k] = 0
        for k in range(n):
            start[sink.bars[k].at + 1] += 1
        for k in range(count):
            start[k + 1] += start[k]
        for k in range(n):  # bucketed by pass, in the order found
            at = sink.bars[k].at
            order[start[at]] = sink.bars[k]
            start[at] += 1
        lo = 0
        for at in range(count):
            m = start[at] - lo  # (start[at] is now the bucket's end)
            if m > 16:
                qsort(&order[lo], m, sizeof(BarRec), _bar_cmp)
            elif m > 1:
                for k in range(lo + 1, lo + m):  # insertion sort: few per pass
                    t = order[k]
                    j = k
                    while j > lo and _bar_less(&t, &order[j - 1]):
                        order[j] = order[j - 1]
                        j -= 1
                    order[j] = t
            if m:
                if at < len(last) and _same_bars(_list_item(<PyObject *> last, at), &order[lo], m):
                    out[at] = <object> _list_item(<PyObject *> last, at)
                else:
                    made = PyTuple_New(m)
                    for k in range(m):
                        Py_INCREF(<object> order[lo + k].barrier)
                        PyTuple_SET_ITEM(made, k, <object> order[lo + k].barrier)
                    out[at] = made
            lo = start[at]
    finally:
        free(start)
        free(order)
    _last_bars = out
    return out


cdef inline bint _same_bars(PyObject *t, BarRec *bars, Py_ssize_t m):
    """Whether ``t`` is a tuple of exactly the ``m`` barriers of ``bars``."""
    cdef Py_ssize_t k
    if not PyTuple_CheckExact(<object> t) or _tuple_size(t) != m:
        return False
    for k in range(m):
        if _tuple_item(t, k) != bars[k].barrier:
            return False
    return True


cdef list _rels_by_pass(_Sink sink):
    """Each pass's releases by (acquiring pass, resource, cell position) (``sync._gather``)."""
    cdef Py_ssize_t count = sink.count, n = sink.nrels, k, m, j, at, lo
    cdef list out = [()] * count
    cdef Py_ssize_t *start
    cdef RelRec *order
    cdef RelRec t
    if n == 0:
        return out
    start = <Py_ssize_t *> malloc((count + 1) * sizeof(Py_ssize_t))
    order = <RelRec *> malloc(n * sizeof(RelRec))
    if start == NULL or order == NULL:
        free(start)
        free(order)
        raise MemoryError()
    try:
        for k in range(count + 1):
            start[k] = 0
        for k in range(n):
            start[sink.rels[k].at + 1] += 1
        for k in range(count):
            start[k + 1] += start[k]
        for k in range(n):  # bucketed by releasing pass, in the order found
            at = sink.rels[k].at
            order[start[at]] = sink.rels[k]
            start[at] += 1
        lo = 0
        for at in range(count):
            m = start[at] - lo
            if m == 1:
                out[at] = <object> order[lo].made
            elif m > 16:
                qsort(&order[lo], m, sizeof(RelRec), _rel_cmp)
                out[at] = tuple([b for k in range(lo, lo + m) for b in <tuple> order[k].made])
            elif m > 1:
                for k in range(lo + 1, lo + m):
                    t = order[k]
                    j = k
                    while j > lo and _rel_less(&t, &order[j - 1]):
                        order[j] = order[j - 1]
                        j -= 1
                    order[j] = t
                out[at] = tuple([b for k in range(lo, lo + m) for b in <tuple> order[k].made])
            lo = start[at]
    finally:
        free(start)
        free(order)
    return out


cdef dict _STAGE_NAMES = {}  # stage mask -> the plan's sorted names


cdef object _stage_names(u64 m):
    """``plan_values.names`` of the stages of mask ``m``."""
    key = m
    found = _STAGE_NAMES.get(key)
    if found is None:
        if len(_STAGE_NAMES) > 4096:
            _STAGE_NAMES.clear()
        found = _STAGE_NAMES[key] = _sorted_names(_fs_stages(m))
    return found


cdef object _wait(queue, value, stages):
    """``pm.Wait(queue, value, stages)``."""
    w = new_slots(WAIT)
    put(w, WAIT, 0, queue)
    put(w, WAIT, 1, value)
    put(w, WAIT, 2, stages)
    return w


cdef object _gather_c(_Sink sink, passes, dict final, dict initial):
    """``sync._gather``."""
    cdef Py_ssize_t count = sink.count, i, g, n
    cdef list signals = [False] * count, values = [0] * count, pass_waits = [()] * count
    cdef dict counters = {}
    cdef WaitRec *r
    cdef tuple made
    for g in range(sink.nwaits):
        signals[sink.waits[g].j] = True
    for i in range(count):  # timeline values per queue, 1, 2, ... in plan order
        if signals[i] is True:
            queue = passes[i].queue
            values[i] = counters[queue] = counters.get(queue, 0) + 1
    for i in range(count):
        g = sink.whead[i]
        if g < 0:
            continue
        n = 0
        while g >= 0:
            n += 1
            g = sink.waits[g].next
        made = PyTuple_New(n)
        g, n = sink.whead[i], 0
        while g >= 0:  # in queue order
            r = &sink.waits[g]
            w = _wait(<object> r.queue, values[r.j], _stage_names(r.stages))
            Py_INCREF(w)
            PyTuple_SET_ITEM(made, n, w)
            n += 1
            g = r.next
        pass_waits[i] = made
    return SyncResult(_bars_by_pass(sink), _rels_by_pass(sink), pass_waits, signals, values, final, initial)


# ---- the resources' fields ------------------------------------------------------------------

cdef object RESOURCE_TRACE = ResourceTrace
#: Field positions: usages 0, first 1, last 2, cells 3 (the fields without a default named).
cdef Slots TRACE = Slots(ResourceTrace, ("usages", "first", "last", "cells", "code", "group"))


cdef inline object _trace_field(object r, Py_ssize_t k, str name):
    """Field ``k`` (named ``name``) of a resource's trace: from its slot where it is exactly a
    ``ResourceTrace``."""
    if type(r) is RESOURCE_TRACE:
        return get(r, TRACE, k)
    return getattr(r, name)


cdef inline PyObject *_cells_of(list rs, Py_ssize_t k):
    """Resource ``k``'s cells list (borrowed), NULL where not an exact ``ResourceTrace``'s list."""
    cdef PyObject *o = _list_item(<PyObject *> rs, k)
    if _type(o) != <PyObject *> RESOURCE_TRACE:
        return NULL
    o = borrowed_field(o, TRACE, 3)
    if o == NULL or not PyList_CheckExact(<object> o):
        return NULL
    return o


cdef void _ahead(list rs, Py_ssize_t k, Py_ssize_t n):
    """Prefetch what the resource loop reads of the traces after ``k`` (``rs``): the chain trace ->
    cells list -> its items -> first cell -> (cell, uses), a step further back each resource
    ahead, so that each pointer read was prefetched a resource earlier (the trace's objects are
    cold by now)."""
    cdef PyObject *o
    if k + 5 < n:
        _prefetch(_list_item(<PyObject *> rs, k + 5))
    if k + 4 < n:
        o = _list_item(<PyObject *> rs, k + 4)
        if _type(o) == <PyObject *> RESOURCE_TRACE and borrowed_field(o, TRACE, 3) != NULL:
            _prefetch(borrowed_field(o, TRACE, 3))
    if k + 3 < n:
        o = _cells_of(rs, k + 3)
        if o != NULL:
            _prefetch((<PyListObject *> o).ob_item)
    if k + 2 < n:
        o = _cells_of(rs, k + 2)
        if o != NULL and _list_size(o):
            _prefetch(_list_item(o, 0))
    if k + 1 < n:
        o = _cells_of(rs, k + 1)
        if o != NULL and _list_size(o):
            o = _list_item(o, 0)
            if PyTuple_CheckExact(<object> o) and _tuple_size(o) == 2:
                _prefetch(_tuple_item(o, 0))
                _prefetch(_tuple_item(o, 1))


# ---- the phase ------------------------------------------------------------------------------

def synchronize(passes, resources, trace, alias_sources=None, ranges=None, outputs=()):
    """``sync.synchronize(...)``, or None where a name set does not fit the masks or another
    walk is running (``_busy``): then the caller runs ``sync.synchronize``."""
    global _busy
    if _busy:
        return None
    _busy = True
    try:
        result = _synchronize(passes, resources, trace, alias_sources, ranges, outputs)
        if result is None and not _overflow:  # the mask table filled up: once more from empty tables
            _reset()
            result = _synchronize(passes, resources, trace, alias_sources, ranges, outputs)
        return result
    finally:
        _busy = False


cdef object _synchronize(passes, resources, trace, alias_sources, ranges, outputs):
    global _overflow
    cdef Py_ssize_t count = len(passes), ncell, g0, ri, nres
    cdef list names, rs
    cdef dict traced = trace.resources, sources, touched, initial = {}, final = {}, ends = {}
    cdef set wanted, kept_outputs
    cdef bint image, persistent, want
    cdef list cells, uses, starts, finals, kept
    cdef tuple cell, aliases, alias_waits
    cdef CellState st, first
    cdef u64 es, ea
    cdef _Sink sink
    if _sync_count > _SYNC_CAP // 4 or _state_count > _STATE_CAP // 4:
        _reset()
    if _sub_count > _SUB_CAP // 4:
        _sub_reset()
    if _bar_count > _BAR_MAX * 3 // 4:  # room for one more graph's barriers
        _bar_reset()
    _overflow = False
    alias_sources = alias_sources or {}
    touched = {n: len(traced[n].cells) for preds in alias_sources.values() for n in preds if n in traced}
    sources = with_partial_handoffs(alias_sources, touched, resources, ranges)
    wanted = {pred for preds in sources.values() for pred in preds}
    kept_outputs = outputs if type(outputs) is set else set(outputs)
    sink = _Sink(count)
    names, rs = list(traced), list(traced.values())
    nres = len(rs)
    for ri in range(nres):
        _ahead(rs, ri, nres)
        name = names[ri]
        r = rs[ri]
        res = resources[name]
        image = resource_field(res, 1) == "image"
        cells = _trace_field(r, 3, "cells")
        ncell = len(cells)
        preds = sources.get(name)
        lifetime = resource_field(res, 2)
        persistent = lifetime == "persistent" or lifetime == "imported"
        want = name in wanted
        layout = "UNDEFINED" if image else None
        if ncell == 1 and not persistent:  # most resources: one cell (every buffer)
            cell = <tuple> cells[0]
            c = <tuple> cell[0]
            uses = <list> cell[1]
            mip, layer = (c[1], c[2]) if image else (0, 0)
            sub = _sub(mip, mip + 1, layer, layer + 1) if image else None
            _fresh(&st, layout)
            if preds:  # start from the earlier occupants' last accesses (UNDEFINED)
                aliases, alias_waits = _alias_start(preds, ends, _trace_field(r, 1, "first"), &st)
                initial[name] = _end_state_of(&st)
            else:
                aliases = alias_waits = ()
                initial[name] = _state(0, 0, layout, None)
            if _walk_c(uses, image, &st, aliases, alias_waits, False, sink, c[0], mip, layer, sub, False):
                return None
            final[name] = _end_state_of(&st)
            if want:
                _end_masks(&st, &es, &ea)
                ends[name] = [(es, ea, <object> st.cq, st.last_pass)]
            continue
        starts, finals = [], []
        kept = ends[name] = [] if want else None
        g0 = sink.ngroups
        sub = None  # the one cell's subresource
        if ncell == 1 and image:
            c = <tuple> (<tuple> cells[0])[0]
            sub = _sub(c[1], c[1] + 1, c[2], c[2] + 1)
        if persistent:  # frame 1 from scratch gives the end state frame 2 starts in
            for cell in cells:
                c = <tuple> cell[0]
                uses = <list> cell[1]
                _fresh(&st, layout)
                if _walk_c(uses, image, &st, (), (), False, None, c[0], 0, 0, None, False):
                    return None
                starts.append(_end_state_of(&st))
                if _walk_c(uses, image, &st, (), (), True, sink, c[0], c[1] if image else 0, c[2] if image else 0,
                           sub, ncell > 1):
                    return None
                finals.append(_end_state_of(&st))
                if kept is not None:
                    _end_masks(&st, &es, &ea)
                    kept.append((es, ea, <object> st.cq, st.last_pass))
        else:
            _fresh(&first, layout)
            aliases = alias_waits = ()
            if preds:  # start from the earlier occupants' last accesses (UNDEFINED)
                aliases, alias_waits = _alias_start(preds, ends, _trace_field(r, 1, "first"), &first)
            first_state = _end_state_of(&first)  # every cell starts alike
            for cell in cells:
                c = <tuple> cell[0]
                uses = <list> cell[1]
                st = first
                starts.append(first_state)
                if _walk_c(uses, image, &st, aliases, alias_waits, False, sink, c[0], c[1] if image else 0,
                           c[2] if image else 0, sub, ncell > 1):
                    return None
                finals.append(_end_state_of(&st))
                if kept is not None:
                    _end_masks(&st, &es, &ea)
                    kept.append((es, ea, <object> st.cq, st.last_pass))
        if ncell > 1:
            _rect_groups(sink, g0, name, resource_field(res, 6), resource_field(res, 5))
        per_cell = lifetime != "transient" or name in kept_outputs
        initial[name] = _end_state_c(per_cell, cells, starts)
        final[name] = _end_state_c(per_cell, cells, finals)
    return _gather_c(sink, passes, final, initial)
