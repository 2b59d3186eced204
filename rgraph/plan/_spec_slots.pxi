# Included after ``_slots.pxi`` by the compiled walks over a spec (``_trace.pyx``, ``_cull.pyx``,
# ``_emit.pyx``, ``_sync_walk.pyx``): the fields of ``AccessSpec``, ``PassSpec`` and
# ``ResourceSpec`` read from their slots when an object is exactly of that class (``get``), else
# through its attributes, so any other object with those attributes still reads right.

from rgraph.spec.specialize import AccessSpec, PassSpec, ResourceSpec

cdef object ACCESS_SPEC = AccessSpec
cdef object PASS_SPEC = PassSpec
cdef object RESOURCE_SPEC = ResourceSpec
#: Field positions: resource 0, usage 1, write 2, mips 3, layers 4, stages 5, optional 6, loc 7, refit 8, cells 9.
cdef Slots SPEC = Slots(AccessSpec, ("resource", "usage", "write", "mips", "layers", "stages", "optional", "loc",
                                     "refit", "cells"))
#: Field positions: name 0, order 1, kind 2, queue 3, impl 4, requires 5, side_effects 6, accesses 7.
cdef Slots PASS = Slots(PassSpec, ("name", "order", "kind", "queue", "impl", "requires", "side_effects", "accesses",
                                   "params", "loc", "requires_any"))

#: Every field of ``ResourceSpec`` (only read, never built): name 0, kind 1, lifetime 2, format 3,
#: extent 4, layers 5, mips 6, samples 7, bytes 8, loc 9, geometry 10, accel 11, scratch_of 12.
cdef tuple RESOURCE_NAMES = ("name", "kind", "lifetime", "format", "extent", "layers", "mips", "samples", "bytes",
                             "loc", "geometry", "accel", "scratch_of")
cdef Slots RES = Slots(ResourceSpec, RESOURCE_NAMES)


cdef inline object access_field(object a, Py_ssize_t k, str name):
    """Field ``k`` (named ``name``) of access ``a``."""
    if type(a) is ACCESS_SPEC:
        return get(a, SPEC, k)
    return getattr(a, name)


cdef inline object pass_field(object p, Py_ssize_t k, str name):
    """Field ``k`` (named ``name``) of pass ``p``."""
    if type(p) is PASS_SPEC:
        return get(p, PASS, k)
    return getattr(p, name)


cdef inline object resource_field(object r, Py_ssize_t k):
    """Field ``k`` (``RESOURCE_NAMES[k]``) of resource ``r``."""
    if type(r) is RESOURCE_SPEC:
        return get(r, RES, k)
    return getattr(r, <str> RESOURCE_NAMES[k])
