"""Cross-references of a well-shaped plan: names, indices, queues, heaps, subresource bounds.

``check_consistency`` returns the first problem as ``(json path, message)``, or None.
"""

from __future__ import annotations

from collections.abc import Iterator

from rgraph.plan.model import Barrier, Plan, PlanResource, State, Subresource

Problem = tuple[str, str]


def check_consistency(plan: Plan) -> Problem | None:
    for check in (_queues, _vocabulary, _passes, _resources):
        for problem in check(plan):
            return problem
    return None


def _duplicates(names: list, where: str, what: str) -> Iterator[Problem]:
    seen: set = set()
    for i, name in enumerate(names):
        if name in seen:
            yield f"{where}[{i}]", f"duplicate {what} {name!r}"
        seen.add(name)


def _queues(plan: Plan) -> Iterator[Problem]:
    yield from _duplicates(list(plan.queues), "queues", "queue")
    yield from _duplicates([r.name for r in plan.resources], "resources", "resource")
    yield from _duplicates([p.name for p in plan.passes], "passes", "pass")
    yield from _duplicates([h.id for h in plan.heaps], "heaps", "heap id")
    for i, name in enumerate(plan.outputs):
        if name not in plan.resource_by_name:
            yield f"outputs[{i}]", f"no resource {name!r} in resources"


def _word(value: str, words: tuple[str, ...] | frozenset[str], where: str, what: str) -> Iterator[Problem]:
    if value not in words:
        yield where, f"unknown {what} {value!r} (expected one of {', '.join(sorted(words))})"


#: usages the compiler adds to plans, never written in a graph file (an accel build's scratch:
#: ``rgraph.compiler.accel``)
PLAN_ONLY_USAGES = ("accel_scratch",)


def _vocabulary(plan: Plan) -> Iterator[Problem]:
    """Pass kinds, usages and formats are the closed vocabularies of FORMAT.md."""
    from rgraph.memory_requirements import ACCEL_BUFFER_USAGES
    from rgraph.spec.vocabulary import PASS_KINDS
    from rgraph.spec.vocabulary import USAGES as GRAPH_USAGES

    usages = (*GRAPH_USAGES, *PLAN_ONLY_USAGES)
    resource_usages = (*usages, *sorted(ACCEL_BUFFER_USAGES - set(usages)))  # + trace_indirect (a device address)
    for i, p in enumerate(plan.passes):
        yield from _word(p.kind, PASS_KINDS, f"passes[{i}].kind", "pass kind")
        for j, a in enumerate(p.accesses):
            yield from _word(a.usage, usages, f"passes[{i}].accesses[{j}].usage", "usage")
    for i, r in enumerate(plan.resources):
        for j, u in enumerate(r.usages):
            yield from _word(u, resource_usages, f"resources[{i}].usages[{j}]", "usage")
        if r.format is not None and not _known_format(r.format):
            yield f"resources[{i}].format", f"unknown format {r.format!r} (VkFormat without VK_FORMAT_)"
        elif r.format is None and r.is_image:
            yield f"resources[{i}].format", f"image {r.name!r} needs a format, got null"


def _known_format(name: str) -> bool:
    from rgraph.formats import lookup

    try:
        return lookup(name).vk_name == name
    except KeyError:
        return False


def _queue(plan: Plan, queue: str, where: str) -> Iterator[Problem]:
    if queue not in plan.queues:
        yield where, f"queue {queue!r} is not in the plan's queues {list(plan.queues)}"


def _bounds(res: PlanResource, sub: Subresource | None, where: str) -> Iterator[Problem]:
    if not res.is_image:
        if sub is not None:
            yield where, f"a subresource on {res.kind} {res.name!r} (expected null)"
        return
    if sub is None:
        yield where, f"image {res.name!r} needs a subresource, got null"
        return
    for key, rng, count in (("mips", sub.mips, res.mips), ("layers", sub.layers, res.layers)):
        if count is not None and rng[1] > count:
            yield f"{where}.{key}", f"range {list(rng)} exceeds {res.name!r}'s {count} {key}"


def _ref(plan: Plan, name: str, where: str) -> Iterator[Problem]:
    if name not in plan.resource_by_name:
        yield where, f"no resource {name!r} in resources"


def _state(plan: Plan, s: State, where: str) -> Iterator[Problem]:
    if s.queue is not None:
        yield from _queue(plan, s.queue, f"{where}.queue")


def _barrier(plan: Plan, b: Barrier, where: str) -> Iterator[Problem]:
    yield from _ref(plan, b.resource, f"{where}.resource")
    if b.resource in plan.resource_by_name:
        yield from _bounds(plan.resource(b.resource), b.subresource, f"{where}.subresource")
    for k, name in enumerate(b.aliases):
        yield from _ref(plan, name, f"{where}.aliases" + (f"[{k}]" if len(b.aliases) > 1 else ""))
    yield from _state(plan, b.src, f"{where}.src")
    yield from _state(plan, b.dst, f"{where}.dst")


def _passes(plan: Plan) -> Iterator[Problem]:
    for i, p in enumerate(plan.passes):
        at = f"passes[{i}]"
        if p.index != i:
            yield f"{at}.index", f"expected {i} (the pass's position), got {p.index}"
        yield from _queue(plan, p.queue, f"{at}.queue")
        for j, a in enumerate(p.accesses):
            where = f"{at}.accesses[{j}]"
            yield from _ref(plan, a.resource, f"{where}.resource")
            if a.resource in plan.resource_by_name:
                yield from _bounds(plan.resource(a.resource), a.subresource, f"{where}.subresource")
        for key in ("barriers", "releases"):
            for j, b in enumerate(getattr(p, key)):
                yield from _barrier(plan, b, f"{at}.{key}[{j}]")
        for j, w in enumerate(p.waits):
            yield from _queue(plan, w.queue, f"{at}.waits[{j}].queue")
        for j, s in enumerate(p.signals):
            if s.queue != p.queue:
                yield f"{at}.signals[{j}].queue", f"a pass signals its own queue {p.queue!r}, got {s.queue!r}"


def _resources(plan: Plan) -> Iterator[Problem]:
    n = len(plan.passes)
    for i, r in enumerate(plan.resources):
        at = f"resources[{i}]"
        heap = plan.heap_by_id.get(r.heap) if r.heap is not None else None
        if r.heap is None or r.offset is None:
            pass
        elif heap is None:
            yield f"{at}.heap", f"no heap with id {r.heap} in heaps"
        elif r.offset + r.bytes > heap.bytes:
            yield f"{at}.offset", f"offset {r.offset} + bytes {r.bytes} exceeds heap {heap.id}'s {heap.bytes} bytes"
        for key in ("first", "last"):
            value = getattr(r, key)
            if value is not None and value >= n:
                yield f"{at}.{key}", f"pass index {value} out of range (the plan has {n} passes)"
        if r.first is not None and r.last is not None and r.first > r.last:
            yield f"{at}.first", f"first {r.first} is after last {r.last}"
        for key in ("initial", "final"):
            end = getattr(r, key)
            if isinstance(end, State):
                yield from _state(plan, end, f"{at}.{key}")
            elif end is not None:
                for j, cell in enumerate(end):
                    yield from _bounds(r, cell.subresource, f"{at}.{key}[{j}].subresource")
                    yield from _state(plan, cell.state, f"{at}.{key}[{j}]")
