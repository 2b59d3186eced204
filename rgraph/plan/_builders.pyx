# cython: language_level=3
"""Compiled ``rgraph.plan.builders.builder``: a callable that builds an instance of a slots
dataclass from C (``_slots.pxi``: allocated as ``object.__new__`` would, each field stored in
its slot), with the class's ``__init__`` signature (positional or keyword fields, defaults).
The Python builder (a twin class with a generated ``__init__``) stays the fallback; both give
equal objects of the same class (``tests/plan/test_builders.py``)."""

include "_slots.pxi"


cdef class FastBuilder:
    """``FastBuilder(cls)(*fields, **named)`` == ``cls(*fields, **named)`` for a plain slots
    dataclass without ``__post_init__``."""

    cdef Slots layout
    cdef tuple names
    cdef tuple defaults  # per field: its default, or _MISSING
    cdef Py_ssize_t n
    cdef readonly object cls

    def __cinit__(self, cls):
        fields = _dataclasses.fields(cls)
        if hasattr(cls, "__post_init__"):
            raise TypeError(f"{cls.__name__}: has __post_init__")
        for f in fields:
            if f.default_factory is not _dataclasses.MISSING:
                raise TypeError(f"{cls.__name__}.{f.name}: default_factory is not supported")
        self.cls = cls
        self.names = tuple([f.name for f in fields])
        self.defaults = tuple([f.default for f in fields])
        self.n = len(fields)
        self.layout = Slots(cls, self.names)  # every field stored by the call

    def __call__(self, *args, **named):
        cdef Py_ssize_t k, given = len(args)
        cdef Slots layout = self.layout
        if given == self.n and not named:  # the hot path: every field, in order
            o = new_slots(layout)
            for k in range(given):
                put(o, layout, k, args[k])
            return o
        if given > self.n:
            raise TypeError(f"{self.cls.__name__}() takes {self.n} fields, {given} given")
        values = list(args) + [_dataclasses.MISSING] * (self.n - given)
        for key, value in named.items():
            try:
                k = self.names.index(key)
            except ValueError:
                raise TypeError(f"{self.cls.__name__}() got an unexpected keyword argument '{key}'") from None
            if k < given:
                raise TypeError(f"{self.cls.__name__}() got multiple values for argument '{key}'")
            values[k] = value
        for k in range(self.n):
            if values[k] is _dataclasses.MISSING:
                if self.defaults[k] is _dataclasses.MISSING:
                    raise TypeError(f"{self.cls.__name__}() missing required argument '{self.names[k]}'")
                values[k] = self.defaults[k]
        o = new_slots(layout)
        for k in range(self.n):
            put(o, layout, k, values[k])
        return o
