"""``rgraph inspect --json``: the views as one JSON document (schema: docs/cli-json.md)."""

from __future__ import annotations

from typing import Any

from rgraph.report.memory import culled_bytes_total
from rgraph.report.summary import counted_barriers, culled_ms

Plan = dict[str, Any]

HEADER_KEYS = ("graph", "source", "scene", "size", "params", "device_profile", "queues", "outputs", "features")


def inspect_document(plan: Plan, timings: dict | None, *, barriers: bool, memory: bool) -> dict[str, Any]:
    """Header, schedule, culled passes (with GPU ms given timings), stats; barriers/memory on request."""
    listed, releases = counted_barriers(plan)
    body: dict[str, Any] = {key: plan.get(key) for key in HEADER_KEYS}
    body["passes"] = [{
        "index": p.get("index", i), "name": p["name"], "kind": p.get("kind"), "queue": p.get("queue", "graphics"),
        "impl": p.get("impl"), "accesses": len(p.get("accesses") or []),
        "barriers": len(p.get("barriers") or []), "releases": len(p.get("releases") or []),
        "waits": p.get("waits") or [], "signals": p.get("signals") or [],
    } for i, p in enumerate(plan["passes"])]
    body["culled"] = [{**c, "gpu_ms": culled_ms(timings, c["pass"])} for c in plan.get("culled") or []]
    measured = [c["gpu_ms"] for c in body["culled"] if c["gpu_ms"] is not None]
    body["culling_saved"] = {"bytes": culled_bytes_total(plan), "gpu_ms": sum(measured) if measured else None}
    body["dropped_reads"] = plan.get("dropped_reads") or []
    body["stats"] = {**(plan.get("stats") or {}), "barriers_listed": listed, "releases": releases}
    if barriers:
        body["barriers"] = [
            {"pass": p["name"], "index": p.get("index", i), "phase": phase, **item}
            for i, p in enumerate(plan["passes"])
            for phase, key in (("wait", "waits"), ("barrier", "barriers"), ("release", "releases"),
                               ("signal", "signals"))
            for item in p.get(key) or []
        ]
    if memory:
        body["resources"] = plan.get("resources") or []
        body["heaps"] = plan.get("heaps") or []
    return body
