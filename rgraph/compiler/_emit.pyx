# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""Compiled mirror of ``rgraph.compiler.emit``'s ``_passes_python``, ``_resources_python`` and
``_culled_python``: the same plan values, each stored slot by slot (``rgraph/plan/_slots.pxi``)
instead of through its builder. Any change to the Python code must be made here too
(tests/compile/test_native_phases.py compares the plans of both)."""

from rgraph.plan import model as pm

include "../plan/_slots.pxi"
include "../plan/_spec_slots.pxi"

from rgraph.compiler.memory import ResourceMemory
cdef object RESOURCE_MEMORY = ResourceMemory
#: bytes 0, alignment 1, memory_type_bits 2, memory_class 3, usages 4, first 5, last 6 (every field, only read).
cdef tuple _MEM_NAMES = ("bytes", "alignment", "memory_type_bits", "memory_class", "usages", "first", "last")
cdef Slots MEM = Slots(ResourceMemory, _MEM_NAMES)


cdef inline object mem_field(object m, Py_ssize_t k):
    """Field ``k`` of ``ResourceMemory`` ``m`` (the same, for ``_MEM_NAMES``)."""
    if type(m) is RESOURCE_MEMORY:
        return get(m, MEM, k)
    return getattr(m, <str> _MEM_NAMES[k])

cdef Slots PLAN_PASS = Slots(pm.PlanPass, ("name", "index", "device", "queue", "kind", "impl", "params", "accesses",
                                     "barriers", "releases", "waits", "signals"))
cdef Slots RESOURCE = Slots(pm.PlanResource, (
    "name", "kind", "format", "bytes", "size_bytes", "alignment", "memory_type_bits", "memory_class", "usages",
    "lifetime", "first", "last", "heap", "offset", "initial", "final", "extent", "mips", "layers", "samples", "accel",
    "scratch_of"))
cdef Slots CULLED = Slots(pm.Culled, ("pass_name", "reason", "resources", "bytes"))
cdef Slots SIGNAL = Slots(pm.Signal, ("queue", "value", "stages"))
cdef object EMPTY = pm.EMPTY


def passes(list passes, list accesses, barriers, releases, waits, signals, signal_values, frozen, tuple signal_stages):
    """``_passes_python``'s tuple; ``frozen``: ``emit._frozen``."""
    cdef Py_ssize_t i, n = len(passes)
    cdef list out = []
    if len(accesses) != n:
        raise ValueError("zip() argument 2 is shorter or longer than argument 1")
    for i in range(n):
        p = passes[i]
        params = pass_field(p, 8, "params")
        queue = pass_field(p, 3, "queue")
        value = new_slots(PLAN_PASS)
        put(value, PLAN_PASS, 0, pass_field(p, 0, "name"))
        put(value, PLAN_PASS, 1, i)
        put(value, PLAN_PASS, 2, 0)
        put(value, PLAN_PASS, 3, queue)
        put(value, PLAN_PASS, 4, pass_field(p, 2, "kind"))
        put(value, PLAN_PASS, 5, pass_field(p, 4, "impl"))
        put(value, PLAN_PASS, 6, frozen(params) if params else EMPTY)
        found = accesses[i]  # a tuple from the compiled trace (kept), a list from the Python one
        put(value, PLAN_PASS, 7, found if type(found) is tuple else tuple(found))
        put(value, PLAN_PASS, 8, barriers[i])
        put(value, PLAN_PASS, 9, releases[i])
        put(value, PLAN_PASS, 10, waits[i])
        if signals[i]:
            signal = new_slots(SIGNAL)
            put(signal, SIGNAL, 0, queue)
            put(signal, SIGNAL, 1, signal_values[i])
            put(signal, SIGNAL, 2, signal_stages)
            put(value, PLAN_PASS, 11, (signal,))
        else:
            put(value, PLAN_PASS, 11, ())
        out.append(value)
    return tuple(out)


def resources(resources, memory, set outputs, initial, final, offsets, frozen_json):
    """``_resources_python``'s tuple; ``frozen_json``: ``emit._frozen_json``."""
    cdef list out = []
    for name in sorted(memory):
        res, mem = resources[name], memory[name]
        heap, offset = offsets[name]
        lifetime = resource_field(res, 2)
        if lifetime == "transient" and name in outputs:
            lifetime = "output"
        fmt = resource_field(res, 3)
        accel = resource_field(res, 11)
        kind = resource_field(res, 1)
        value = new_slots(RESOURCE)
        put(value, RESOURCE, 0, name)
        put(value, RESOURCE, 1, kind)
        put(value, RESOURCE, 2, fmt.vk_name if fmt is not None else None)
        put(value, RESOURCE, 3, mem_field(mem, 0))
        put(value, RESOURCE, 5, mem_field(mem, 1))
        put(value, RESOURCE, 6, mem_field(mem, 2))
        put(value, RESOURCE, 7, mem_field(mem, 3))
        put(value, RESOURCE, 8, mem_field(mem, 4))
        put(value, RESOURCE, 9, lifetime)
        put(value, RESOURCE, 10, mem_field(mem, 5))
        put(value, RESOURCE, 11, mem_field(mem, 6))
        put(value, RESOURCE, 12, heap)
        put(value, RESOURCE, 13, offset)
        put(value, RESOURCE, 14, initial.get(name))
        put(value, RESOURCE, 15, final.get(name))
        if kind == "image":
            put(value, RESOURCE, 4, None)
            put(value, RESOURCE, 16, tuple(resource_field(res, 4)))
            put(value, RESOURCE, 17, resource_field(res, 6))
            put(value, RESOURCE, 18, resource_field(res, 5))
            put(value, RESOURCE, 19, resource_field(res, 7))
        else:
            put(value, RESOURCE, 4, resource_field(res, 8))
            put(value, RESOURCE, 16, None)
            put(value, RESOURCE, 17, None)
            put(value, RESOURCE, 18, None)
            put(value, RESOURCE, 19, None)
        put(value, RESOURCE, 20, frozen_json(accel.as_plan()) if accel is not None else None)
        put(value, RESOURCE, 21, resource_field(res, 12))
        out.append(value)
    return tuple(out)


def culled(culled, culled_only, culled_bytes):
    """``_culled_python``'s tuple."""
    cdef list out = []
    for x in culled:
        name = x.pass_name
        only = culled_only.get(name)
        value = new_slots(CULLED)
        put(value, CULLED, 0, name)
        put(value, CULLED, 1, x.reason)
        if only is None:
            put(value, CULLED, 2, ())
            put(value, CULLED, 3, 0)
        else:
            put(value, CULLED, 2, only)
            put(value, CULLED, 3, sum([culled_bytes.get(r, 0) for r in only]))
        out.append(value)
    return tuple(out)
