"""Derive every barrier, layout transition, queue ownership transfer and semaphore.

State is tracked per subresource cell (resource, mip, layer; a buffer is one cell):
its layout, owning queue, last write and the reads since. Each cell touched by a pass gets
at most one barrier there; cells with identical barriers are merged into mip/layer
rectangles, so a pass has one batch. Cells do not affect each other's barriers, so each
cell's timeline (``rgraph.compiler.trace``) is walked in one go (``_walk``: its state in local
variables), resources in the order of their first pass. A resource with one touched cell
(every buffer) gets its plan barriers in the walk; the cells of the others are merged into
rectangles once the resource is walked. The barriers are the plan's values
(``rgraph.plan.model.Barrier``): emit does not rebuild them.

Rules (DESIGN.md invariants): srcAccess holds writes only; a layout transition is a write;
read-after-read in one layout needs nothing; the first read after a write gets one
barrier whose dst covers every later read of that cell in the same layout on the same
queue before the next write (all those reads share it). A cell moving between queues gets
a release/acquire pair and a timeline-semaphore wait. Persistent and imported resources
start the frame in the state the frame ends in (simulated twice to reach the fixed point);
transient cells whose memory was used by an earlier resource (aliasing) start from that
resource's last accesses and UNDEFINED.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence

from rgraph.compiler.alias_starts import alias_state, with_partial_handoffs
from rgraph.compiler.plan_values import get_state, get_subresource, make_barrier, plan_state, subresource
from rgraph.compiler.plan_values import names as sorted_names
from rgraph.compiler.rectangles import mip_layer_rectangles
from rgraph.compiler.sync_types import EMPTY, StateKey, SyncResult
from rgraph.compiler.trace import Trace, Use
from rgraph.ir.graph import Cell
from rgraph.native import load
from rgraph.plan import model as pm
from rgraph.plan.builders import builder
from rgraph.spec.specialize import PassSpec, ResourceSpec

__all__ = ["EMPTY", "StateKey", "SyncResult", "synchronize"]

PERSISTENT = ("persistent", "imported")
EMPTY2 = (EMPTY, EMPTY)
_new_wait = builder(pm.Wait)
#: This phase compiled as a whole (``rgraph/compiler/_sync_walk.pyx``: ``synchronize``; the cell's
#: state in a C struct), None where it is not built or ``RGRAPH_NATIVE=0``.
_WALK = load("rgraph.compiler._sync_walk")
#: A transient with nothing aliased before it starts in this layout and plan state (an image, a buffer).
_START_IMAGE = ("UNDEFINED", plan_state((EMPTY, EMPTY, "UNDEFINED", None)))
_START_BUFFER = (None, plan_state((EMPTY, EMPTY, None, None)))

#: A cell's state between walks: (layout, queue, write, reads, last pass, visible) where write
#: is (stages, write access) of the last write or None, reads the union of the stages of the
#: reads since it (None: no read since; kept as one running union, so that a resource read by
#: many passes costs no union over all of them at each barrier),
#: visible the dst scope (stages, access) of the barriers since it.
CellEnd = tuple
#: A barrier's key: (src state, dst state, aliases); in a group of several cells the plan's states
#: (interned). Cells of one resource and pass with equal
#: keys (and release pass) share one barrier rectangle.
Key = tuple
#: Where the walk puts what it finds, per executed pass: (barriers as (resource, [mips, layers,]
#: plan barrier) sort entries, releases as (acquiring pass, resource, cell position, barriers),
#: waits as queue -> (pass, stages), and for a resource of several cells its barrier groups
#: per pass (``_rectangles``), else None).
Sink = tuple


def synchronize(
    passes: Sequence[PassSpec],
    resources: Mapping[str, ResourceSpec],
    trace: Trace,
    alias_sources: Mapping[str, Sequence[str]] | None = None,
    ranges: Mapping[str, tuple[int, int, int]] | None = None,
    outputs: Collection[str] = (),
) -> SyncResult:
    """Barriers and semaphores for ``passes`` (executed order; ``trace``: theirs).

    ``alias_sources`` maps a transient resource to the resources whose memory it reuses
    (all of them ended before it starts); ``ranges`` gives (heap, first byte, end byte) of
    the placed resources, so that older occupants reached through a partial hand-off count
    only where their bytes overlap. ``outputs``: the graph's outputs (an output's cells may
    end in different states: the plan lists them, as for persistent resources).
    """
    count = len(passes)
    alias_sources = alias_sources or {}
    traced = trace.resources
    touched = {n: len(traced[n].cells) for preds in alias_sources.values() for n in preds if n in traced}  # earlier occupants
    sources = with_partial_handoffs(alias_sources, touched, resources, ranges)
    bars: list[list | None] = [None] * count
    rels: list[list | None] = [None] * count
    waits: list[dict | None] = [None] * count
    initial: dict[str, pm.EndState] = {}
    final: dict[str, pm.EndState] = {}
    ends: dict[str, list[tuple[StateKey, int | None]]] = {}  # aliased-from resources: (end state, last pass) per cell
    wanted = {pred for preds in sources.values() for pred in preds}
    one_sink = (bars, rels, waits, None)
    fresh = {True: _START_IMAGE, False: _START_BUFFER}  # (layout, plan state) of an unaliased start
    # resources in the order of their first pass: every earlier occupant of a resource's memory
    # ends before it starts, so it is walked before it
    for name, r in trace.resources.items():
        res = resources[name]
        image = res.kind == "image"
        cells = r.cells
        preds = sources.get(name)
        lifetime = res.lifetime
        if len(cells) == 1 and lifetime not in PERSISTENT:  # most resources: one cell (every buffer)
            c, uses = cells[0]
            if image:
                (_, mip, layer) = c
                sub = subresource((mip, mip + 1), (layer, layer + 1))
            else:
                sub = None
            if preds:  # start from the earlier occupants' last accesses (UNDEFINED)
                layout = "UNDEFINED" if image else None
                stages, access, queue, last, aliases, alias_waits = alias_state(
                    preds, [end for pred in preds for end in ends.get(pred, ())], r.first)
                write = (stages, access) if stages or access else None
                first = _state((layout, queue, write, None, last, EMPTY2))
                initial[name] = get_state(first) or plan_state(first)
                end = _walk(uses, image, (layout, queue, write, None, last, EMPTY2), aliases, alias_waits, False,
                                 one_sink, c, sub)
            else:
                layout, initial[name] = fresh[image]
                end = _walk(uses, image, (layout, None, None, None, None, EMPTY2), (), (), False, one_sink, c, sub)
            st = _state(end)
            final[name] = get_state(st) or plan_state(st)
            if name in wanted:
                ends[name] = [(st, end[4])]
            continue
        layout = "UNDEFINED" if image else None
        starts: dict[Cell, StateKey] = {}
        finals: dict[Cell, StateKey] = {}
        kept: list[tuple[StateKey, int | None]] | None = None
        if name in wanted:
            kept = ends[name] = []
        multi: dict[int, list[list]] | None = None
        sub = None  # the one cell's subresource
        if len(cells) > 1:
            multi = {}
        elif image:
            (_, mip, layer), _ = cells[0]
            sub = subresource((mip, mip + 1), (layer, layer + 1))
        sink = (bars, rels, waits, multi)
        if lifetime in PERSISTENT:  # frame 1 from scratch gives the end state frame 2 starts in
            for c, uses in cells:
                lay, queue, write, reads, last, visible = _walk(uses, image, (layout, None, None, None, None, EMPTY2),
                                                                     (), (), False, None, c, None)
                start = (lay, queue, write, reads, last, visible)
                starts[c] = _state(start)
                end = _walk(uses, image, start, (), (), True, sink, c, sub)
                finals[c] = st = _state(end)
                if kept is not None:
                    kept.append((st, end[4]))
        else:
            aliases: tuple[str, ...] = ()
            alias_waits: tuple[tuple[str, int], ...] = ()
            queue = write = last = None
            if preds:  # start from the earlier occupants' last accesses (UNDEFINED)
                stages, access, queue, last, aliases, alias_waits = alias_state(
                    preds, [end for pred in preds for end in ends.get(pred, ())], r.first)
                write = (stages, access) if stages or access else None
            first_state = _state((layout, queue, write, None, last, EMPTY2))  # every cell starts alike
            for c, uses in cells:
                start = (layout, queue, write, None, last, EMPTY2)
                starts[c] = first_state
                end = _walk(uses, image, start, aliases, alias_waits, False, sink, c, sub)
                finals[c] = st = _state(end)
                if kept is not None:
                    kept.append((st, end[4]))
        if multi:
            _rectangles(name, multi, bars, rels, (0, res.mips), (0, res.layers))
        per_cell = lifetime != "transient" or name in outputs
        initial[name] = _end_state(per_cell, starts)
        final[name] = _end_state(per_cell, finals)
    return _gather(bars, rels, waits, passes, final, initial)


def _end_state(per_cell: bool, states: Mapping[Cell, StateKey]) -> pm.EndState:
    """A resource's state at the frame's start or end, as the plan has it: one state when
    every cell agrees; otherwise a per-cell list if ``per_cell`` (it outlives the frame), else
    None (docs/plan.md)."""
    if not states:
        return None
    if len(states) == 1:
        for st in states.values():
            return get_state(st) or plan_state(st)
    distinct = set(states.values())
    if len(distinct) == 1:
        return plan_state(next(iter(distinct)))
    if not per_cell:
        return None
    return tuple(pm.CellState(pm.Subresource((mip, mip + 1), (layer, layer + 1)), plan_state(st))
                 for (_, mip, layer), st in sorted(states.items()))


def _state(end: CellEnd) -> StateKey:
    """What later accesses must wait for: the reads since the write, else the write."""
    layout, queue, write, reads, _, _ = end
    if reads is not None:
        return (reads, EMPTY, layout, queue)
    if write:
        return (write[0], write[1], layout, queue)
    return (EMPTY, EMPTY, layout, queue)


def _walk(uses: list[Use], image: bool, start: CellEnd, aliases: tuple[str, ...],
          alias_waits: tuple[tuple[str, int], ...], last_prev: bool, sink: Sink | None, c: Cell,
          sub: pm.Subresource | None) -> CellEnd:
    """Walk one cell through its uses from ``start``; put what each pass gets into ``sink``
    (None: end state only). ``aliases``/``alias_waits``: the earlier occupants of its memory
    (and (queue, last pass) of each) that its first use hands over and waits for;
    ``last_prev``: the start state is the previous frame's; ``sub``: the subresource of a
    resource's only cell (its barriers are built here)."""
    layout, cq, write, reads, last_pass, visible = start
    if sink is not None:
        bars, rels, waits, multi = sink
    covered_until = -1  # index in ``uses`` of the last read already covered by a barrier
    end = len(uses) - 1
    for k, (i, s, w, queue, pos) in enumerate(uses):
        if alias_waits or (cq != queue and cq is not None):
            if alias_waits:  # aliased memory used on another queue
                wait_on = [(q, j) for q, j in alias_waits if q != queue]
            else:
                wait_on = []
            transfer = False
            release_at = None
            if cq != queue and cq is not None:
                if last_pass is not None and not last_prev:
                    wait_on.append((cq, last_pass))  # earlier frames: the runtime's frame-boundary waits
                if image:
                    transfer = layout not in (None, "UNDEFINED")
                else:
                    transfer = not aliases and (write is not None or reads is not None)
                if transfer:
                    release_at = last_pass
            src_queue = cq if transfer else queue
        else:  # the same queue as the cell's last use (or its first use), nothing to wait for
            wait_on = ()
            transfer = False
            release_at = None
            src_queue = queue
        new_layout = s.layout
        key = None
        if w or new_layout != layout:
            if reads is not None:
                src = (reads, EMPTY, layout, src_queue)
            elif write:
                src = (write[0], write[1], layout, src_queue)
            else:
                src = (EMPTY, EMPTY, layout, src_queue)
            if src[0] or src[1] or new_layout != layout or transfer:
                if w:
                    key = (src, (s.stages, s.access, new_layout, queue), aliases)
                else:  # a transition for a read group: cover the whole group
                    if k == end or (u := uses[k + 1])[2] or u[1].layout != new_layout or u[3] != queue:
                        dst_stages, dst_access, covered_until = s.stages, s.access, k  # a group of one
                    else:
                        dst_stages, dst_access, covered_until = _group(uses, k, new_layout, queue)
                    visible = (dst_stages, dst_access)
                    key = (src, (dst_stages, dst_access, new_layout, queue), aliases)
            if w:
                write = s.write_scope
                reads = None
                covered_until = k
                visible = EMPTY2
            else:  # a layout change: a transition is a write; from UNDEFINED it happens once, at creation
                write = (s.stages, EMPTY) if layout != "UNDEFINED" else None
                reads = s.stages
        else:  # a read in the current layout
            if transfer or (write and k > covered_until
                            and not (s.stages <= visible[0] and s.access <= visible[1])):  # e.g. last frame's barrier
                if reads is not None:  # the write is already available: chain through the reads
                    src = (reads, EMPTY, layout, src_queue)
                elif write:
                    src = (write[0], write[1], layout, src_queue)
                else:
                    src = (EMPTY, EMPTY, layout, src_queue)
                if k == end or (u := uses[k + 1])[2] or u[1].layout != new_layout or u[3] != queue:
                    dst_stages, dst_access, covered_until = s.stages, s.access, k  # a group of one
                else:
                    dst_stages, dst_access, covered_until = _group(uses, k, new_layout, queue)
                visible = (dst_stages, dst_access)
                if transfer or src[0] or src[1]:
                    key = (src, (dst_stages, dst_access, new_layout, queue), aliases)
            if reads is None:
                reads = s.stages
            elif not s.stages <= reads:
                reads = reads | s.stages
        layout = new_layout
        cq = queue
        last_pass = i
        if aliases or alias_waits or last_prev:
            aliases = ()
            alias_waits = ()
            last_prev = False
        if sink is None or (key is None and not wait_on):
            continue
        if wait_on:
            wait_stages = s.stages
            if key is not None and src_queue == queue:
                # A semaphore wait orders only its own stages, and a barrier chains after it
                # only through its source stages: they must meet (the swapchain-acquire pattern).
                src = key[0]
                if not src[0]:
                    src = (s.stages, src[1], src[2], src[3])
                    key = (src, key[1], key[2])
                wait_stages = wait_stages | src[0]
            found = waits[i]
            if found is None:
                found = waits[i] = {}
            for q, j in wait_on:
                prev = found.get(q)
                found[q] = (max(j, prev[0]), prev[1] | wait_stages) if prev else (j, wait_stages)
        if key is None:
            continue
        src, dst, names = key
        ps = get_state(src)
        if ps is None:
            ps = plan_state(src)
        pd = get_state(dst)
        if pd is None:
            pd = plan_state(dst)
        if multi is not None:  # per pass: [(plan src, plan dst, aliases), release pass, first cell position, cells]
            key = (ps, pd, names)  # (few keys per pass; plan states are interned: compared by identity first)
            groups = multi.get(i)
            if groups is None:
                multi[i] = [[key, release_at, pos, [(c[1], c[2])]]]
                continue
            for group in groups:  # compared in a list: hashing a key (nested tuples) costs more
                if group[1] == release_at and group[0] == key:
                    group[3].append((c[1], c[2]))
                    if pos < group[2]:
                        group[2] = pos
                    break
            else:
                groups.append([key, release_at, pos, [(c[1], c[2])]])
            continue
        res = c[0]
        barrier = make_barrier(res, sub, ps, pd, names)
        found = bars[i]
        if found is None:
            bars[i] = [(res, barrier)]
        else:
            found.append((res, barrier))
        if release_at is not None:
            found = rels[release_at]
            if found is None:
                rels[release_at] = [(i, res, pos, (barrier,))]
            else:
                found.append((i, res, pos, (barrier,)))
    return layout, cq, write, reads, last_pass, visible


def _rectangles(res: str, by_pass: dict[int, list[list]], bars: list, rels: list,
                all_mips: tuple[int, int], all_layers: tuple[int, int]) -> None:
    """A resource of several cells (``all_mips`` x ``all_layers``): per pass, its cells with
    one key and release pass (grouped by the walks: [(plan src state, plan dst state, aliases),
    release pass, first cell position, (mip, layer) cells], each cell once) merged into mip x layer rectangles (an acquire's
    rectangles equal its release's: the layer pairs ownership transfers by exact subresource
    range). A group of every cell (most groups of several) is the one whole rectangle."""
    get_sub = get_subresource
    count = (all_mips[1] - all_mips[0]) * (all_layers[1] - all_layers[0])
    whole = None  # the whole resource's subresource, once needed
    for i, groups in by_pass.items():
        for (ps, pd, names), release_at, first, cells in groups:
            if len(cells) == 1:
                ((mip, layer),) = cells
                mips, layers = (mip, mip + 1), (layer, layer + 1)
                sub = get_sub((mips, layers)) or subresource(mips, layers)
                entries = [(res, mips, layers, make_barrier(res, sub, ps, pd, names))]
            elif len(cells) == count:
                if whole is None:
                    whole = subresource(all_mips, all_layers)
                entries = [(res, all_mips, all_layers, make_barrier(res, whole, ps, pd, names))]
            else:
                entries = [(res, mips, layers, make_barrier(res, subresource(mips, layers), ps, pd, names))
                           for mips, layers in mip_layer_rectangles(cells)]
            if bars[i] is None:
                bars[i] = entries
            else:
                bars[i] += entries
            if release_at is not None:
                made = tuple([e[3] for e in entries])
                if rels[release_at] is None:
                    rels[release_at] = [(i, res, first, made)]
                else:
                    rels[release_at].append((i, res, first, made))


def _gather(bars: list, rels: list, waits: list, passes: Sequence[PassSpec], final: dict, initial: dict) -> SyncResult:
    """Each pass's barriers in (resource, mips, layers) order, the releases it owes later
    acquires (by acquiring pass, resource, then the order that pass touches the cells), its
    waits by queue (the plan's values: a wait names the timeline value that its pass signals)
    and whether it signals."""
    count = len(bars)
    barriers: list[tuple[pm.Barrier, ...]] = [()] * count
    releases: list[tuple[pm.Barrier, ...]] = [()] * count
    pass_waits: list[tuple[pm.Wait, ...]] = [()] * count
    signals = [False] * count
    for i in range(count):
        found = bars[i]
        if found is not None:
            if len(found) == 1:
                barriers[i] = (found[0][-1],)
            else:
                found.sort()  # (resource, [mips, layers]) never tie within a pass: barriers not compared
                barriers[i] = tuple([e[-1] for e in found])  # compiled: no call per entry (``map(last, ...)``)
        found = rels[i]
        if found is not None:
            if len(found) == 1:
                releases[i] = found[0][3]
            else:
                found.sort()  # (acquiring pass, resource, cell position) never tie
                releases[i] = tuple([b for e in found for b in e[3]])
        found = waits[i]
        if found is not None:
            for j, _ in found.values():
                signals[j] = True
    values = [0] * count  # timeline values per queue, 1, 2, ... in plan order
    counters: dict[str, int] = {}
    for i in range(count):
        if signals[i]:
            queue = passes[i].queue
            values[i] = counters[queue] = counters.get(queue, 0) + 1
    new_wait = _new_wait
    for i in range(count):
        found = waits[i]
        if found is not None:
            if len(found) == 1:
                for q, (j, stages) in found.items():
                    pass_waits[i] = (new_wait(q, values[j], sorted_names(stages)),)
            else:
                pass_waits[i] = tuple([new_wait(q, values[j], sorted_names(stages)) for q, (j, stages) in sorted(found.items())])
    return SyncResult(barriers, releases, pass_waits, signals, values, final, initial)


def _group(uses: list[Use], k: int, layout: str | None, queue: str) -> tuple[frozenset[str], frozenset[str], int]:
    """Stages and accesses of the read group starting at use ``k``, and its last use."""
    end = k
    last = len(uses) - 1
    while end < last:
        _, sync, write, q, _ = uses[end + 1]
        if write or sync.layout != layout or q != queue:
            break
        end += 1
    if end == k:
        only = uses[k][1]
        return only.stages, only.access, end
    stages: set[str] = set()
    access: set[str] = set()
    for u in uses[k : end + 1]:
        stages |= u[1].stages
        access |= u[1].access
    return frozenset(stages), frozenset(access), end
