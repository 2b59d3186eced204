# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""Compiled mirror of ``rgraph.compiler.memory``'s ``requirements_python``,
``resource_memory_python`` and ``alias_sources_python``, and of
``rgraph.compiler.phases._culled_only_python``: the same values, with typed locals, C arrays
for the spans of one heap's resources, and the results stored slot by slot
(``rgraph/plan/_slots.pxi``). Any change to the Python code must be made here too
(tests/compile/test_native_phases.py compares the plans of both)."""

from libc.stdlib cimport free, malloc

from rgraph.compiler.memory import Requirement, ResourceMemory
from rgraph.errors import RGraphError
from rgraph.memory.model import Block
from rgraph.memory_requirements import ProfileMemoryRequirements

include "../plan/_slots.pxi"

include "_bisect.pxi"

cdef Slots REQUIREMENT = Slots(Requirement, ("bytes", "alignment", "memory_type_bits", "tiling"))
cdef Slots MEMORY = Slots(ResourceMemory, ("bytes", "alignment", "memory_type_bits", "memory_class", "usages",
                                           "first", "last"))


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
    cdef dict by_name = {}, only_by_pass = {}
    cdef list used_by = []
    cdef set only
    if not culled:
        return {}, []
    for p in passes:
        by_name[p.name] = p
    for x in culled:
        p = by_name[x.pass_name]
        only = None
        for a in p.accesses:
            name = a.resource
            if name not in traced:
                if only is None:
                    only = {name}
                else:
                    only.add(name)
        if only is not None:
            only_by_pass[p.name] = tuple(sorted(only))
            used_by.append(p)
    return only_by_pass, used_by


cdef int _heap_sources(list names, offsets, memory, dict out) except -1:
    """``alias_sources_python``'s loop over one heap's resources ``names`` (at least two)."""
    cdef Py_ssize_t n = len(names), k, t, m, v, r_k
    cdef dict span = {}, pos = {}
    cdef i64 *first = <i64 *> malloc(4 * n * sizeof(i64))
    cdef i64 *vis = <i64 *> malloc(3 * n * sizeof(i64))
    cdef i64 *last = first + n
    cdef i64 *lo = first + 2 * n
    cdef i64 *hi = first + 3 * n
    cdef i64 r_first, r_lo, r_hi, p_first, p_last, p_lo, p_hi, both_lo, both_hi, stop
    cdef bint covered
    cdef list keep
    if first == NULL or vis == NULL:
        free(first)
        free(vis)
        raise MemoryError()
    try:
        for name in names:
            mem = memory[name]
            off = offsets[name][1]
            span[name] = (mem.first, mem.last, off, off + mem.bytes)
        ordered = sorted(names, key=lambda x: (span[x][0], x))
        by_last = sorted(names, key=lambda x: (span[x][1], x))
        for k in range(n):  # the spans in by_last's order
            f, l, a, b = span[by_last[k]]
            first[k], last[k], lo[k], hi[k] = f, l, a, b
        for r in ordered:
            f, _, a, b = span[r]
            r_first, r_lo, r_hi = f, a, b
            m = 0
            stop = -1
            keep = []
            for k in range(_bisect_left(last, n, r_first) - 1, -1, -1):
                p_first, p_last, p_lo, p_hi = first[k], last[k], lo[k], hi[k]
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
                    keep.append(by_last[k])
                vis[3 * m], vis[3 * m + 1], vis[3 * m + 2] = p_first, p_lo, p_hi
                m += 1
                if p_lo <= r_lo and r_hi <= p_hi:
                    if p_first > stop:
                        stop = p_first
            if keep:
                out[r] = sorted(keep, key=lambda x: (span[x][0], x))
    finally:
        free(first)
        free(vis)
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
    new = Block.__new__
    for n in names:
        m = memory[n]
        b = new(Block)
        d = b.__dict__
        size, alignment = m.bytes, m.alignment
        d["name"], d["start"], d["end"], d["size"] = n, m.first, m.last, size
        d["alignment"], d["memory_class"] = alignment, m.memory_class
        if type(size) is int and type(alignment) is int and alignment >= 1:
            rem = size % alignment
            d["aligned_size"] = size if rem == 0 else size + alignment - rem
        out.append(b)
    return out


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
