# Types for the compiled twin of rgraph/compiler/sync.py (setup.py: TWINS). Cython reads this
# file when it compiles sync.py as rgraph.compiler._sync: the helpers become C functions and the
# hot locals C integers and exact list/tuple/dict types. Only declarations: sync.py is the code.
cimport cython


@cython.locals(count=Py_ssize_t, image=bint, cells=list, bars=list, rels=list, waits=list, initial=dict,
               final=dict, ends=dict, starts=dict, finals=dict, kept=list, multi=dict, sources=dict)
cpdef synchronize(passes, resources, trace, alias_sources=*, ranges=*, outputs=*)

@cython.locals(distinct=set)
cdef _end_state(bint per_cell, dict states)

cdef tuple _state(tuple end)

@cython.locals(k=Py_ssize_t, end=Py_ssize_t, covered_until=Py_ssize_t, w=bint, transfer=bint,
               visible=tuple, u=tuple, src=tuple, key=tuple, write=tuple, bars=list, rels=list, waits=list,
               multi=dict, groups=list, group=list)
cdef tuple _walk(list uses, bint image, tuple start, tuple aliases, tuple alias_waits, bint last_prev, tuple sink,
                 tuple c, sub)

@cython.locals(count=Py_ssize_t, groups=list, cells=list, entries=list)
cdef _rectangles(str res, dict by_pass, list bars, list rels, tuple all_mips, tuple all_layers)

@cython.locals(i=Py_ssize_t, count=Py_ssize_t, barriers=list, releases=list, pass_waits=list, signals=list,
               values=list, counters=dict)
cdef _gather(list bars, list rels, list waits, passes, dict final, dict initial)

@cython.locals(end=Py_ssize_t, last=Py_ssize_t, stages=set, access=set)
cdef tuple _group(list uses, Py_ssize_t k, layout, queue)
