# Included by the compiled compiler phases (``rgraph/compiler/_*.pyx``, ``rgraph/ir/_cull.pyx``):
# instances of the plan's frozen slots dataclasses built the way ``rgraph.plan.builders`` builds
# them, but from C: the object is allocated as its class's ``__new__`` would (``object.__new__``:
# ``PyType_GenericAlloc``) and each field is stored in its slot at the offset its member
# descriptor gives (what the descriptor's ``__set__`` does, without the frozen ``__setattr__``).
# Every slot must be stored before the object is used (an unset slot reads as AttributeError).

from cpython.ref cimport Py_INCREF, PyObject
from cpython.object cimport PyTypeObject

import dataclasses as _dataclasses
import types as _types


cdef extern from "Python.h":
    ctypedef struct PyMemberDef:
        int type
        Py_ssize_t offset
    ctypedef struct PyMemberDescrObject:
        PyMemberDef *d_member
    object _generic_alloc "PyType_GenericAlloc" (PyTypeObject *type, Py_ssize_t nitems)

cdef enum:
    _MAX_SLOTS = 40
cdef int _T_OBJECT_EX = 16


cdef class Slots:
    """Where each field of a slots dataclass lives in its instances. The caller stores the
    fields ``names`` (the class's first fields, in its order: checked); ``new_slots`` stores the
    defaults of the others."""

    cdef object cls
    cdef Py_ssize_t n, given
    cdef Py_ssize_t off[_MAX_SLOTS]
    cdef list defaults

    def __cinit__(self, cls, tuple names):
        cdef PyMemberDescrObject *d
        fields = _dataclasses.fields(cls)
        if len(fields) > _MAX_SLOTS or cls.__new__ is not object.__new__ or type(cls).__call__ is not type.__call__:
            raise TypeError(f"{cls.__name__}: not a plain slots dataclass")
        if tuple(f.name for f in fields[:len(names)]) != names:
            raise TypeError(f"{cls.__name__}: fields {[f.name for f in fields]}, expected {names} first")
        self.cls, self.n, self.given, self.defaults = cls, len(fields), len(names), []
        for k, f in enumerate(fields):
            descr = next((vars(base)[f.name] for base in cls.__mro__ if f.name in vars(base)), None)
            if type(descr) is not _types.MemberDescriptorType:
                raise TypeError(f"{cls.__name__}.{f.name}: not a slot")
            d = <PyMemberDescrObject *> descr
            if d.d_member.type != _T_OBJECT_EX:
                raise TypeError(f"{cls.__name__}.{f.name}: not an object slot")
            self.off[k] = d.d_member.offset
            if k >= len(names):
                if f.default is _dataclasses.MISSING:
                    raise TypeError(f"{cls.__name__}.{f.name}: no default")
                self.defaults.append(f.default)


cdef inline void put(object o, Slots layout, Py_ssize_t k, object value):
    """Store ``value`` in field ``k`` of a new (``new_slots``) object: each field once."""
    Py_INCREF(value)
    (<PyObject **> ((<char *> <PyObject *> o) + layout.off[k]))[0] = <PyObject *> value


cdef inline object new_slots(Slots layout):
    """An instance of ``layout.cls`` with the fields after ``names`` at their defaults and the
    others to store (``put``)."""
    o = _generic_alloc(<PyTypeObject *> layout.cls, 0)
    cdef Py_ssize_t k
    for k in range(layout.given, layout.n):
        put(o, layout, k, layout.defaults[k - layout.given])
    return o


cdef inline object get(object o, Slots layout, Py_ssize_t k):
    """Field ``k`` of ``o``, an instance of exactly ``layout.cls`` (the caller checks its type):
    read from its slot, as the member descriptor's ``__get__`` does."""
    cdef PyObject *v = (<PyObject **> ((<char *> <PyObject *> o) + layout.off[k]))[0]
    if v == NULL:
        raise AttributeError(f"{type(o).__name__}: field {k} is not set")
    return <object> v


cdef inline PyObject *borrowed_field(PyObject *o, Slots layout, Py_ssize_t k):
    """Field ``k`` of ``o`` (exactly ``layout``'s class), borrowed; NULL where unset (for
    walks that only follow or prefetch the pointer)."""
    return (<PyObject **> ((<char *> o) + layout.off[k]))[0]
