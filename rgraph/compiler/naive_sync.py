"""``--sync naive``: the plan with the most conservative synchronization, for comparison.

A transformation of a compiled plan (docs/plan.md), so check, inspect and the runtime read
it unchanged:

- every pass runs on the graphics queue: no async compute, no ownership transfers,
  no semaphores (``waits``, ``signals`` and ``releases`` are empty);
- before each pass, every subresource it accesses gets a full barrier: src
  ``ALL_COMMANDS`` + ``MEMORY_WRITE``, dst ``ALL_COMMANDS`` + ``MEMORY_READ|MEMORY_WRITE``,
  with the layout transition to the access's layout (old == new when it already is);
- an aliased resource's first barriers keep the normal plan's ``aliases``;
- resources' ``initial``/``final`` states move to the graphics queue;
  ``stats.sync`` is ``"naive"``, ``stats.barriers`` the new count, ``stats.semaphores`` 0.

Memory placement, culling and pass order are the normal plan's.

    from rgraph.compiler.naive_sync import naive_sync
    plan = naive_sync(compile_graph("surgery"))
"""

from __future__ import annotations

import copy
from collections import defaultdict
from typing import Any

from rgraph.compiler.sync import mip_layer_rectangles

QUEUE = "graphics"
SRC = {"stages": ["ALL_COMMANDS"], "access": ["MEMORY_WRITE"]}
DST = {"stages": ["ALL_COMMANDS"], "access": ["MEMORY_READ", "MEMORY_WRITE"]}

Cell = tuple[int, int]  # (mip, layer); buffers: (0, 0)


def naive_sync(plan: dict[str, Any]) -> dict[str, Any]:
    """A copy of ``plan`` with naive synchronization (see the module docstring)."""
    out = copy.deepcopy(plan)
    resources = {r["name"]: r for r in out["resources"]}
    layouts = {name: _initial_layouts(res) for name, res in resources.items()}
    aliases = _alias_names(plan)
    handed_over: set[str] = set()
    count = 0
    for p in out["passes"]:
        p["queue"] = QUEUE
        p["waits"], p["signals"], p["releases"] = [], [], []
        wanted: dict[str, dict[Cell, str | None]] = defaultdict(dict)
        for a in p["accesses"]:
            for cell in _cells(resources[a["resource"]], a["subresource"]):
                wanted[a["resource"]][cell] = a["layout"]
        barriers = []
        for name in sorted(wanted):
            res = resources[name]
            groups: dict[tuple[str | None, str | None], list[Cell]] = defaultdict(list)
            for cell, layout in wanted[name].items():
                groups[(layouts[name].get(cell), layout)].append(cell)
                layouts[name][cell] = layout
            for (old, new), cells in sorted(groups.items(), key=lambda kv: (str(kv[0][0]), str(kv[0][1]))):
                for rect in mip_layer_rectangles(cells):
                    barriers.append(_barrier(res, rect, old, new, aliases.get(name) if name not in handed_over else None))
            handed_over.add(name)
        p["barriers"] = barriers
        count += len(barriers)
    out["queues"] = [QUEUE]
    for res in out["resources"]:
        for key in ("initial", "final"):
            _move_to_graphics(res.get(key))
    out["stats"] = {**out.get("stats", {}), "sync": "naive", "barriers": count, "semaphores": 0}
    return out


def _initial_layouts(res: dict) -> dict[Cell, str | None]:
    if res["kind"] != "image":
        return {(0, 0): None}
    initial = res.get("initial")
    default = "UNDEFINED"
    if isinstance(initial, dict) and res["lifetime"] in ("persistent", "imported"):
        default = initial["layout"]
    out = {(m, layer): default for m in range(res["mips"]) for layer in range(res["layers"])}
    if isinstance(initial, list):  # non-uniform: one entry per rectangle of cells
        for entry in initial:
            for cell in _cells(res, entry["subresource"]):
                out[cell] = entry["layout"]
    return out


def _alias_names(plan: dict) -> dict[str, Any]:
    """Per resource, the ``aliases`` of its normal plan's hand-off barriers (names merged)."""
    found: dict[str, list[str]] = {}
    for p in plan["passes"]:
        for b in p["barriers"]:
            names = b.get("aliases")
            if names:
                merged = found.setdefault(b["resource"], [])
                for n in [names] if isinstance(names, str) else names:
                    if n not in merged:
                        merged.append(n)
    return {k: (v[0] if len(v) == 1 else sorted(v)) for k, v in found.items()}


def _cells(res: dict, sub: dict | None) -> list[Cell]:
    if res["kind"] != "image":
        return [(0, 0)]
    sub = sub or {"mips": [0, res["mips"]], "layers": [0, res["layers"]]}
    return [(m, layer) for m in range(*sub["mips"]) for layer in range(*sub["layers"])]


def _barrier(res: dict, rect, old: str | None, new: str | None, aliases: Any) -> dict:
    image = res["kind"] == "image"
    return {
        "resource": res["name"],
        "subresource": {"mips": list(rect[0]), "layers": list(rect[1])} if image else None,
        "src": {**SRC, "layout": old if image else None, "queue": QUEUE},
        "dst": {**DST, "layout": new if image else None, "queue": QUEUE},
        "aliases": aliases if image and old == "UNDEFINED" or not image and aliases else None,
    }


def _move_to_graphics(state: Any) -> None:
    if isinstance(state, dict):
        state["queue"] = QUEUE
    elif isinstance(state, list):
        for entry in state:
            entry["queue"] = QUEUE
