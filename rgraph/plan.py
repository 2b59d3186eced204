"""Assemble the plan document (FORMAT.md section 3, docs/plan.md) and write it deterministically."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from functools import lru_cache
from typing import Any

from rgraph.compiler.sync import Barrier, State, SyncResult
from rgraph.ir.cull import Culling
from rgraph.memory.model import Placement
from rgraph.spec.specialize import PassSpec, ResourceSpec, Spec

PLAN_FORMAT = "rgraph-plan/1"
QUEUE_ORDER = ("graphics", "compute", "transfer")
SIGNAL_STAGES = ["ALL_COMMANDS"]


def dumps(plan: Mapping[str, Any]) -> str:
    """The canonical text of a plan: sorted keys, one-space indent, trailing newline."""
    return json.dumps(plan, sort_keys=True, indent=1, ensure_ascii=True) + "\n"


@lru_cache(maxsize=65536)
def _state_items(st: State) -> tuple:
    return (sorted(st.stages), sorted(st.access), st.layout, st.queue)


def _state(st: State) -> dict[str, Any]:
    stages, access, layout, queue = _state_items(st)
    return {"stages": list(stages), "access": list(access), "layout": layout, "queue": queue}


def _subresource(res: ResourceSpec, mips, layers) -> dict[str, list[int]] | None:
    if not res.is_image:
        return None
    return {"mips": list(mips), "layers": list(layers)}


def _barrier(b: Barrier, resources: Mapping[str, ResourceSpec]) -> dict[str, Any]:
    res = resources[b.resource]
    return {
        "resource": b.resource,
        "subresource": _subresource(res, b.mips, b.layers),
        "src": _state(b.key.src),
        "dst": _state(b.key.dst),
        "aliases": _aliases(b.key.aliases),
    }


def _aliases(names: tuple[str, ...]) -> str | list[str] | None:
    """The previous occupant of aliased memory: a name, a list when several, else null."""
    if not names:
        return None
    return names[0] if len(names) == 1 else list(names)


def _end_state(res: ResourceSpec, lifetime: str, states: Mapping[Any, State] | None) -> Any:
    """One state object when every cell agrees. Otherwise: null for transients (nothing
    outlives the frame), a list of per-cell states for the others (docs/plan.md)."""
    if not states:
        return None
    distinct = set(states.values())
    if len(distinct) == 1:
        return _state(next(iter(distinct)))
    if lifetime == "transient":
        return None
    return [
        {"subresource": {"mips": [mip, mip + 1], "layers": [layer, layer + 1]}, **_state(st)}
        for (_, mip, layer), st in sorted(states.items())
    ]


def build_plan(
    spec: Spec,
    culling: Culling,
    passes: Sequence[PassSpec],
    sync: SyncResult,
    placement: Placement,
    reqs: Mapping[str, tuple[int, int, int, str]],
    classes: Mapping[str, str],
    spans: Mapping[str, tuple[int, int]],
    usages: Mapping[str, set[str]],
    profile_name: str,
    culled_bytes: Mapping[str, int] | None = None,
) -> dict[str, Any]:
    resources = spec.resources
    queues = [q for q in QUEUE_ORDER if any(p.queue == q for p in passes)]
    signal_values = _signal_values(passes, sync)
    plan_passes = []
    barrier_count = 0
    for i, p in enumerate(passes):
        ps = sync.passes[i]
        accesses = []
        for a, s in zip(p.accesses, sync.access_sync[i], strict=True):
            res = resources[a.resource]
            accesses.append(
                {
                    "resource": a.resource,
                    "subresource": _subresource(res, a.mips, a.layers),
                    "usage": a.usage,
                    "stages": sorted(s.stages),
                    "access": sorted(s.access),
                    "layout": s.layout,
                    "write": a.write,
                }
            )
        barriers = [_barrier(b, resources) for b in ps.barriers]
        barrier_count += len(barriers)
        plan_passes.append(
            {
                "name": p.name,
                "index": i,
                "device": 0,
                "queue": p.queue,
                "kind": p.kind,
                "impl": p.impl,
                "params": dict(sorted(p.params.items())),
                "accesses": accesses,
                "barriers": barriers,
                "releases": [_barrier(b, resources) for b in ps.releases],
                "waits": [
                    {"queue": w.queue, "value": signal_values[w.signal_pass], "stages": sorted(w.stages)}
                    for w in ps.waits
                ],
                "signals": (
                    [{"queue": p.queue, "value": signal_values[i], "stages": SIGNAL_STAGES}] if ps.signal else []
                ),
            }
        )
    plan_resources = []
    for name in sorted(reqs):
        res = resources[name]
        size, align, bits, _tiling = reqs[name]
        heap, offset = placement.offsets[name]
        lifetime = "output" if (name in spec.outputs and res.lifetime == "transient") else res.lifetime
        entry: dict[str, Any] = {
            "name": name,
            "kind": res.kind,
            "format": res.format.vk_name if res.format else None,
            "bytes": size,
            "size_bytes": None if res.is_image else res.bytes,
            "alignment": align,
            "memory_type_bits": bits,
            "memory_class": classes[name],
            "usages": sorted(usages.get(name, ())),
            "lifetime": lifetime,
            "first": spans[name][0],
            "last": spans[name][1],
            "heap": heap,
            "offset": offset,
            "initial": _end_state(res, lifetime, sync.initial.get(name)),
            "final": _end_state(res, lifetime, sync.final.get(name)),
        }
        if res.is_image:
            entry.update({"extent": list(res.extent), "mips": res.mips, "layers": res.layers, "samples": res.samples})
        if res.accel is not None:
            entry["accel"] = res.accel.as_plan()
        if res.scratch_of is not None:
            entry["scratch_of"] = res.scratch_of
        plan_resources.append(entry)
    stats = placement.stats
    kept_resources = set(reqs)
    by_name = {p.name: p for p in spec.passes}
    return {
        "format": PLAN_FORMAT,
        "graph": spec.name,
        "source": spec.source,
        "scene": spec.scene_name,
        "scene_source": spec.scene_source,
        "size": list(spec.size),
        "params": dict(sorted(spec.params.items())),
        "features": dict(sorted(spec.features.items())),
        "device_profile": profile_name,
        "queues": queues,
        "passes": plan_passes,
        "culled": [_culled_entry(c, by_name[c.pass_name], kept_resources, culled_bytes or {}) for c in culling.culled],
        "dropped_reads": [
            {"pass": d.pass_name, "resource": d.resource, "reason": d.reason} for d in culling.dropped_reads
        ],
        "resources": plan_resources,
        "heaps": [
            {"id": h.id, "bytes": h.bytes, "memory_class": h.memory_class, "alignment": h.alignment}
            for h in placement.heaps
        ],
        "outputs": list(spec.outputs),
        "stats": {
            "barriers": barrier_count,
            "semaphores": sum(1 for p in plan_passes if p["signals"]),
            "peak_bytes": stats.peak_bytes,
            "lower_bound_bytes": stats.lower_bound_bytes,
            "unaliased_bytes": stats.unaliased_bytes,
            "allocations": stats.allocations,
            "policy": stats.policy,
        },
    }


def _culled_entry(c, p: PassSpec, kept_resources: set[str], sizes: Mapping[str, int]) -> dict[str, Any]:
    """A culled pass with the resources only culled passes used, and their bytes."""
    only = sorted({a.resource for a in p.accesses} - kept_resources)
    return {"pass": c.pass_name, "reason": c.reason, "resources": only, "bytes": sum(sizes.get(r, 0) for r in only)}


def _signal_values(passes: Sequence[PassSpec], sync: SyncResult) -> dict[int, int]:
    """Timeline values per queue, 1, 2, ... in plan order."""
    counters: dict[str, int] = {}
    values: dict[int, int] = {}
    for i, p in enumerate(passes):
        if sync.passes[i].signal:
            counters[p.queue] = counters.get(p.queue, 0) + 1
            values[i] = counters[p.queue]
    return values
