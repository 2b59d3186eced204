"""Multi-device plans: ``merge`` per-device plans into one, ``project`` one device back out.

In a merged plan device 0's passes and resources keep their names; device ``d > 0``'s get
the suffix ``@d`` (``depth@1``), and every pass, resource and heap carries its ``device``.
Device 0's passes up to its first cross-device wait come first, then every other device's,
then the rest of device 0's (each device's own order is kept). A copy from device ``d``
(``copy_from`` in the receiving pass's params) waits on the sending pass's timeline value
with ``device: d``; the sending pass signals it. ``project(plan, d)`` gives device ``d``'s
own plan (names without the suffix, cross-device waits and their signals left out): what
the runtime runs on that device and what ``rgraph check`` replays per device.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from types import MappingProxyType
from typing import Any

from rgraph.plan.model import Access, Barrier, Plan, PlanPass, Signal, Stats, Wait

SUFFIX = "@"
# Pass params and impl names a multi-device plan carries (shared by the compiler and the runtime).
SCISSOR = "rgraph.scissor"
DRAWS = "rgraph.draws"
PROBE_INDEX = "rgraph.probe_index"
DOWNLOAD_IMPL = "rgraph.multi.download"
UPLOAD_IMPL = "rgraph.multi.upload"
COMPOSITE_IMPL = "rgraph.multi.depth_composite"


def rename(name: str, device: int) -> str:
    return name if device == 0 else f"{name}{SUFFIX}{device}"


def base_name(name: str, device: int) -> str:
    tail = f"{SUFFIX}{device}"
    return name[: -len(tail)] if device and name.endswith(tail) else name


def _access(a: Access, f) -> Access:
    return replace(a, resource=f(a.resource))


def _barrier(b: Barrier, f) -> Barrier:
    return replace(b, resource=f(b.resource), aliases=tuple(f(x) for x in b.aliases))


def _retag(p: PlanPass, f, pname, index: int, device: int, waits, signals) -> PlanPass:
    return replace(p, name=pname(p.name), index=index, device=device,
                   accesses=tuple(_access(a, f) for a in p.accesses),
                   barriers=tuple(_barrier(b, f) for b in p.barriers),
                   releases=tuple(_barrier(b, f) for b in p.releases), waits=waits, signals=signals)


def _cross_copies(p: PlanPass) -> Mapping[str, Any] | None:
    source = p.params.get("copy_from")
    return source if isinstance(source, Mapping) else None


def merge(plans: Sequence[Plan], info: Mapping[str, Any], culled: Sequence[Any] = ()) -> Plan:
    """One plan from ``plans[d]`` (device ``d``'s plan); ``info`` becomes ``multi_device``."""
    first0 = next((i for i, p in enumerate(plans[0].passes) if _cross_copies(p)), len(plans[0].passes))
    order = [(0, p) for p in plans[0].passes[:first0]]
    for d in range(1, len(plans)):
        order += [(d, p) for p in plans[d].passes]
    order += [(0, p) for p in plans[0].passes[first0:]]
    index = {(d, p.index): i for i, (d, p) in enumerate(order)}
    # cross-device signals: the sending pass signals its queue's next value
    sends: dict[tuple[int, str], Signal] = {}
    for _d, p in order:
        src = _cross_copies(p)
        if src is None:
            continue
        sd, sname = int(src["device"]), base_name(str(src["pass"]), int(src["device"]))
        sender = next(q for q in plans[sd].passes if q.name == sname)
        top = max((s.value for q in plans[sd].passes for s in q.signals if s.queue == sender.queue), default=0)
        sends.setdefault((sd, sname), Signal(sender.queue, top + 1, ("ALL_TRANSFER",)))
    passes = []
    for i, (d, p) in enumerate(order):
        waits = p.waits
        src = _cross_copies(p)
        if src is not None:
            sd = int(src["device"])
            s = sends[(sd, base_name(str(src["pass"]), sd))]
            waits = waits + (Wait(s.queue, s.value, ("ALL_TRANSFER",), sd),)
        signals = p.signals + ((sends[(d, p.name)],) if (d, p.name) in sends else ())
        passes.append(_retag(p, lambda n, d=d: rename(n, d), lambda n, d=d: rename(n, d), i, d, waits, signals))
    resources, heaps = [], []
    for d, plan in enumerate(plans):
        base = len(heaps)
        heaps += [replace(h, id=base + h.id, device=d) for h in plan.heaps]
        for r in plan.resources:
            resources.append(replace(r, name=rename(r.name, d), device=d,
                                     heap=None if r.heap is None else base + r.heap,
                                     first=None if r.first is None else index[(d, r.first)],
                                     last=None if r.last is None else index[(d, r.last)]))
    resources.sort(key=lambda r: r.name)
    queues = tuple(q for q in ("graphics", "compute", "transfer") if any(q in p.queues for p in plans))
    stats = Stats(barriers=sum(len(p.barriers) for p in passes),
                  semaphores=sum(pl.stats.semaphores or 0 for pl in plans) + len(sends),
                  peak_bytes=sum(pl.stats.peak_bytes or 0 for pl in plans),
                  lower_bound_bytes=sum(pl.stats.lower_bound_bytes or 0 for pl in plans),
                  unaliased_bytes=sum(pl.stats.unaliased_bytes or 0 for pl in plans),
                  allocations=sum(pl.stats.allocations or 0 for pl in plans), policy=plans[0].stats.policy)
    return replace(plans[0], passes=tuple(passes), resources=tuple(resources), heaps=tuple(heaps), queues=queues,
                   stats=stats, culled=tuple(culled) or plans[0].culled, multi_device=MappingProxyType(dict(info)))


def devices_of(plan: Plan) -> int:
    return int(plan.multi_device["devices"]) if plan.multi_device else 1


def project(plan: Plan, device: int) -> Plan:
    """Device ``device``'s own plan out of a merged one (see the module docstring)."""
    crossing = {(w.device, w.queue, w.value) for p in plan.passes for w in p.waits if w.device is not None}
    mine = [p for p in plan.passes if p.device == device]
    index = {p.index: i for i, p in enumerate(mine)}
    f = lambda n: base_name(n, device)  # noqa: E731
    passes = tuple(_retag(p, f, f, index[p.index], 0,
                          tuple(w for w in p.waits if w.device is None),
                          tuple(s for s in p.signals if (device, s.queue, s.value) not in crossing))
                   for p in mine)
    heaps = [h for h in plan.heaps if h.device == device]
    heap_id = {h.id: i for i, h in enumerate(heaps)}
    resources = tuple(sorted((replace(r, name=f(r.name), device=0,
                                      heap=None if r.heap is None else heap_id[r.heap],
                                      first=None if r.first is None else index[r.first],
                                      last=None if r.last is None else index[r.last])
                              for r in plan.resources if r.device == device), key=lambda r: r.name))
    outputs = tuple(o for o in plan.outputs) if device == 0 else tuple(
        r.name for r in resources if r.lifetime == "output")
    return replace(plan, passes=passes, resources=resources, outputs=outputs,
                   heaps=tuple(replace(h, id=heap_id[h.id], device=0) for h in heaps),
                   queues=tuple(q for q in ("graphics", "compute", "transfer") if any(p.queue == q for p in passes)),
                   stats=replace(plan.stats, barriers=sum(len(p.barriers) for p in passes)),
                   culled=plan.culled if device == 0 else (), multi_device=None)
