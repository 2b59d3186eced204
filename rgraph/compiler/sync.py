"""Derive every barrier, layout transition, queue ownership transfer and semaphore.

State is tracked per subresource cell (resource, mip, layer; a buffer is one cell):
its layout, owning queue, last write and the reads since. For each pass, in executed
order, each cell it touches gets at most one barrier; cells with identical barriers are
merged into mip/layer rectangles, so a pass has one batch.

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
from dataclasses import dataclass

from rgraph.compiler.alias_starts import PREVIOUS_FRAME, AliasStarts, with_partial_handoffs
from rgraph.compiler.rectangles import barriers_of, mip_layer_rectangles, rectangles
from rgraph.compiler.sync_inputs import Use, access_syncs, sync_inputs
from rgraph.compiler.sync_types import EMPTY, Barrier, BarrierKey, PassSync, State, SyncResult, Wait
from rgraph.compiler.usages import Sync
from rgraph.ir.graph import Cell
from rgraph.spec.specialize import PassSpec, ResourceSpec

__all__ = ["EMPTY", "Barrier", "BarrierKey", "PassSync", "State", "SyncResult", "Wait", "access_syncs",
           "mip_layer_rectangles", "synchronize"]

PERSISTENT = ("persistent", "imported")


@dataclass(slots=True)
class _Cell:
    layout: str | None
    queue: str | None
    write: tuple[int, frozenset[str], frozenset[str]] | None  # (pass, stages, write access)
    reads: list[tuple[int, frozenset[str]]]  # (pass, stages) since the write
    image: bool
    uses: list[Use]  # the cell's timeline: every pass that touches it, in order
    covered_until: int = -1  # timeline index of the last read already covered by a barrier
    cursor: int = 0  # timeline index of the next access
    aliases: tuple[str, ...] = ()
    last_pass: int | None = None
    last_in_previous_frame: bool = False
    visible: tuple[frozenset[str], frozenset[str]] = (EMPTY, EMPTY)  # dst scope since the write
    alias_waits: tuple[tuple[str, int], ...] = ()  # (queue, last pass) of each previous occupant

    def state(self) -> State:
        if self.reads:
            return _new(State, (self.read_stages(), EMPTY, self.layout, self.queue))
        if self.write:
            return _new(State, (self.write[1], self.write[2], self.layout, self.queue))
        return _new(State, (EMPTY, EMPTY, self.layout, self.queue))

    def read_stages(self) -> frozenset[str]:
        reads = self.reads
        if len(reads) == 1:
            return reads[0][1]
        return EMPTY.union(*[s for _, s in reads])


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
    syncs, per_pass_cells, timeline = inputs.syncs, inputs.per_pass_cells, inputs.timeline
    alias_sources = with_partial_handoffs(alias_sources or {}, inputs.touched, resources, ranges)
    image = {name: res.is_image for name, res in resources.items()}
    persistent = {name for name, res in resources.items() if res.lifetime in PERSISTENT}

    def fresh(c: Cell, uses: list[Use]) -> _Cell:
        im = image[c[0]]
        return _Cell("UNDEFINED" if im else None, None, None, [], im, uses)

    # Frame 1 from scratch gives the end-of-frame state; frame 2 starts persistent cells there.
    first_cells: dict[Cell, _Cell] = {}
    if persistent:
        first = _Simulation(passes, per_pass_cells)
        first.run_states({c: fresh(c, uses) for c, uses in timeline.items() if c[0] in persistent})
        first_cells = first.cells
    start: dict[Cell, _Cell] = {}
    for c, uses in timeline.items():
        if c[0] in persistent:
            st = first_cells[c]
            write = (PREVIOUS_FRAME, st.write[1], st.write[2]) if st.write else None
            reads = [(PREVIOUS_FRAME, stages) for _, stages in st.reads]
            start[c] = _Cell(
                st.layout, st.queue, write, reads, st.image, uses, last_pass=st.last_pass,
                last_in_previous_frame=True, visible=st.visible,
            )
        else:
            start[c] = fresh(c, uses)
    sim = _Simulation(passes, per_pass_cells)
    initial = {c: st.state() for c, st in start.items()}
    sim.run(start, AliasStarts(alias_sources, start, inputs.first_pass, initial))
    return SyncResult(sim.out, syncs, _by_resource(sim.final_states()), _by_resource(initial))


def _by_resource(states: Mapping[Cell, State]) -> dict[str, dict[Cell, State]]:
    out: dict[str, dict[Cell, State]] = {}
    for c, st in states.items():
        name = c[0]
        if name in out:
            out[name][c] = st
        else:
            out[name] = {c: st}
    return out


_new = tuple.__new__  # a named tuple's own ``__new__`` is a Python function: twice the cost per value
_NOTHING: tuple = (None, None, ())  # what ``_step`` returns when a cell needs no barrier and no wait


class _Simulation:
    def __init__(self, passes: Sequence[PassSpec], per_pass_cells: list[list[tuple[Cell, Sync, bool]]]) -> None:
        self.passes = passes
        self.per_pass_cells = per_pass_cells
        self.out = [PassSync() for _ in passes]
        self.cells: dict[Cell, _Cell] = {}

    def run_states(self, start: dict[Cell, _Cell]) -> None:
        """``run`` for the end states of the cells in ``start`` only (others are skipped): the
        barriers it would derive are not kept."""
        self.cells = start
        get = start.get
        for i, p in enumerate(self.passes):
            queue = p.queue
            for c, s, w in self.per_pass_cells[i]:
                cell = get(c)
                if cell is not None:
                    _step(cell, i, queue, s, w)

    def run(self, start: dict[Cell, _Cell], alias_starts: AliasStarts) -> None:
        self.cells = cells_now = start
        out = self.out
        starting = alias_starts.at
        for i, p in enumerate(self.passes):
            if i in starting:
                alias_starts.apply(i)
            found: list[tuple[Cell, BarrierKey, int | None]] = []
            # acquires grouped by their release pass too, so that each acquire's rectangles equal
            # its release's (the layer pairs ownership transfers by exact subresource range)
            release_groups: dict[tuple[int, str, BarrierKey], list[Cell]] | None = None
            waits: dict[str, tuple[int, set[str]]] | None = None
            queue = p.queue
            for c, s, w in self.per_pass_cells[i]:
                key, release_at, wait_on = _step(cells_now[c], i, queue, s, w)
                if key is not None:
                    if wait_on:
                        wait_stages = set(s.stages)
                        if key.src.queue == queue:
                            # A semaphore wait orders only its own stages, and a barrier chains after it
                            # only through its source stages: they must meet (the swapchain-acquire pattern).
                            if not key.src.stages:
                                key = key._replace(src=key.src._replace(stages=frozenset(s.stages)))
                            wait_stages |= key.src.stages
                    found.append((c, key, release_at))
                    if release_at is not None:
                        if release_groups is None:
                            release_groups = {}
                        release_groups.setdefault((release_at, c[0], key), []).append(c)
                elif wait_on:
                    wait_stages = set(s.stages)
                if wait_on:
                    if waits is None:
                        waits = {}
                    for q, j in wait_on:
                        prev = waits.get(q)
                        waits[q] = (max(j, prev[0]) if prev else j, (prev[1] if prev else set()) | wait_stages)
            if found:
                out[i].barriers = barriers_of(found)
            if release_groups:
                for (j, res, key), cs in sorted(release_groups.items(), key=lambda kv: (kv[0][0], kv[0][1])):
                    out[j].releases.extend(rectangles(res, key, cs))
            if waits:
                for q, (j, stages) in sorted(waits.items()):
                    out[i].waits.append(Wait(q, j, frozenset(stages)))
                    out[j].signal = True

    def final_states(self) -> dict[Cell, State]:
        return {c: cell.state() for c, cell in self.cells.items()}


def _step(cell: _Cell, i: int, queue: str, s: Sync, write: bool):
    """Update one cell for pass ``i``; return (barrier key, release pass, [(queue, wait pass)])."""
    k = cell.cursor
    cell.cursor = k + 1
    cell_queue = cell.queue
    cross = cell_queue is not None and cell_queue != queue
    if cell.alias_waits:  # aliased memory used on another queue
        wait_on = [(q, j) for q, j in cell.alias_waits if q != queue]
    elif cross:
        wait_on = []
    else:
        wait_on = ()
    transfer = False
    release_at = None
    if cross:
        if cell.last_pass is not None and not cell.last_in_previous_frame:
            wait_on.append((cell_queue, cell.last_pass))  # earlier frames: the runtime's frame-boundary waits
        if cell.image:
            transfer = cell.layout not in (None, "UNDEFINED")
        else:
            transfer = not cell.aliases and (cell.write is not None or bool(cell.reads))
        if transfer:
            release_at = cell.last_pass
    src_queue = cell_queue if transfer else queue
    layout = s.layout
    cell_layout = cell.layout
    layout_change = layout != cell_layout
    key: BarrierKey | None = None
    if write or layout_change:
        reads = cell.reads
        if reads:
            src = _new(State, (reads[0][1] if len(reads) == 1 else cell.read_stages(), EMPTY, cell_layout, src_queue))
        elif cell.write:
            src = _new(State, (cell.write[1], cell.write[2], cell_layout, src_queue))
        else:
            src = _new(State, (EMPTY, EMPTY, cell_layout, src_queue))
        if src.stages or src.access or layout_change or transfer:
            if write:
                key = _new(BarrierKey, (src, _new(State, (s.stages, s.access, layout, queue)), cell.aliases))
            else:  # a transition for a read group: cover the whole group
                dst_stages, dst_access, cell.covered_until = _group(cell.uses, k, layout, queue)
                cell.visible = (dst_stages, dst_access)
                key = _new(BarrierKey, (src, _new(State, (dst_stages, dst_access, layout, queue)), cell.aliases))
        if write:
            cell.write = (i, s.stages, s.writes)
            cell.reads = []
            cell.covered_until = k
            cell.visible = (EMPTY, EMPTY)
        else:
            if layout_change:  # a transition is a write; from UNDEFINED it happens once, at creation
                cell.write = (i, s.stages, EMPTY) if cell_layout != "UNDEFINED" else None
                cell.reads = [(i, s.stages)]
            else:
                reads.append((i, s.stages))
    else:  # a read in the current layout
        visible = cell.visible
        if transfer or (cell.write and k > cell.covered_until
                        and not (s.stages <= visible[0] and s.access <= visible[1])):  # e.g. last frame's barrier
            reads = cell.reads
            if reads:  # the write is already available: chain through the reads
                src = _new(State, (reads[0][1] if len(reads) == 1 else cell.read_stages(), EMPTY, cell_layout, src_queue))
            elif cell.write:
                src = _new(State, (cell.write[1], cell.write[2], cell_layout, src_queue))
            else:
                src = _new(State, (EMPTY, EMPTY, cell_layout, src_queue))
            dst_stages, dst_access, cell.covered_until = _group(cell.uses, k, layout, queue)
            cell.visible = (dst_stages, dst_access)
            if transfer or src.stages or src.access:
                key = _new(BarrierKey, (src, _new(State, (dst_stages, dst_access, layout, queue)), cell.aliases))
        cell.reads.append((i, s.stages))
    cell.layout = layout
    cell.queue = queue
    if cell.aliases or cell.alias_waits:
        cell.aliases = ()
        cell.alias_waits = ()
    cell.last_pass = i
    cell.last_in_previous_frame = False
    if key is None:
        return _NOTHING if not wait_on else (None, None, wait_on)
    return key, release_at, wait_on


def _group(uses: list[Use], k: int, layout: str | None, queue: str) -> tuple[frozenset[str], frozenset[str], int]:
    """Stages and accesses of the read group starting at use ``k``, and its last use."""
    end = k
    last = len(uses) - 1
    while end < last:
        _, sync, write, q = uses[end + 1]
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
