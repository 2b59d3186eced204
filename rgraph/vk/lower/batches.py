"""Batches of passes (one command buffer and one VkSubmitInfo2 each) and frame 0's releases."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class PlanBatch:
    queue: str  # plan queue of the first pass (all passes share its VkQueue)
    passes: list[dict] = field(default_factory=list)


#: ``make_batches`` cuts: ``queue`` (default) only where a semaphore is needed (a wait on, or
#: a signal waited by, another VkQueue); ``plan`` at every plan wait and signal (before
#: session 11: with one VkQueue a frame still had two command buffers and two VkSubmitInfo2).
BATCH_CUTS = ("queue", "plan")


def make_batches(plan: dict, queues: Any, one_per_pass: bool = False, cuts: str = "queue") -> list[PlanBatch]:
    """Contiguous runs (in plan order) on one VkQueue (``queues.same_queue``), cut before a
    pass that waits for another VkQueue and after a pass whose signal another VkQueue waits for
    (``cuts="plan"``: before every pass with waits and after every pass with signals);
    ``one_per_pass`` (under validation) gives each pass its own command buffer so that
    validation messages name the pass."""
    if cuts not in BATCH_CUTS:
        raise ValueError(f"batch cuts must be one of {', '.join(BATCH_CUTS)}, not {cuts!r}")
    by_plan = cuts == "plan"
    waiters: dict[tuple[str, int], list[str]] = {}  # (signalling queue, value) -> the waiting passes' queues
    for p in plan["passes"]:
        for w in p["waits"]:
            waiters.setdefault((w["queue"], w["value"]), []).append(p["queue"])

    def waits_across(p: dict) -> bool:
        return any(by_plan or not queues.same_queue(w["queue"], p["queue"]) for w in p["waits"])

    def signals_across(p: dict) -> bool:
        return any(by_plan or not queues.same_queue(q, p["queue"])
                   for s in p["signals"] for q in waiters.get((p["queue"], s["value"]), ()))

    batches: list[PlanBatch] = []
    for p in plan["passes"]:
        last = batches[-1] if batches else None
        if (one_per_pass or last is None or not queues.same_queue(last.queue, p["queue"]) or waits_across(p)
                or signals_across(last.passes[-1])):
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
