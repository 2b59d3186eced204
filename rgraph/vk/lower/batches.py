"""Batches of passes (one command buffer and one VkSubmitInfo2 each) and frame 0's releases."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class PlanBatch:
    queue: str  # plan queue of the first pass (all passes share its VkQueue)
    passes: list[dict] = field(default_factory=list)


def make_batches(plan: dict, queues: Any, one_per_pass: bool = False) -> list[PlanBatch]:
    """Contiguous runs (in plan order) on one VkQueue (``queues.same_queue``), cut before a
    pass with waits and after a pass with signals; ``one_per_pass`` (under validation) gives
    each pass its own command buffer so that validation messages name the pass."""
    batches: list[PlanBatch] = []
    for p in plan["passes"]:
        last = batches[-1] if batches else None
        if (one_per_pass or last is None or not queues.same_queue(last.queue, p["queue"]) or p["waits"]
                or last.passes[-1]["signals"]):
            batches.append(PlanBatch(p["queue"], [p]))
        else:
            last.passes.append(p)
    return batches


def first_frame_releases(plan: dict, shared: set[str]) -> dict[str, list[dict]]:
    """Plan releases (by releasing queue) of ``shared`` resources whose acquire comes at or
    before the releasing pass: they hand the resource to the next frame.

    A persistent resource whose last use in a frame is on another queue family than its first
    use is released at that last use and acquired at the next frame's first use. Frame 0 has
    no previous frame, so after initialisation (which leaves the resource in its ``final``
    state on its final queue) the runtime records those same releases once."""
    def key(b: dict) -> tuple:
        return b["resource"], str(b.get("subresource")), b["src"]["queue"], b["dst"]["queue"]

    acquires = {key(b): i for i, p in enumerate(plan["passes"]) for b in p["barriers"]
                if b["src"]["queue"] != b["dst"]["queue"]}
    by_queue: dict[str, list[dict]] = {}
    for i, p in enumerate(plan["passes"]):
        for b in p["releases"]:
            if b["resource"] in shared and acquires.get(key(b), len(plan["passes"])) <= i:
                by_queue.setdefault(b["src"]["queue"], []).append(b)
    return by_queue
