"""The trace phase: one walk over the executed passes' accesses, for every later phase.

It gives each access its sync2 scope (``usages.sync_of``; read groups moved to GENERAL by
``read_layouts``) and its plan value (``rgraph.plan.model.Access``: emit does not walk the
accesses again), each resource its usages, its first and last pass and the timeline of
each of its cells (``Use``: the accesses of one pass to one cell merged into one), and each
pass the other queues it already waits for (a cell whose previous use was on another
queue). ``measure`` reads the usages and lifetimes, ``place`` the cross-queue waits
(``queue_order``), ``synchronize`` the scopes and timelines: each access is visited once.
"""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from operator import itemgetter

from rgraph.compiler.plan_values import get_subresource, names, subresource
from rgraph.compiler.read_layouts import to_general
from rgraph.compiler.usages import Sync, merge, sync_of
from rgraph.ir.graph import Cell
from rgraph.native import load
from rgraph.plan import model as pm
from rgraph.plan.builders import builder
from rgraph.spec.specialize import PassSpec, ResourceSpec

#: One pass's use of a cell: (executed pass index, merged sync, written, queue, position of the
#: cell in the pass's cell list); a plain tuple (one per cell per pass: a named tuple costs twice
#: as much to build).
Use = tuple[int, Sync, bool, str, int]

#: (sync_of, its stage names, its access names, its layout) by (usage, kind, stages, format code, refit)
_SCOPES: dict[tuple, tuple[Sync, tuple[str, ...], tuple[str, ...], str | None]] = {}


@dataclass(slots=True)
class ResourceTrace:
    """One used resource: its usages (raytrace indirect arguments also ``trace_indirect``), its
    first and last executed pass, and its cells with their uses, in first-touch order."""

    usages: set[str]
    first: int
    last: int
    cells: list[tuple[Cell, list[Use]]]
    code: int  # format part of the scope's key: image + 2 * depth + 4 * stencil
    group: list[tuple[int, int, bool, str, str | None]] | None  # read_layouts candidates: (pass, access, write,
    # usage, layout)
    single: bool = False  # one cell (buffers, accels, one-mip one-layer images): its uses are ``cells[0][1]``


_new_trace = builder(ResourceTrace)
_pass_of = itemgetter(0)  # a Use's pass
_new_access = builder(pm.Access)

#: The compiled mirror of :func:`walk_python` (``rgraph/compiler/_trace.pyx``), None where it
#: is not built or ``RGRAPH_NATIVE=0``.
NATIVE = load("rgraph.compiler._trace")


@dataclass
class Trace:
    accesses: list[Sequence[pm.Access]]  # per pass, per declared access: the plan's values (tuples from the
    # compiled walk: the plan keeps them; lists from the Python one)
    resources: dict[str, ResourceTrace]  # used resources, in the order of their first use
    #: per pass (only those that have one): queue -> the latest pass on that queue that a cell's
    #: previous use was, i.e. the semaphore waits the dedicated plan has there
    waits: dict[int, dict[str, int]]


def _start(res: ResourceSpec, i: int, usage: str) -> ResourceTrace:
    """A resource's trace at its first use (pass ``i``, ``usage``)."""
    fmt = res.format
    image = res.kind == "image"
    depth, stencil = bool(fmt and fmt.has_depth), bool(fmt and fmt.has_stencil)
    # read_layouts' candidates: transient colour images
    group = [] if image and res.lifetime == "transient" and fmt is not None and not depth and not stencil else None
    single = not image or res.mips * res.layers == 1
    return _new_trace({usage}, i, i, [], image + 2 * depth + 4 * stencil, group, single)


def _scope(key: tuple) -> tuple[Sync, tuple[str, ...], tuple[str, ...], str | None]:
    usage, kind, stages, code, refit = key
    if len(_SCOPES) > 4096:
        _SCOPES.clear()
    s = sync_of(usage, kind, explicit_stages=stages, is_image=bool(code & 1), depth_format=bool(code & 2),
                stencil_format=bool(code & 4), refit=refit)
    found = _SCOPES[key] = (s, names(s.stages), names(s.access), s.layout)
    return found


def trace(passes: Sequence[PassSpec], resources: Mapping[str, ResourceSpec]) -> Trace:
    """Scopes, usages, lifetimes, timelines and cross-queue waits in one walk (compiled where
    built: :data:`NATIVE`, else :func:`walk_python`); the reads ``read_layouts`` moves to
    GENERAL are patched in afterwards (a few per graph)."""
    if NATIVE is None:
        return _finish(passes, *walk_python(passes, resources))
    moved: list[tuple[int, int]] = []  # the compiled walk groups the reads for read_layouts itself
    return _finish(passes, *NATIVE.walk(passes, resources, _SCOPES, _scope, moved), moved=moved)


Walked = tuple[list[list[pm.Access]], dict[str, ResourceTrace], dict[Cell, list[Use]], dict[int, dict[str, int]]]


def walk_python(passes: Sequence[PassSpec], resources: Mapping[str, ResourceSpec]) -> Walked:
    """The walk: per pass its plan accesses; the resources' traces; the timelines of the cells
    of resources of several cells; the cross-queue waits. ``rgraph/compiler/_trace.pyx``
    mirrors it (same values)."""
    plan_accesses: list[list[pm.Access]] = []
    info: dict[str, ResourceTrace] = {}
    full: dict[str, tuple] = {}  # read-group candidates: (0, mips), (0, layers)
    timeline: dict[Cell, list[Use]] = {}
    waits: dict[int, dict[str, int]] = {}
    scopes = _SCOPES
    get_info, get_uses, get_scope, get_sub, new_access = info.get, timeline.get, scopes.get, get_subresource, _new_access
    for i, p in enumerate(passes):
        queue, kind = p.queue, p.kind
        raytrace = kind == "raytrace"
        values: list[pm.Access] = []
        pos = 0
        for j, a in enumerate(p.accesses):
            name, usage, w = a.resource, a.usage, a.write
            r = get_info(name)
            if r is None:
                res = resources[name]
                r = info[name] = _start(res, i, usage)
                if r.group is not None:
                    full[name] = ((0, res.mips), (0, res.layers))
            else:
                r.usages.add(usage)
                r.last = i
            if raytrace and usage == "indirect":  # vkCmdTraceRaysIndirectKHR: a device address
                r.usages.add("trace_indirect")
            key = (usage, kind, a.stages, r.code, a.refit)
            scope = get_scope(key)
            if scope is None:
                scope = _scope(key)
            s = scope[0]
            mips = a.mips
            if mips is None:  # buffers and accels
                sub = None
            else:
                sub = get_sub((mips, a.layers))
                if sub is None:
                    sub = subresource(mips, a.layers)
            values.append(new_access(name, sub, usage, scope[1], scope[2], scope[3], w))
            group = r.group
            if group is not None:
                whole = full[name]
                if a.mips != whole[0] or a.layers != whole[1]:  # not the whole image: never unified
                    r.group = None
                else:
                    group.append((i, j, w, usage, s.layout))
            if r.single:  # most resources: the one cell's uses without a lookup by cell
                cells = r.cells
                if not cells:
                    cells.append((a.cells[0], [(i, s, w, queue, pos)]))
                    pos += 1
                    continue
                uses = cells[0][1]
                prev = uses[-1]
                if prev[0] == i:  # a second access to the cell in this pass: one merged use
                    uses[-1] = (i, merge(prev[1], s), prev[2] or w, queue, prev[4])
                    continue
                q = prev[3]
                if q != queue:  # the dedicated plan waits for that use
                    found = waits.get(i)
                    if found is None:
                        waits[i] = {q: prev[0]}
                    elif found.get(q, -1) < prev[0]:
                        found[q] = prev[0]
                uses.append((i, s, w, queue, pos))
                pos += 1
                continue
            for c in a.cells:
                uses = get_uses(c)
                if uses is None:
                    timeline[c] = uses = [(i, s, w, queue, pos)]
                    r.cells.append((c, uses))
                    pos += 1
                    continue
                prev = uses[-1]
                if prev[0] == i:  # a second access to the cell in this pass: one merged use
                    uses[-1] = (i, merge(prev[1], s), prev[2] or w, queue, prev[4])
                    continue
                q = prev[3]
                if q != queue:  # the dedicated plan waits for that use
                    found = waits.get(i)
                    if found is None:
                        waits[i] = {q: prev[0]}
                    elif found.get(q, -1) < prev[0]:
                        found[q] = prev[0]
                uses.append((i, s, w, queue, pos))
                pos += 1
        plan_accesses.append(values)
    return plan_accesses, info, timeline, waits


def _finish(passes: Sequence[PassSpec], plan_accesses: list[list[pm.Access]], info: dict[str, ResourceTrace],
            timeline: dict[Cell, list[Use]], waits: dict[int, dict[str, int]],
            moved: list[tuple[int, int]] | None = None) -> Trace:
    """The walk's results with the reads ``read_layouts`` moves to GENERAL patched in (``moved``:
    those, where the walk found them; else ``to_general`` of its read groups)."""
    if moved is None:
        moved = to_general({name: r.group for name, r in info.items() if r.group is not None})
    elif NATIVE is not None:  # the compiled walk's: patched by the compiled mirror of what follows
        NATIVE.patch(passes, plan_accesses, info, timeline, moved, _SCOPES, _scope)
        return Trace(plan_accesses, info, waits)
    general: dict[int, tuple[Sync, Sync]] = {}  # id(scope): (scope, in GENERAL); few distinct scopes
    rows: dict[int, list[Sync]] = {}  # the passes with a moved read: the scope of each access
    for i, j in moved:
        row = rows.get(i)
        if row is None:
            row = rows[i] = _row(passes[i], info)
        scope = row[j]
        found = general.get(id(scope))
        if found is None:
            found = general[id(scope)] = (scope, replace(scope, layout="GENERAL"))
        row[j] = found[1]
        v = plan_accesses[i][j]
        plan_accesses[i][j] = _new_access(v.resource, v.subresource, v.usage, v.stages, v.access, "GENERAL", v.write)
    for i, j in moved:
        _repatch(passes[i], i, passes[i].accesses[j].cells, rows[i], timeline, info)
    return Trace(plan_accesses, info, waits)


def _row(p: PassSpec, info: Mapping[str, ResourceTrace]) -> list[Sync]:
    """The scope of each access of ``p`` as the walk found it (by the same keys)."""
    out = []
    for a in p.accesses:
        key = (a.usage, p.kind, a.stages, info[a.resource].code, a.refit)
        found = _SCOPES.get(key)
        out.append((found or _scope(key))[0])
    return out


def _repatch(p: PassSpec, i: int, cells: Sequence[Cell], row: Sequence[Sync], timeline: dict[Cell, list[Use]],
             info: Mapping[str, ResourceTrace]) -> None:
    """Pass ``i``'s use of ``cells`` with its accesses' (changed) syncs merged again
    (``timeline``: the uses of the cells of resources of several cells)."""
    for c in cells:
        merged = None
        for a, s in zip(p.accesses, row, strict=True):
            if c in a.cells:
                merged = s if merged is None else merge(merged, s)
        uses = timeline.get(c)
        if uses is None:  # a resource of one cell
            uses = info[c[0]].cells[0][1]
        k = bisect_left(uses, i, key=_pass_of)  # uses are in pass order, one per pass: the use of pass i
        _, _, w, queue, pos = uses[k]
        uses[k] = (i, merged, w, queue, pos)
