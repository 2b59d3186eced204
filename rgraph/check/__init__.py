"""``rgraph check``: an independent happens-before replay of a plan JSON.

It reads only the plan (docs/plan.md), never the compiler's objects, and models
Vulkan synchronization itself (execution chains, availability/visibility, layouts,
queue-family ownership, timeline semaphores, aliasing), so it can judge the barrier
generator's output.

    from rgraph.check import check_plan
    hazards = check_plan(plan_dict)     # [] when the plan is clean

Each ``Hazard`` has ``kind`` (one of ``ALL_KINDS``), ``pass_index``, ``pass_name``,
``resource``, ``subresource`` and ``message`` (the full report line).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rgraph.check.hazards import (
    ALIASING_HANDOFF,
    ALIASING_OVERLAP,
    ALL_KINDS,
    FINAL_STATE,
    LAYOUT_MISMATCH,
    LIFETIME,
    MEMORY_LAYOUT,
    QUEUE_OWNERSHIP,
    RAW,
    SEMAPHORE,
    UNDEFINED_CONTENTS,
    WAR,
    WAW,
    Hazard,
)
from rgraph.check.jsonread import read_json
from rgraph.check.layout import check_layout
from rgraph.check.plan import Plan, PlanShapeError, read_plan
from rgraph.check.replay import Replay
from rgraph.errors import RGraphError
from rgraph.jsonloc import locate

__all__ = [
    "ALIASING_HANDOFF", "ALIASING_OVERLAP", "ALL_KINDS", "FINAL_STATE", "LAYOUT_MISMATCH", "LIFETIME", "MEMORY_LAYOUT",
    "QUEUE_OWNERSHIP", "RAW", "SEMAPHORE", "UNDEFINED_CONTENTS", "WAR", "WAW",
    "Hazard", "check_plan", "check_file", "load_plan_file",
]


def _model(plan: dict[str, Any], file: str, text: str | None) -> tuple[Plan, list[Hazard]]:
    """The checker's model of ``plan`` and its memory-layout hazards."""
    try:
        model = read_plan(plan)
        return model, check_layout(plan)
    except PlanShapeError as exc:
        line, col = locate(text, exc.path) if text is not None else (1, 1)
        raise RGraphError.in_file(file, f"malformed plan: {exc}", line, col) from None


def check_plan(plan: dict[str, Any]) -> list[Hazard]:
    """Every hazard in ``plan`` (a decoded plan JSON): memory layout first, then in replay
    order; [] when clean. A malformed plan raises ``RGraphError`` (located at line 1, as
    there is no text)."""
    if plan.get("multi_device"):
        return _check_devices(plan, "<plan>", None)[1]
    model, layout = _model(plan, "<plan>", None)
    return layout + Replay(model).run()


def _check_devices(plan: dict[str, Any], file: str, text: str | None) -> tuple[Plan, list[Hazard]]:
    """A multi-device plan: cross-device ordering, then each device's own plan replayed.
    The model returned is the whole plan's (for the counts a report prints)."""
    from rgraph.check.devices import cross_device_hazards, device_plan

    whole, _ = _model(plan, file, text)  # memory layout is checked per device below
    found = cross_device_hazards(plan)
    if any(" accesses " in h.message for h in found):  # a device's plan would name a resource it lacks
        return whole, found
    for d in range(int(plan["multi_device"].get("devices", 1))):
        model, layout = _model(device_plan(plan, d), file, text)
        found += [Hazard(h.kind, h.pass_index, h.pass_name, h.resource, h.subresource, f"device {d}: {h.message}")
                  for h in layout + Replay(model).run()]
    return whole, found


def load_plan_file(path: str | Path) -> tuple[dict[str, Any], str]:
    """The decoded plan and its text; ``RGraphError`` for unreadable or invalid JSON."""
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise RGraphError.in_file(path, "plan file not found")
    return read_json(path)


def check_file(path: str | Path) -> tuple[Plan, list[Hazard]]:
    """Read, validate and replay a plan file; ``RGraphError`` if it is not a readable plan."""
    plan, text = load_plan_file(path)
    if isinstance(plan, dict) and plan.get("multi_device"):
        return _check_devices(plan, str(path), text)
    model, layout = _model(plan, str(path), text)
    return model, layout + Replay(model).run()
