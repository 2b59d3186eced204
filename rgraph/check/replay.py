"""Replay a plan against a small happens-before model and collect hazards.

Same queue: execution dependency chains (chains.py) and per-cell memory dependencies
(availability chains and visibility rectangles on each write record).
Across queues: timeline semaphores as vector clocks. A signal after pass P on queue Q
makes everything submitted on Q up to P (with its releases) happen-before, and visible
to, the stages in the wait's stage mask of everything after a wait on Q >= value (the
wait's second synchronization scope is limited to those stages; later barriers on the
waiting queue extend it like any execution chain). ``vc[q][Q]`` is the last pass on Q
that is ordered before the current point of queue q in *some* stage, which is what a
signal on q passes on; ``arrivals[q]`` keeps, per chain class of wait stages, the clock
that reached q through waits in those stages (a round trip through another queue orders
a queue's own past too).
"""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Iterable
from dataclasses import replace

from rgraph.check import hazards as hz
from rgraph.check import vocab
from rgraph.check.aliasing import analyse
from rgraph.check.cells import CellMap, intersect, merge_rects
from rgraph.check.chains import BarrierStages, ChainRegistry, batch_add
from rgraph.check.plan import Access, Barrier, EndState, Pass, Plan, Rect, Resource
from rgraph.check.state import READ, TRANSITION, WRITE, CellState, Rec, Release

NOTHING = -2  # vector clock entry: no pass of that queue is known to be complete
PREVIOUS_FRAME = -1  # pass index of the previous frame's final accesses
PREVIOUS_ORIGIN = "the previous frame"
PREVIOUS_WRITE = "the previous frame's last write (visible to its final reads only)"

Finding = tuple[str, str]  # (kind, detail)


def _phrase(kind: str) -> str:
    return f"{kind} hazard" if kind in (hz.RAW, hz.WAR, hz.WAW) else kind


def _sub(res: Resource, rect: Rect | None) -> hz.Subresource | None:
    if not res.is_image:
        return None
    r = rect or res.whole
    return ((r[0], r[1]), (r[2], r[3]))


class Replay:
    def __init__(self, plan: Plan) -> None:
        self.plan = plan
        self.queues = plan.queues
        nq = max(len(plan.queues), 1)
        self.chains = [ChainRegistry() for _ in range(nq)]
        # Frame-boundary waits (docs/plan.md): the previous frame's accesses on *other*
        # queues are ordered before, and visible to, everything in this frame.
        self.vc = [[NOTHING if q == other else PREVIOUS_FRAME for other in range(nq)] for q in range(nq)]
        every = [chains.get(vocab.ALL_STAGES, vocab.ALL_STAGES) for chains in self.chains]
        self.arrivals: list[dict[int, list[int]]] = [{every[q]: list(self.vc[q])} for q in range(nq)]
        self.signals: list[list[tuple[int, int, list[int]]]] = [[] for _ in range(nq)]
        self.hazards: list[hz.Hazard] = []
        self.touched = [False] * len(plan.resources)
        self.alias = analyse(plan)
        self.wrap_acquires = self._wraparound_acquires()
        self.cells = [self._initial_cells(i, res) for i, res in enumerate(plan.resources)]

    # --- setup --------------------------------------------------------------------------

    def _wraparound_acquires(self) -> dict[int, list[Barrier]]:
        """Acquires in the first pass touching a persistent/imported resource: their release
        ran at the end of the previous frame (docs/plan.md, ownership across the boundary)."""
        out: dict[int, list[Barrier]] = {}
        for i, res in enumerate(self.plan.resources):
            span = self.alias.used[i]
            if res.lifetime not in ("persistent", "imported") or span is None:
                continue
            acquires = [b for b in self.plan.passes[span[0]].barriers if b.resource == i and b.is_transfer]
            if acquires:
                out[i] = acquires
        return out

    def _initial_cells(self, res_index: int, res: Resource) -> CellMap[CellState]:
        fresh = CellState(layout=vocab.UNDEFINED if res.is_image else None, owner=-1, defined=False, touched=False)
        cells: CellMap[CellState] = CellMap(res.whole, fresh)
        if res.lifetime in ("transient", "output") or not res.initial:
            return cells
        for entry in res.initial:
            state = self._carried_state(res, entry)
            cells.update(entry.rect, lambda _old, state=state: state)
        for b in self.wrap_acquires.get(res_index, []):
            cells.update(b.rect, lambda old, b=b: self._released_at_start(res, b, old))
        return cells

    def _carried_state(self, res: Resource, init: EndState) -> CellState:
        """A cell as the previous frame left it: its final accesses just happened on its queue."""
        queue = init.queue if init.queue is not None else 0
        origin = PREVIOUS_ORIGIN
        writes: list[Rec] = []
        reads: list[Rec] = []
        write_bits = init.access & vocab.WRITE_MASK
        for stage in vocab.bits(init.stages):
            if write_bits:
                writes.append(Rec(WRITE, queue, PREVIOUS_FRAME, stage, write_bits, -1, origin))
            else:
                cls = self.chains[queue].get(stage, 0)
                reads.append(Rec(READ, queue, PREVIOUS_FRAME, stage, init.access, cls, origin))
        if reads:
            # The write those reads saw is available, chained to their stages and visible to
            # them only (any read access when 'access' does not name them).
            seen = init.access & vocab.READ_MASK or vocab.READ_MASK
            writes.append(Rec(WRITE, queue, PREVIOUS_FRAME, 0, 0, self.chains[queue].get(init.stages, init.stages),
                              PREVIOUS_WRITE, ((init.stages, seen),)))
        return CellState(
            layout=init.layout if res.is_image else None, owner=queue, defined=True, touched=True,
            writes=tuple(writes), reads=tuple(reads),
        )

    def _released_at_start(self, res: Resource, b: Barrier, old: CellState) -> CellState:
        if old.owner != b.src.queue:
            return old  # the acquire will report the mismatch
        image = res.is_image
        rel = Release(b.src.queue, b.dst.queue, old.layout if image else None, b.dst.layout if image else None,
                      PREVIOUS_FRAME, "the previous frame's final release")
        if image and old.layout != b.dst.layout:
            trans = Rec(TRANSITION, b.src.queue, PREVIOUS_FRAME, 0, 0, -1,
                        f"layout transition {old.layout} -> {b.dst.layout} by the previous frame's final release")
            return replace(old, release=rel, layout=b.dst.layout, writes=(trans,), reads=())
        return replace(old, release=rel)

    # --- queries ------------------------------------------------------------------------

    def semaphore_reach(self, rec: Rec, q: int) -> int:
        """The stages of later commands on ``q`` that semaphores order after (and make see) ``rec``."""
        if rec.pass_index > self.vc[q][rec.queue]:
            return 0
        chains = self.chains[q]
        reach = 0
        for cls, clock in self.arrivals[q].items():
            if rec.pass_index <= clock[rec.queue]:
                reach |= chains.reach(cls)
        return reach

    def _cross_visible(self, rec: Rec, q: int) -> tuple[int, int]:
        """(stages, accesses) that barriers on ``q`` chained after semaphores made ``rec`` visible to."""
        stages = access = 0
        for xq, vis_stages, vis_access in rec.xvis:
            if xq == q:
                stages |= vis_stages
                access |= vis_access
        return stages, access

    def covered(self, rec: Rec, q: int) -> bool:
        """Ordered before (and visible to) every stage of everything now on ``q`` through semaphores."""
        return self.semaphore_reach(rec, q) == vocab.ALL_STAGES

    def exec_after(self, rec: Rec, stages: int, q: int) -> bool:
        """Is a command on ``q`` in all of ``stages`` ordered after ``rec``?"""
        through = self.semaphore_reach(rec, q) | self._cross_visible(rec, q)[0]
        if stages & ~through == 0:
            return True
        if rec.queue != q or rec.cls < 0:
            return False
        return stages & ~(self.chains[q].reach(rec.cls) | through) == 0

    def invisible_stages(self, rec: Rec, stages: int, access: int, q: int) -> int:
        """The stages of ``stages`` at which ``access`` does not see write ``rec``."""
        through = self.semaphore_reach(rec, q)
        stages &= ~through
        if not stages:
            return 0
        if rec.queue != q:
            missing = 0
            for stage in vocab.bits(stages):
                got = 0
                for xq, vis_stages, vis_access in rec.xvis:
                    if xq == q and vis_stages & stage:
                        got |= vis_access
                if access & ~got:
                    missing |= stage
            return missing
        missing = 0
        for stage in vocab.bits(stages):
            got = 0
            for vis_stages, vis_access in rec.vis:
                if vis_stages & stage:
                    got |= vis_access
            if access & ~got:
                missing |= stage
        return missing

    def in_first_access_scope(self, rec: Rec, b: Barrier) -> bool:
        return rec.kind == WRITE and bool(rec.stage & b.src.stages) and not rec.access & ~b.src.access

    def _through_semaphores(self, rec: Rec, b: Barrier, q: int) -> bool:
        """Does a semaphore chain order ``rec`` before barrier ``b`` on ``q``? The wait's stages must
        meet the barrier's source stages, except for an acquire, which its release orders."""
        if b.is_transfer and b.src.queue != q:
            return rec.pass_index <= self.vc[q][rec.queue]
        return bool(self.semaphore_reach(rec, q) & b.src.stages)

    def barrier_orders_read(self, rec: Rec, b: Barrier, q: int) -> bool:
        if self._through_semaphores(rec, b, q):
            return True
        if rec.queue != q:
            return False
        c, _ = self.chains[q].masks(rec.cls)
        return bool(c & b.src.stages)

    def barrier_takes_write(self, rec: Rec, b: Barrier, q: int) -> bool:
        """Is write ``rec`` ordered before ``b`` and made available by it (or earlier)?"""
        if self._through_semaphores(rec, b, q):
            return True  # a semaphore signal makes every write available
        if rec.queue != q:
            return False
        if self.in_first_access_scope(rec, b):
            return True
        return rec.cls >= 0 and bool(self.chains[q].reach(rec.cls) & b.src.stages)

    # --- messages -----------------------------------------------------------------------

    def _queue_name(self, q: int) -> str:
        return self.queues[q] if 0 <= q < len(self.queues) else str(q)

    def _describe(self, recs: Iterable[Rec], q: int, missing: dict[int, int] | None = None) -> list[str]:
        """'write by pass 3 'x' (STAGES/ACCESS)' for each origin among ``recs``."""
        groups: dict[tuple[int, str, int], list[int]] = {}
        for rec in recs:
            key = (rec.kind, rec.origin, rec.queue)
            entry = groups.setdefault(key, [0, 0, 0])
            entry[0] |= rec.stage
            entry[1] |= rec.access
            if missing is not None:
                entry[2] |= missing.get(id(rec), 0)
        out = []
        for (kind, origin, queue), (stages, access, miss) in groups.items():
            if kind == TRANSITION or origin == PREVIOUS_WRITE:
                text = origin
            else:
                verb = "write" if kind == WRITE else "read"
                if origin == PREVIOUS_ORIGIN:
                    text = f"{verb} by the previous frame ({vocab.stage_names(stages)}/{vocab.access_names(access)})"
                else:
                    text = f"{verb} by {origin} ({vocab.stage_names(stages)}/{vocab.access_names(access)})"
            if queue != q:
                text += f" on queue '{self._queue_name(queue)}', with no semaphore ordering it"
            elif miss:
                text += f" [missing for {vocab.stage_names(miss)}]"
            out.append(text)
        return out

    def _emit(self, kind: str, p: Pass | None, res: Resource | None, rects: list[Rect | None],
              head: str, detail: str) -> None:
        """One hazard per merged rectangle; ``head`` is formatted with ``{sub}``."""
        real = [r for r in rects if r is not None]
        parts: list[Rect | None] = merge_rects(real) if real else [None]
        for rect in parts:
            sub = _sub(res, rect) if res is not None else None
            line = f"{head.format(sub=hz.format_subresource(sub))}: {_phrase(kind)}: {detail}"
            self.hazards.append(hz.Hazard(
                kind=kind, pass_index=None if p is None else p.index, pass_name=None if p is None else p.name,
                resource=None if res is None else res.name, subresource=sub, message=line,
            ))

    def _emit_findings(self, found: dict[Finding, list[Rect]], p: Pass | None, res: Resource, head: str) -> None:
        for (kind, detail), rects in found.items():
            self._emit(kind, p, res, list(rects), head, detail)

    # --- the replay ---------------------------------------------------------------------

    def run(self) -> list[hz.Hazard]:
        for res_index, span in self.alias.lifetime_errors:
            res = self.plan.resources[res_index]
            self._emit(hz.LIFETIME, None, res, [None], f"resource '{res.name}'",
                       f"declared lifetime [{res.first}, {res.last}] does not cover the passes that use it "
                       f"[{span[0]}, {span[1]}]")
        for a, b, (lo, hi) in self.alias.overlaps:
            ra, rb = self.plan.resources[a], self.plan.resources[b]
            ua, ub = self.alias.used[a], self.alias.used[b]
            self._emit(hz.ALIASING_OVERLAP, None, rb, [None], f"resources '{ra.name}' and '{rb.name}'",
                       f"both occupy heap {rb.heap} bytes [{lo}, {hi}) while both are alive "
                       f"('{ra.name}' {ra.lifetime} passes {ua}, '{rb.name}' {rb.lifetime} passes {ub})")
        for p in self._schedule():
            self._run_pass(p)
        self._check_final_states()
        return self.hazards

    def _schedule(self) -> Iterable[Pass]:
        """Passes in plan order, except that a pass waiting on a signal not yet recorded
        lets other queues go first (queues stay in order). Unsatisfiable waits are
        reported and then ignored."""
        pending: dict[int, list[Pass]] = {}
        for p in self.plan.passes:
            pending.setdefault(p.queue, []).append(p)
        heads = {q: 0 for q in pending}
        while True:
            candidates = sorted((ps[heads[q]].index, q) for q, ps in pending.items() if heads[q] < len(ps))
            if not candidates:
                return
            chosen = None
            for _, q in candidates:
                p = pending[q][heads[q]]
                if all(self._signal_for(w.queue, w.value) is not None for w in p.waits):
                    chosen = p
                    break
            if chosen is None:
                chosen = pending[candidates[0][1]][heads[candidates[0][1]]]
                for w in chosen.waits:
                    if self._signal_for(w.queue, w.value) is None:
                        self._emit(hz.SEMAPHORE, chosen, None, [None], chosen.label,
                                   f"waits for queue '{self._queue_name(w.queue)}' >= {w.value}, which is never "
                                   f"signalled before it (deadlock)")
            heads[chosen.queue] += 1
            yield chosen

    def _arrive(self, q: int, clock: list[int], stages: int) -> None:
        """A wait in ``stages`` on ``q`` for a signal that carried ``clock``."""
        chains = self.chains[q]
        arrivals: dict[int, list[int]] = {}
        for cls, old in self.arrivals[q].items():  # classes merge as barriers extend them
            root = chains.find(cls)
            merged = arrivals.get(root)
            arrivals[root] = old if merged is None else [max(a, b) for a, b in zip(merged, old, strict=True)]
        root = chains.find(chains.get(stages, stages))
        merged = arrivals.get(root)
        arrivals[root] = list(clock) if merged is None else [max(a, b) for a, b in zip(merged, clock, strict=True)]
        self.arrivals[q] = arrivals

    def _signal_for(self, queue: int, value: int) -> tuple[int, int, list[int]] | None:
        """The first recorded signal of ``queue`` that reaches ``value`` (values increase)."""
        signals = self.signals[queue]
        i = bisect_left(signals, value, key=lambda sig: sig[0])
        return signals[i] if i < len(signals) else None

    def _run_pass(self, p: Pass) -> None:
        q = p.queue
        for w in p.waits:
            sig = self._signal_for(w.queue, w.value)
            if sig is not None:
                row = self.vc[q]
                for i, v in enumerate(sig[2]):
                    if v > row[i]:
                        row[i] = v
                self._arrive(q, sig[2], w.stages)
        if p.barriers:
            self._barrier_batch(p, p.barriers, before=True)
        self._accesses(p)
        if p.releases:
            self._barrier_batch(p, p.releases, before=False)
        for s in p.signals:
            if s.queue != q:
                self._emit(hz.SEMAPHORE, p, None, [None], p.label,
                           f"signals the timeline of queue '{self._queue_name(s.queue)}' but runs on "
                           f"'{self._queue_name(q)}'")
                continue
            previous = self.signals[q][-1][0] if self.signals[q] else 0
            if s.value <= previous:
                self._emit(hz.SEMAPHORE, p, None, [None], p.label,
                           f"signals queue '{self._queue_name(q)}' to {s.value}, not above its previous "
                           f"value {previous}")
                continue
            snapshot = list(self.vc[q])
            snapshot[q] = p.index
            self.signals[q].append((s.value, p.index, snapshot))

    # --- barriers -----------------------------------------------------------------------

    def _barrier_head(self, p: Pass, b: Barrier, before: bool, res: Resource) -> str:
        which = "barrier" if before else "release"
        if b.is_transfer:
            which = "acquire" if before else "release"
        layouts = f"{b.src.layout} -> {b.dst.layout}, " if res.is_image else ""
        return (f"{p.label} {which} {b.position} on '{res.name}'{{sub}} ({layouts}"
                f"{vocab.stage_names(b.src.stages)}/{vocab.access_names(b.src.access)} -> "
                f"{vocab.stage_names(b.dst.stages)}/{vocab.access_names(b.dst.access)})")

    def _barrier_batch(self, p: Pass, blist: list[Barrier], before: bool) -> None:
        q = p.queue
        chains = self.chains[q]
        pairs: BarrierStages = [(b.src.stages, b.dst.stages) for b in blist if before or not b.is_transfer]
        first_touch: dict[int, list[Barrier]] = {}
        for b in blist:
            if b.resource >= 0 and not self.touched[b.resource]:
                first_touch.setdefault(b.resource, []).append(b)
        for res_index, bl in first_touch.items():
            self._handoff(p, res_index, bl, None)
            self.touched[res_index] = True
        for b in blist:
            targets = range(len(self.plan.resources)) if b.resource < 0 else (b.resource,)
            for res_index in targets:
                res = self.plan.resources[res_index]
                cells = self.cells[res_index]
                memo: dict[int, tuple[CellState, list[Finding]]] = {}
                found: dict[Finding, list[Rect]] = {}
                for rect, st in cells.query(b.rect):
                    key = id(st)
                    if key not in memo:
                        memo[key] = self._barrier_cell(p, b, before, res, st, pairs)
                    for finding in memo[key][1]:
                        found.setdefault(finding, []).append(rect)
                if found:
                    self._emit_findings(found, p, res, self._barrier_head(p, b, before, res))
                cells.update(b.rect, lambda st, memo=memo: memo[id(st)][0])
        chains.apply_batch(pairs)

    def _barrier_cell(self, p: Pass, b: Barrier, before: bool, res: Resource, st: CellState,
                      pairs: BarrierStages) -> tuple[CellState, list[Finding]]:
        q = p.queue
        out: list[Finding] = []
        image = res.is_image
        is_acquire = before and b.is_transfer
        is_release = not before and b.is_transfer
        matched: Release | None = None

        if is_acquire:
            if b.dst.queue != q:
                out.append((hz.QUEUE_OWNERSHIP, f"acquires for queue '{self._queue_name(b.dst.queue)}' "
                                                f"but runs on '{self._queue_name(q)}'"))
            rel = st.release
            if rel is None:
                owner = f"owned by '{self._queue_name(st.owner)}'" if st.owner >= 0 else "never used"
                out.append((hz.QUEUE_OWNERSHIP, f"no matching release on queue '{self._queue_name(b.src.queue)}' "
                                                 f"precedes this acquire (the cells are {owner})"))
            elif (rel.src_queue, rel.dst_queue, rel.src_layout, rel.dst_layout) != (
                    b.src.queue, b.dst.queue, b.src.layout if image else None, b.dst.layout if image else None):
                out.append((hz.QUEUE_OWNERSHIP, f"does not match the release by {rel.origin}"))
            else:
                if rel.pass_index > self.vc[q][rel.src_queue]:
                    out.append((hz.QUEUE_OWNERSHIP, f"the release by {rel.origin} on queue "
                                                     f"'{self._queue_name(rel.src_queue)}' is not ordered before "
                                                     f"this acquire by a semaphore"))
                matched = rel
        else:
            if is_release and b.src.queue != q:
                out.append((hz.QUEUE_OWNERSHIP, f"releases from queue '{self._queue_name(b.src.queue)}' "
                                                 f"but runs on '{self._queue_name(q)}'"))
            elif not b.is_transfer and b.src.queue != q:
                out.append((hz.QUEUE_OWNERSHIP, f"names queue '{self._queue_name(b.src.queue)}' but runs on "
                                                 f"'{self._queue_name(q)}'"))
            if st.release is not None:
                out.append((hz.QUEUE_OWNERSHIP, f"the cells were released by {st.release.origin} to queue "
                                                 f"'{self._queue_name(st.release.dst_queue)}' and not acquired"))
            elif st.owner >= 0 and st.owner != q:
                discards = image and b.src.layout == vocab.UNDEFINED
                if not discards and (image or st.defined):
                    out.append((hz.QUEUE_OWNERSHIP, f"the cells are owned by queue '{self._queue_name(st.owner)}' "
                                                     f"(no ownership transfer to '{self._queue_name(q)}')"))

        if matched is not None:
            # A matched acquire: the transition (if any) ran at the release; the semaphore
            # made everything before the release visible. Restart the write at the acquire.
            if image and b.is_transition:
                cls = self.chains[q].born(b.dst.stages, b.dst.stages)
                trans = Rec(TRANSITION, q, p.index, 0, 0, cls,
                            f"layout transition {b.src.layout} -> {b.dst.layout} by acquire {b.position} "
                            f"of {p.label}", ((b.dst.stages, b.dst.access),))
                return replace(st, owner=q, release=None, layout=b.dst.layout, writes=(trans,), reads=(),
                               touched=True), out
            return replace(st, owner=q, release=None, touched=True,
                           writes=self._make_available(b, st.writes, q, pairs)), out

        if image and b.src.layout != vocab.UNDEFINED and b.src.layout != st.layout:
            out.append((hz.LAYOUT_MISMATCH, f"the barrier expects {b.src.layout} but the cells are in {st.layout}"))

        if image and b.is_transition:
            out += self._transition_checks(b, st, q)
            discards = b.src.layout == vocab.UNDEFINED
            label = "release" if is_release else ("acquire" if is_acquire else "barrier")
            origin = f"layout transition {b.src.layout} -> {b.dst.layout} by {label} {b.position} of {p.label}"
            if is_release:
                trans = Rec(TRANSITION, q, p.index, 0, 0, -1, origin)
            else:
                cls = self.chains[q].born(b.dst.stages, b.dst.stages)
                trans = Rec(TRANSITION, q, p.index, 0, 0, cls, origin, ((b.dst.stages, b.dst.access),))
            new = CellState(
                layout=b.dst.layout, owner=q, defined=st.defined and not discards, touched=True,
                writes=(trans,), reads=(),
                discarded_by=origin if discards and st.defined else (None if discards else st.discarded_by),
            )
        else:
            new = replace(st, owner=q, touched=True, writes=self._make_available(b, st.writes, q, pairs))
        if is_release:
            new = replace(new, release=Release(b.src.queue, b.dst.queue, b.src.layout if image else None,
                                               b.dst.layout if image else None, p.index,
                                               f"release {b.position} of {p.label}"))
        elif is_acquire:
            new = replace(new, owner=q, release=None)
        return new, out

    def _transition_checks(self, b: Barrier, st: CellState, q: int) -> list[Finding]:
        out: list[Finding] = []
        late_reads = [r for r in st.reads if not self.barrier_orders_read(r, b, q)]
        for text in self._describe(late_reads, q):
            out.append((hz.WAR, f"layout transition not ordered after {text}"))
        late_writes = [w for w in st.writes if not self.barrier_takes_write(w, b, q)]
        for text in self._describe(late_writes, q):
            out.append((hz.WAW, f"layout transition not ordered after {text}, or that write is not "
                                f"in the source access scope"))
        return out

    def _make_available(self, b: Barrier, writes: tuple[Rec, ...], q: int,
                        pairs: BarrierStages) -> tuple[Rec, ...]:
        """Apply the memory dependency of a non-transition barrier to the cell's last write.

        A write from another queue that semaphores order before the barrier (an acquire, or a
        barrier whose source stages meet the waits' stages) becomes visible on this queue in the
        barrier's destination scope too (``Rec.xvis``)."""
        if not writes:
            return writes
        chains = self.chains[q]
        out = []
        changed = False
        for w in writes:
            if w.queue != q and not self.covered(w, q) and self._through_semaphores(w, b, q):
                out.append(replace(w, xvis=w.xvis + ((q, b.dst.stages, b.dst.access),)))
                changed = True
                continue
            if w.queue != q or self.covered(w, q) or not self.barrier_takes_write(w, b, q):
                out.append(w)
                continue
            reach = 0
            if w.cls >= 0:
                reach = chains.reach(w.cls)
                reach |= batch_add(pairs, reach)
            reach |= b.dst.stages
            out.append(replace(w, cls=chains.born(reach, reach), vis=w.vis + ((b.dst.stages, b.dst.access),)))
            changed = True
        return tuple(out) if changed else writes

    # --- aliasing hand-off ----------------------------------------------------------------

    def _handoff(self, p: Pass, later: int, barriers: list[Barrier] | None, access: Access | None) -> None:
        q = p.queue
        res = self.plan.resources[later]
        for earlier in self.alias.handoffs.get(later, []):
            prev = self.plan.resources[earlier]
            recs: dict[int, Rec] = {}
            for _, st in self.cells[earlier].states():
                for rec in st.writes + st.reads:
                    recs[id(rec)] = rec
            if not recs:
                continue
            if barriers:
                late = []
                for rec in recs.values():
                    if rec.kind == READ:
                        ok = any(self.barrier_orders_read(rec, b, q) for b in barriers)
                    else:
                        ok = any(self.barrier_takes_write(rec, b, q) for b in barriers)
                    if not ok:
                        late.append(rec)
                head = f"{p.label} first barrier of '{res.name}'{{sub}}"
                for text in self._describe(late, q):
                    self._emit(hz.ALIASING_HANDOFF, p, res, [None], head,
                               f"does not hand over memory from '{prev.name}': not ordered after {text}")
            elif access is not None:
                head = f"{p.label} first access to '{res.name}'{{sub}}"
                if res.is_image:
                    self._emit(hz.ALIASING_HANDOFF, p, res, [None], head,
                               f"no barrier from UNDEFINED hands over the memory of '{prev.name}'")
                    continue
                late = [rec for rec in recs.values() if not self.exec_after(rec, access.stages, q)]
                for text in self._describe(late, q):
                    self._emit(hz.ALIASING_HANDOFF, p, res, [None], head,
                               f"no barrier hands over memory from '{prev.name}': not ordered after {text}")

    # --- accesses -------------------------------------------------------------------------

    def _access_head(self, p: Pass, a: Access, res: Resource) -> str:
        verb = "writes" if a.write else "reads"
        return (f"{p.label} {verb} '{res.name}'{{sub}} "
                f"({vocab.stage_names(a.stages)}/{vocab.access_names(a.access)})")

    def _accesses(self, p: Pass) -> None:
        for a in p.accesses:
            if not self.touched[a.resource]:
                self._handoff(p, a.resource, None, a)
                self.touched[a.resource] = True
            res = self.plan.resources[a.resource]
            memo: dict[int, list[Finding]] = {}
            found: dict[Finding, list[Rect]] = {}
            for rect, st in self.cells[a.resource].query(a.rect):
                key = id(st)
                if key not in memo:
                    memo[key] = self._access_checks(p, a, res, st)
                for finding in memo[key]:
                    found.setdefault(finding, []).append(rect)
            if found:
                self._emit_findings(found, p, res, self._access_head(p, a, res))
        for a in sorted(p.accesses, key=lambda a: not a.write):
            self.cells[a.resource].update(a.rect, lambda st, a=a: self._apply_access(p, a, st))

    def _access_checks(self, p: Pass, a: Access, res: Resource, st: CellState) -> list[Finding]:
        q = p.queue
        out: list[Finding] = []
        if st.release is not None:
            out.append((hz.QUEUE_OWNERSHIP, f"the cells were released by {st.release.origin} to queue "
                                             f"'{self._queue_name(st.release.dst_queue)}' and not acquired"))
        elif st.owner >= 0 and st.owner != q and (res.is_image or st.defined):
            out.append((hz.QUEUE_OWNERSHIP, f"the cells are owned by queue '{self._queue_name(st.owner)}' "
                                             f"(no ownership transfer to '{self._queue_name(q)}')"))
        if res.is_image and a.layout != st.layout:
            hint = " (no transition from UNDEFINED)" if st.layout == vocab.UNDEFINED else ""
            out.append((hz.LAYOUT_MISMATCH, f"accessed as {a.layout} but the cells are in {st.layout}{hint}"))
        if not a.write and not st.defined:
            why = f"discarded by the {st.discarded_by}" if st.discarded_by else "never written this frame"
            out.append((hz.UNDEFINED_CONTENTS, f"read of undefined contents ({why})"))
        read_bits = a.read_bits
        # The read half of a writing access (depth test, blending) on discarded contents reads
        # nothing that needs to be visible: such a pass clears or overwrites first.
        if read_bits and st.writes and (st.defined or not a.write):
            missing: dict[int, int] = {}
            late = []
            for w in st.writes:
                miss = self.invisible_stages(w, a.stages, read_bits, q)
                if miss:
                    missing[id(w)] = miss
                    late.append(w)
            for text in self._describe(late, q, missing):
                out.append((hz.RAW, f"not visible after {text}"))
        if a.write:
            if st.reads:
                late = [r for r in st.reads if not self.exec_after(r, a.stages, q)]
                for text in self._describe(late, q):
                    out.append((hz.WAR, f"not ordered after {text}"))
                if not late:  # ordered after the reads: the write before them must be chained too
                    late = [w for w in st.writes if not self.exec_after(w, a.stages, q)]
                    for text in self._describe(late, q):
                        out.append((hz.WAW, f"not ordered after {text} by a chain that made it available"))
            elif st.writes:
                missing = {}
                late = []
                for w in st.writes:
                    miss = self.invisible_stages(w, a.stages, a.write_bits, q)
                    if miss:
                        missing[id(w)] = miss
                        late.append(w)
                for text in self._describe(late, q, missing):
                    out.append((hz.WAW, f"not made available and visible after {text}"))
        return out

    def _apply_access(self, p: Pass, a: Access, st: CellState) -> CellState:
        q = p.queue
        if a.write:
            new = tuple(Rec(WRITE, q, p.index, stage, a.write_bits, -1, p.label) for stage in vocab.bits(a.stages))
            same_pass = bool(st.writes) and all(w.pass_index == p.index and w.queue == q and w.kind == WRITE
                                                for w in st.writes)
            writes = st.writes + new if same_pass else new
            return CellState(layout=st.layout, owner=q, defined=True, touched=True, writes=writes, reads=())
        chains = self.chains[q]
        reads: dict[tuple[int, int, int], Rec] = {}
        for r in st.reads:
            self._add_read(reads, r)
        for stage in vocab.bits(a.stages):
            self._add_read(reads, Rec(READ, q, p.index, stage, a.access, chains.get(stage, 0), p.label))
        return replace(st, owner=q, touched=True, release=None, reads=tuple(reads.values()))

    def _add_read(self, reads: dict[tuple[int, int, int], Rec], r: Rec) -> None:
        key = (r.queue, self.chains[r.queue].find(r.cls), r.stage)
        old = reads.get(key)
        if old is None or old.pass_index <= r.pass_index:
            reads[key] = r if old is None else replace(r, access=r.access | old.access)
        else:
            reads[key] = replace(old, access=r.access | old.access)

    # --- end of frame -----------------------------------------------------------------------

    def _check_final_states(self) -> None:
        for res_index, res in enumerate(self.plan.resources):
            if res.final is None or self.alias.used[res_index] is None:
                continue
            found: dict[Finding, list[Rect]] = {}
            for entry in res.final:
                for rect, st in self.cells[res_index].query(entry.rect):
                    if st.touched:
                        for finding in self._final_findings(res_index, res, entry, st):
                            found.setdefault(finding, []).append(rect)
                        if st.release is None and self._expects_release(res_index, rect):
                            found.setdefault((hz.QUEUE_OWNERSHIP, "the next frame's first acquire expects a "
                                              "release at the end of this frame, and none happened"), []).append(rect)
            if res.lifetime in ("persistent", "imported") and res.initial is not None and (
                    [_end_key(e) for e in res.initial] != [_end_key(e) for e in res.final]):
                found.setdefault((hz.FINAL_STATE, "'initial' differs from 'final' (the next frame starts from "
                                                  "this frame's final state)"), []).append(res.whole)
            self._emit_findings(found, None, res, f"end of frame: '{res.name}'{{sub}}")

    def _expects_release(self, res_index: int, rect: Rect) -> bool:
        """Does an acquire at the start of the frame (wrapping around) cover ``rect``?"""
        return any(b.rect is None or intersect(b.rect, rect) is not None for b in self.wrap_acquires.get(res_index, []))

    def _wraps(self, res_index: int, rel: Release) -> bool:
        """Is ``rel`` the end-of-frame release that the next frame's first acquire matches?"""
        for b in self.wrap_acquires.get(res_index, []):
            if (b.src.queue, b.dst.queue, b.dst.layout if self.plan.resources[res_index].is_image else None) == (
                    rel.src_queue, rel.dst_queue, rel.dst_layout):
                return True
        return False

    def _final_findings(self, res_index: int, res: Resource, final: EndState, st: CellState) -> list[Finding]:
        out: list[Finding] = []
        layout, owner = st.layout, st.owner
        rel = st.release
        if rel is not None:
            if not self._wraps(res_index, rel):
                return [(hz.QUEUE_OWNERSHIP, f"released by {rel.origin} and never acquired")]
            layout, owner = rel.src_layout, rel.src_queue  # 'final' is the state before that release
        if res.is_image and layout != final.layout:
            out.append((hz.FINAL_STATE, f"ends in {layout} but 'final' declares {final.layout}"))
        if final.queue is not None and owner >= 0 and owner != final.queue:
            out.append((hz.FINAL_STATE, f"ends owned by queue '{self._queue_name(owner)}' but 'final' "
                                         f"declares '{self._queue_name(final.queue)}'"))
        if res.lifetime == "transient":
            return out
        if st.reads:
            stages = 0
            for r in st.reads:
                stages |= r.stage
            if stages & ~final.stages:
                out.append((hz.FINAL_STATE, f"last reads at {vocab.stage_names(stages)} are not covered by "
                                             f"'final' stages {vocab.stage_names(final.stages)}"))
        else:
            stages = access = 0
            for w in st.writes:
                if w.kind == WRITE:
                    stages |= w.stage
                    access |= w.access
            if stages & ~final.stages or access & ~final.access:
                out.append((hz.FINAL_STATE, f"last write ({vocab.stage_names(stages)}/{vocab.access_names(access)}) "
                                             f"is not covered by 'final' ({vocab.stage_names(final.stages)}/"
                                             f"{vocab.access_names(final.access)})"))
        return out


def _end_key(e: EndState) -> tuple[object, ...]:
    return (e.rect, e.layout, e.queue, e.stages, e.access)
