"""Plan model -> JSON: the canonical text (sorted keys, indent 1, ASCII, trailing newline)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

from rgraph.plan.model import (
    IMAGE_KEYS,
    Access,
    Barrier,
    CellState,
    EndState,
    Heap,
    Plan,
    PlanPass,
    PlanResource,
    Signal,
    State,
    Stats,
    Subresource,
    Wait,
)


def dumps_json(document: Mapping[str, Any]) -> str:
    """The canonical text of a JSON plan document (a dict)."""
    return json.dumps(document, sort_keys=True, indent=1, ensure_ascii=True) + "\n"


def dump(plan: Plan) -> str:
    """The plan's canonical JSON text; ``load(dump(p)) == p``."""
    return dumps_json(to_json_dict(plan))


def aliases_json(names: tuple[str, ...]) -> str | list[str] | None:
    """The previous occupant(s) of aliased memory: a name, a list when several, else null."""
    if not names:
        return None
    return names[0] if len(names) == 1 else list(names)


def subresource_json(s: Subresource | None) -> dict[str, list[int]] | None:
    return None if s is None else {"mips": list(s.mips), "layers": list(s.layers)}


def state_json(s: State) -> dict[str, Any]:
    return {"stages": list(s.stages), "access": list(s.access), "layout": s.layout, "queue": s.queue}


def _end_state(e: EndState) -> Any:
    if e is None:
        return None
    if isinstance(e, State):
        return state_json(e)
    return [_cell(c) for c in e]


def _cell(c: CellState) -> dict[str, Any]:
    return {"subresource": subresource_json(c.subresource), **state_json(c.state)}


def barrier_json(b: Barrier) -> dict[str, Any]:
    return {"resource": b.resource, "subresource": subresource_json(b.subresource), "src": state_json(b.src),
            "dst": state_json(b.dst), "aliases": aliases_json(b.aliases)}


def _access(a: Access) -> dict[str, Any]:
    return {"resource": a.resource, "subresource": subresource_json(a.subresource), "usage": a.usage,
            "stages": list(a.stages), "access": list(a.access), "layout": a.layout, "write": a.write}


def _thaw(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {k: _thaw(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return [_thaw(v) for v in value]
    return value


def _timeline(t: Wait | Signal) -> dict[str, Any]:
    out: dict[str, Any] = {"queue": t.queue, "value": t.value, "stages": list(t.stages)}
    if t.device is not None:
        out["device"] = t.device
    return out


def _pass(p: PlanPass) -> dict[str, Any]:
    return {
        "name": p.name, "index": p.index, "device": p.device, "queue": p.queue, "kind": p.kind, "impl": p.impl,
        "params": _thaw(p.params),
        "accesses": [_access(a) for a in p.accesses],
        "barriers": [barrier_json(b) for b in p.barriers],
        "releases": [barrier_json(b) for b in p.releases],
        "waits": [_timeline(w) for w in p.waits],
        "signals": [_timeline(s) for s in p.signals],
    }


def _resource(r: PlanResource) -> dict[str, Any]:
    out: dict[str, Any] = {
        "name": r.name, "kind": r.kind, "format": r.format, "bytes": r.bytes, "size_bytes": r.size_bytes,
        "alignment": r.alignment, "memory_type_bits": r.memory_type_bits, "memory_class": r.memory_class,
        "usages": list(r.usages), "lifetime": r.lifetime, "first": r.first, "last": r.last, "heap": r.heap,
        "offset": r.offset, "initial": _end_state(r.initial), "final": _end_state(r.final),
    }
    image = {"extent": None if r.extent is None else list(r.extent), "mips": r.mips, "layers": r.layers,
             "samples": r.samples}
    absent = r.absent if r.absent is not None else (IMAGE_KEYS if r.extent is None else ())
    out.update({k: v for k, v in image.items() if k not in absent})
    if r.accel is not None:
        out["accel"] = _thaw(r.accel)
    if r.scratch_of is not None:
        out["scratch_of"] = r.scratch_of
    if r.device:
        out["device"] = r.device
    return out


def _heap(h: Heap) -> dict[str, Any]:
    out: dict[str, Any] = {"id": h.id, "bytes": h.bytes, "memory_class": h.memory_class, "alignment": h.alignment}
    if h.device:
        out["device"] = h.device
    return out


def _stats(s: Stats) -> dict[str, Any]:
    keys = ("barriers", "semaphores", "peak_bytes", "lower_bound_bytes", "unaliased_bytes", "allocations",
            "policy", "sync", "schedule")
    return {k: getattr(s, k) for k in keys if getattr(s, k) is not None}


def to_json_dict(plan: Plan) -> dict[str, Any]:
    """The plan as the decoded JSON document (docs/plan.md), fresh and mutable."""
    out: dict[str, Any] = {
        "format": plan.format, "graph": plan.graph, "source": plan.source, "scene": plan.scene,
        "scene_source": plan.scene_source, "size": list(plan.size), "params": _thaw(plan.params),
        "features": _thaw(plan.features), "device_profile": plan.device_profile, "queues": list(plan.queues),
        "passes": [_pass(p) for p in plan.passes],
        "culled": [{"pass": c.pass_name, "reason": c.reason, "resources": list(c.resources), "bytes": c.bytes}
                   for c in plan.culled],
        "dropped_reads": [{"pass": d.pass_name, "resource": d.resource, "reason": d.reason}
                          for d in plan.dropped_reads],
        "resources": [_resource(r) for r in plan.resources],
        "heaps": [_heap(h) for h in plan.heaps],
        "outputs": list(plan.outputs),
        "stats": _stats(plan.stats),
    }
    if plan.camera:
        out["camera"] = plan.camera
    if plan.multi_device is not None:
        out["multi_device"] = _thaw(plan.multi_device)
    for key in plan.absent:
        del out[key]
    return out
