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
