# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""Compiled mirror of ``rgraph.compiler.sync._walk`` (one cell through its uses): the same
barriers, releases, waits, groups and end state, with the cell's state in C locals. Stage
and access sets are 64-bit masks inside the walk (one bit per name, numbered as names are
first seen); the values it hands back are the Python walk's (frozensets, the plan's states
from ``plan_values.plan_state``). A name set that does not fit 64 bits makes ``walk`` return
None before it touches the sink: the caller then runs the Python walk. Any change to
``_walk`` must be made here too (tests/compile/test_native_phases.py compares the plans)."""

from libc.stdint cimport uint64_t
from libc.string cimport memset
from cpython.ref cimport PyObject

from rgraph.compiler.plan_values import make_barrier, plan_state
from rgraph.compiler.usages import WRITE_ACCESS

ctypedef uint64_t u64

# ---- name sets as masks -------------------------------------------------------------------

cdef dict _STAGE_BITS = {}, _ACCESS_BITS = {}  # name -> its bit
cdef dict _SETS_STAGES = {}, _SETS_ACCESS = {}  # mask -> frozenset
cdef bint _overflow = False
#: A walk is running: its tables are in use. A walk started meanwhile (another thread, while
#: this one is in ``plan_state``; or reentered through it) hands its cell to the Python walk,
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


cdef inline bint _differ(object a, object b):
    """``a != b`` for the walk's strings and None (identity first)."""
    if a is b:
        return False
    return a != b


cdef inline object _fs_stages(u64 m):
    return _names(m, _STAGE_BITS, _SETS_STAGES)


cdef inline object _fs_access(u64 m):
    return _names(m, _ACCESS_BITS, _SETS_ACCESS)


cdef Py_ssize_t _group_of(list uses, Py_ssize_t k, Py_ssize_t last, object layout, object queue, SyncInfo *first,
                          u64 *stages, u64 *access):
    """``_group``: stages and accesses (into ``stages``, ``access``) of the read group starting at
    use ``k``; returns its last use."""
    cdef Py_ssize_t e = k
    cdef tuple u
    cdef SyncInfo *sj
    stages[0] = first.stages
    access[0] = first.access
    while e < last:
        u = <tuple> uses[e + 1]
        sj = _sync(u[1])  # registered by the walk before it started
        if u[2] or _differ(<object> sj.layout, layout) or _differ(u[3], queue):
            break
        stages[0] |= sj.stages
        access[0] |= sj.access
        e += 1
    return e


def walk(list uses, bint image, tuple start, tuple aliases, tuple alias_waits, bint last_prev, sink, c, sub):
    """``sync._walk(uses, image, start, aliases, alias_waits, last_prev, sink, c, sub)``, or
    None (sink untouched) where the walk's name sets do not fit its masks or another walk is
    running (``_busy``)."""
    global _busy
    if _busy:
        return None
    _busy = True
    try:
        return _walk(uses, image, start, aliases, alias_waits, last_prev, sink, c, sub)
    finally:
        _busy = False


cdef object _walk(list uses, bint image, tuple start, tuple aliases, tuple alias_waits, bint last_prev, sink, c,
                  sub):
    global _overflow
    cdef Py_ssize_t n = len(uses), k, end = n - 1, covered_until = -1, i = 0, last_pass, release_at
    cdef SyncInfo *si
    cdef bint w, has_write, has_reads, transfer, has_key, changed
    cdef u64 w_st, w_ac, rd, vis_st, vis_ac, src_st, src_ac, dst_st, dst_ac, wait_st
    cdef list bars = None, rels = None, waits = None, groups, found_list
    cdef dict multi = None, found
    cdef tuple u
    if _sync_count + n > _SYNC_CAP // 2 or _state_count + 2 * n > _STATE_CAP // 2:
        _reset()
    _overflow = False
    for k in range(n):  # every scope's masks before anything is written
        if _sync((<tuple> uses[k])[1]) == NULL:
            return None
    layout, cq, write, reads, last, visible = start
    has_write = write is not None
    w_st = w_ac = rd = 0
    if has_write:
        w_st = _mask(write[0], _STAGE_BITS)
        w_ac = _mask(write[1], _ACCESS_BITS)
    has_reads = reads is not None
    if has_reads:
        rd = _mask(reads, _STAGE_BITS)
    vis_st = _mask(visible[0], _STAGE_BITS)
    vis_ac = _mask(visible[1], _ACCESS_BITS)
    if _overflow:
        return None
    last_pass = -1 if last is None else <Py_ssize_t> last
    if sink is not None:
        bars, rels, waits, multi = sink
    for k in range(n):
        u = <tuple> uses[k]
        i = <Py_ssize_t> u[0]
        s = u[1]
        w = u[2]
        queue = u[3]
        pos = u[4]
        si = _sync(s)
        wait_on = None
        transfer = False
        release_at = -1
        if alias_waits or (cq is not None and _differ(cq, queue)):
            if alias_waits:  # aliased memory used on another queue
                wait_on = [(q, j) for q, j in alias_waits if q != queue]
            else:
                wait_on = []
            if cq is not None and _differ(cq, queue):
                if last_pass >= 0 and not last_prev:
                    wait_on.append((cq, last_pass))  # earlier frames: the runtime's frame-boundary waits
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
                    covered_until = _group_of(uses, k, end, new_layout, queue, si, &dst_st, &dst_ac)
                    vis_st, vis_ac = dst_st, dst_ac
                has_key = True
                key_src_layout = layout
                key_dst_layout = new_layout
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
                covered_until = _group_of(uses, k, end, new_layout, queue, si, &dst_st, &dst_ac)
                vis_st, vis_ac = dst_st, dst_ac
                if transfer or src_st or src_ac:
                    has_key = True
                    key_src_layout = layout
                    key_dst_layout = new_layout
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
        if sink is None or (not has_key and not wait_on):
            continue
        if wait_on:
            wait_st = si.stages
            if has_key and not _differ(src_queue, queue):
                # A semaphore wait orders only its own stages, and a barrier chains after it
                # only through its source stages: they must meet (the swapchain-acquire pattern).
                if not src_st:
                    src_st = si.stages
                wait_st = wait_st | src_st
            wait_stages = _fs_stages(wait_st)
            found = waits[i]
            if found is None:
                found = waits[i] = {}
            for q, j in wait_on:
                prev = found.get(q)
                found[q] = (max(j, prev[0]), prev[1] | wait_stages) if prev else (j, wait_stages)
        if not has_key:
            continue
        ps = _state(src_st, src_ac, key_src_layout, src_queue)
        pd = _state(dst_st, dst_ac, key_dst_layout, queue)
        if multi is not None:  # per pass: [(plan src, plan dst, aliases), release pass, first cell position, cells]
            key = (ps, pd, key_aliases)
            rel = None if release_at < 0 else release_at
            groups = multi.get(i)
            cell = (c[1], c[2])
            if groups is None:
                multi[i] = [[key, rel, pos, [cell]]]
                continue
            for group in groups:
                if group[1] == rel and group[0] == key:
                    group[3].append(cell)
                    if pos < group[2]:
                        group[2] = pos
                    break
            else:
                groups.append([key, rel, pos, [cell]])
            continue
        res = c[0]
        barrier = make_barrier(res, sub, ps, pd, key_aliases)
        found_list = bars[i]
        if found_list is None:
            bars[i] = [(res, barrier)]
        else:
            found_list.append((res, barrier))
        if release_at >= 0:
            found_list = rels[release_at]
            if found_list is None:
                rels[release_at] = [(i, res, pos, (barrier,))]
            else:
                found_list.append((i, res, pos, (barrier,)))
    end_write = (_fs_stages(w_st), _fs_access(w_ac)) if has_write else None
    end_reads = _fs_stages(rd) if has_reads else None
    return (layout, cq, end_write, end_reads, None if last_pass < 0 else last_pass,
            (_fs_stages(vis_st), _fs_access(vis_ac)))
