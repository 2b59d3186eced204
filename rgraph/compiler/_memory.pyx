# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""Compiled mirror of ``rgraph.compiler.memory``'s ``requirements_python``,
``resource_memory_python`` and ``alias_sources_python``, and of
``rgraph.compiler.phases._culled_only_python``: the same values, with typed locals, C arrays
for the spans of one heap's resources, and the results stored slot by slot
(``rgraph/plan/_slots.pxi``). Any change to the Python code must be made here too
(tests/compile/test_native_phases.py compares the plans of both)."""

from cpython.dict cimport PyDict_Next
from cpython.object cimport newfunc
from libc.stdlib cimport calloc, free, malloc

from rgraph.compiler.memory import Requirement, ResourceMemory
from rgraph.errors import RGraphError
from rgraph.memory.model import Block
from rgraph.memory_requirements import ProfileMemoryRequirements

include "../plan/_slots.pxi"

include "_bisect.pxi"
include "../memory/_sort.pxi"

cdef Slots REQUIREMENT = Slots(Requirement, ("bytes", "alignment", "memory_type_bits", "tiling"))
cdef Slots MEMORY = Slots(ResourceMemory, ("bytes", "alignment", "memory_type_bits", "memory_class", "usages",
                                           "first", "last"))

# The slots of the values ``measure`` reads (set on first use: their modules import later
# than this one); each read checks the exact type first, else falls back to ``getattr``.
cdef Slots TRACE = None, ACCESS = None, PASS = None, CULLED = None, RES = None
cdef object TRACE_T = None, ACCESS_T = None, PASS_T = None, CULLED_T = None, RES_T = None


cdef int _layouts() except -1:
    global TRACE, ACCESS, PASS, CULLED, RES, TRACE_T, ACCESS_T, PASS_T, CULLED_T, RES_T
    from rgraph.compiler.trace import ResourceTrace
    from rgraph.ir.cull import Culled
    from rgraph.spec.specialize import AccessSpec, PassSpec, ResourceSpec

    TRACE = Slots(ResourceTrace, ("usages", "first", "last", "cells", "code", "group"))
    ACCESS = Slots(AccessSpec, ("resource", "usage", "write", "mips", "layers", "stages", "optional", "loc",
                                "refit", "cells"))
    PASS = Slots(PassSpec, ("name", "order", "kind", "queue", "impl", "requires", "side_effects", "accesses",
                            "params", "loc", "requires_any"))
    CULLED = Slots(Culled, ("pass_name", "reason"))
    RES = Slots(ResourceSpec, ("name", "kind", "lifetime", "format", "extent", "layers", "mips", "samples", "bytes",
                               "loc"))
    TRACE_T, ACCESS_T, PASS_T, CULLED_T, RES_T = ResourceTrace, AccessSpec, PassSpec, Culled, ResourceSpec
    return 0


def requirements(resources, used, outputs, provider, dict same_buffer_flag):
    """``requirements_python(resources, used, outputs, provider)``; ``same_buffer_flag``:
    ``memory._SAME_BUFFER_FLAG``."""
    cdef dict out = {}, memo = None, buffer_memo = None
    cdef set kept = set(outputs), usage_set
    cdef list usages
    if type(provider) is ProfileMemoryRequirements:  # its memos read here: no call per resource once filled
        memo = provider.__dict__.get("_image_memo")
        buffer_memo = provider.__dict__.get("_buffer_memo")
    for name in sorted(used):
        res = resources[name]
        usage_set = set(used[name])
        if name in kept or res.lifetime == "output":
            usage_set.add("transfer_src")
        usages = sorted(usage_set)
        try:
            if res.kind == "image":  # ``res.is_image``
                fmt = res.format
                assert fmt is not None
                found = None
                if memo is not None:  # ``ProfileMemoryRequirements.image``'s key
                    found = memo.get((fmt.vk_name, tuple(res.extent), res.mips, res.layers, res.samples,
                                      tuple(usages)))
                if found is None:
                    found = provider.image(fmt.vk_name, res.extent, res.mips, res.layers, res.samples, usages)
                size, align, bits = found
                tiling = "optimal"
            else:
                flags = sorted({same_buffer_flag.get(u, u) for u in usages})
                found = None
                if buffer_memo is not None:  # ``ProfileMemoryRequirements.buffer``'s key
                    found = buffer_memo.get((res.bytes, tuple(flags)))
                if found is None:
                    found = provider.buffer(res.bytes, flags)
                size, align, bits = found
                tiling = "linear"
        except RGraphError as err:
            raise RGraphError.at(res.loc, f"resource '{name}': {err.first.message}") from None
        value = new_slots(REQUIREMENT)
        put(value, REQUIREMENT, 0, size)
        put(value, REQUIREMENT, 1, align)
        put(value, REQUIREMENT, 2, bits)
        put(value, REQUIREMENT, 3, tiling)
        out[name] = value
    return out


def resource_memory(reqs, used, spans):
    """``resource_memory_python(reqs, used, spans)`` (``memory_classes`` inside)."""
    cdef dict bits_by_tiling = {}, base = {}, out = {}
    cdef tuple span
    for r in reqs.values():
        found = bits_by_tiling.get(r.tiling)
        if found is None:
            bits_by_tiling[r.tiling] = {r.memory_type_bits}
        else:
            (<set> found).add(r.memory_type_bits)
    for tiling, found in bits_by_tiling.items():
        base[tiling] = f"device_local_{tiling}" if len(<set> found) == 1 else None
    for name, r in reqs.items():
        cls = base[r.tiling]
        if cls is None:
            cls = f"device_local_{r.tiling}_types_{r.memory_type_bits:x}"
        span = spans[name]
        value = new_slots(MEMORY)
        put(value, MEMORY, 0, r.bytes)
        put(value, MEMORY, 1, r.alignment)
        put(value, MEMORY, 2, r.memory_type_bits)
        put(value, MEMORY, 3, cls)
        put(value, MEMORY, 4, tuple(sorted(used[name])))
        put(value, MEMORY, 5, span[0])
        put(value, MEMORY, 6, span[1])
        out[name] = value
    return out


def culled_only(passes, culled, traced):
    """``_culled_only_python(spec, culled, traced)`` for ``passes``: ``spec.passes``."""
    if TRACE is None:
        _layouts()
    return _culled_only(passes, culled, traced)


cdef struct PtrMap:
    # Open addressing on object addresses (no reference held, no hash read from the object):
    # a slot is free while its key is NULL.
    size_t mask
    void **keys
    void **values


cdef int ptr_map_init(PtrMap *m, Py_ssize_t count) except -1:
    cdef size_t size = 16
    while size < 2 * <size_t> count:
        size *= 2
    m.mask = size - 1
    m.keys = <void **> calloc(2 * size, sizeof(void *))
    if m.keys == NULL:
        raise MemoryError()
    m.values = m.keys + size
    return 0


cdef inline size_t ptr_slot(const PtrMap *m, void *key) noexcept nogil:
    cdef size_t h = (<size_t> key >> 4) * <size_t> 0x9E3779B97F4A7C15ULL
    h = (h >> 32) & m.mask
    while m.keys[h] != NULL and m.keys[h] != key:
        h = (h + 1) & m.mask
    return h


cdef inline void ptr_put(PtrMap *m, void *key, void *value) noexcept nogil:
    cdef size_t h = ptr_slot(m, key)
    m.keys[h] = key
    m.values[h] = value


cdef inline void *ptr_get(const PtrMap *m, void *key) noexcept nogil:
    """The value stored for ``key``, NULL where none is."""
    cdef size_t h = ptr_slot(m, key)
    return m.values[h] if m.keys[h] != NULL else NULL


cdef inline void *slot_ptr(object o, Slots layout, Py_ssize_t k) noexcept:
    """Field ``k`` of ``o`` (exactly ``layout.cls``) as a borrowed pointer, NULL where unset."""
    return (<void **> ((<char *> <PyObject *> o) + layout.off[k]))[0]


cdef tuple _culled_only(passes, culled, traced):
    """``_culled_only_python``. Where every pass is a ``PassSpec`` (and the trace a dict), the
    passes are found by the address of their name and the traced resources by the address of
    theirs (a culled pass's name is its ``PassSpec``'s own string, an access's resource the
    trace's key): the strings are not read (on a 1,000-pass graph they were most of its
    time, each a cache miss); a name or resource not found by address is looked up by value."""
    cdef dict by_name = None, only_by_pass = {}
    cdef list used_by = []
    cdef set only
    cdef PtrMap names, seen
    cdef bint fast = type(passes) is list and type(traced) is dict
    cdef Py_ssize_t pos = 0
    cdef PyObject *key
    cdef PyObject *value
    cdef void *found
    if not culled:
        return {}, []
    if fast:
        for p in <list> passes:
            if type(p) is not PASS_T:
                fast = False
                break
    names.keys = seen.keys = names.values = seen.values = NULL
    names.mask = seen.mask = 0
    try:
        if fast:
            ptr_map_init(&names, len(<list> passes))
            for p in <list> passes:
                found = slot_ptr(p, PASS, 0)
                if found != NULL:
                    ptr_put(&names, found, <void *> p)
            ptr_map_init(&seen, len(<dict> traced))
            while PyDict_Next(<dict> traced, &pos, &key, &value):
                ptr_put(&seen, <void *> key, <void *> key)
        for x in culled:
            pass_name = get(x, CULLED, 0) if type(x) is CULLED_T else x.pass_name
            found = ptr_get(&names, <void *> pass_name) if fast else NULL
            if found != NULL:
                p = <object> found
            else:
                if by_name is None:
                    by_name = {}
                    for q in passes:
                        by_name[get(q, PASS, 0) if type(q) is PASS_T else q.name] = q
                p = by_name[pass_name]
            only = None
            for a in (get(p, PASS, 7) if type(p) is PASS_T else p.accesses):
                if type(a) is ACCESS_T:
                    if fast and ptr_get(&seen, slot_ptr(a, ACCESS, 0)) != NULL:
                        continue  # traced (found by address)
                    name = get(a, ACCESS, 0)
                else:
                    name = a.resource
                if name not in traced:
                    if only is None:
                        only = {name}
                    else:
                        only.add(name)
            if only is not None:
                only_by_pass[get(p, PASS, 0) if type(p) is PASS_T else p.name] = tuple(sorted(only))
                used_by.append(p)
    finally:
        free(names.keys)
        free(seen.keys)
    return only_by_pass, used_by


cdef dict _usages_by_resource(list passes):
    """``memory.usages_by_resource(passes)``."""
    cdef dict used = {}
    cdef set found
    cdef bint raytrace
    for p in passes:
        if type(p) is PASS_T:
            raytrace = get(p, PASS, 2) == "raytrace"
            accesses = get(p, PASS, 7)
        else:
            raytrace = p.kind == "raytrace"
            accesses = p.accesses
        for a in accesses:
            if type(a) is ACCESS_T:
                name, usage = get(a, ACCESS, 0), get(a, ACCESS, 1)
            else:
                name, usage = a.resource, a.usage
            got = used.get(name)
            if got is None:
                found = {usage}
                used[name] = found
            else:
                found = <set> got
                found.add(usage)
            if raytrace and usage == "indirect":
                found.add("trace_indirect")
    return used


def measure(resources, traced, outputs, provider, culled, passes, empty, dict same_buffer_flag):
    """``phases._measure_python``'s ``(memory, culled_bytes, culled_only)``: the
    requirements of the used resources (``requirements_python`` of their usages), their
    ``resource_memory_python`` values, and the culled-only resources' bytes, in one pass
    over the used resources: each usage set sorted once (twice where ``transfer_src`` joins
    it), no ``Requirement`` made for them, the trace and the resources read from their slots."""
    cdef dict out = {}, memo = None, buffer_memo = None, flags_memo = {}
    cdef dict culled_bytes = {}, only_by_pass
    cdef set kept = set(outputs), usage_set
    cdef list names, usages, founds = [], tuples = [], firsts = [], lasts = []
    cdef list culled_passes
    cdef Py_ssize_t k, n
    cdef int many_optimal = 0, many_linear = 0  # several memoryTypeBits within the tiling
    cdef bint image
    cdef tuple key_usages, utuple, flags_pair, found
    if TRACE is None:
        _layouts()
    if type(provider) is ProfileMemoryRequirements:  # its memos read here: no call per resource once filled
        memo = provider.__dict__.get("_image_memo")
        buffer_memo = provider.__dict__.get("_buffer_memo")
    names = sorted(traced)
    n = len(names)
    cdef char *tilings = <char *> malloc(max(n, 1))
    if tilings == NULL:
        raise MemoryError()
    bits_optimal = bits_linear = None
    try:
        for k in range(n):
            name = names[k]
            rt = traced[name]
            if type(rt) is TRACE_T:
                usage_set = get(rt, TRACE, 0)
                firsts.append(get(rt, TRACE, 1))
                lasts.append(get(rt, TRACE, 2))
            else:
                usage_set = rt.usages
                firsts.append(rt.first)
                lasts.append(rt.last)
            res = resources[name]
            if type(res) is RES_T:  # its slots read directly
                kind, lifetime, fmt, extent = get(res, RES, 1), get(res, RES, 2), get(res, RES, 3), get(res, RES, 4)
                layers, mips, samples, size_ = get(res, RES, 5), get(res, RES, 6), get(res, RES, 7), get(res, RES, 8)
            else:
                kind, lifetime, fmt, extent = res.kind, res.lifetime, res.format, res.extent
                layers, mips, samples, size_ = res.layers, res.mips, res.samples, res.bytes
            usages = sorted(usage_set)
            utuple = tuple(usages)
            tuples.append(utuple)
            if name in kept or lifetime == "output":
                usages = sorted(usage_set | {"transfer_src"})
                key_usages = tuple(usages)
            else:
                key_usages = utuple
            try:
                image = kind == "image"  # ``res.is_image``
                if image:
                    assert fmt is not None
                    got = None
                    if memo is not None:  # ``ProfileMemoryRequirements.image``'s key
                        got = memo.get((fmt.vk_name, tuple(extent), mips, layers, samples, key_usages))
                    if got is None:
                        got = provider.image(fmt.vk_name, extent, mips, layers, samples, usages)
                else:
                    flags_pair = flags_memo.get(key_usages)
                    if flags_pair is None:
                        flags = sorted({same_buffer_flag.get(u, u) for u in usages})
                        flags_pair = (flags, tuple(flags))
                        flags_memo[key_usages] = flags_pair
                    got = None
                    if buffer_memo is not None:  # ``ProfileMemoryRequirements.buffer``'s key
                        got = buffer_memo.get((size_, flags_pair[1]))
                    if got is None:
                        got = provider.buffer(size_, list(flags_pair[0]))
                if type(got) is tuple and len(<tuple> got) == 3:
                    found = <tuple> got
                    bits = found[2]
                else:
                    size, align, bits = got
                    found = (size, align, bits)
            except RGraphError as err:
                raise RGraphError.at(res.loc, f"resource '{name}': {err.first.message}") from None
            founds.append(found)
            if image:
                tilings[k] = 1
                if bits_optimal is None:
                    bits_optimal = bits
                elif not many_optimal and bits != bits_optimal:
                    many_optimal = 1
            else:
                tilings[k] = 0
                if bits_linear is None:
                    bits_linear = bits
                elif not many_linear and bits != bits_linear:
                    many_linear = 1
        for k in range(n):
            found = <tuple> founds[k]
            bits = found[2]
            if tilings[k]:
                cls = f"device_local_optimal_types_{bits:x}" if many_optimal else "device_local_optimal"
            else:
                cls = f"device_local_linear_types_{bits:x}" if many_linear else "device_local_linear"
            value = new_slots(MEMORY)
            put(value, MEMORY, 0, found[0])
            put(value, MEMORY, 1, found[1])
            put(value, MEMORY, 2, bits)
            put(value, MEMORY, 3, cls)
            put(value, MEMORY, 4, tuples[k])
            put(value, MEMORY, 5, firsts[k])
            put(value, MEMORY, 6, lasts[k])
            out[names[k]] = value
    finally:
        free(tilings)
    only_by_pass, culled_passes = _culled_only(passes, culled, traced)
    if culled_passes:
        culled_used = {r: u for r, u in _usages_by_resource(culled_passes).items() if r not in traced}
        if culled_used:
            for r, q in requirements(resources, culled_used, outputs, provider, same_buffer_flag).items():
                culled_bytes[r] = 0 if r in empty else (<object> q).bytes
    return out, culled_bytes, only_by_pass


cdef struct Span:
    i64 first, last, lo, hi  # first and last pass, first and end byte
    i64 rank  # the name's rank in name order among the heap's resources
    Py_ssize_t at  # index in ``names``


cdef int _heap_sources(list names, offsets, memory, dict out) except -1:
    """``alias_sources_python``'s loop over one heap's resources ``names`` (at least two): the
    spans in C, sorted by (first pass, name) and (last pass, name) with each name's rank in
    name order (its place in ``names`` where those are sorted already, as the compiler's
    placements list them), the earlier occupants kept by their place in the by-last order."""
    cdef Py_ssize_t n = len(names), k, t, m, v, a, nkeep
    cdef Span *spans = <Span *> malloc(3 * n * sizeof(Span))
    cdef Span *ordered = spans + n
    cdef Span *given = spans + 2 * n  # in names' order
    cdef Triple *keys = <Triple *> malloc(2 * n * sizeof(Triple))
    cdef Triple *sorted_keys
    cdef i64 *vis = <i64 *> malloc(3 * n * sizeof(i64))
    cdef i64 *last = <i64 *> malloc(n * sizeof(i64))
    cdef Py_ssize_t *keep = <Py_ssize_t *> malloc(n * sizeof(Py_ssize_t))
    cdef i64 r_first, r_lo, r_hi, p_first, p_last, p_lo, p_hi, both_lo, both_hi, stop
    cdef bint covered, in_order = True
    cdef list kept
    cdef dict rank_of
    if spans == NULL or vis == NULL or last == NULL or keep == NULL or keys == NULL:
        free(spans)
        free(keys)
        free(vis)
        free(last)
        free(keep)
        raise MemoryError()
    try:
        for k in range(1, n):
            if not names[k - 1] < names[k]:
                in_order = False
                break
        if not in_order:
            rank_of = {name: t for t, name in enumerate(sorted(names))}
        for k in range(n):
            name = names[k]
            mem = memory[name]
            if type(mem) is ResourceMemory:
                first, lst, size = get(mem, MEMORY, 5), get(mem, MEMORY, 6), get(mem, MEMORY, 0)
            else:
                first, lst, size = mem.first, mem.last, mem.bytes
            off = offsets[name][1]
            given[k].first, given[k].last, given[k].lo, given[k].hi = first, lst, off, off + size
            given[k].rank = k if in_order else rank_of[name]
            given[k].at = k
        for k in range(n):  # (first pass, name rank): ordered
            keys[k].a, keys[k].b, keys[k].c = given[k].first, given[k].rank, k
        sorted_keys = sort_triples(keys, keys + n, n)
        for k in range(n):
            ordered[k] = given[sorted_keys[k].c]
        for k in range(n):  # (last pass, name rank): spans
            keys[k].a, keys[k].b, keys[k].c = given[k].last, given[k].rank, k
        sorted_keys = sort_triples(keys, keys + n, n)
        for k in range(n):
            spans[k] = given[sorted_keys[k].c]
        for k in range(n):
            last[k] = spans[k].last
        for t in range(n):
            r_first, r_lo, r_hi = ordered[t].first, ordered[t].lo, ordered[t].hi
            m = 0
            nkeep = 0
            stop = -1
            for k in range(_bisect_left(last, n, r_first) - 1, -1, -1):
                p_first, p_last, p_lo, p_hi = spans[k].first, spans[k].last, spans[k].lo, spans[k].hi
                if p_last < stop:
                    break
                if not (r_lo < p_hi and p_lo < r_hi):
                    continue
                both_lo = p_lo if p_lo > r_lo else r_lo
                both_hi = p_hi if p_hi < r_hi else r_hi
                covered = False
                for v in range(m):
                    if vis[3 * v] > p_last and vis[3 * v + 1] <= both_lo and both_hi <= vis[3 * v + 2]:
                        covered = True
                        break
                if not covered:
                    keep[nkeep] = k
                    nkeep += 1
                vis[3 * m], vis[3 * m + 1], vis[3 * m + 2] = p_first, p_lo, p_hi
                m += 1
                if p_lo <= r_lo and r_hi <= p_hi:
                    if p_first > stop:
                        stop = p_first
            if nkeep:
                for a in range(1, nkeep):  # insertion sort by (first pass, name): a few
                    k = keep[a]
                    v = a
                    while v > 0 and (spans[keep[v - 1]].first > spans[k].first or (
                            spans[keep[v - 1]].first == spans[k].first and spans[keep[v - 1]].rank > spans[k].rank)):
                        keep[v] = keep[v - 1]
                        v -= 1
                    keep[v] = k
                kept = [names[spans[keep[a]].at] for a in range(nkeep)]
                out[names[ordered[t].at]] = kept
    finally:
        free(spans)
        free(keys)
        free(vis)
        free(last)
        free(keep)
    return 0


def alias_sources(placement, memory):
    """``alias_sources_python(placement, memory)``."""
    cdef dict by_heap = {}, out = {}
    offsets = placement.offsets
    for name, where in offsets.items():
        heap = where[0]
        found = by_heap.get(heap)
        if found is None:
            by_heap[heap] = [name]
        else:
            (<list> found).append(name)
    for names in by_heap.values():
        if len(<list> names) < 2:
            continue
        _heap_sources(<list> names, offsets, memory, out)
    return out


def blocks(list names, memory):
    """``place_resources``' blocks: ``[Block(n, m.first, m.last, m.bytes, m.alignment,
    m.memory_class) for n in names for m in (memory[n],)]``, each built without a call to its
    ``__init__`` (its fields in its ``__dict__``, as that ``__init__`` writes them) and with its
    ``aligned_size`` stored already (what ``Block.aligned_size`` computes on first use; not where
    the alignment is below 1: ``check_blocks`` reports that)."""
    cdef list out = []
    cdef dict d
    cdef tuple no_args = ()
    cdef newfunc tp_new = (<PyTypeObject *> Block).tp_new  # object.__new__'s: Block defines none
    if Block.__new__ is not object.__new__:
        tp_new = NULL
    new = Block.__new__
    for n in names:
        m = memory[n]
        b = tp_new(Block, <PyObject *> no_args, NULL) if tp_new != NULL else new(Block)
        d = b.__dict__
        if type(m) is ResourceMemory:  # its slots read directly
            size, alignment, first, last, cls = get(m, MEMORY, 0), get(m, MEMORY, 1), get(m, MEMORY, 5), \
                get(m, MEMORY, 6), get(m, MEMORY, 3)
        else:
            size, alignment, first, last, cls = m.bytes, m.alignment, m.first, m.last, m.memory_class
        d["name"], d["start"], d["end"], d["size"] = n, first, last, size
        d["alignment"], d["memory_class"] = alignment, cls
        if type(size) is int and type(alignment) is int and alignment >= 1:
            rem = size % alignment
            d["aligned_size"] = size if rem == 0 else size + alignment - rem
        out.append(b)
    return out


def columns(list names, memory):
    """``blocks(names, memory)`` as the columns of ``rgraph.memory._fit.Columns``: ``(start,
    end, size, alignment, memory_class)``, the first and last pass, bytes, alignment and
    class of each name's ``memory``."""
    cdef list start = [], end = [], size = [], alignment = [], classes = []
    for n in names:
        m = memory[n]
        if type(m) is ResourceMemory:  # its slots read directly
            start.append(get(m, MEMORY, 5))
            end.append(get(m, MEMORY, 6))
            size.append(get(m, MEMORY, 0))
            alignment.append(get(m, MEMORY, 1))
            classes.append(get(m, MEMORY, 3))
        else:
            start.append(m.first)
            end.append(m.last)
            size.append(m.bytes)
            alignment.append(m.alignment)
            classes.append(m.memory_class)
    return start, end, size, alignment, classes


def split(resources, memory, outputs):
    """``place_resources``' ``(aliasable, rest)``: the names of ``memory`` in sorted order,
    the transients that are not ``outputs`` in the first list, the others in the second."""
    cdef set kept = set(outputs)
    cdef list aliasable = [], rest = []
    for n in sorted(memory):
        if resources[n].lifetime == "transient" and n not in kept:
            aliasable.append(n)
        else:
            rest.append(n)
    return aliasable, rest


def split_transients(resources, memory, outputs):
    """``phases.place``'s candidates and ``split(resources, memory, outputs)`` in one pass
    where ``memory`` is in name order (the measure phase's is): ``(transients, aliasable,
    rest)``, ``transients`` the names of ``memory`` whose resource is transient, in
    ``memory``'s order (outputs included)."""
    cdef set kept = set(outputs)
    cdef list names = list(memory), ordered = sorted(names), transients = [], aliasable, rest
    cdef Py_ssize_t k, n = len(names)
    if ordered != names:  # another order: the two lists apart
        for name in names:
            if resources[name].lifetime == "transient":
                transients.append(name)
        aliasable, rest = split(resources, memory, outputs)
        return transients, aliasable, rest
    aliasable, rest = [], []
    for k in range(n):
        name = names[k]
        if resources[name].lifetime == "transient":
            transients.append(name)
            if name not in kept:
                aliasable.append(name)
                continue
        rest.append(name)
    return transients, aliasable, rest


def dedicated(list rest, memory, list heaps, dict offsets, heap):
    """``place_resources``' loop giving each of ``rest`` its own heap (``heap``: the ``Heap``
    builder), appended to ``heaps`` and written to ``offsets``; returns their bytes."""
    extra = 0
    for n in rest:
        m = memory[n]
        h = heap(len(heaps), m.bytes, m.memory_class, m.alignment)
        heaps.append(h)
        offsets[n] = (h.id, 0)
        extra += m.bytes
    return extra
