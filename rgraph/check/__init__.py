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
    model, layout = _model(plan, "<plan>", None)
    return layout + Replay(model).run()


def load_plan_file(path: str | Path) -> tuple[dict[str, Any], str]:
    """The decoded plan and its text; ``RGraphError`` for unreadable or invalid JSON."""
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise RGraphError.in_file(path, "plan file not found")
    return read_json(path)


def check_file(path: str | Path) -> tuple[Plan, list[Hazard]]:
    """Read, validate and replay a plan file; ``RGraphError`` if it is not a readable plan."""
    plan, text = load_plan_file(path)
    model, layout = _model(plan, str(path), text)
    return model, layout + Replay(model).run()
