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
    plan = naive_sync(compile_graph_plan("surgery"))   # a Plan (a plan dict gives a dict)
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import replace
from typing import Any, overload

from rgraph.compiler.rectangles import mip_layer_rectangles
from rgraph.plan import from_json_dict, to_json_dict
from rgraph.plan.model import Barrier, CellState, EndState, Plan, PlanResource, State, Subresource

QUEUE = "graphics"
SRC_STAGES, SRC_ACCESS = ("ALL_COMMANDS",), ("MEMORY_WRITE",)
DST_STAGES, DST_ACCESS = ("ALL_COMMANDS",), ("MEMORY_READ", "MEMORY_WRITE")

Cell = tuple[int, int]  # (mip, layer); buffers: (0, 0)


@overload
def naive_sync(plan: Plan) -> Plan: ...
@overload
def naive_sync(plan: dict[str, Any]) -> dict[str, Any]: ...


def naive_sync(plan: Plan | dict[str, Any]) -> Plan | dict[str, Any]:
    """``plan`` with naive synchronization (see the module docstring); a dict gives a dict."""
    if isinstance(plan, dict):
        return to_json_dict(naive_sync(from_json_dict(plan)))
    resources = plan.resource_by_name
    layouts = {name: _initial_layouts(res) for name, res in resources.items()}
    aliases = _alias_names(plan)
    handed_over: set[str] = set()
    passes = []
    for p in plan.passes:
        wanted: dict[str, dict[Cell, str | None]] = defaultdict(dict)
        for a in p.accesses:
            for cell in _cells(resources[a.resource], a.subresource):
                wanted[a.resource][cell] = a.layout
        barriers = []
        for name in sorted(wanted):
            res = resources[name]
            groups: dict[tuple[str | None, str | None], list[Cell]] = defaultdict(list)
            for cell, layout in wanted[name].items():
                groups[(layouts[name].get(cell), layout)].append(cell)
                layouts[name][cell] = layout
            for (old, new), cells in sorted(groups.items(), key=lambda kv: (str(kv[0][0]), str(kv[0][1]))):
                for rect in mip_layer_rectangles(cells):
                    barriers.append(_barrier(res, rect, old, new, aliases.get(name, ()) if name not in handed_over
                                             else ()))
            handed_over.add(name)
        passes.append(replace(p, queue=QUEUE, waits=(), signals=(), releases=(), barriers=tuple(barriers)))
    count = sum(len(p.barriers) for p in passes)
    return replace(
        plan, queues=(QUEUE,), passes=tuple(passes),
        resources=tuple(replace(r, initial=_on_graphics(r.initial), final=_on_graphics(r.final))
                        for r in plan.resources),
        stats=replace(plan.stats, sync="naive", barriers=count, semaphores=0),
    )


def _initial_layouts(res: PlanResource) -> dict[Cell, str | None]:
    if not res.is_image:
        return {(0, 0): None}
    initial = res.initial
    default = "UNDEFINED"
    if isinstance(initial, State) and res.lifetime in ("persistent", "imported"):
        default = initial.layout
    out = {(m, layer): default for m in range(res.mips or 1) for layer in range(res.layers or 1)}
    if isinstance(initial, tuple):  # non-uniform: one entry per cell rectangle
        for entry in initial:
            for cell in _cells(res, entry.subresource):
                out[cell] = entry.state.layout
    return out


def _alias_names(plan: Plan) -> dict[str, tuple[str, ...]]:
    """Per resource, the ``aliases`` of its normal plan's hand-off barriers (names merged)."""
    found: dict[str, list[str]] = {}
    for p in plan.passes:
        for b in p.barriers:
            if b.aliases:
                merged = found.setdefault(b.resource, [])
                merged.extend(n for n in b.aliases if n not in merged)
    return {k: (tuple(v) if len(v) == 1 else tuple(sorted(v))) for k, v in found.items()}


def _cells(res: PlanResource, sub: Subresource | None) -> list[Cell]:
    if not res.is_image:
        return [(0, 0)]
    mips, layers = (sub.mips, sub.layers) if sub is not None else ((0, res.mips or 1), (0, res.layers or 1))
    return [(m, layer) for m in range(*mips) for layer in range(*layers)]


def _barrier(res: PlanResource, rect, old: str | None, new: str | None, aliases: tuple[str, ...]) -> Barrier:
    image = res.is_image
    return Barrier(
        resource=res.name,
        subresource=Subresource(tuple(rect[0]), tuple(rect[1])) if image else None,
        src=State(SRC_STAGES, SRC_ACCESS, old if image else None, QUEUE),
        dst=State(DST_STAGES, DST_ACCESS, new if image else None, QUEUE),
        aliases=aliases if image and old == "UNDEFINED" or not image else (),
    )


def _on_graphics(state: EndState) -> EndState:
    if isinstance(state, State):
        return replace(state, queue=QUEUE)
    if isinstance(state, tuple):
        return tuple(CellState(c.subresource, replace(c.state, queue=QUEUE)) for c in state)
    return state
