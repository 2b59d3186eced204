"""Derive every barrier, layout transition, queue ownership transfer and semaphore.

State is tracked per subresource cell (resource, mip, layer; a buffer is one cell):
its layout, owning queue, last write and the reads since. Each cell touched by a pass gets
at most one barrier there; cells with identical barriers are merged into mip/layer
rectangles, so a pass has one batch. Cells do not affect each other's barriers, so each
cell's timeline is walked in one go (``_walk``: its state in local variables), resources in
the order of their first pass, and the barriers and waits are then gathered per pass.

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

from collections.abc import Mapping, Sequence

from rgraph.compiler.alias_starts import PREVIOUS_FRAME, alias_state, with_partial_handoffs
from rgraph.compiler.rectangles import BARRIER_ORDER, barriers_of, rectangles
from rgraph.compiler.sync_inputs import Use, sync_inputs
from rgraph.compiler.sync_types import EMPTY, Barrier, BarrierKey, PassSync, State, SyncResult, Wait
from rgraph.ir.graph import Cell
from rgraph.spec.specialize import PassSpec, ResourceSpec

__all__ = ["EMPTY", "Barrier", "BarrierKey", "PassSync", "State", "SyncResult", "Wait", "synchronize"]

PERSISTENT = ("persistent", "imported")
_new = tuple.__new__  # a named tuple's own ``__new__`` is a Python function: twice the cost per value

#: A cell's state between walks: (layout, queue, write, reads, last pass, visible) where write
#: is (pass, stages, write access) or None, reads the (pass, stages) since it, visible the dst
#: scope (stages, access) of the barriers since it.
CellEnd = tuple
#: What a pass gets from one of its cells: (position in the pass's cells, cell, barrier key or
#: None, release pass or None, [(queue, pass)] to wait for, the wait's stages, and the barrier
#: itself when the cell is its resource's only one, else None).
Event = tuple


def synchronize(
    passes: Sequence[PassSpec],
    resources: Mapping[str, ResourceSpec],
    alias_sources: Mapping[str, Sequence[str]] | None = None,
    ranges: Mapping[str, tuple[int, int, int]] | None = None,
) -> SyncResult:
    """Barriers and semaphores for ``passes`` (executed order).

    ``alias_sources`` maps a transient resource to the resources whose memory it reuses
    (all of them ended before it starts); ``ranges`` gives (heap, first byte, end byte) of
    the placed resources, so that older occupants reached through a partial hand-off count
    only where their bytes overlap.
    """
    inputs = sync_inputs(passes, resources)
    first_pass = inputs.first_pass
    sources = with_partial_handoffs(alias_sources or {}, inputs.touched, resources, ranges)
    cells_of: dict[str, list[tuple[Cell, list[Use]]]] = {}
    for c, uses in inputs.timeline.items():
        if c[0] in cells_of:
            cells_of[c[0]].append((c, uses))
        else:
            cells_of[c[0]] = [(c, uses)]
    events: list[list[Event] | None] = [None] * len(passes)
    initial: dict[str, dict[Cell, State]] = {}
    final: dict[str, dict[Cell, State]] = {}
    ends: dict[str, list[tuple[State, int | None]]] = {}  # aliased-from resources: (end state, last pass) per cell
    wanted = {pred for preds in sources.values() for pred in preds}
    # every earlier occupant of a resource's memory ends before its first pass: walked before it
    for name in sorted(cells_of, key=first_pass.__getitem__):
        res = resources[name]
        image = res.is_image
        layout = "UNDEFINED" if image else None
        starts: dict[Cell, State] = {}
        finals: dict[Cell, State] = {}
        kept: list[tuple[State, int | None]] | None = None
        if name in wanted:
            kept = ends[name] = []
        preds = sources.get(name)
        single = len(cells_of[name]) == 1
        if res.lifetime in PERSISTENT:  # frame 1 from scratch gives the end state frame 2 starts in
            for c, uses in cells_of[name]:
                lay, queue, write, reads, last, visible = _walk(uses, image, (layout, None, None, [], None, EMPTY2),
                                                                 (), (), False, None, c)
                start = (lay, queue, (PREVIOUS_FRAME, write[1], write[2]) if write else None,
                         [(PREVIOUS_FRAME, stages) for _, stages in reads], last, visible)
                starts[c] = _state(start)
                end = _walk(uses, image, start, (), (), True, events, c, single)
                finals[c] = st = _state(end)
                if kept is not None:
                    kept.append((st, end[4]))
        else:
            aliases: tuple[str, ...] = ()
            waits: tuple[tuple[str, int], ...] = ()
            queue = write = last = None
            if preds:  # start from the earlier occupants' last accesses (UNDEFINED)
                stages, access, queue, last, aliases, waits = alias_state(
                    preds, [end for pred in preds for end in ends.get(pred, ())], first_pass[name])
                write = (PREVIOUS_FRAME, stages, access) if stages or access else None
            for c, uses in cells_of[name]:
                start = (layout, queue, write, [], last, EMPTY2)
                starts[c] = _state(start)
                end = _walk(uses, image, start, aliases, waits, False, events, c, single)
                finals[c] = st = _state(end)
                if kept is not None:
                    kept.append((st, end[4]))
        initial[name] = starts
        final[name] = finals
    return SyncResult(_gather(events), inputs.syncs, final, initial)


EMPTY2 = (EMPTY, EMPTY)


def _state(end: CellEnd) -> State:
    """What later accesses must wait for: the reads since the write, else the write."""
    layout, queue, write, reads, _, _ = end
    if reads:
        return _new(State, (reads[0][1] if len(reads) == 1 else EMPTY.union(*[s for _, s in reads]), EMPTY, layout,
                            queue))
    if write:
        return _new(State, (write[1], write[2], layout, queue))
    return _new(State, (EMPTY, EMPTY, layout, queue))


def _walk(uses: list[Use], image: bool, start: CellEnd, aliases: tuple[str, ...],
          alias_waits: tuple[tuple[str, int], ...], last_prev: bool, events: list | None, c: Cell,
          single: bool = False) -> CellEnd:
    """Walk one cell through its uses from ``start``; append each pass's ``Event`` to
    ``events[pass]`` (None: end state only). ``aliases``/``alias_waits``: the earlier occupants
    of its memory (and (queue, last pass) of each) that its first use hands over and waits for;
    ``last_prev``: the start state is the previous frame's; ``single``: the cell is its
    resource's only one (its barriers need no merging into rectangles)."""
    layout, cq, write, reads, last_pass, visible = start
    covered_until = -1  # index in ``uses`` of the last read already covered by a barrier
    for k, (i, s, w, queue, pos) in enumerate(uses):
        cross = cq is not None and cq != queue
        if alias_waits:  # aliased memory used on another queue
            wait_on = [(q, j) for q, j in alias_waits if q != queue]
        elif cross:
            wait_on = []
        else:
            wait_on = ()
        transfer = False
        release_at = None
        if cross:
            if last_pass is not None and not last_prev:
                wait_on.append((cq, last_pass))  # earlier frames: the runtime's frame-boundary waits
            if image:
                transfer = layout not in (None, "UNDEFINED")
            else:
                transfer = not aliases and (write is not None or bool(reads))
            if transfer:
                release_at = last_pass
        src_queue = cq if transfer else queue
        new_layout = s.layout
        layout_change = new_layout != layout
        key = None
        if w or layout_change:
            if reads:
                src = _new(State, (reads[0][1] if len(reads) == 1 else EMPTY.union(*[x for _, x in reads]), EMPTY,
                                   layout, src_queue))
            elif write:
                src = _new(State, (write[1], write[2], layout, src_queue))
            else:
                src = _new(State, (EMPTY, EMPTY, layout, src_queue))
            if src[0] or src[1] or layout_change or transfer:
                if w:
                    key = _new(BarrierKey, (src, _new(State, (s.stages, s.access, new_layout, queue)), aliases))
                else:  # a transition for a read group: cover the whole group
                    dst_stages, dst_access, covered_until = _group(uses, k, new_layout, queue)
                    visible = (dst_stages, dst_access)
                    key = _new(BarrierKey, (src, _new(State, (dst_stages, dst_access, new_layout, queue)), aliases))
            if w:
                write = (i, s.stages, s.writes)
                reads = []
                covered_until = k
                visible = EMPTY2
            elif layout_change:  # a transition is a write; from UNDEFINED it happens once, at creation
                write = (i, s.stages, EMPTY) if layout != "UNDEFINED" else None
                reads = [(i, s.stages)]
            else:
                reads.append((i, s.stages))
        else:  # a read in the current layout
            if transfer or (write and k > covered_until
                            and not (s.stages <= visible[0] and s.access <= visible[1])):  # e.g. last frame's barrier
                if reads:  # the write is already available: chain through the reads
                    src = _new(State, (reads[0][1] if len(reads) == 1 else EMPTY.union(*[x for _, x in reads]),
                                       EMPTY, layout, src_queue))
                elif write:
                    src = _new(State, (write[1], write[2], layout, src_queue))
                else:
                    src = _new(State, (EMPTY, EMPTY, layout, src_queue))
                dst_stages, dst_access, covered_until = _group(uses, k, new_layout, queue)
                visible = (dst_stages, dst_access)
                if transfer or src[0] or src[1]:
                    key = _new(BarrierKey, (src, _new(State, (dst_stages, dst_access, new_layout, queue)), aliases))
            reads.append((i, s.stages))
        layout = new_layout
        cq = queue
        last_pass = i
        if aliases or alias_waits or last_prev:
            aliases = ()
            alias_waits = ()
            last_prev = False
        if events is not None and (key is not None or wait_on):
            wait_stages = EMPTY
            if wait_on:
                wait_stages = s.stages
                if key is not None and src_queue == queue:
                    # A semaphore wait orders only its own stages, and a barrier chains after it
                    # only through its source stages: they must meet (the swapchain-acquire pattern).
                    if not key[0][0]:
                        key = key._replace(src=key[0]._replace(stages=s.stages))
                    wait_stages = wait_stages | key[0][0]
            if key is None:
                event = (pos, c, None, None, wait_on, wait_stages, None)
            else:
                event = (pos, c, key, release_at, wait_on, wait_stages,
                         _new(Barrier, (c[0], (c[1], c[1] + 1), (c[2], c[2] + 1), key)) if single else None)
            found = events[i]
            if found is None:
                events[i] = [event]
            else:
                found.append(event)
    return layout, cq, write, reads, last_pass, visible


def _gather(events: list[list[Event] | None]) -> list[PassSync]:
    """Each pass's barriers, the releases it owes later acquires, its waits and signal."""
    out = [PassSync() for _ in events]
    for i, found in enumerate(events):
        if found is None:
            continue
        ready: list[Barrier] = []  # one-cell resources' barriers
        merged: list[tuple[Cell, BarrierKey, int | None]] = []  # cells of resources with several
        # acquires grouped by their release pass too, so that each acquire's rectangles equal
        # its release's (the layer pairs ownership transfers by exact subresource range)
        release_groups: dict[tuple[int, str, BarrierKey], tuple[int, list[Cell]]] | None = None
        waits: dict[str, tuple[int, frozenset[str]]] | None = None
        for pos, c, key, release_at, wait_on, wait_stages, barrier in found:
            if key is not None:
                if barrier is not None:
                    ready.append(barrier)
                else:
                    merged.append((c, key, release_at))
                if release_at is not None:
                    if release_groups is None:
                        release_groups = {}
                    group = (release_at, c[0], key)
                    if group in release_groups:
                        first, cs = release_groups[group]
                        cs.append(c)
                        if pos < first:
                            release_groups[group] = (pos, cs)
                    else:
                        release_groups[group] = (pos, [c])
            if wait_on:
                if waits is None:
                    waits = {}
                for q, j in wait_on:
                    prev = waits.get(q)
                    waits[q] = (max(j, prev[0]), prev[1] | wait_stages) if prev else (j, wait_stages)
        if merged:
            ready += barriers_of(merged)
        if ready:
            if len(ready) > 1:
                ready.sort(key=BARRIER_ORDER)
            out[i].barriers = ready
        if release_groups:
            # by release pass and resource, then in the order the pass touches the cells
            for (j, res, key), (_, cs) in sorted(release_groups.items(), key=_release_order):
                out[j].releases.extend(rectangles(res, key, cs))
        if waits:
            for q, (j, stages) in sorted(waits.items()):
                out[i].waits.append(Wait(q, j, frozenset(stages)))
                out[j].signal = True
    return out


def _release_order(item: tuple) -> tuple[int, str, int]:
    (j, res, _), (first, _) = item
    return j, res, first


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
