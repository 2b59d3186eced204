"""Memory aliasing between placed resources: overlaps, hand-off duties, lifetimes.

Resources on the same heap whose byte ranges overlap share memory. If both are alive
at once (by the passes that actually touch them) that is an overlap error. Otherwise
the later one's first barrier must hand the memory over from each earlier occupant it
directly follows on some byte (an older occupant fully covered by a later one was
already handed over to that one -- if that later one touches all of its subresources:
one that touches only some hands over only their bytes, so the older occupant still
needs a hand-off from the next resource on its bytes).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rgraph.check.plan import Plan


@dataclass(slots=True)
class AliasInfo:
    used: list[tuple[int, int] | None]  # actual [first, last] pass per resource
    overlaps: list[tuple[int, int, tuple[int, int]]] = field(default_factory=list)  # (a, b, bytes)
    handoffs: dict[int, list[int]] = field(default_factory=dict)  # later -> earlier occupants
    lifetime_errors: list[tuple[int, tuple[int, int]]] = field(default_factory=list)


def actual_lifetimes(plan: Plan) -> list[tuple[int, int] | None]:
    used: list[tuple[int, int] | None] = [None] * len(plan.resources)

    def note(res: int, index: int) -> None:
        if res < 0:
            return
        span = used[res]
        used[res] = (index, index) if span is None else (min(span[0], index), max(span[1], index))

    for p in plan.passes:
        for a in p.accesses:
            note(a.resource, p.index)
        for b in p.barriers:
            note(b.resource, p.index)
        for b in p.releases:
            note(b.resource, p.index)
    return used


def analyse(plan: Plan) -> AliasInfo:
    used = actual_lifetimes(plan)
    info = AliasInfo(used=used)
    frame = (0, max(len(plan.passes) - 1, 0))
    for i, res in enumerate(plan.resources):
        span = used[i]
        if span is None or res.first is None or res.last is None:
            if span is not None and (res.first is None or res.last is None):
                info.lifetime_errors.append((i, span))
            continue
        if span[0] < res.first or span[1] > res.last:
            info.lifetime_errors.append((i, span))

    def alive(i: int) -> tuple[int, int] | None:
        span = used[i]
        if span is None:
            return None
        return span if plan.resources[i].lifetime == "transient" else frame

    placed: dict[int, list[int]] = {}
    for i, res in enumerate(plan.resources):
        if res.heap is not None and res.offset is not None and res.bytes and used[i] is not None:
            placed.setdefault(res.heap, []).append(i)

    earlier: dict[int, list[int]] = {}
    for members in placed.values():
        members.sort(key=lambda i: plan.resources[i].offset or 0)
        for x, a in enumerate(members):
            ra = plan.resources[a]
            a_end = (ra.offset or 0) + (ra.bytes or 0)
            for b in members[x + 1:]:
                rb = plan.resources[b]
                if (rb.offset or 0) >= a_end:
                    break
                bytes_range = (rb.offset or 0, min(a_end, (rb.offset or 0) + (rb.bytes or 0)))
                la, lb = alive(a), alive(b)
                assert la is not None and lb is not None
                if la[0] <= lb[1] and lb[0] <= la[1]:
                    info.overlaps.append((a, b, bytes_range))
                elif la[1] < lb[0]:
                    earlier.setdefault(b, []).append(a)
                else:
                    earlier.setdefault(a, []).append(b)

    whole = _wholly_touched(plan)
    for later, candidates in earlier.items():
        rl = plan.resources[later]
        lo, hi = rl.offset or 0, (rl.offset or 0) + (rl.bytes or 0)
        covered: list[tuple[int, int]] = []
        chosen = []
        for e in sorted(candidates, key=lambda i: -(used[i] or (0, 0))[1]):
            re_ = plan.resources[e]
            span = (max(lo, re_.offset or 0), min(hi, (re_.offset or 0) + (re_.bytes or 0)))
            if not _covered(span, covered):
                chosen.append(e)
            if whole[e]:
                covered = _union(covered, span)
        info.handoffs[later] = chosen
    return info


def _wholly_touched(plan: Plan) -> list[bool]:
    """Per resource: do the frame's accesses touch every subresource (buffers: any access)?"""
    cells: list[set[tuple[int, int]] | None] = [None] * len(plan.resources)
    for p in plan.passes:
        for a in p.accesses:
            if a.resource < 0:
                continue
            res = plan.resources[a.resource]
            seen = cells[a.resource] if cells[a.resource] is not None else set()
            rect = a.rect or res.whole
            seen.update((m, layer) for m in range(rect[0], rect[1]) for layer in range(rect[2], rect[3]))
            cells[a.resource] = seen
    return [c is not None and (not res.is_image or len(c) == res.mips * res.layers)
            for c, res in zip(cells, plan.resources, strict=True)]


def _covered(span: tuple[int, int], intervals: list[tuple[int, int]]) -> bool:
    pos = span[0]
    for lo, hi in intervals:
        if lo <= pos < hi:
            pos = hi
        if pos >= span[1]:
            return True
    return pos >= span[1]


def _union(intervals: list[tuple[int, int]], span: tuple[int, int]) -> list[tuple[int, int]]:
    out: list[tuple[int, int]] = []
    for lo, hi in sorted(intervals + [span]):
        if out and lo <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], hi))
        else:
            out.append((lo, hi))
    return out
