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

from collections import defaultdict
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import NamedTuple

from rgraph.compiler.read_layouts import unify_read_layouts
from rgraph.compiler.usages import Sync, merge, sync_of
from rgraph.ir.graph import Cell
from rgraph.spec.specialize import PassSpec, ResourceSpec

PERSISTENT = ("persistent", "imported")
PREVIOUS_FRAME = -1


class State(NamedTuple):
    """Where a cell stands: stages/access of the last accesses that later ones must wait for.
    (A named tuple: hashed and compared in C, as barrier group keys are many.)"""

    stages: frozenset[str]
    access: frozenset[str]  # writes only
    layout: str | None
    queue: str | None


class BarrierKey(NamedTuple):
    src: State
    dst: State
    aliases: tuple[str, ...] = ()


EMPTY: frozenset[str] = frozenset()


class Barrier(NamedTuple):
    resource: str
    mips: tuple[int, int] | None
    layers: tuple[int, int] | None
    key: BarrierKey


class Wait(NamedTuple):
    queue: str
    signal_pass: int  # executed index of the pass whose signal is waited for
    stages: frozenset[str]


@dataclass(slots=True)
class PassSync:
    barriers: list[Barrier] = field(default_factory=list)
    releases: list[Barrier] = field(default_factory=list)
    waits: list[Wait] = field(default_factory=list)
    signal: bool = False


@dataclass
class SyncResult:
    passes: list[PassSync]
    access_sync: list[list[Sync]]  # per pass, per declared access
    final: dict[str, dict[Cell, State]]  # per resource: end-of-frame state per cell
    initial: dict[str, dict[Cell, State]]


@dataclass(slots=True)
class _Cell:
    layout: str | None
    queue: str | None
    write: tuple[int, frozenset[str], frozenset[str]] | None  # (pass, stages, write access)
    reads: list[tuple[int, frozenset[str]]]  # (pass, stages) since the write
    covered_until: int = -1  # timeline index of the last read already covered by a barrier
    cursor: int = 0  # timeline index of the next access
    aliases: tuple[str, ...] = ()
    last_pass: int | None = None
    last_in_previous_frame: bool = False
    visible: tuple[frozenset[str], frozenset[str]] = (frozenset(), frozenset())  # dst scope since the write
    alias_waits: tuple[tuple[str, int], ...] = ()  # (queue, last pass) of each previous occupant

    def state(self) -> State:
        if self.reads:
            return State(self.read_stages(), EMPTY, self.layout, self.queue)
        if self.write:
            return State(self.write[1], self.write[2], self.layout, self.queue)
        return State(EMPTY, EMPTY, self.layout, self.queue)

    def read_stages(self) -> frozenset[str]:
        reads = self.reads
        if len(reads) == 1:
            return reads[0][1]
        return EMPTY.union(*[s for _, s in reads])


class _Use(NamedTuple):
    pass_pos: int
    sync: Sync
    write: bool
    queue: str


@lru_cache(maxsize=4096)
def _sync(usage: str, kind: str, stages: tuple[str, ...] | None, image: bool, depth: bool, stencil: bool,
          refit: bool) -> Sync:
    """``sync_of`` by position (a positional cache key is cheaper to build than keywords)."""
    return sync_of(usage, kind, explicit_stages=stages, is_image=image, depth_format=depth, stencil_format=stencil,
                   refit=refit)


def access_syncs(p: PassSpec, resources: Mapping[str, ResourceSpec]) -> list[Sync]:
    out = []
    kind = p.kind
    for a in p.accesses:
        res = resources[a.resource]
        fmt = res.format
        out.append(_sync(a.usage, kind, a.stages, res.kind == "image", bool(fmt and fmt.has_depth),
                         bool(fmt and fmt.has_stencil), a.refit))
    return out


def _pass_cells(p: PassSpec, syncs: list[Sync]) -> dict[Cell, tuple[Sync, bool]]:
    merged: dict[Cell, tuple[Sync, bool]] = {}
    for a, s in zip(p.accesses, syncs, strict=True):
        for c in a.cells:
            if c in merged:
                prev, w = merged[c]
                merged[c] = (merge(prev, s), w or a.write)
            else:
                merged[c] = (s, a.write)
    return merged


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
    alias_sources = alias_sources or {}
    syncs = unify_read_layouts(passes, resources, [access_syncs(p, resources) for p in passes])
    per_pass_cells = [_pass_cells(p, s) for p, s in zip(passes, syncs, strict=True)]
    timeline: dict[Cell, list[_Use]] = defaultdict(list)
    for i, (p, pc) in enumerate(zip(passes, per_pass_cells, strict=True)):
        for c, (s, w) in pc.items():
            timeline[c].append(_Use(i, s, w, p.queue))

    alias_sources = _with_partial_handoffs(alias_sources, timeline, resources, ranges)

    def fresh(c: Cell) -> _Cell:
        res = resources[c[0]]
        return _Cell("UNDEFINED" if res.is_image else None, None, None, [])

    # Frame 1 from scratch gives the end-of-frame state; frame 2 starts persistent cells there.
    needed = {r for r, res in resources.items() if res.lifetime in PERSISTENT}
    first_cells: dict[Cell, _Cell] = {}
    if needed:
        first = _Simulation(passes, per_pass_cells, timeline, resources)
        first.run_states({c: fresh(c) for c in timeline if c[0] in needed})  # the other cells are skipped
        first_cells = first.cells
    start: dict[Cell, _Cell] = {}
    for c in timeline:
        res = resources[c[0]]
        if res.lifetime in PERSISTENT:
            st = first_cells[c]
            write = (PREVIOUS_FRAME, st.write[1], st.write[2]) if st.write else None
            reads = [(PREVIOUS_FRAME, stages) for _, stages in st.reads]
            start[c] = _Cell(
                st.layout, st.queue, write, reads, last_pass=st.last_pass, last_in_previous_frame=True,
                visible=st.visible,
            )
        else:
            start[c] = fresh(c)
    sim = _Simulation(passes, per_pass_cells, timeline, resources)
    initial = {c: st.state() for c, st in start.items()}
    sim.run(start, _AliasStarts(alias_sources, start, timeline, initial))
    final = sim.final_states()
    return SyncResult(sim.out, syncs, _by_resource(final), _by_resource(initial))


class _AliasStarts:
    """Transient cells whose memory an earlier resource used start from that resource's last
    accesses (``_alias_state``). Every earlier occupant ends before the resource's first
    pass, so its cells already hold their end-of-frame state when that pass comes: the
    states are taken then, from the one simulation of the frame. (A transient's end state
    does not depend on where it started: its first access to each cell writes it or reads
    it, and either replaces what ``state()`` reports.)"""

    def __init__(self, alias_sources: Mapping[str, Sequence[str]], start: dict[Cell, _Cell],
                 timeline: Mapping[Cell, list], initial: dict[Cell, State]) -> None:
        self.cells_of: dict[str, list[tuple[Cell, _Cell]]] = defaultdict(list)
        for c, st in start.items():
            self.cells_of[c[0]].append((c, st))
        first_pass: dict[str, int] = {}
        for c, uses in timeline.items():
            i = uses[0].pass_pos
            if first_pass.get(c[0], i) >= i:
                first_pass[c[0]] = i
        self.at: dict[int, list[str]] = defaultdict(list)  # pass -> resources that start there
        for name, preds in alias_sources.items():
            if preds and name in first_pass:
                self.at[first_pass[name]].append(name)
        self.sources = alias_sources
        self.initial = initial

    def apply(self, i: int) -> None:
        """Start the aliased resources whose first pass is ``i``."""
        for name in self.at.get(i, ()):
            stages, access, queue, last, names, waits = _alias_state(
                self.sources[name], [st for pred in self.sources[name] for _, st in self.cells_of[pred]], i)
            for c, cell in self.cells_of[name]:
                cell.write = (PREVIOUS_FRAME, stages, access) if stages or access else None
                cell.queue = queue
                cell.last_pass = last
                cell.aliases = names
                cell.alias_waits = waits
                self.initial[c] = cell.state()


def _by_resource(states: Mapping[Cell, State]) -> dict[str, dict[Cell, State]]:
    out: dict[str, dict[Cell, State]] = defaultdict(dict)
    for c, st in states.items():
        out[c[0]][c] = st
    return dict(out)


def _with_partial_handoffs(
    alias_sources: Mapping[str, Sequence[str]], timeline: Mapping[Cell, list], resources: Mapping[str, ResourceSpec],
    ranges: Mapping[str, tuple[int, int, int]] | None = None,
) -> dict[str, list[str]]:
    """``alias_sources`` plus, through every predecessor that touches only some of its
    subresources, that predecessor's own predecessors (recursively).

    The memory planner leaves out an older occupant whose bytes a later one fully covers,
    counting on the later one's hand-off. But a resource hands over only the cells it
    touches: the bytes of its untouched subresources still hold the older occupant's last
    accesses, so the next resource must wait for those itself (random graph seed 32, 10
    passes, aliased: img2 used on one layer of two left img4's colour writes unordered
    before img3's first transition)."""
    touched: dict[str, int] = defaultdict(int)
    for c in timeline:
        touched[c[0]] += 1

    def partial(name: str) -> bool:
        res = resources[name]
        return res.is_image and touched[name] < res.mips * res.layers

    out: dict[str, list[str]] = {}
    for name, preds in alias_sources.items():
        found: list[str] = []
        stack = list(preds)
        while stack:
            pred = stack.pop(0)
            if pred in found:
                continue
            if ranges is not None and not _share_bytes(ranges, name, pred):
                continue
            found.append(pred)
            if partial(pred):
                stack.extend(alias_sources.get(pred, ()))
        out[name] = found
    return out


def _share_bytes(ranges: Mapping[str, tuple[int, int, int]], a: str, b: str) -> bool:
    (ha, lo_a, hi_a), (hb, lo_b, hi_b) = ranges[a], ranges[b]
    return ha == hb and lo_a < hi_b and lo_b < hi_a


def _alias_state(preds: Sequence[str], pred_cells: Sequence[_Cell], at: int):
    """Union of the last accesses of an aliased resource's predecessors (their cells, each
    last used before pass ``at``)."""
    stages: set[str] = set()
    access: set[str] = set()
    last: tuple[int, str | None] = (-1, None)
    waits: set[tuple[str, int]] = set()
    for st in pred_cells:
        assert st.last_pass is None or st.last_pass < at, "an earlier occupant outlives its successor's start"
        s = st.state()
        stages |= s.stages
        access |= s.access
        if st.last_pass is not None and st.last_pass > last[0]:
            last = (st.last_pass, st.queue)
        if st.last_pass is not None and st.queue is not None:
            waits.add((st.queue, st.last_pass))
    return (
        frozenset(stages), frozenset(access), last[1], last[0] if last[0] >= 0 else None, tuple(sorted(preds)),
        tuple(sorted(waits)),
    )


class _Simulation:
    def __init__(self, passes, per_pass_cells, timeline, resources) -> None:
        self.passes = passes
        self.per_pass_cells = per_pass_cells
        self.timeline = timeline
        self.resources = resources
        self.out = [PassSync() for _ in passes]
        self.cells: dict[Cell, _Cell] = {}
        self.image = {name: res.is_image for name, res in resources.items()}

    def run_states(self, start: dict[Cell, _Cell]) -> None:
        """``run`` for the end states of the cells in ``start`` only (others are skipped): the
        barriers it would derive are not kept."""
        self.cells = cells_now = start
        step, get = self._step, cells_now.get
        for i, p in enumerate(self.passes):
            queue = p.queue
            for c, (s, w) in self.per_pass_cells[i].items():
                cell = get(c)
                if cell is not None:
                    step(c, cell, i, queue, s, w)

    def run(self, start: dict[Cell, _Cell], alias_starts: _AliasStarts | None = None) -> None:
        self.cells = cells_now = start
        step, out = self._step, self.out
        starting = alias_starts.at if alias_starts is not None else {}
        for i, p in enumerate(self.passes):
            if i in starting:
                alias_starts.apply(i)
            # acquires grouped by their release pass too, so that each acquire's rectangles equal
            # its release's (the layer pairs ownership transfers by exact subresource range)
            groups: dict[tuple[str, BarrierKey, int | None], list[Cell]] = {}
            release_groups: dict[tuple[int, str, BarrierKey], list[Cell]] = {}
            waits: dict[str, tuple[int, set[str]]] = {}
            queue = p.queue
            for c, (s, w) in self.per_pass_cells[i].items():
                key, release_at, wait_on = step(c, cells_now[c], i, queue, s, w)
                if key is not None:
                    if wait_on:
                        wait_stages = set(s.stages)
                        if key.src.queue == queue:
                            # A semaphore wait orders only its own stages, and a barrier chains after it
                            # only through its source stages: they must meet (the swapchain-acquire pattern).
                            if not key.src.stages:
                                key = key._replace(src=key.src._replace(stages=frozenset(s.stages)))
                            wait_stages |= key.src.stages
                    group = (c[0], key, release_at)
                    if group in groups:
                        groups[group].append(c)
                    else:
                        groups[group] = [c]
                    if release_at is not None:
                        release_groups.setdefault((release_at, c[0], key), []).append(c)
                elif wait_on:
                    wait_stages = set(s.stages)
                for q, j in wait_on:
                    prev = waits.get(q)
                    waits[q] = (max(j, prev[0]) if prev else j, (prev[1] if prev else set()) | wait_stages)
            out[i].barriers = _rectangles(groups) if groups else []
            if release_groups:
                for (j, res, key), cs in sorted(release_groups.items(), key=lambda kv: (kv[0][0], kv[0][1])):
                    out[j].releases.extend(_rectangles({(res, key): cs}))
            if waits:
                for q, (j, stages) in sorted(waits.items()):
                    out[i].waits.append(Wait(q, j, frozenset(stages)))
                    out[j].signal = True

    def _step(self, c: Cell, cell: _Cell, i: int, queue: str, s: Sync, write: bool):
        """Update one cell for pass ``i``; return (barrier key, release pass, (queue, wait pass))."""
        k = cell.cursor
        cell.cursor += 1
        if self.image[c[0]]:
            has_content = cell.layout not in (None, "UNDEFINED")
        else:
            has_content = not cell.aliases and (cell.write is not None or bool(cell.reads))
        cross = cell.queue is not None and cell.queue != queue
        release_at = None
        # aliased memory used on another queue
        wait_on = [(q, j) for q, j in cell.alias_waits if q != queue] if cell.alias_waits else []
        if cross and cell.last_pass is not None and not cell.last_in_previous_frame:
            wait_on.append((cell.queue, cell.last_pass))  # earlier frames: the runtime's frame-boundary waits
        transfer = cross and has_content
        if transfer and cell.last_pass is not None:
            release_at = cell.last_pass
        src_queue = cell.queue if transfer else queue
        layout_change = s.layout != cell.layout
        key: BarrierKey | None = None
        if write or layout_change:
            if cell.reads:
                src = State(cell.read_stages(), EMPTY, cell.layout, src_queue)
            elif cell.write:
                src = State(cell.write[1], cell.write[2], cell.layout, src_queue)
            else:
                src = State(EMPTY, EMPTY, cell.layout, src_queue)
            if src.stages or src.access or layout_change or transfer:
                dst_stages, dst_access = s.stages, s.access
                if not write:  # a transition for a read group: cover the whole group
                    dst_stages, dst_access, cell.covered_until = self._group(self.timeline[c], k, s.layout, queue)
                    cell.visible = (dst_stages, dst_access)
                key = BarrierKey(src, State(dst_stages, dst_access, s.layout, queue), cell.aliases)
            if write:
                cell.write = (i, s.stages, s.writes)
                cell.reads = []
                cell.covered_until = k
                cell.visible = (EMPTY, EMPTY)
            else:
                if layout_change:  # a transition is a write; from UNDEFINED it happens once, at creation
                    cell.write = (i, s.stages, EMPTY) if cell.layout != "UNDEFINED" else None
                if layout_change:
                    cell.reads = []
                cell.reads.append((i, s.stages))
        else:  # a read in the current layout
            seen = s.stages <= cell.visible[0] and s.access <= cell.visible[1]  # e.g. last frame's barrier
            if transfer or (cell.write and k > cell.covered_until and not seen):
                if cell.reads:  # the write is already available: chain through the reads
                    src = State(cell.read_stages(), EMPTY, cell.layout, src_queue)
                else:
                    src = State(cell.write[1] if cell.write else EMPTY, cell.write[2] if cell.write else EMPTY, cell.layout, src_queue)
                dst_stages, dst_access, cell.covered_until = self._group(self.timeline[c], k, s.layout, queue)
                cell.visible = (dst_stages, dst_access)
                key = BarrierKey(src, State(dst_stages, dst_access, s.layout, queue), cell.aliases)
            cell.reads.append((i, s.stages))
        if key is not None and not (key.src.stages or key.src.access) and key.src.layout == key.dst.layout and not transfer:
            key = None
        if key is None:
            release_at = None
        cell.layout = s.layout
        cell.queue = queue
        cell.aliases = ()
        cell.alias_waits = ()
        cell.last_pass = i
        cell.last_in_previous_frame = False
        return key, release_at, wait_on

    @staticmethod
    def _group_end(uses: list[_Use], k: int, layout: str | None, queue: str) -> int:
        j = k
        while j + 1 < len(uses):
            u = uses[j + 1]
            if u.write or u.sync.layout != layout or u.queue != queue:
                break
            j += 1
        return j

    def _group(self, uses: list[_Use], k: int, layout: str | None, queue: str) -> tuple[frozenset[str], frozenset[str], int]:
        """Stages and accesses of the read group starting at use ``k``, and its last use."""
        end = self._group_end(uses, k, layout, queue)
        if end == k:
            only = uses[k].sync
            return only.stages, only.access, end
        stages: set[str] = set()
        access: set[str] = set()
        for u in uses[k : end + 1]:
            stages |= u.sync.stages
            access |= u.sync.access
        return frozenset(stages), frozenset(access), end

    def final_states(self) -> dict[Cell, State]:
        return {c: cell.state() for c, cell in self.cells.items()}


def _rectangles(groups: Mapping[tuple, list[Cell]]) -> list[Barrier]:
    """Merge cells with one barrier into mip x layer rectangles (deterministic order); a group
    key is (resource, BarrierKey, ...)."""
    out = []
    for (res, key, *_), cs in groups.items():
        if len(cs) == 1:  # one cell (every buffer): its own rectangle
            _, mip, layer = cs[0]
            out.append(Barrier(res, (mip, mip + 1), (layer, layer + 1), key))
        else:
            out += [Barrier(res, mips, layers, key)
                    for mips, layers in mip_layer_rectangles((mip, layer) for _, mip, layer in cs)]
    if len(out) > 1:
        out.sort(key=_barrier_sort_key)
    return out


def mip_layer_rectangles(cells: Iterable[tuple[int, int]]) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """(mip, layer) cells -> disjoint half-open (mips, layers) rectangles: runs of layers per
    mip, with consecutive mips of equal runs merged."""
    by_mip: dict[int, list[int]] = defaultdict(list)
    for mip, layer in cells:
        by_mip[mip].append(layer)
    runs_by_mip = {m: _runs(sorted(ls)) for m, ls in by_mip.items()}
    mips = sorted(runs_by_mip)
    out = []
    start = 0
    while start < len(mips):
        end = start
        while (
            end + 1 < len(mips)
            and mips[end + 1] == mips[end] + 1
            and runs_by_mip[mips[end + 1]] == runs_by_mip[mips[start]]
        ):
            end += 1
        out += [((mips[start], mips[end] + 1), run) for run in runs_by_mip[mips[start]]]
        start = end + 1
    return out


def _barrier_sort_key(b: Barrier):
    return (b.resource, b.mips or (0, 0), b.layers or (0, 0))


def _runs(values: list[int]) -> list[tuple[int, int]]:
    runs: list[tuple[int, int]] = []
    for v in values:
        if runs and runs[-1][1] == v:
            runs[-1] = (runs[-1][0], v + 1)
        else:
            runs.append((v, v + 1))
    return runs
