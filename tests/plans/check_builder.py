"""Small helpers for the checker's tests: load the fixture plans, build tiny plans, mutate.

The fixture plans (tests/plans/*.json) are hand-written and correct; tests mutate
copies to show each hazard kind being detected.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

from rgraph.check import check_plan

PLANS = Path(__file__).parent
FIXTURES = sorted(p.stem for p in PLANS.glob("*.json"))
WHOLE = {"mips": [0, 1], "layers": [0, 1]}
Plan = dict[str, Any]


def load(name: str) -> Plan:
    return json.loads((PLANS / f"{name}.json").read_text())


def kinds(plan: Plan) -> set[str]:
    return {h.kind for h in check_plan(plan)}


def pass_named(plan: Plan, name: str) -> dict[str, Any]:
    return next(p for p in plan["passes"] if p["name"] == name)


def resource_named(plan: Plan, name: str) -> dict[str, Any]:
    return next(r for r in plan["resources"] if r["name"] == name)


def barrier_on(plan: Plan, pass_name: str, resource: str, key: str = "barriers") -> dict[str, Any]:
    return next(b for b in pass_named(plan, pass_name)[key] if b["resource"] == resource)


def without(plan: Plan, pass_name: str, resource: str, key: str = "barriers") -> Plan:
    """A copy of ``plan`` with the barrier on ``resource`` before ``pass_name`` removed."""
    out = copy.deepcopy(plan)
    p = pass_named(out, pass_name)
    p[key] = [b for b in p[key] if b["resource"] != resource]
    return out


def every_single_drop(plan: Plan):
    """(label, mutated plan) for every barrier, release, wait and signal removed alone."""
    for i, p in enumerate(plan["passes"]):
        for key in ("barriers", "releases", "waits", "signals"):
            for k in range(len(p.get(key, []))):
                out = copy.deepcopy(plan)
                del out["passes"][i][key][k]
                yield f"{p['name']}.{key}[{k}]", out


# --- building tiny plans ------------------------------------------------------------------


def scope(stages: list[str], access: list[str], layout: str | None, queue: str = "graphics") -> dict[str, Any]:
    return {"stages": sorted(stages), "access": sorted(access), "layout": layout, "queue": queue}


def access(resource: str, stages: list[str], access_: list[str], layout: str | None = None, write: bool = False,
           sub: dict[str, Any] | None = None, usage: str = "") -> dict[str, Any]:
    return {"resource": resource, "subresource": (sub or WHOLE) if layout else None, "usage": usage,
            "stages": sorted(stages), "access": sorted(access_), "layout": layout, "write": write}


def barrier(resource: str, src: dict[str, Any], dst: dict[str, Any], sub: dict[str, Any] | None = None,
            aliases: str | None = None) -> dict[str, Any]:
    image = src["layout"] is not None or dst["layout"] is not None
    return {"resource": resource, "subresource": (sub or WHOLE) if image else None, "src": src, "dst": dst,
            "aliases": aliases}


def gpass(index: int, name: str, accesses: list[dict[str, Any]], barriers: list[dict[str, Any]] = (),
          queue: str = "graphics", releases=(), waits=(), signals=()) -> dict[str, Any]:
    return {"name": name, "index": index, "device": 0, "queue": queue, "kind": "compute", "impl": None,
            "params": {}, "accesses": list(accesses), "barriers": list(barriers), "releases": list(releases),
            "waits": list(waits), "signals": list(signals)}


def resource(name: str, kind: str = "image", first: int | None = 0, last: int | None = 0, lifetime: str = "transient",
             mips: int = 1, layers: int = 1, heap: int | None = None, offset: int | None = None,
             nbytes: int = 65536, initial: dict[str, Any] | None = None,
             final: dict[str, Any] | None = None) -> dict[str, Any]:
    return {"name": name, "kind": kind, "mips": mips, "layers": layers, "bytes": nbytes, "lifetime": lifetime,
            "first": first, "last": last, "heap": heap, "offset": offset,
            "initial": initial or scope([], [], "UNDEFINED" if kind == "image" else None),
            "final": final}


def plan_of(passes: list[dict[str, Any]], resources: list[dict[str, Any]],
            queues: list[str] = ("graphics",)) -> Plan:
    return {"format": "rgraph-plan/1", "graph": "test", "queues": list(queues), "passes": passes,
            "resources": sorted(resources, key=lambda r: r["name"]), "heaps": []}
