# Included after ``_slots.pxi`` by the compiled walks over a spec's passes (``_trace.pyx``,
# ``_cull.pyx``): the fields of ``AccessSpec`` and ``PassSpec`` read from their slots when an
# object is exactly of that class (``get``), else through its attributes, so any other object
# with those attributes still reads right.

from rgraph.spec.specialize import AccessSpec, PassSpec

cdef object ACCESS_SPEC = AccessSpec
cdef object PASS_SPEC = PassSpec
#: Field positions: resource 0, usage 1, write 2, mips 3, layers 4, stages 5, optional 6, loc 7, refit 8, cells 9.
cdef Slots SPEC = Slots(AccessSpec, ("resource", "usage", "write", "mips", "layers", "stages", "optional", "loc",
                                     "refit", "cells"))
#: Field positions: name 0, order 1, kind 2, queue 3, impl 4, requires 5, side_effects 6, accesses 7.
cdef Slots PASS = Slots(PassSpec, ("name", "order", "kind", "queue", "impl", "requires", "side_effects", "accesses",
                                   "params", "loc", "requires_any"))


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
